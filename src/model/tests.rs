use super::{
    load_model, load_model_str, CreepageKind, FasteningModel, HoldPattern, Model, ModelError,
    ModelSource, Preset, RigidRegion, StartKind, BUILTIN_DUTCH, DEFAULT_INITIATION_THRESHOLD,
    DEFAULT_REST_START_DISTANCE_M,
};
fn dutch_with(overrides: &[&str]) -> Result<Model, ModelError> {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    load_model(&ModelSource::Builtin, &o)
}

#[test]
fn embedded_default_is_dutch_rpm3_with_stated_parameters() {
    let m = Model::default_model();
    assert_eq!(m.fastening.model(), FasteningModel::Rpm3);
    // Stated / literature values of docs/theory.md §3.6.
    assert_eq!(m.run.speed_kmh, 140.0);
    assert_eq!(m.wheel.radius, 0.46);
    assert_eq!(m.contact.friction, 0.4);
    assert_eq!(m.contact.traction_coefficient, 0.15);
    assert_eq!(m.track.sleeper_spacing, 0.6);
    assert_eq!(m.fastening.springs.vertical_stiffness, 1.3e9);
    assert_eq!(m.fastening.springs.vertical_damping, 45e3);
    assert_eq!(m.ballast.vertical_stiffness, 45e6);
    assert_eq!(m.vehicle.primary_stiffness, 1.15e6);
    assert!((m.run.speed() - 38.888_888_888_9).abs() < 1e-9);
}

#[test]
fn the_five_model_files_load_and_differ_only_in_the_fastening_model() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("models");
    let base = Model::default_model();
    for (i, want) in [
        FasteningModel::Rpm1,
        FasteningModel::Rpm2,
        FasteningModel::Rpm3,
        FasteningModel::Rpm4,
        FasteningModel::Rpm5,
    ]
    .into_iter()
    .enumerate()
    {
        let path = dir.join(format!("dutch-rpm{}.toml", i + 1));
        let m = load_model(&ModelSource::File(path), &[]).unwrap();
        assert_eq!(m.fastening.model(), want);
        let mut m2 = m.clone();
        m2.fastening.holds = base.fastening.holds.clone();
        assert_eq!(
            m2,
            base,
            "RPM{} differs from the base beyond the model",
            i + 1
        );
    }
}

use std::path::Path;

#[test]
fn overrides_use_toml_syntax_and_accept_bare_words() {
    let m = dutch_with(&[
        "fastening.model=RPM1",
        "track.bays=12",
        "run.speed_kmh=54.8",
    ])
    .unwrap();
    assert_eq!(m.fastening.model(), FasteningModel::Rpm1);
    assert_eq!(m.track.bays, 12);
    assert_eq!(m.run.speed_kmh, 54.8);
    let m = dutch_with(&[
        "fastening.model=\"RPM5\"",
        "mesh.sleeper_elements=[2, 6, 1]",
    ])
    .unwrap();
    assert_eq!(m.fastening.model(), FasteningModel::Rpm5);
    assert_eq!(m.mesh.sleeper_elements, [2, 6, 1]);
}

fn err_text(r: Result<Model, ModelError>) -> String {
    r.expect_err("must fail").to_string()
}

#[test]
fn unknown_key_names_the_key() {
    let e = err_text(dutch_with(&["fastening.stifness=1.0"]));
    assert!(
        e.contains("fastening.stifness") || e.contains("stifness"),
        "{e}"
    );
    assert!(e.contains("unknown field"), "{e}");
    let e = err_text(dutch_with(&["fastning.model=RPM1"]));
    assert!(e.contains("unknown section `fastning`"), "{e}");
}

#[test]
fn negative_stiffness_is_out_of_range_with_allowed_range() {
    let e = err_text(dutch_with(&["fastening.vertical_stiffness=-1e9"]));
    assert!(e.contains("fastening.vertical_stiffness"), "{e}");
    assert!(e.contains("allowed"), "{e}");
}

#[test]
fn poisson_ratio_of_one_half_is_rejected() {
    let e = err_text(dutch_with(&["rail.poisson_ratio=0.5"]));
    assert!(e.contains("rail.poisson_ratio") && e.contains("0.5"), "{e}");
}

#[test]
fn unknown_fastening_model_lists_the_allowed_names() {
    let e = err_text(dutch_with(&["fastening.model=RPM7"]));
    assert!(e.contains("fastening.model"), "{e}");
    assert!(e.contains("RPM1") && e.contains("custom"), "{e}");
}

