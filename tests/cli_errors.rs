//! Bad input gets a clear one-line error naming the key, a non-zero exit code and no panic.
//! These run the real binary.

mod common;

use common::{is_one_line_error, run, SMALL_MODEL};

fn assert_clean_error(args: &[&str], must_contain: &[&str]) {
    let (code, _out, err) = run(args);
    assert_ne!(code, 0, "{args:?} must fail");
    assert_ne!(code, 101, "{args:?} panicked: {err}");
    assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
    assert!(is_one_line_error(&err), "one-line error expected: {err}");
    for s in must_contain {
        assert!(err.contains(s), "{args:?}: error `{err}` lacks `{s}`");
    }
}

/// A file `name` holding `text` in a fresh temporary directory, removed when the returned
/// guard drops.
fn tmp_file(name: &str, text: &str) -> (tempfile::TempDir, std::path::PathBuf) {
    let d = tempfile::Builder::new()
        .prefix("corrugation-cli-")
        .tempdir()
        .unwrap();
    let p = d.path().join(name);
    std::fs::write(&p, text).unwrap();
    (d, p)
}

#[test]
fn missing_file() {
    assert_clean_error(
        &["model", "--model", "/nonexistent/track.toml"],
        &["/nonexistent/track.toml", "cannot read"],
    );
}

#[test]
fn toml_syntax_error() {
    let (_dir, p) = tmp_file(
        "syntax.toml",
        "extends = \"builtin:dutch\"\n[track\nbays = 3\n",
    );
    assert_clean_error(
        &["model", "--model", p.to_str().unwrap()],
        &["syntax.toml", "TOML syntax error", "line 2"],
    );
}

#[test]
fn unknown_key() {
    let (_dir, p) = tmp_file(
        "unknown.toml",
        "extends = \"builtin:dutch\"\n[rail]\nyoungs_modulos = 2e11\n",
    );
    assert_clean_error(
        &["model", "--model", p.to_str().unwrap()],
        &["unknown.toml", "rail.youngs_modulos", "unknown field"],
    );
}

/// A model file copied out of `models/` whose `extends` names a parent that is not beside
/// it: the error names the key, the path it looked for, that the path is relative to the
/// file, and the file's own typo as well (not hidden behind the missing parent).
#[test]
fn a_copied_file_whose_parent_is_missing_names_extends_and_its_own_typo() {
    let (_dir, p) = tmp_file(
        "copied.toml",
        "extends = \"reference-described-base.toml\"\n[rail]\nyoungs_modulos = 2e11\n",
    );
    assert_clean_error(
        &["model", "--model", p.to_str().unwrap()],
        &[
            "copied.toml",
            "`extends`",
            "reference-described-base.toml",
            "relative to this file's directory",
            "rail.youngs_modulos",
        ],
    );
}

#[test]
fn negative_stiffness() {
    assert_clean_error(
        &["model", "--set", "ballast.vertical_stiffness=-45e6"],
        &["ballast.vertical_stiffness", "-45000000", "allowed"],
    );
}

#[test]
fn poisson_ratio_at_least_one_half() {
    assert_clean_error(
        &["model", "--set", "sleeper.poisson_ratio=0.55"],
        &["sleeper.poisson_ratio", "0.55"],
    );
}

#[test]
fn unknown_fastening_model() {
    assert_clean_error(
        &["model", "--set", "fastening.model=RPM9"],
        &["fastening.model", "RPM9", "RPM1"],
    );
}

