//! The reduced-order passage on a small model (4 bays, coarse mesh, modes below 1.5 kHz, a
//! coarse contact grid): conservation and equilibrium checks that hold at any resolution.
//! The resolution-dependent checks (convergence, RPM comparisons) are in validation/.

mod common;

use corrugation::dynamics::passage::{PassageOptions, PreparedModel};
use corrugation::eigen::cache::ModalCache;
use corrugation::model::{load_model, ModelSource};

fn small_model() -> corrugation::model::Model {
    let mut sets: Vec<String> = common::SMALL_MODEL
        .chunks(2)
        .map(|c| c[1].to_string())
        .collect();
    sets.extend(
        [
            "track.bays=6",
            "run.fmax=1500",
            "run.solution_zone_offset=0.3",
            "run.solution_zone_length=0.4",
            "contact.grid_nx=16",
            "contact.grid_ny=12",
        ]
        .map(String::from),
    );
    load_model(&ModelSource::Builtin, &sets).expect("valid model")
}

fn cache() -> ModalCache {
    ModalCache::new(std::env::temp_dir().join("corrugation-test-cache-passage"))
}

/// Static equilibrium and the driving torque: in the solution zone the mean normal force is
/// the static wheel load along the inclined contact normal, W / cos α, and the mean
/// longitudinal force is the traction coefficient times W, both within 1 % (issue 5).
/// The integrator's energy bookkeeping closes to round-off on the structural side:
/// external work + contact work = Δ(kinetic + strain) + damper dissipation (to 0.1 %: the
/// damper and contact powers are integrated by the trapezoidal rule).
#[test]
fn passage_holds_the_static_load_and_the_traction_and_balances_energy() {
    let m = small_model();
    let opts = PassageOptions::default();
    let p = PreparedModel::new(&m, &cache(), &opts).expect("modal model");
    let rec = p
        .engine
        .passage(m.run.speed(), None, &opts, None)
        .expect("passage runs");
    let s = corrugation::dynamics::analysis::summarise(&rec).unwrap();
    let w = m.vehicle.wheel_load;
    let cos_a = m.rail.inclination.atan().cos();
    let fn_err = (s.mean_fn_n - w / cos_a).abs() / w;
    let fl_err = (s.mean_fl_n - m.contact.traction_coefficient * w).abs()
        / (m.contact.traction_coefficient * w);
    assert!(fn_err < 0.01, "mean F_N {} vs {}", s.mean_fn_n, w / cos_a);
    assert!(fl_err < 0.01, "mean F_L {} vs {}", s.mean_fl_n, 0.15 * w);
    let e = &rec.energy;
    let structural =
        (e.external_work_j + e.contact_work_j) - (e.stored_change_j + e.damper_dissipation_j);
    assert!(
        structural.abs() < 1e-3 * e.external_work_j.abs(),
        "structural energy residual {structural} J ({e:?})"
    );
    assert!(s.wear_mean > 0.0 && s.wear_band_rms.is_finite());
    // Rail point record: one displacement per step, finite, the rail deflects downwards
    // when the wheel is over it.
    let rp = rec.rail_point.as_ref().unwrap();
    assert_eq!(rp.displacement_m.len(), rec.steps);
    let min_uz = rp
        .displacement_m
        .iter()
        .map(|u| u[2])
        .fold(f64::INFINITY, f64::min);
    assert!(min_uz < -1e-5, "rail point min u_z {min_uz}");
}