#[test]
fn nan_values_are_rejected_not_propagated() {
    let e = err_text(dutch_with(&["vehicle.wheel_load=nan"]));
    assert!(e.contains("vehicle.wheel_load"), "{e}");
}

#[test]
fn syntax_error_names_the_file_and_line() {
    let e = load_model_str("[track\nbays = 3", "bad.toml", &[])
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("bad.toml: TOML syntax error"), "{e}");
    assert!(e.contains("line 1"), "{e}");
}

#[test]
fn custom_pattern_round_trips_and_is_checked() {
    let m = dutch_with(&[
        "fastening.model=custom",
        "fastening.custom.x={ rigid = \"columns\", indices = [0, 2] }",
        "fastening.custom.y={ rigid = \"rows\", indices = [0, 3] }",
        "fastening.custom.z={ rigid = \"none\" }",
    ])
    .unwrap();
    let p = m.fastening.hold_pattern();
    assert_eq!(p.x.indices, vec![0, 2]);
    assert_eq!(p.z.rigid, RigidRegion::None);
    let e = err_text(dutch_with(&[
        "fastening.model=custom",
        "fastening.custom.x={ rigid = \"columns\", indices = [3] }",
        "fastening.custom.y={ rigid = \"none\" }",
        "fastening.custom.z={ rigid = \"none\" }",
    ]));
    assert!(
        e.contains("fastening.custom.x.indices") && e.contains("0..=2"),
        "{e}"
    );
    let e = err_text(dutch_with(&["fastening.model=custom"]));
    assert!(e.contains("fastening.custom"), "{e}");
}

#[test]
fn presets_follow_the_method_table() {
    use RigidRegion::{Columns, Continuous, Rows};
    let p = |m| HoldPattern::preset(m, 4, 3);
    // docs/theory.md §3.2 table: vertical / longitudinal / lateral.
    let r1 = p(Preset::Rpm1);
    assert_eq!(
        (r1.z.rigid, r1.x.rigid, &r1.x.indices[..]),
        (RigidRegion::None, Columns, &[0, 1, 2][..])
    );
    let r2 = p(Preset::Rpm2);
    assert_eq!((r2.z.rigid, r2.x.rigid), (RigidRegion::None, Continuous));
    let r3 = p(Preset::Rpm3);
    assert_eq!(
        (r3.z.rigid, r3.x.rigid, &r3.x.indices[..]),
        (RigidRegion::None, Columns, &[1][..])
    );
    let r4 = p(Preset::Rpm4);
    assert_eq!(
        (r4.z.rigid, r4.x.rigid, &r4.x.indices[..]),
        (Continuous, Columns, &[1][..])
    );
    let r5 = p(Preset::Rpm5);
    assert_eq!((r5.z.rigid, r5.x.rigid), (Continuous, Continuous));
    for r in [r1, r2, r3, r4, r5] {
        assert_eq!((r.y.rigid, &r.y.indices[..]), (Rows, &[0, 1, 2, 3][..]));
    }
    assert!(FasteningModel::Custom.preset().is_none());
}

