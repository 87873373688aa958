//! A passage on the substructured track basis against the same passage on the full Lanczos
//! basis (the reference), on the 4-bay test track. Tolerances as in
//! validation/substructure.md: band RMS of F_L, F_N and wear within 10 %, dominant wear
//! wavelength within 2 %.

use corrugation::dynamics::PassageRunner;
use corrugation::dynamics::{passage::PassageOptions, prepared::PreparedModel};
use corrugation::eigen::basis::track_basis;
use corrugation::eigen::cache::ModalCache;
use corrugation::eigen::substructure::{
    passage_track_basis_timed, substructured_track_basis, track_components, ReducedShapes,
    SubstructureOptions,
};
use corrugation::studies::speeds::Shard;

use corrugation::structure::TrackStructure;

/// The 4-bay test track at f_max 3 kHz with a 0.8 GN/m railpad, a modal cache in a fresh
/// temporary directory named after `name`, and the track's component bases.
struct Setup {
    m: corrugation::model::Model,
    dir: std::path::PathBuf,
    cache: ModalCache,
    track: TrackStructure,
    comp: corrugation::eigen::substructure::TrackComponents,
}

impl Setup {
    fn new(name: &str) -> Self {
        let m = corrugation::model::test_problems::small_model(&[
            "run.fmax=3000",
            "fastening.vertical_stiffness=0.8e9",
        ])
        .unwrap();
        let dir = std::env::temp_dir().join(format!("{name}-{}", std::process::id()));
        let cache = ModalCache::new(&dir);
        let track = TrackStructure::build(&m).unwrap();
        let opts = SubstructureOptions::default();
        let comp = track_components(&m, &track, &cache, m.run.fmax, &opts).unwrap();
        Setup {
            m,
            dir,
            cache,
            track,
            comp,
        }
    }

    /// One passage at 140 km/h on the track basis `tb`.
    fn passage(
        &self,
        tb: corrugation::eigen::basis::ModalBasis<corrugation::eigen::classify::TrackModeClass>,
    ) -> corrugation::dynamics::PassageSummary {
        let opts = PassageOptions::default();
        PreparedModel::with_track_basis(&self.m, &self.track, tb, &self.cache, None, &opts)
            .unwrap()
            .run(corrugation::units::Speed::from_kmh(140.0), None)
            .unwrap()
    }
}

