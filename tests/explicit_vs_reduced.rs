//! The reduced passage on the small test track at a high `run.fmax`, the configuration the
//! comparison with the explicit FE path (docs/theory.md §8.6) needs: the free wheel's rigid
//! modes must stay rigid however many elastic modes are kept.

mod common;

use corrugation::dynamics::{
    passage::{PassageOptions, RIGID_HZ},
    prepared::PreparedModel,
};
use corrugation::eigen::cache::ModalCache;
use corrugation::model::{load_model, ModelSource};

/// The small test track and coarse wheel (tests/common) at `run.fmax` = 4.5 kHz, where the
/// shift-invert eigen-solver returns two of the wheel's three rigid-body modes with exact
/// shapes but eigenvalues of (2π · 1.8 Hz)² (round-off of its shifts), above
/// [`RIGID_HZ`]. Closed forms: a free body's rigid modes have ω = 0, so the reduced model
/// must keep exactly three wheel modes below [`RIGID_HZ`] (x, z, rotation about the axle),
/// and a smooth passage must hold the static load (mean F_N = W/cos α within 5 %, mean F_L =
/// μ_t W within 2 %: the 6.8 Hz bounce on the primary suspension is not averaged out over a
/// 21 ms passage; at 3 kHz the means are 1.7 % and 0.6 % off). Counted as elastic, the two
/// modes' static start divides their load by ω² and the wheel leaves the rail at the first
/// step.
#[test]
fn wheel_rigid_modes_stay_rigid_at_a_high_fmax() {
    let mut sets: Vec<String> = common::SMALL_MODEL
        .chunks(2)
        .map(|c| c[1].to_string())
        .collect();
    sets.extend(
        [
            "run.solution_zone_offset=0.2",
            "run.solution_zone_length=0.6",
            "run.fmax=4500",
        ]
        .map(String::from),
    );
    let m = load_model(&ModelSource::Builtin, &sets).unwrap();
    let cache = ModalCache::new(
        std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("explicit-vs-reduced-modes"),
    );
    let opts = PassageOptions {
        energy: false,
        rail_point_offset_m: None,
    };
    let p = PreparedModel::new(&m, &cache, &opts).unwrap();
    let f = &p.wheel_frequencies_hz;
    eprintln!(
        "wheel: {} modes, lowest {:?} Hz",
        f.len(),
        &f[..f.len().min(5)]
    );
    let rigid: Vec<f64> = f.iter().copied().filter(|&x| x < RIGID_HZ).collect();
    assert_eq!(rigid.len(), 3, "wheel modes below {RIGID_HZ} Hz: {rigid:?}");
    let rec = p.engine.passage(m.run.speed(), None, &opts, None).unwrap();
    let s = corrugation::dynamics::analysis::summarise(&rec).unwrap();
    let w = m.vehicle.wheel_load;
    let cos_a = m.rail.inclination.atan().cos();
    eprintln!(
        "reduced passage at 4.5 kHz: mean F_N {:.0} N (W/cos α {:.0} N), mean F_L {:.0} N",
        s.mean_fn_n,
        w / cos_a,
        s.mean_fl_n
    );
    assert!((s.mean_fn_n - w / cos_a).abs() / w < 0.05);
    assert!((s.mean_fl_n - 0.15 * w).abs() / (0.15 * w) < 0.02);
}