#[test]
fn extends_chain_resolves_relative_paths_and_detects_loops() {
    let dir = std::env::temp_dir().join(format!("corrugation-model-test-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    std::fs::write(
        dir.join("a.toml"),
        "extends = \"builtin:dutch\"\n[track]\nbays = 10\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("sub/b.toml"),
        "extends = \"../a.toml\"\n[run]\nspeed_kmh = 100.0\n",
    )
    .unwrap();
    let m = load_model(&ModelSource::File(dir.join("sub/b.toml")), &[]).unwrap();
    assert_eq!((m.track.bays, m.run.speed_kmh), (10, 100.0));
    std::fs::write(dir.join("loop.toml"), "extends = \"loop.toml\"\n").unwrap();
    let e = load_model(&ModelSource::File(dir.join("loop.toml")), &[]).unwrap_err();
    assert!(matches!(e, ModelError::ExtendsLoop { .. }), "{e}");
    let e = load_model(&ModelSource::File(dir.join("missing.toml")), &[]).unwrap_err();
    assert!(e.to_string().contains("missing.toml: cannot read"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn explicit_section_takes_a_safety_factor_and_an_optional_step() {
    let m = dutch_with(&[]).unwrap();
    assert_eq!(m.explicit.safety, 0.9);
    assert_eq!(m.explicit.time_step, None);
    assert!(dutch_with(&["explicit.time_step=5e-8"]).is_ok());
    let e = err_text(dutch_with(&["explicit.safety=1.5"]));
    assert!(e.contains("explicit.safety"), "{e}");
    let e = err_text(dutch_with(&["explicit.time_step=1.0"]));
    assert!(e.contains("explicit.time_step"), "{e}");
    // The removed key is refused by name.
    let e = err_text(dutch_with(&["explicit.element_length=0.0008"]));
    assert!(e.contains("element_length"), "{e}");
}

#[test]
fn material_parameters_outside_their_physical_range_are_rejected_with_the_range() {
    // Each limit is the stated constant: just inside passes, just outside fails naming the key.
    for (part, key) in [
        ("rail", "youngs_modulus"),
        ("sleeper", "youngs_modulus"),
        ("wheel", "youngs_modulus"),
    ] {
        for v in ["1e-12", "9.9e8", "1.1e13"] {
            let e = err_text(dutch_with(&[&format!("{part}.{key}={v}")]));
            assert!(
                e.contains(&format!("{part}.{key}"))
                    && e.contains("1000000000 to 10000000000000 Pa"),
                "{e}"
            );
        }
    }
    assert!(dutch_with(&["sleeper.youngs_modulus=1e9", "wheel.youngs_modulus=1e9"]).is_ok());
    for (key, bad) in [
        ("rail.density", "999"),
        ("wheel.density", "1e-3"),
        ("sleeper.density", "20001"),
        ("rail.poisson_ratio", "0.4999"),
        ("wheel.poisson_ratio", "0.46"),
        ("sleeper.poisson_ratio", "-0.1"),
    ] {
        let e = err_text(dutch_with(&[&format!("{key}={bad}")]));
        assert!(e.contains(key) && e.contains("allowed"), "{key}: {e}");
    }
}

#[test]
fn poisson_ratio_near_one_half_is_blamed_not_the_time_step() {
    let e = err_text(dutch_with(&["rail.poisson_ratio=0.4999"]));
    assert!(
        e.contains("rail.poisson_ratio") && e.contains("0 to 0.45"),
        "{e}"
    );
    assert!(!e.contains("explicit.time_step"), "{e}");
}

#[test]
fn gravity_sleeper_size_and_conicity_are_checked_by_the_model_not_later() {
    for (kv, key) in [
        ("vehicle.gravity=0", "vehicle.gravity"),
        ("vehicle.gravity=1e-3", "vehicle.gravity"),
        ("sleeper.height=1e-4", "sleeper.height"),
        ("sleeper.width=1e-3", "sleeper.width"),
        // The wheel mesh needs |c| < 0.2: the model must refuse 0.2 itself.
        ("wheel.conicity=0.2", "wheel.conicity"),
    ] {
        let e = err_text(dutch_with(&[kv]));
        assert!(e.contains(key) && e.contains("allowed"), "{kv}: {e}");
    }
    assert!(dutch_with(&["vehicle.gravity=9.78", "wheel.conicity=0.05"]).is_ok());
}

#[test]
fn zero_railpad_stiffness_without_a_rigid_hold_names_the_fastening() {
    // RPM3 holds z by the springs alone: k_z = 0 leaves the rail unsupported vertically.
    let e = err_text(dutch_with(&["fastening.vertical_stiffness=0"]));
    assert!(e.contains("fastening.vertical_stiffness"), "{e}");
    assert!(!e.contains("ballast"), "{e}");
    // RPM4 holds z rigidly everywhere: there k_z = 0 is allowed; x is always held by RPM1-5.
    assert!(dutch_with(&["fastening.model=RPM4", "fastening.vertical_stiffness=0"]).is_ok());
    assert!(
        dutch_with(&[])
            .unwrap()
            .fastening
            .springs
            .longitudinal_stiffness
            == 0.0
    );
}

#[test]
fn elastic_holds_parse_and_nonsense_is_an_error_naming_the_key() {
    let custom = |x: &str| {
        dutch_with(&[
            "fastening.model=custom",
            &format!("fastening.custom.x={x}"),
            "fastening.custom.y={ rigid = \"rows\", indices = [0, 3] }",
            "fastening.custom.z={ rigid = \"none\" }",
        ])
    };
    let m =
        custom("{ elastic = \"columns\", indices = [1], stiffness = 1e9, damping = 5.0 }").unwrap();
    let p = m.fastening.hold_pattern();
    assert_eq!(p.x.region(), RigidRegion::Columns);
    assert_eq!(p.x.rigid, RigidRegion::None);
    assert_eq!(p.x.elastic_stiffness_damping(), Some((1e9, 5.0)));
    assert_eq!(p.y.elastic_stiffness_damping(), None);
    // A preset made elastic in x only; damping defaults to 0.
    let m = dutch_with(&[
        "fastening.hold=\"elastic\"",
        "fastening.hold_stiffness=3e8",
        "fastening.hold_directions=[\"x\"]",
    ])
    .unwrap();
    let p = m.fastening.hold_pattern();
    assert_eq!(
        (p.x.region(), p.x.elastic_stiffness_damping()),
        (RigidRegion::Columns, Some((3e8, 0.0)))
    );
    assert_eq!((p.y.rigid, p.y.elastic), (RigidRegion::Rows, None));
    for (x, key, what) in [
        (
            "{ elastic = \"columns\", indices = [1], stiffness = 0.0 }",
            "fastening.custom.x.stiffness",
            "1e4 to 1e13 N/m",
        ),
        (
            "{ elastic = \"columns\", indices = [1], stiffness = -1e9 }",
            "fastening.custom.x.stiffness",
            "1e4 to 1e13 N/m",
        ),
        (
            "{ elastic = \"columns\", indices = [1] }",
            "fastening.custom.x.stiffness",
            "needs stiffness",
        ),
        (
            "{ elastic = \"columns\", indices = [3], stiffness = 1e9 }",
            "fastening.custom.x.indices",
            "0..=2",
        ),
        (
            "{ elastic = \"columns\", indices = [1, 1], stiffness = 1e9 }",
            "fastening.custom.x.indices",
            "distinct",
        ),
        (
            "{ elastic = \"rows\", indices = [4], stiffness = 1e9 }",
            "fastening.custom.x.indices",
            "0..=3",
        ),
        (
            "{ elastic = \"continuous\", indices = [0], stiffness = 1e9 }",
            "fastening.custom.x.indices",
            "only allowed",
        ),
        (
            "{ elastic = \"grid_points\", stiffness = 1e9, damping = -1.0 }",
            "fastening.custom.x.damping",
            "0 to",
        ),
        (
            "{ elastic = \"none\", stiffness = 1e9 }",
            "fastening.custom.x.elastic",
            "needs a region",
        ),
        (
            "{ rigid = \"columns\", elastic = \"columns\", indices = [1], stiffness = 1e9 }",
            "fastening.custom.x",
            "not both",
        ),
        (
            "{ rigid = \"columns\", indices = [1], stiffness = 1e9 }",
            "fastening.custom.x.stiffness",
            "only allowed with an elastic",
        ),
    ] {
        let e = err_text(custom(x));
        assert!(e.contains(key) && e.contains(what), "{x}: {e}");
    }
    for (sets, key, what) in [
        (
            vec!["fastening.hold=\"elastic\""],
            "fastening.hold_stiffness",
            "needs hold_stiffness",
        ),
        (
            vec![
                "fastening.hold=\"elastic\"",
                "fastening.hold_stiffness=1e14",
            ],
            "fastening.hold_stiffness",
            "1e4 to 1e13 N/m",
        ),
        (
            vec!["fastening.hold_stiffness=1e9"],
            "fastening.hold_stiffness",
            "only allowed with fastening.hold",
        ),
        (
            vec![
                "fastening.hold=\"elastic\"",
                "fastening.hold_stiffness=1e9",
                "fastening.hold_directions=[\"z\"]",
            ],
            "fastening.hold_directions",
            "RPM3 holds nothing",
        ),
        (vec!["fastening.hold=\"plastic\""], "fastening.hold", ""),
    ] {
        let e = err_text(dutch_with(&sets));
        assert!(e.contains(key) && e.contains(what), "{sets:?}: {e}");
    }
    let e = err_text(dutch_with(&[
        "fastening.model=custom",
        "fastening.custom.x={ rigid = \"none\" }",
        "fastening.custom.y={ rigid = \"none\" }",
        "fastening.custom.z={ rigid = \"none\" }",
        "fastening.hold=\"elastic\"",
        "fastening.hold_stiffness=1e9",
    ]));
    assert!(e.contains("fastening.hold") && e.contains("custom"), "{e}");
}

#[test]
fn fastening_model_prints_as_in_model_files() {
    for m in [
        FasteningModel::Rpm1,
        FasteningModel::Rpm2,
        FasteningModel::Rpm3,
        FasteningModel::Rpm4,
        FasteningModel::Rpm5,
        FasteningModel::Custom,
    ] {
        let serde_name = serde_json::to_value(m).unwrap();
        assert_eq!(serde_name.as_str(), Some(m.to_string().as_str()));
    }
    assert_eq!(FasteningModel::Rpm3.to_string(), "RPM3");
}

#[test]
fn initiation_threshold_is_read_defaulted_and_range_checked() {
    // A model file without the key gets the default.
    let text = BUILTIN_DUTCH.replace("initiation_threshold = 0.01", "");
    assert!(!text.contains("initiation_threshold ="));
    let m = load_model_str(&text, "no-threshold.toml", &[]).unwrap();
    assert_eq!(m.wear.initiation_threshold, DEFAULT_INITIATION_THRESHOLD);
    let m = dutch_with(&["wear.initiation_threshold=0.002"]).unwrap();
    assert_eq!(m.wear.initiation_threshold, 0.002);
    let e = dutch_with(&["wear.initiation_threshold=1.5"])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("wear.initiation_threshold") && e.contains("0 to 1"),
        "{e}"
    );
}

/// `run.start`, `run.rest_start_distance` and `run.wheel_residual_flexibility`: defaults
/// when absent, read when given, and nonsense is an error naming the file, the key and the
/// allowed values or range.
#[test]
fn start_keys_are_read_defaulted_and_range_checked() {
    let text = BUILTIN_DUTCH
        .lines()
        .filter(|l| {
            !(l.starts_with("start =")
                || l.starts_with("rest_start_distance =")
                || l.starts_with("wheel_residual_flexibility ="))
        })
        .collect::<Vec<_>>()
        .join("\n");
    let m = load_model_str(&text, "no-start.toml", &[]).unwrap();
    assert_eq!(m.run.start, StartKind::Static);
    assert_eq!(m.run.rest_start_distance, DEFAULT_REST_START_DISTANCE_M);
    assert!(m.run.wheel_residual_flexibility);
    let m = dutch_with(&["run.start=rest", "run.rest_start_distance=0.2"]).unwrap();
    assert_eq!(m.run.start, StartKind::Rest);
    assert_eq!(m.run.rest_start_distance, 0.2);
    let e = err_text(dutch_with(&["run.start=moving"]));
    assert!(e.contains("run.start") || e.contains("start"), "{e}");
    assert!(e.contains("static") && e.contains("rest"), "{e}");
    for bad in ["0", "-0.1", "nan", "11"] {
        let e = err_text(dutch_with(&[&format!("run.rest_start_distance={bad}")]));
        assert!(
            e.contains("run.rest_start_distance") && e.contains("at most 10"),
            "{bad}: {e}"
        );
    }
    // Beyond the run-in (0.3 m): an error with the start from rest, naming the keys to change.
    let e = err_text(dutch_with(&[
        "run.start=rest",
        "run.rest_start_distance=0.5",
    ]));
    assert!(
        e.contains("run.rest_start_distance")
            && e.contains("run-in 0.300 m")
            && e.contains("run.solution_zone_offset")
            && e.contains("track.bays")
            && e.contains("builtin:dutch"),
        "{e}"
    );
    // ... but not with the static start, which does not read it.
    assert!(dutch_with(&["run.rest_start_distance=0.5"]).is_ok());
    // A short track leaves less run-in than the offset: 4 bays (2.4 m), zone 2 m → 0.2 m.
    let e = err_text(dutch_with(&[
        "track.bays=4",
        "run.solution_zone_length=2.0",
        "run.start=rest",
    ]));
    assert!(e.contains("run-in 0.200 m"), "{e}");
}

/// `run.creepage`: `"velocity"` when absent, `"increment"` read when given, and another
/// value an error naming the key and the allowed values.
#[test]
fn creepage_key_is_read_defaulted_and_checked() {
    assert_eq!(
        dutch_with(&[]).unwrap().run.creepage,
        CreepageKind::Velocity
    );
    let m = dutch_with(&["run.creepage=increment"]).unwrap();
    assert_eq!(m.run.creepage, CreepageKind::Increment);
    let e = err_text(dutch_with(&["run.creepage=mean"]));
    assert!(e.contains("creepage"), "{e}");
    assert!(e.contains("velocity") && e.contains("increment"), "{e}");
}

/// An absorbing layer that would reach into the wheel's travel is refused, naming the key and
/// the room the track leaves; the default track leaves room for the default layer.
#[test]
fn an_absorbing_layer_in_the_wheels_travel_is_refused() {
    assert!(dutch_with(&["track.ends=\"absorbing\""]).is_ok());
    let e = err_text(dutch_with(&[
        "track.ends=\"absorbing\"",
        "track.absorbing_layer_length=4.5",
    ]));
    assert!(e.contains("track.absorbing_layer_length"), "{e}");
    assert!(e.contains("wheel's travel"), "{e}");
    let e = err_text(dutch_with(&["track.absorbing_layer_rate=-1"]));
    assert!(e.contains("track.absorbing_layer_rate"), "{e}");
    let e = err_text(dutch_with(&["track.ends=\"sponge\""]));
    assert!(e.contains("track.ends") || e.contains("ends"), "{e}");
}

#[test]
fn node_line_holds_parse_and_nonsense_is_an_error_naming_the_key() {
    let custom = |x: &str| {
        dutch_with(&[
            "fastening.model=custom",
            &format!("fastening.custom.x={x}"),
            "fastening.custom.y={ rigid = \"rows\", indices = [0, 1, 2, 3], node_lines = true }",
            "fastening.custom.z={ rigid = \"none\" }",
        ])
    };
    let m = custom("{ rigid = \"columns\", indices = [0, 1, 2], node_lines = true }").unwrap();
    let p = m.fastening.hold_pattern();
    assert!(p.x.on_node_lines() && p.y.on_node_lines() && !p.z.on_node_lines());
    assert_eq!(p.x.elastic_stiffness_damping(), None);
    let m = custom(
        "{ elastic = \"columns\", indices = [1], node_lines = true, line_stiffness = 3e8, line_damping = 2.0 }",
    )
    .unwrap();
    let p = m.fastening.hold_pattern();
    assert_eq!(p.x.elastic_stiffness_damping(), Some((3e8, 2.0)));
    // Without node_lines the strips keep their keys.
    assert!(!Model::default_model()
        .fastening
        .hold_pattern()
        .x
        .on_node_lines());
    for (x, key, what) in [
        (
            "{ elastic = \"columns\", indices = [1], node_lines = true }",
            "fastening.custom.x.line_stiffness",
            "N/m per held line",
        ),
        (
            "{ elastic = \"columns\", indices = [1], node_lines = true, line_stiffness = 0.0 }",
            "fastening.custom.x.line_stiffness",
            "1e4 to 1e13 N/m per held line",
        ),
        (
            "{ elastic = \"rows\", indices = [0], node_lines = true, line_stiffness = nan }",
            "fastening.custom.x.line_stiffness",
            "per held line",
        ),
        (
            "{ elastic = \"columns\", indices = [1], node_lines = true, line_stiffness = 1e8, line_damping = -1.0 }",
            "fastening.custom.x.line_damping",
            "0 to 1e12 N s/m per held line",
        ),
        (
            "{ elastic = \"columns\", indices = [1], node_lines = true, stiffness = 1e8 }",
            "fastening.custom.x.stiffness",
            "line_stiffness",
        ),
        (
            "{ elastic = \"columns\", indices = [1], stiffness = 1e8, line_stiffness = 1e8 }",
            "fastening.custom.x.line_stiffness",
            "node_lines = true",
        ),
        (
            "{ rigid = \"columns\", indices = [1], node_lines = true, line_stiffness = 1e8 }",
            "fastening.custom.x.line_stiffness",
            "only allowed with an elastic",
        ),
        (
            "{ rigid = \"continuous\", node_lines = true }",
            "fastening.custom.x.node_lines",
            "\"columns\" and \"rows\" only",
        ),
        (
            "{ rigid = \"columns\", indices = [3], node_lines = true }",
            "fastening.custom.x.indices",
            "0..=2",
        ),
        (
            "{ rigid = \"columns\", indices = [1], node_lines = 1 }",
            "fastening",
            "bool",
        ),
    ] {
        let e = err_text(custom(x));
        assert!(e.contains(key) && e.contains(what), "{x}: {e}");
        assert_eq!(e.lines().count(), 1, "{x}: {e}");
    }
}

/// Computed bounds print as a reader writes them: the default rim's smallest radius is
/// 0.39 + 0.03 = 0.42 m (not 0.42000000000000004), the rim's thickest 0.46 - 0.2 = 0.26 m.
#[test]
fn computed_bounds_print_without_round_off_digits() {
    let e = err_text(dutch_with(&["wheel.radius=0.3"]));
    assert!(e.contains("allowed 0.42 to 0.8 m"), "{e}");
    let e = err_text(dutch_with(&["wheel.rim_thickness=0.5"]));
    assert!(e.contains("allowed 0.03 to 0.26 m"), "{e}");
    for e in [
        err_text(dutch_with(&["wheel.radius=0.3"])),
        err_text(dutch_with(&["wheel.rim_thickness=0.5"])),
        err_text(dutch_with(&["wheel.web_thickness=0.09"])),
    ] {
        assert!(!e.contains("0000000"), "{e}");
    }
}

/// A position off the track is refused by the model, naming what gave it and the track's
/// length; the ends are on the track.
#[test]
fn positions_off_the_track_are_refused_by_the_model() {
    let m = crate::model::test_problems::small_model(&[]).unwrap();
    let l = m.track_length();
    assert!(m.check_on_track("--at", &[0.0, 0.5 * l, l]).is_ok());
    for bad in [-0.1, l + 0.1, f64::NAN] {
        let e = m
            .check_on_track("--at", &[1.0, bad])
            .unwrap_err()
            .to_string();
        assert!(e.contains("--at") && e.contains("off the track"), "{e}");
    }
}

/// An override parses into its key path and TOML value (every kind; a bare word is a string),
/// prints and parses back to itself, and applied puts its value at its key path.
#[test]
fn assignments_equal_their_text_overrides() {
    use super::{apply_assignment, Assignment};
    use toml::Value;
    let mut hold = toml::Table::new();
    hold.insert("rigid".into(), Value::String("none".into()));
    for (arg, key, want) in [
        (
            "fastening.vertical_stiffness=1.3e9",
            "fastening.vertical_stiffness",
            Value::Float(1.3e9),
        ),
        (
            "fastening.model=RPM1",
            "fastening.model",
            Value::String("RPM1".into()),
        ),
        (
            "fastening.model=\"RPM2\"",
            "fastening.model",
            Value::String("RPM2".into()),
        ),
        (" track.bays = 12 ", "track.bays", Value::Integer(12)),
        (
            "run.residual_flexibility=false",
            "run.residual_flexibility",
            Value::Boolean(false),
        ),
        (
            "mesh.sleeper_elements=[4, 3, 2]",
            "mesh.sleeper_elements",
            Value::Array(vec![
                Value::Integer(4),
                Value::Integer(3),
                Value::Integer(2),
            ]),
        ),
        (
            "fastening.custom.x={ rigid = \"none\" }",
            "fastening.custom.x",
            Value::Table(hold.clone()),
        ),
        ("run.speed_kmh=-5", "run.speed_kmh", Value::Integer(-5)),
    ] {
        let a = Assignment::parse(arg).unwrap();
        assert_eq!((a.key.as_str(), &a.value), (key, &want), "{arg}");
        assert_eq!(Assignment::parse(&a.to_string()).unwrap(), a, "{arg}");
        // applied, the value stands at its key path of the table
        let mut t: toml::Table = super::BUILTIN_DUTCH.parse().unwrap();
        apply_assignment(&mut t, &a).unwrap();
        let (path, leaf) = key.rsplit_once('.').unwrap();
        let section = path.split('.').fold(&t, |t, p| t[p].as_table().unwrap());
        assert_eq!(section[leaf], want, "{arg}");
    }
    for bad in ["track.bays", "=3", "a..b=1", "x=[1,"] {
        assert!(Assignment::parse(bad).is_err(), "{bad}");
    }
    let e = apply_assignment(
        &mut toml::Table::new(),
        &Assignment {
            key: "fastening.railpad.k".into(),
            value: toml::Value::Float(6e8),
        },
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("fastening.railpad.k=600000000.0") && e.contains("unknown section"),
        "{e}"
    );
}