#[test]
fn resolved_model_round_trips_as_a_model_file() {
    // `corrugation model` prints a complete model: saved to a file it loads to the same model.
    let (code, out, err) = run(&[
        "model",
        "--set",
        "fastening.model=RPM1",
        "--set",
        "track.bays=12",
    ]);
    assert_eq!(code, 0, "{err}");
    let (_dir, p) = tmp_file("resolved.toml", &out);
    let (code, out2, err) = run(&["model", "--model", p.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(out, out2);
    assert!(out.contains("model = \"RPM1\"") && out.contains("bays = 12"));
}

#[test]
fn mesh_command_json_vtu_and_matrix_market() {
    let tmp = tempfile::Builder::new()
        .prefix("corrugation-cli-mesh-")
        .tempdir()
        .unwrap();
    let dir = tmp.path();
    let vtu = dir.join("mesh.vtu");
    let mtx = dir.join("mtx");
    let mut args = vec![
        "mesh",
        "--json",
        "--vtu",
        vtu.to_str().unwrap(),
        "--mtx",
        mtx.to_str().unwrap(),
    ];
    args.extend(SMALL_MODEL);
    let (code, out, err) = run(&args);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).expect("--json prints one JSON object");
    for key in [
        "nodes",
        "elements",
        "free_dofs",
        "rail_area_m2",
        "rail_mass_per_m_kg",
        "rail_i_vertical_m4",
        "rail_i_lateral_m4",
        "mass_by_part_kg",
        "constrained_dofs",
    ] {
        assert!(v.get(key).is_some(), "missing key {key}: {out}");
    }
    let free = v["free_dofs"].as_u64().unwrap() as usize;
    // K.mtx is square over the free DOFs; dofs.csv has one row per free DOF.
    let k = std::fs::read_to_string(mtx.join("K.mtx")).unwrap();
    let size_line = k.lines().find(|l| !l.starts_with('%')).unwrap();
    assert!(
        size_line.starts_with(&format!("{free} {free} ")),
        "{size_line}"
    );
    let dofs = std::fs::read_to_string(mtx.join("dofs.csv")).unwrap();
    assert_eq!(dofs.lines().count(), free + 1);
    for f in ["M.mtx", "wheel_K.mtx", "wheel_M.mtx", "wheel_dofs.csv"] {
        assert!(mtx.join(f).exists(), "{f}");
    }
    let text = std::fs::read_to_string(&vtu).unwrap();
    assert!(
        text.contains("<VTKFile")
            && text.contains("held_xyz")
            && text.trim_end().ends_with("</VTKFile>")
    );
}

#[test]
fn contact_rejects_a_negative_friction_coefficient_cleanly() {
    assert_clean_error(&["contact", "--friction", "-0.4"], &["friction"]);
}

#[test]
fn contact_command_json_keys_and_hertz_geometry() {
    // Transient rolling from rest over 20 grid steps with a prescribed creepage: the normal
    // part is the Hertz problem of the model (a = 7.162 mm, b = 5.387 mm, p0 = 1237.6 MPa,
    // approach 104.1 µm for the reference wheel on the R300 crown, docs/theory.md §6.2).
    let (code, out, err) = run(&["contact", "--json", "--creepage", "-0.001", "--steps", "20"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    for key in [
        "a_mm",
        "b_mm",
        "p0_mpa",
        "approach_um",
        "area_mm2",
        "fx_n",
        "fy_n",
        "creepage",
        "slip_area_fraction",
    ] {
        assert!(v[key].is_number(), "missing {key}: {out}");
    }
    let rel = |k: &str, want: f64| (v[k].as_f64().unwrap() - want).abs() / want;
    assert!(
        rel("a_mm", 7.162) < 0.02 && rel("b_mm", 5.387) < 0.02,
        "{out}"
    );
    assert!(
        rel("approach_um", 104.1) < 0.01 && rel("p0_mpa", 1237.6) < 0.02,
        "{out}"
    );
    // Driving creepage (ξ < 0) gives a positive force on the wheel, below µN.
    let fx = v["fx_n"].as_f64().unwrap();
    assert!(fx > 0.0 && fx < 0.4 * 100e3, "{out}");
}

/// A steel damping value is refused as an unknown key (steel damping is not modelled: all
/// damping sits in the discrete dampers), not silently ignored.
#[test]
fn rail_structural_damping_is_an_unknown_key() {
    let (code, _, err) = common::run(&["model", "--set", "rail.structural_damping=1e-6"]);
    assert_ne!(code, 0);
    assert!(err.contains("structural_damping"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

/// `S` of the robustness reproductions: a short passage model.
const S: [&str; 4] = ["--set", "run.fmax=1000", "--set", "track.bays=6"];

fn with_s<'a>(args: &[&'a str]) -> Vec<&'a str> {
    let mut v = args.to_vec();
    v.extend(S);
    v
}

#[test]
fn unphysical_youngs_modulus_is_refused_before_any_allocation() {
    // Rail E = 1e-12 Pa panicked on a 47.5 GB allocation; sleeper E = 1e-12 Pa hung.
    for key in ["rail", "sleeper", "wheel"] {
        let set = format!("{key}.youngs_modulus=1e-12");
        assert_clean_error(
            &with_s(&["passage", "--set", &set]),
            &[
                &format!("{key}.youngs_modulus"),
                "1000000000 to 10000000000000 Pa",
            ],
        );
    }
}

#[test]
fn tiny_gravity_density_and_sleeper_height_name_their_key() {
    for (set, key) in [
        ("vehicle.gravity=0", "vehicle.gravity"),
        ("vehicle.gravity=1e-3", "vehicle.gravity"),
        ("wheel.density=1e-3", "wheel.density"),
        ("sleeper.height=1e-4", "sleeper.height"),
        ("wheel.conicity=0.2", "wheel.conicity"),
        ("rail.poisson_ratio=0.4999", "rail.poisson_ratio"),
    ] {
        assert_clean_error(&with_s(&["mesh", "--set", set]), &[key, "allowed"]);
    }
}

#[test]
fn zero_railpad_stiffness_is_blamed_on_the_fastening() {
    let (_, _, err) = run(&with_s(&[
        "passage",
        "--set",
        "fastening.vertical_stiffness=0",
    ]));
    assert!(
        err.contains("fastening.vertical_stiffness") && !err.contains("ballast"),
        "{err}"
    );
    assert_clean_error(
        &with_s(&["passage", "--set", "fastening.vertical_stiffness=0"]),
        &["fastening.vertical_stiffness"],
    );
}

#[test]
fn a_cause_the_message_already_prints_is_not_repeated() {
    let (code, _, err) = run(&["model", "--model", "/nonexistent/track.toml"]);
    assert_ne!(code, 0);
    // The OS message appears once, although the error also carries it as its source.
    let os = std::io::Error::from(std::io::ErrorKind::NotFound).to_string();
    let first = err
        .find("No such file")
        .or_else(|| err.find(&os))
        .expect(&err);
    assert!(!err[first + 1..].contains("No such file"), "{err}");
}

#[test]
fn zero_friction_is_refused_by_the_model_and_the_contact_command() {
    // µ = 0 with traction 0 ran into a secant failure printed twice.
    assert_clean_error(
        &with_s(&[
            "passage",
            "--set",
            "contact.friction=0",
            "--set",
            "contact.traction_coefficient=0",
        ]),
        &["contact.friction", "greater than 0"],
    );
    assert_clean_error(
        &["contact", "--friction", "0", "--traction-coefficient", "0"],
        &["--friction", "greater than 0"],
    );
}

#[test]
fn contact_normal_load_and_steps_are_range_checked() {
    // 1e12 N gave a 1.5 m patch; the range is that of vehicle.wheel_load (0, 500 kN].
    assert_clean_error(
        &["contact", "--normal-load", "1e12"],
        &["--normal-load", "500000 N", "vehicle.wheel_load"],
    );
    assert_clean_error(&["contact", "--normal-load", "0"], &["--normal-load"]);
    // 1e9 steps ran for hours.
    assert_clean_error(&["contact", "--steps", "1000000000"], &["--steps", "10000"]);
    assert_clean_error(&["contact", "--steps", "0"], &["--steps"]);
}

#[test]
fn a_contact_grid_beyond_a_reasonable_passage_time_is_refused() {
    // 256 x 256 is inside each key's range but ran for over 600 s: 256^2 * 256 = 16777216
    // > 12 * 32^2 * 24 = 294912.
    assert_clean_error(
        &with_s(&[
            "passage",
            "--set",
            "contact.grid_nx=256",
            "--set",
            "contact.grid_ny=256",
        ]),
        &["contact.grid_nx", "16777216", "294912"],
    );
    let (code, _, err) = run(&[
        "model",
        "--set",
        "contact.grid_nx=64",
        "--set",
        "contact.grid_ny=64",
    ]);
    assert_eq!(code, 0, "{err}");
}

#[test]
fn a_mesh_beyond_the_size_limit_is_refused_with_its_estimate_and_keys() {
    // Each of these aborted on an allocation. The limit is 1e6 DOFs per substructure.
    for (sets, key) in [
        (
            vec!["mesh.fine_element_length=1e-4"],
            "mesh.fine_element_length",
        ),
        (
            vec!["mesh.section_size=0.002", "mesh.head_size=0.001"],
            "mesh.section_size",
        ),
        (
            vec!["mesh.sleeper_elements=[64,64,64]"],
            "mesh.sleeper_elements",
        ),
        (
            vec!["mesh.wheel_segments=720", "mesh.wheel_element_size=0.005"],
            "mesh.wheel_segments",
        ),
    ] {
        let mut args = vec!["mesh"];
        for s in &sets {
            args.extend(["--set", s]);
        }
        assert_clean_error(&args, &[key, "DOFs", "GiB", "limit of 1000000 DOFs"]);
    }
}

#[test]
fn a_wheel_that_leaves_the_rail_is_an_error_not_zero_forces() {
    // A primary suspension of 1e3 N/m let the wheel leave the rail; the passage exited 0
    // with every force zero.
    let tmp = tempfile::Builder::new()
        .prefix("corrugation-cli-lost-")
        .tempdir()
        .unwrap();
    let dir = tmp.path();
    let out = dir.join("out");
    let cache = dir.join("cache");
    let mut args = vec![
        "passage",
        "--out",
        out.to_str().unwrap(),
        "--cache",
        cache.to_str().unwrap(),
        "--set",
        "run.fmax=1000",
        "--set",
        "vehicle.primary_stiffness=1e3",
    ];
    args.extend(SMALL_MODEL);
    assert_clean_error(&args, &["lost contact", "vehicle.primary_stiffness"]);
    assert!(!out.join("forces.csv").exists());
}

#[test]
fn a_sweep_beyond_the_model_speed_limit_is_refused() {
    // run.speed_kmh allows 40 to 500 km/h; `sweep --speeds 600` ran anyway.
    assert_clean_error(
        &[
            "sweep",
            "--speeds",
            "600",
            "--out",
            "/nonexistent/never-written",
        ],
        &["--speeds", "600", "40 to 500 km/h"],
    );
}

#[test]
fn a_corrugation_csv_without_a_header_is_refused_not_shortened() {
    // A numeric first line is data, not a header: refusing it keeps the first row from being lost.
    let (_dir, p) = tmp_file("no_header.csv", "1.0,0.0\n1.01,5.0\n1.02,0.0\n");
    assert_clean_error(
        &[
            "passage",
            "--corrugation",
            p.to_str().unwrap(),
            "--out",
            "/nonexistent/x",
        ],
        &["no_header.csv", "`1.0, 0.0`", "header"],
    );
}

#[test]
fn an_unwritable_out_directory_is_refused_before_the_computation() {
    // `passage` found out only after the whole passage. A regular file cannot hold outputs.
    let (_dir, f) = tmp_file("not_a_dir", "x");
    let out = f.join("sub");
    for cmd in ["passage", "sweep", "grow", "predict", "modes"] {
        let t = std::time::Instant::now();
        assert_clean_error(
            &[cmd, "--out", out.to_str().unwrap()],
            &["--out", "not_a_dir", "cannot write there"],
        );
        assert!(t.elapsed().as_secs_f64() < 10.0, "{cmd} computed first");
    }
}

/// A user time step above `explicit.safety` × the explicit path's computed critical step is
/// refused with the keys and the limit (after the set-up's progress line), by `explicit` and by
/// `passage --engine explicit` alike.
#[test]
fn explicit_time_step_above_the_computed_limit_is_refused() {
    for cmd in [&["explicit"][..], &["passage", "--engine", "explicit"][..]] {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("out").to_string_lossy().into_owned();
        let mut args: Vec<&str> = cmd.to_vec();
        args.extend(SMALL_MODEL);
        args.extend(["--set", "explicit.time_step=1e-5", "--out", &out]);
        let (code, _o, err) = run(&args);
        assert_ne!(code, 0, "{args:?} must fail");
        assert!(!err.contains("panicked"), "{err}");
        let last = err.trim_end().lines().last().unwrap_or("");
        assert!(
            last.contains("explicit.time_step")
                && last.contains("explicit.safety")
                && last.contains("critical step"),
            "{err}"
        );
    }
}

/// Flags that only the reduced passage reads are refused with `passage --engine explicit`
/// (not ignored), and the argument checks of `modes`, `grow` and `initiation` stop before
/// any computation.
#[test]
fn reduced_only_flags_and_bad_counts_are_refused_before_any_work() {
    let no = "/nonexistent/never-written";
    for flag in [
        &["--no-coupled"][..],
        &["--no-nodal"],
        &["--nodal-at", "5.0"],
        &["--cache", no],
    ] {
        let mut args = vec!["passage", "--engine", "explicit", "--out", no];
        args.extend(flag);
        assert_clean_error(&args, &[flag[0], "reduced engine"]);
    }
    assert_clean_error(
        &["modes", "--fmax", "1e6", "--out", no],
        &["--fmax", "100 to 20000 Hz"],
    );
    assert_clean_error(
        &[
            "grow",
            "--rounds",
            "2",
            "--passages-per-round",
            "0",
            "--out",
            no,
        ],
        &["--passages-per-round", "at least 1"],
    );
    assert_clean_error(
        &[
            "initiation",
            "--model",
            "a.toml",
            "--models",
            "b.toml",
            "--out",
            no,
        ],
        &["--model", "--models"],
    );
}

#[test]
fn trial_amplitudes_are_range_checked_by_grow_and_predict() {
    for cmd in ["grow", "predict"] {
        for bad in ["0", "-10", "6000", "NaN"] {
            let arg = format!("--amplitudes-um={bad}");
            assert_clean_error(
                &[cmd, &arg, "--out", "/nonexistent/never-written"],
                &["--amplitudes-um", bad, "(0, 5000] µm"],
            );
        }
    }
}

#[test]
fn cache_limits_are_range_checked_and_an_empty_cache_lists_nothing() {
    assert_clean_error(&["cache", "--max-size-gb", "-1"], &["--max-size-gb", "≥ 0"]);
    assert_clean_error(&["cache", "--max-idle-days", "NaN"], &["--max-idle-days"]);
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("cache");
    let (code, out, err) = run(&["cache", "--cache", dir.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["entries"].as_array().map(Vec::len), Some(0), "{out}");
    assert_eq!(v["total_bytes"], 0);
}

/// `--audit` with the rotating wheel is refused before any computation (the audit replays the
/// fixed wheel's passage only), not silently dropped.
#[test]
fn explicit_audit_with_the_rotating_wheel_is_refused() {
    let mut args: Vec<&str> = vec!["explicit"];
    args.extend(SMALL_MODEL);
    args.extend([
        "--wheel",
        "rotating",
        "--audit",
        "--out",
        "/nonexistent/never-written",
    ]);
    assert_clean_error(&args, &["--audit", "rotating", "--wheel fixed"]);
}

/// Every command's help is plain text: no rustdoc link syntax (`` [`NAME`] ``) leaks from the
/// doc comments clap turns into help.
#[test]
fn help_texts_carry_no_rustdoc_links() {
    let (code, top, _) = run(&["--help"]);
    assert_eq!(code, 0);
    let commands: Vec<&str> = top
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .collect();
    assert!(commands.len() > 10, "{top}");
    for c in commands {
        let (code, help, _) = run(&[c, "--help"]);
        assert_eq!(code, 0, "{c}");
        assert!(!help.contains("[`"), "{c} --help: {help}");
    }
}

/// `predict --speed 120` says how to set the prediction's speed instead of clap's suggestion
/// of `--speeds` (the short sweep's speeds).
#[test]
fn predict_speed_points_to_the_model_key() {
    assert_clean_error(
        &["predict", "--speed", "120"],
        &["--speed", "--set run.speed_kmh=120", "--speeds only sets"],
    );
}

/// A railpad stiffness typed in MN/m (1300 for 1.3e9 N/m) runs, with a warning naming the
/// key and the unit; the default model gets none.
#[test]
fn a_unit_slip_is_warned_about() {
    let (code, _, err) = run(&["model", "--set", "fastening.vertical_stiffness=1300"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("warning: builtin:dutch: fastening.vertical_stiffness = 1300 N/m"),
        "{err}"
    );
    let (code, _, err) = run(&["model"]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("warning"), "{err}");
}

/// A study case whose value looks like a unit slip is warned about, naming the file and the
/// case, before any work (here the run stops at once: its --out is the modal cache).
#[test]
fn a_study_case_with_a_unit_slip_is_warned_about() {
    let (dir, p) = tmp_file(
        "slip.toml",
        "title = \"pads\"\nmodel = \"builtin:dutch\"\n[[parameter]]\nkey = \"fastening.vertical_stiffness\"\nvalues = [1300.0, 1.3e9]\n",
    );
    let cache = dir.path().join("cache");
    std::fs::create_dir_all(&cache).unwrap();
    let c = cache.to_str().unwrap();
    let (code, _, err) = run(&["study", p.to_str().unwrap(), "--cache", c, "--out", c]);
    assert_ne!(code, 0, "{err}");
    assert!(
        err.contains("slip.toml case 0 (fastening.vertical_stiffness=1300.0)")
            && err.contains("1300 N/m"),
        "{err}"
    );
    assert!(!err.contains("case 1"), "{err}");
}

/// The small explicit preset loads and is warned about: its 80 mm node planes put the mesh's
/// element-passing ripple into the 20–80 mm band (the default model's 10 mm do not).
#[test]
fn the_small_explicit_preset_warns_that_its_mesh_is_in_the_band() {
    let p = concat!(env!("CARGO_MANIFEST_DIR"), "/models/small-explicit.toml");
    let (code, _, err) = run(&["model", "--model", p]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("warning:")
            && err.contains("mesh.fine_element_length = 0.08 m")
            && err.contains("inside the 20–80 mm band"),
        "{err}"
    );
}

/// The fe-patch is the reduced engine's: the explicit engine refuses it by its key before any
/// work (no patch is built), by `explicit` and by `passage --engine explicit` alike.
#[test]
fn the_explicit_engine_refuses_the_fe_patch_by_its_key() {
    for args in [
        &["explicit", "--set", "contact.influence=fe-patch"][..],
        &[
            "passage",
            "--engine",
            "explicit",
            "--set",
            "contact.influence=fe-patch",
        ][..],
    ] {
        assert_clean_error(args, &["contact.influence", "fe-patch", "reduced engine"]);
    }
}

/// An fe-patch whose submodels would not fit (beyond the submodels' DOF bound, or the
/// machine's memory) is refused before it is built, naming the grid keys (a 64 × 64 grid:
/// about 2.4 M DOFs and 90 GB by the estimate).
#[test]
fn an_fe_patch_beyond_the_machine_is_refused_before_it_is_built() {
    assert_clean_error(
        &[
            "contact",
            "--set",
            "contact.influence=fe-patch",
            "--set",
            "contact.grid_nx=64",
            "--set",
            "contact.grid_ny=64",
        ],
        &["fe-patch", "GB", "contact.grid_nx", "half-space"],
    );
}

/// The fe-patch needs the residual flexibilities (its split takes the global mesh's share of
/// the local compliance off the contact, and that share is in them): refused with the key at
/// the model's load, before any work.
#[test]
fn the_fe_patch_without_the_residual_flexibility_is_refused_by_its_key() {
    for key in ["run.residual_flexibility", "run.wheel_residual_flexibility"] {
        let set = format!("{key}=false");
        assert_clean_error(
            &[
                "passage",
                "--set",
                "contact.influence=fe-patch",
                "--set",
                &set,
            ],
            &[key, "fe-patch"],
        );
    }
}
