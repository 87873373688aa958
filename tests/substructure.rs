//! A passage on the substructured track basis against the same passage on the full Lanczos
//! basis (the reference), on the 4-bay test track. Tolerances as in
//! validation/substructure.md: band RMS of F_L, F_N and wear within 10 %, dominant wear
//! wavelength within 2 %.

use corrugation::dynamics::PassageRunner;
use corrugation::dynamics::{passage::PassageOptions, prepared::PreparedModel};
use corrugation::eigen::basis::track_basis;
use corrugation::eigen::cache::ModalCache;
use corrugation::eigen::substructure::{
    substructured_track_basis, track_components, SubstructureOptions,
};

use corrugation::structure::TrackStructure;

#[test]
fn passage_on_the_substructured_basis_matches_the_full_basis() {
    let m = corrugation::model::test_problems::small_model(&[
        "run.fmax=3000",
        "fastening.vertical_stiffness=0.8e9",
    ])
    .unwrap();
    let dir = std::env::temp_dir().join(format!("substructure-passage-{}", std::process::id()));
    let cache = ModalCache::new(&dir);
    let track = TrackStructure::build(&m).unwrap();
    let fmax = m.run.fmax;
    let comp = track_components(&m, &track, &cache, fmax, &SubstructureOptions::default()).unwrap();
    let sub = substructured_track_basis(&track, &comp, fmax).unwrap();
    let full = track_basis(&m, &track, &cache, fmax).unwrap();
    let opts = PassageOptions::default();
    let run = |tb| {
        PreparedModel::with_track_basis(&m, &track, tb, &cache, None, &opts)
            .unwrap()
            .run(corrugation::units::Speed::from_kmh(140.0), None)
            .unwrap()
    };
    let (a, b) = (run(full), run(sub));
    let _ = std::fs::remove_dir_all(&dir);
    let rel = |x: f64, y: f64| (y - x).abs() / x.abs();
    eprintln!(
        "full: F_L {} N, F_N {} N, wear {} , dominant {:?} mm; substructured: {} N, {} N, {}, {:?} mm",
        a.fl_band_rms_n,
        a.fn_band_rms_n,
        a.wear_band_rms,
        a.dominant_wavelength_mm,
        b.fl_band_rms_n,
        b.fn_band_rms_n,
        b.wear_band_rms,
        b.dominant_wavelength_mm
    );
    assert!(rel(a.fl_band_rms_n, b.fl_band_rms_n) < 0.10);
    assert!(rel(a.fn_band_rms_n, b.fn_band_rms_n) < 0.10);
    assert!(rel(a.wear_band_rms, b.wear_band_rms) < 0.10);
    let (wa, wb) = (
        a.dominant_wavelength_mm.unwrap(),
        b.dominant_wavelength_mm.unwrap(),
    );
    assert!(rel(wa, wb) < 0.02, "{wa} vs {wb} mm");
}
