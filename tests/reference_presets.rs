//! The reference presets `models/reference-rpm1.toml` … `reference-rpm5.toml` parse, keep
//! their fastening model, and build the track and wheel substructures (on the small test
//! mesh, so the check takes seconds); the claims-map study files parse and have the
//! registered cells. The reference-described presets `models/reference-described-rpm*.toml`
//! hold the rail foot as the reference's table of fastening models says, carry its described
//! track, start and contact, name the source of every value, and build.

mod common;

use corrugation::model::{load_model, Holds, ModelSource, RailEnds, RigidRegion, StartKind};
use corrugation::structure::{TrackStructure, WheelStructure};

fn small_sets() -> Vec<String> {
    common::SMALL_MODEL
        .chunks(2)
        .map(|c| c[1].to_string())
        .collect()
}

#[test]
fn reference_presets_parse_and_build() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models");
    for k in 1..=5 {
        let path = dir.join(format!("reference-rpm{k}.toml"));
        let m = load_model(&ModelSource::File(path.clone()), &small_sets())
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.contains(&format!("model = \"RPM{k}\"")),
            "{} must name RPM{k}",
            path.display()
        );
        assert!(
            text.contains("Why this representation"),
            "{} must say why its hold representation was chosen",
            path.display()
        );
        TrackStructure::build(&m).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        WheelStructure::build(&m).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    }
}

#[test]
fn claims_map_study_files_parse() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/studies");
    for h in 0..=5 {
        let path = dir.join(format!("reference-claims-h{h}.toml"));
        let s = corrugation::studies::study::Study::load(&path)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let cases = s.cases();
        let expect = if h == 5 { 2 } else { 10 };
        assert_eq!(cases.len(), expect, "{}", path.display());
    }
}

/// The hold of one direction as the reference's table reads: (region, indices, on node lines).
type Described = (RigidRegion, &'static [usize], bool);

/// The reference's table of fastening models (vertical, longitudinal, lateral), written out
/// independently of the files: RPM1 V-3-4, RPM2 V-∞-4, RPM3 V-1-4, RPM4 ∞-1-4, RPM5 ∞-∞-4;
/// "rigid at n columns / 4 rows" on the node lines through the spring grid's columns and rows,
/// "∞" every rail-foot node (continuous), "V" the railpad springs alone.
fn described_holds(k: usize) -> [Described; 3] {
    use RigidRegion::{Columns, Continuous, None, Rows};
    let rows: Described = (Rows, &[0, 1, 2, 3], true);
    let (x, z): (Described, Described) = match k {
        1 => ((Columns, &[0, 1, 2], true), (None, &[], false)),
        2 => ((Continuous, &[], false), (None, &[], false)),
        3 => ((Columns, &[1], true), (None, &[], false)),
        4 => ((Columns, &[1], true), (Continuous, &[], false)),
        5 => ((Continuous, &[], false), (Continuous, &[], false)),
        _ => unreachable!(),
    };
    [x, rows, z]
}

#[test]
fn reference_described_presets_hold_as_described_and_build() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models");
    for k in 1..=5 {
        let path = dir.join(format!("reference-described-rpm{k}.toml"));
        let m = load_model(&ModelSource::File(path.clone()), &[])
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let Holds::Custom(p) = &m.fastening.holds else {
            panic!("{}: not a custom hold pattern", path.display());
        };
        for (dir_name, (got, want)) in ["x", "y", "z"]
            .into_iter()
            .zip([&p.x, &p.y, &p.z].into_iter().zip(described_holds(k)))
        {
            let (region, indices, node_lines) = want;
            assert!(
                got.rigid == region
                    && got.elastic.is_none()
                    && got.indices == indices
                    && got.node_lines == node_lines,
                "RPM{k} {dir_name}: {got:?}, described {want:?}"
            );
        }
        // The described track, start and contact (about 20.5 m, non-reflecting ends, from
        // rest 0.3 m before the zone, µ 0.4, traction 0.15, 140 km/h), and the pads' springs
        // in x and y at every cell.
        let length = m.track.bays as f64 * m.track.sleeper_spacing;
        assert!((20.0..=21.0).contains(&length), "RPM{k}: {length} m");
        assert_eq!(m.track.ends, RailEnds::Absorbing);
        assert_eq!(m.run.start, StartKind::Rest);
        assert_eq!(m.run.solution_zone_offset, 0.3);
        assert_eq!(m.contact.friction, 0.4);
        assert_eq!(m.contact.traction_coefficient, 0.15);
        assert_eq!(m.run.speed_kmh, 140.0);
        assert!(m.fastening.springs.longitudinal_stiffness > 0.0);
        assert!(m.fastening.springs.lateral_stiffness > 0.0);
        // Builds on the small mesh (4 bays: too short for the absorbing layers, so free ends).
        let mut sets = small_sets();
        sets.push("track.ends=\"free\"".into());
        let small = load_model(&ModelSource::File(path.clone()), &sets)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        TrackStructure::build(&small).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    }
}

/// Every value the common file of the reference-described presets sets names its source
/// ("described", "published", "estimate" with its reason, or "this model").
#[test]
fn reference_described_values_name_their_source() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("models/reference-described-base.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let sources = ["described", "published", "estimate", "this model"];
    let mut n = 0;
    for line in text.lines() {
        let code = line.split('#').next().unwrap_or("");
        if code.contains('=') && !code.trim_start().starts_with("extends") {
            n += 1;
            let comment = line.split_once('#').map(|(_, c)| c).unwrap_or("");
            assert!(
                sources.iter().any(|s| comment.contains(s)),
                "{}: `{}` names no source",
                path.display(),
                line.trim()
            );
        }
    }
    assert!(n >= 10, "{n} values");
}