#[test]
fn passage_on_the_substructured_basis_matches_the_full_basis() {
    let s = Setup::new("substructure-passage");
    let fmax = s.m.run.fmax;
    let sub = substructured_track_basis(&s.track, &s.comp, fmax).unwrap();
    let full = track_basis(&s.m, &s.track, &s.cache, fmax).unwrap();
    let run = |tb| s.passage(tb);
    let (a, b) = (run(full), run(sub));
    let _ = std::fs::remove_dir_all(&s.dir);
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

/// A passage on the passage basis (the modes' rows at the springs and the running surface
/// only, classes from the component coordinates) against the same passage on the fully
/// expanded substructured basis: tolerances stated before measuring, relative: mean forces
/// 1e-6, band RMS of F_L, F_N and wear 1e-4, dominant wear wavelength 1e-5 (the expanded
/// rows agree to round-off, which the contact's iterative solves amplify).
#[test]
fn a_passage_on_the_passage_basis_matches_the_fully_expanded_basis() {
    let s = Setup::new("substructure-rows");
    let fmax = s.m.run.fmax;
    let full = substructured_track_basis(&s.track, &s.comp, fmax).unwrap();
    let shapes = ReducedShapes::new(&s.track, &s.comp).unwrap();
    let (part, _) = passage_track_basis_timed(&s.track, &s.comp, &shapes, fmax).unwrap();
    let run = |tb| s.passage(tb);
    let (a, b) = (run(full), run(part));
    let _ = std::fs::remove_dir_all(&s.dir);
    let rel = |x: f64, y: f64| (y - x).abs() / x.abs();
    let pairs = [
        ("mean F_N", a.mean_fn_n, b.mean_fn_n, 1e-6),
        ("mean F_L", a.mean_fl_n, b.mean_fl_n, 1e-6),
        ("F_L band RMS", a.fl_band_rms_n, b.fl_band_rms_n, 1e-4),
        ("F_N band RMS", a.fn_band_rms_n, b.fn_band_rms_n, 1e-4),
        ("wear band RMS", a.wear_band_rms, b.wear_band_rms, 1e-4),
        (
            "dominant wavelength",
            a.dominant_wavelength_mm.unwrap(),
            b.dominant_wavelength_mm.unwrap(),
            1e-5,
        ),
    ];
    for (what, x, y, tol) in pairs {
        eprintln!("{what}: {x} vs {y} (relative {:e})", rel(x, y));
        assert!(rel(x, y) < tol, "{what}: {x} vs {y}");
    }
}

/// A substructured railpad-stiffness study on the small passage model run with one case at a
/// time and with three at a time (after the first) writes byte-identical `study.csv` and
/// case files: the cases' numbers do not depend on the concurrency (each case is computed
/// whole by one worker from the shared, read-only component bases and caches). A one-case
/// study fills the modal cache first, so that both runs read the same cached bases (a base
/// read back from the cache may differ from the freshly built one in the last bits).
#[test]
fn a_concurrent_study_writes_the_serial_study_files() {
    use corrugation::model::test_problems::{SMALL_MODEL, SMALL_PASSAGE};
    use corrugation::studies::study::{run_study, CaseRunners, Study};
    let root = std::env::temp_dir().join(format!("substructure-study-{}", std::process::id()));
    let set: Vec<String> = SMALL_MODEL
        .iter()
        .chain(&SMALL_PASSAGE)
        .map(|s| format!("{s:?}"))
        .collect();
    let run = |concurrent: usize, values: &str| -> std::collections::BTreeMap<String, Vec<u8>> {
        let text = format!(
            "model = \"builtin:dutch\"\nset = [{}]\nspeeds_kmh = [140.0]\nbasis = \"substructured\"\nconcurrent_cases = {concurrent}\n[[parameter]]\nkey = \"fastening.vertical_stiffness\"\nvalues = [{values}]\n",
            set.join(", ")
        );
        let n = values.split(',').count();
        let out = root.join(format!("out-{concurrent}-{n}"));
        let study = Study::parse_str(&text, "s.toml", &root, "s").unwrap();
        assert_eq!(study.concurrent_cases, concurrent);
        let runners = CaseRunners::new(&study, &root.join("cache"));
        let factory = |m: &corrugation::model::Model| -> Result<
            Box<dyn PassageRunner>,
            corrugation::studies::BoxError,
        > { Ok(Box::new(runners.prepared(m)?)) };
        let o = run_study(
            &study,
            &factory,
            None,
            &out,
            Shard::ALL,
            &corrugation::progress::Silent,
        )
        .unwrap();
        assert_eq!((o.computed, o.reused), (n, 0));
        let mut files = std::collections::BTreeMap::new();
        files.insert(
            "study.csv".to_string(),
            std::fs::read(out.join("study.csv")).unwrap(),
        );
        for i in 0..n {
            let name = format!("cases/{i:04}.json");
            files.insert(name.clone(), std::fs::read(out.join(&name)).unwrap());
        }
        files
    };
    run(1, "1.1e9");
    let values = "0.6e9, 0.9e9, 1.3e9, 1.8e9, 2.4e9";
    let serial = run(1, values);
    let concurrent = run(3, values);
    assert_eq!(serial.len(), 6);
    let _ = std::fs::remove_dir_all(&root);
    for (name, bytes) in &serial {
        assert!(
            concurrent.get(name) == Some(bytes),
            "{name} differs between one and three cases at a time"
        );
    }
}
