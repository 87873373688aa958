//! The reference presets `models/reference-rpm1.toml` … `reference-rpm5.toml` parse, keep
//! their fastening model, and build the track and wheel substructures (on the small test
//! mesh, so the check takes seconds); the claims-map study files parse and have the
//! registered cells.

mod common;

use corrugation::model::{load_model, ModelSource};
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
