//! The rotating wheel of the explicit path (docs/theory.md §8.7) against Bryan's closed form
//! for a thin ring, the conservation of the scheme's discrete energy, and the fixed wheel's
//! passage in the limit of no rotation. Small models only.

mod common;

use std::f64::consts::PI;

use corrugation::dynamics::passage::PassageOptions;
use corrugation::explicit::rotating::SpinFrame;
use corrugation::explicit::{ExplicitModel, ExplicitOperator, ExplicitOptions, StableStep};
use corrugation::fe::assembly::{assemble, AssemblyOptions, DofMap, MassKind};
use corrugation::fe::material::IsotropicElastic;
use corrugation::mesh::{Hex8, Mesh, Part};
use corrugation::model::{load_model, ExplicitLocalCompliance, ExplicitWheel, Model, ModelSource};
use corrugation::passage::record::EnergyBalance;
use corrugation::structure::WheelStructure;

const STEEL: IsotropicElastic = IsotropicElastic {
    youngs_modulus: 210e9,
    poisson_ratio: 0.3,
    density: 7850.0,
};

/// A free thin steel ring about the y axis, in the wheel frame's convention (node at angle θ
/// at `(r sin θ, y, −r cos θ)`): mean radius 0.3 m, radial thickness 10 mm, axial width
/// 20 mm, 48 hexahedra around (one through the thickness and the width).
fn ring() -> (Mesh, usize) {
    let (n, r, h, b) = (48usize, 0.3, 0.01, 0.02);
    let mut nodes = Vec::with_capacity(4 * n);
    for k in 0..2 {
        // k = 0 outer, 1 inner (ζ inwards keeps det J > 0 with ξ along θ and η along y).
        let rr = r + 0.5 * h - k as f64 * h;
        for j in 0..2 {
            let y = j as f64 * b;
            for i in 0..n {
                let t = 2.0 * PI * i as f64 / n as f64;
                nodes.push([rr * t.sin(), y, -rr * t.cos()]);
            }
        }
    }
    let id = |i: usize, j: usize, k: usize| (i % n) + n * (j + 2 * k);
    let elements = (0..n)
        .map(|i| Hex8 {
            nodes: [
                id(i, 0, 0),
                id(i + 1, 0, 0),
                id(i + 1, 1, 0),
                id(i, 1, 0),
                id(i, 0, 1),
                id(i + 1, 0, 1),
                id(i + 1, 1, 1),
                id(i, 1, 1),
            ],
            material: 0,
            part: Part::Wheel,
        })
        .collect();
    (Mesh { nodes, elements }, n)
}

/// The n = 2 Fourier coefficient `Σ u_r e^{−2iθ}` (re, im) of the radial displacement of
/// the outer nodes of the ring.
fn radial_fourier2(mesh: &Mesh, n_around: usize, u: &[f64]) -> (f64, f64) {
    let (mut re, mut im) = (0.0, 0.0);
    for i in 0..n_around {
        let p = mesh.nodes[i];
        let t = p[0].atan2(-p[2]);
        let ur = t.sin() * u[3 * i] - t.cos() * u[3 * i + 2];
        re += ur * (2.0 * t).cos();
        im -= ur * (2.0 * t).sin();
    }
    (re, im)
}

/// The frequency (rad/s) of the free vibration started as `u = φ1`, `v = ±ω0 φ2` in the
/// spinning frame: the slope of the unwrapped phase of `z = q1 + i q2` (the M-projections
/// on φ1, φ2) by least squares over `periods` periods of ω0 (positive for a wave travelling
/// towards +θ).
fn wave_frequency(
    op: &ExplicitOperator,
    spin: &SpinFrame,
    [p1, p2]: [&[f64]; 2],
    sign: f64,
    omega0: f64,
    periods: f64,
) -> f64 {
    let n = op.n();
    let m = op.mass();
    let dt = 0.5 * StableStep::estimate(op).unwrap().critical_s;
    let steps = (periods * 2.0 * PI / omega0 / dt).ceil() as usize;
    let mut u = p1.to_vec();
    // v_{−½} ≈ v(0) (the start's half-step offset only shifts the phase).
    let mut v: Vec<f64> = p2.iter().map(|x| sign * omega0 * x).collect();
    let f = vec![0.0; n];
    let mut sc = spin.scratch(op);
    let proj = |u: &[f64], p: &[f64]| -> f64 { (0..n).map(|i| p[i] * m[i] * u[i]).sum() };
    let (mut st, mut sp, mut stt, mut stp, mut cnt) = (0.0, 0.0, 0.0, 0.0, 0.0);
    let mut last = 0.0f64;
    let mut unwrapped = 0.0;
    for k in 0..=steps {
        if k > 0 {
            spin.step(op, dt, &mut u, &mut v, &f, &mut sc);
        }
        let ph = proj(&u, p2).atan2(proj(&u, p1));
        let mut d = ph - last;
        d -= 2.0 * PI * (d / (2.0 * PI)).round();
        unwrapped += if k == 0 { ph } else { d };
        last = ph;
        let t = k as f64 * dt;
        st += t;
        sp += unwrapped;
        stt += t * t;
        stp += t * unwrapped;
        cnt += 1.0;
    }
    (cnt * stp - st * sp) / (cnt * stt - st * st)
}

/// Bryan's effect on a free thin ring: in the frame spinning with the ring at Ω, the two
/// in-plane flexural waves of n = 2 nodal diameters travel at `ω_n ± 2nΩ/(n²+1)` (Bryan
/// 1890): the wave against the spin is the faster. The split measured from free vibrations
/// of the explicit gyroscopic step (Ω = 5 % of ω_n, six periods, phase slope by least
/// squares) is `4nΩ/(n²+1)` within 2 % (thin-ring theory at h/R = 1/30 and the 48-element
/// mesh), and the mean stays at the dense eigen-solver's ω_n within 0.5 % (the
/// centrifugal terms shift it by O(Ω²/ω²)). Seen from the ground the two waves are at
/// `ω_n ∓ nΩ(n²−1)/(n²+1)` (printed).
#[test]
fn thin_ring_pair_splits_as_bryan_says() {
    let (mesh, n_around) = ring();
    let dm = DofMap::new(mesh.nodes.len());
    let fm = assemble(
        &mesh,
        &[STEEL],
        &[],
        &[],
        &dm,
        AssemblyOptions {
            mass: MassKind::Lumped,
        },
    )
    .unwrap();
    let op = ExplicitOperator::new(fm.k.as_ref(), fm.m.as_ref(), fm.c.as_ref()).unwrap();
    let (vals, vecs) = common::dense_modes(&op);
    // Six rigid modes, then the in-plane n = 2 pair (the out-of-plane pair is stiffer for a
    // ring twice as wide as thick).
    let (w1, w2) = (vals[6].sqrt(), vals[7].sqrt());
    assert!(vals[5] < 1e-6 * vals[6], "rigid modes: {:?}", &vals[..8]);
    assert!(
        (w2 - w1).abs() < 1e-6 * w1,
        "pair not degenerate: {w1} {w2}"
    );
    let in_plane = |v: &[f64]| {
        let m = op.mass();
        let all: f64 = (0..op.n()).map(|i| m[i] * v[i] * v[i]).sum();
        let y: f64 = (0..op.n())
            .filter(|i| i % 3 == 1)
            .map(|i| m[i] * v[i] * v[i])
            .sum();
        1.0 - y / all
    };
    assert!(in_plane(&vecs[6]) > 0.99 && in_plane(&vecs[7]) > 0.99);
    let p1 = vecs[6].clone();
    let mut p2 = vecs[7].clone();
    // Orient the pair so that u = φ1 cos ωt + φ2 sin ωt travels towards +θ (Fourier
    // coefficient ratio c2/c1 = −i).
    let (a1, b1) = radial_fourier2(&mesh, n_around, &p1);
    let (a2, b2) = radial_fourier2(&mesh, n_around, &p2);
    let im_ratio = (b2 * a1 - a2 * b1) / (a1 * a1 + b1 * b1);
    if im_ratio > 0.0 {
        p2.iter_mut().for_each(|x| *x = -*x);
    }
    let wn = w1;
    let omega = 0.05 * wn;
    let spin = SpinFrame::new(&op, &dm, &mesh.nodes, 0..mesh.nodes.len(), omega).unwrap();
    let against = wave_frequency(&op, &spin, [&p1, &p2], 1.0, wn, 6.0);
    let with = -wave_frequency(&op, &spin, [&p1, &p2], -1.0, wn, 6.0);
    let nn = 2.0;
    let bryan = 4.0 * nn * omega / (nn * nn + 1.0);
    let split = against - with;
    let ground = [
        against - nn * omega,
        with + nn * omega,
        nn * omega * (nn * nn - 1.0) / (nn * nn + 1.0),
    ];
    eprintln!(
        "ring n=2: ω_n {wn:.3} rad/s, Ω {omega:.3}; spinning frame: against {against:.4}, with {with:.4}, split {split:.4} vs Bryan 4nΩ/(n²+1) = {bryan:.4} ({:+.3} %); ground: {:.4} and {:.4} (ω_n ∓ {:.4})",
        100.0 * (split / bryan - 1.0),
        ground[0],
        ground[1],
        ground[2]
    );
    assert!(
        (split / bryan - 1.0).abs() < 0.02,
        "split {split} vs {bryan}"
    );
    assert!((0.5 * (against + with) / wn - 1.0).abs() < 0.005);
}

/// The small test wheel without its suspension (a free elastic wheel and the free sprung
/// mass), undamped: the structure, its explicit operator and the spin rate V/R (rad/s) at
/// 140 km/h.
fn free_small_wheel() -> (WheelStructure, ExplicitOperator, f64) {
    let sets: Vec<String> = common::SMALL_MODEL
        .chunks(2)
        .map(|c| c[1].to_string())
        .collect();
    let model = load_model(&ModelSource::Builtin, &sets).unwrap();
    let mut wheel = WheelStructure::build(&model).unwrap();
    wheel.springs.clear();
    let (fm, _) = wheel.assemble().unwrap();
    let op = ExplicitOperator::new(fm.k.as_ref(), fm.m.as_ref(), fm.c.as_ref()).unwrap();
    let omega = 140.0 / 3.6 / model.wheel.radius;
    (wheel, op, omega)
}

/// The small test wheel (12 segments) without its suspension (a free elastic wheel and the
/// free sprung mass), undamped, spinning at V/R for 140 km/h: the scheme's discrete energy
/// `½ vᵀMv + ½ u_kᵀ(K − Ω²S)u_{k+1}` stays constant within 1e-9 of its value over 5 000
/// steps of 0.9 × the critical step from a pseudo-random start (the Coriolis term at the
/// midpoint of the half-step velocities does no work; taken at the lagged velocity it would
/// add energy every step).
#[test]
fn undamped_spinning_wheel_conserves_the_discrete_energy() {
    let (wheel, op, omega) = free_small_wheel();
    let ring = (0..wheel.mesh.nodes.len()).filter(|&nd| nd != wheel.sprung_node);
    let spin = SpinFrame::new(&op, &wheel.dofmap, &wheel.mesh.nodes, ring, omega).unwrap();
    let n = op.n();
    let mut s: u64 = 987654321;
    let mut u: Vec<f64> = (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 1e-6
        })
        .collect();
    let mut v = vec![0.0; n];
    let f = vec![0.0; n];
    let dt = 0.9 * StableStep::estimate(&op).unwrap().critical_s;
    let mut sc = spin.scratch(&op);
    let mut ku = vec![0.0; n];
    let mut prev = u.clone();
    spin.step(&op, dt, &mut u, &mut v, &f, &mut sc);
    let e0 = spin.discrete_energy(&op, &prev, &u, &v, &mut ku);
    let mut worst: f64 = 0.0;
    for _ in 0..5_000 {
        prev.copy_from_slice(&u);
        spin.step(&op, dt, &mut u, &mut v, &f, &mut sc);
        let e = spin.discrete_energy(&op, &prev, &u, &v, &mut ku);
        worst = worst.max((e - e0).abs() / e0.abs());
    }
    eprintln!(
        "spinning wheel: {n} DOFs, Ω {omega:.2} rad/s, Δt {dt:.3e} s, energy {e0:.6e} J, largest relative change {worst:.2e}"
    );
    assert!(e0 > 0.0);
    assert!(worst < 1e-9, "discrete energy changed by {worst}");
}

/// A free body spinning about its axis is neutral to a turn about that axis: in the
/// spinning frame a rigid rotation `u = α ŷ × X` at rest is a solution (the centrifugal
/// forces stay radial; the prestress's geometric stiffness balances the spin softening on
/// it exactly). The small test wheel without its suspension, undamped, spinning at V/R for
/// 140 km/h, started at rest from a rigid rotation of 1 mrad (M-orthogonal to the in-plane
/// translations): after 0.2/Ω of free motion the rotation has changed by less than 1e-6 of
/// itself (threshold set before the first run; spin softening on the rigid rotation,
/// `−Ω² I α`, would make it grow as `cosh Ωt`, by 2 % here). The first run started from the
/// raw `ŷ × X`, whose small translation content (the graded mesh's lumped-mass centroid is
/// off the axle) the spin softening rightly acts on: 3.4e-6.
#[test]
fn rigid_rotation_about_the_spin_axis_is_force_free() {
    let (wheel, op, omega) = free_small_wheel();
    let spinning: Vec<usize> = (0..wheel.mesh.nodes.len())
        .filter(|&nd| nd != wheel.sprung_node)
        .collect();
    let spin = SpinFrame::new(
        &op,
        &wheel.dofmap,
        &wheel.mesh.nodes,
        spinning.iter().copied(),
        omega,
    )
    .unwrap();
    let n = op.n();
    // ŷ × X = (z, 0, −x) on the spinning nodes.
    let mut r = vec![0.0; n];
    for &nd in &spinning {
        let p = wheel.mesh.nodes[nd];
        for (c, val) in [(0, p[2]), (2, -p[0])] {
            if let Some(i) = wheel.dofmap.free_index(3 * nd + c) {
                r[i] = val;
            }
        }
    }
    let m = op.mass();
    // The turn M-orthogonal to the in-plane translations of the spinning nodes: the
    // graded mesh's lumped-mass centroid is not exactly on the axle, and a translation in
    // the spinning frame is rightly spin-softened.
    let mut offset = [0.0; 2];
    for (k, c) in [0usize, 2].into_iter().enumerate() {
        let (mut num, mut den) = (0.0, 0.0);
        for &nd in &spinning {
            if let Some(i) = wheel.dofmap.free_index(3 * nd + c) {
                num += m[i] * r[i];
                den += m[i];
            }
        }
        offset[k] = num / den;
        for &nd in &spinning {
            if let Some(i) = wheel.dofmap.free_index(3 * nd + c) {
                r[i] -= offset[k];
            }
        }
    }
    let angle = |u: &[f64]| -> f64 {
        let num: f64 = (0..n).map(|i| m[i] * r[i] * u[i]).sum();
        let den: f64 = (0..n).map(|i| m[i] * r[i] * r[i]).sum();
        num / den
    };
    let alpha0 = 1e-3;
    let mut u: Vec<f64> = r.iter().map(|x| alpha0 * x).collect();
    let mut v = vec![0.0; n];
    let f = vec![0.0; n];
    let dt = 0.9 * StableStep::estimate(&op).unwrap().critical_s;
    let t_end = 0.2 / omega;
    let steps = (t_end / dt).ceil() as usize;
    let mut sc = spin.scratch(&op);
    for _ in 0..steps {
        spin.step(&op, dt, &mut u, &mut v, &f, &mut sc);
    }
    let change = (angle(&u) - alpha0).abs() / alpha0;
    let unfixed = (0.2f64).cosh() - 1.0;
    eprintln!(
        "rigid rotation in the spinning frame: {steps} steps over {t_end:.3e} s, relative change {change:.2e} (spin softening on it: {unfixed:.2e}); centroid offset of the spinning nodes' lumped mass (z, −x) {:.3e}, {:.3e} m",
        offset[0], offset[1]
    );
    assert!(change < 1e-6, "rigid rotation changed by {change}");
}

/// The small track with a one-sleeper-pitch solution zone (as tests/explicit.rs).
fn passage_model(extra: &[&str]) -> Model {
    let mut sets: Vec<String> = common::SMALL_MODEL
        .chunks(2)
        .map(|c| c[1].to_string())
        .collect();
    sets.extend(
        [
            "run.solution_zone_offset=0.2",
            "run.solution_zone_length=0.6",
        ]
        .iter()
        .chain(extra)
        .map(|s| s.to_string()),
    );
    load_model(&ModelSource::Builtin, &sets).unwrap()
}

/// The rotating wheel's passage with the spin set to zero is the fixed wheel's passage: the
/// same forces step by step within 1e-5 of the wheel load (the two differ only by rounding:
/// the rotating path spreads and reads the contact force in Cartesian components and its
/// unit responses are per Cartesian direction; the contact solver's iterations carry these
/// 1e-16 differences up to about 1e-6 of the load).
/// (A 0.1 m zone: the identity holds step by step, so a short passage shows it.)
#[test]
#[ignore = "heavy (about 2 minutes on 2 cores): two explicit passages; bash validation/run.sh explicit"]
fn rotating_passage_without_spin_is_the_fixed_passage() {
    let m = passage_model(&["run.solution_zone_length=0.1"]);
    let popts = PassageOptions::default();
    let fixed = ExplicitModel::new(&m, ExplicitOptions::default()).unwrap();
    let a = fixed.passage(m.run.speed(), None, &popts, None).unwrap();
    let rot = ExplicitModel::new(
        &m,
        ExplicitOptions {
            wheel: ExplicitWheel::Rotating,
            spin_rate_rad_s: Some(0.0),
            ..ExplicitOptions::default()
        },
    )
    .unwrap();
    let b = rot.passage(m.run.speed(), None, &popts, None).unwrap();
    assert_eq!(b.info.wheel, "rotating");
    let (ha, hb) = (&a.record.histories, &b.record.histories);
    assert_eq!(ha.normal_n.len(), hb.normal_n.len());
    let w = m.vehicle.wheel_load;
    let mut worst: f64 = 0.0;
    for (x, y) in [
        (&ha.normal_n, &hb.normal_n),
        (&ha.longitudinal_n, &hb.longitudinal_n),
        (&ha.lateral_n, &hb.lateral_n),
    ] {
        for (p, q) in x.iter().zip(y.iter()) {
            worst = worst.max((p - q).abs());
        }
    }
    eprintln!(
        "rotating (Ω = 0) vs fixed: {} contact steps, largest force difference {worst:.3e} N",
        hb.normal_n.len()
    );
    assert!(worst < 1e-5 * w, "forces differ by {worst} N");
    // Without spin the rotating wheel's ledger is the fixed wheel's (whose contact work
    // tests/explicit.rs checks against the nodal work of a replay): no frame work, and the
    // same balance up to the forces' rounding.
    let (ea, eb) = (&a.record.energy, &b.record.energy);
    eprintln!(
        "energy error fixed {:.4e}, rotating (Ω = 0) {:.4e}; frame work {:.1e} J",
        ea.relative_error(),
        eb.relative_error(),
        eb.frame_work_j
    );
    assert!(eb.frame_work_j.abs() < 1e-12);
    // Without spin the contact stays at the tread's reference angle: no tread correction.
    assert_eq!(eb.tread_correction_work_j, 0.0);
    assert!((ea.relative_error() - eb.relative_error()).abs() < 1e-4);
}

/// A short rotating passage of the small model (a 0.1 m zone after a 0.05 m run-in) with
/// the tread's local compliance `lc`; prints and returns its energy balance after checking
/// that `energy_error` is reported and the wheel is driven.
fn rotating_ledger(lc: ExplicitLocalCompliance) -> EnergyBalance {
    let m = passage_model(&[
        "run.solution_zone_offset=0.05",
        "run.solution_zone_length=0.1",
    ]);
    let opts = ExplicitOptions {
        wheel: ExplicitWheel::Rotating,
        local_compliance: lc,
        ..ExplicitOptions::default()
    };
    let em = ExplicitModel::new(&m, opts).unwrap();
    let rec = em.passage(m.run.speed(), None, &PassageOptions::default(), None);
    let rec = rec.unwrap();
    let e = rec.record.energy;
    match lc {
        ExplicitLocalCompliance::Mesh => assert_eq!(e.tread_correction_work_j, 0.0),
        ExplicitLocalCompliance::Constant => assert!(e.tread_correction_work_j != 0.0),
    }
    eprintln!(
        "rotating ledger ({lc:?}): {} contact steps, Ω = {:.2} rad/s, {:.1} s; energy error {:.3} %; {e:?}",
        rec.info.contact_steps,
        rec.info.spin_rate_rad_s,
        rec.info.seconds,
        100.0 * e.relative_error()
    );
    assert!((rec.info.energy_error - e.relative_error()).abs() < 1e-15);
    assert!(e.torque_work_j > 0.0, "{e:?}");
    e
}

/// The rotating wheel's energy ledger closes on a short passage of the small model, with the
/// mesh's own tread compliance: the work of the wheel loads (driving torque; gravity and
/// resistance on the ground frame's displacements), the spin and convective rolling work
/// (with the contact moving round the wheel) and the spinning frame's work = change of the
/// stored energy (`½ vᵀMv + ½ uᵀ(K − Ω² S)u` with the suspension along the ground vertical)
/// plus damper and frictional dissipation and the change of the contact's elastic energy,
/// within 1 % (the criterion of the fixed wheel's ledger, tests/explicit.rs). The
/// convective work is the normal one only: the creepages read the material point's
/// increment, which holds no change of place (docs/theory.md §8.8). The Coriolis term does
/// no work (`MJ` skew), so it has no entry.
#[test]
fn rotating_passage_energy_ledger_closes() {
    let e = rotating_ledger(ExplicitLocalCompliance::Mesh);
    let err = e.relative_error();
    assert!(err.abs() < 0.01, "energy error {err}: {e:?}");
}

/// The same with the tread corrections on (the default, `"constant"`: the local compliance's
/// variation with the angle and the convective deflection removed from the contact, booked
/// as a series spring and as the tread corrections' work: the force through the convective
/// deflection and the trapezoidal work of the removed normal compliance's explicit time
/// dependence), against the same 1 %.
#[test]
fn rotating_passage_energy_ledger_closes_with_the_tread_corrections() {
    let e = rotating_ledger(ExplicitLocalCompliance::Constant);
    let err = e.relative_error();
    assert!(err.abs() < 0.01, "energy error {err}: {e:?}");
}

/// The start from rest on the rotating wheel (docs/theory.md §7.5): the wheel rolls freely
/// until the torque's onset, 0.03 m before the zone (mean F_L over those steps within 10 %
/// of `μ_t W` of zero: the start's ringing makes F_L oscillate about it), and is driven
/// after it (the mean F_L over the zone's last half within 5 % of `μ_t W`, the train's
/// resistance it balances). The energy balance misses the contact's tangential elastic
/// energy built up from zero (docs/theory.md §7.8; with every mode kept both engines miss the
/// same amount, tests/explicit_vs_reduced.rs), so its bound here, 5 %, is a regression guard,
/// not a conservation check.
#[test]
fn rotating_passage_from_rest_rolls_freely_until_the_torque_steps_on() {
    let sets = [
        "run.solution_zone_offset=0.05",
        "run.solution_zone_length=0.1",
    ];
    let rest = passage_model(&[
        sets[0],
        sets[1],
        "run.start=\"rest\"",
        "run.rest_start_distance=0.03",
    ]);
    let opts = ExplicitOptions {
        wheel: ExplicitWheel::Rotating,
        ..ExplicitOptions::default()
    };
    let em = ExplicitModel::new(&rest, opts).unwrap();
    let rec = em
        .passage(rest.run.speed(), None, &PassageOptions::default(), None)
        .unwrap();
    let h = &rec.record.histories;
    let mu_w = rest.contact.traction_coefficient * rest.vehicle.wheel_load;
    let [z0, z1] = rec.record.zone_m;
    let onset = z0 - 0.03;
    let before: Vec<f64> = h
        .x_m
        .iter()
        .zip(&h.longitudinal_n)
        .filter(|(x, _)| **x < onset)
        .map(|(_, f)| *f)
        .collect();
    assert!(before.len() > 10, "{} steps before the onset", before.len());
    let worst = before.iter().fold(0.0f64, |a, f| a.max(f.abs()));
    let mean_before = before.iter().sum::<f64>() / before.len() as f64;
    let late: Vec<f64> = h
        .x_m
        .iter()
        .zip(&h.longitudinal_n)
        .filter(|(x, _)| **x > 0.5 * (z0 + z1) && **x < z1)
        .map(|(_, f)| *f)
        .collect();
    let mean_late = late.iter().sum::<f64>() / late.len() as f64;
    let e = rec.record.energy;
    eprintln!(
        "rotating from rest: mean F_L {mean_before:.1} N, |F_L| ≤ {worst:.1} N before the onset ({} steps), mean F_L {mean_late:.0} N over the zone's last half (μ_t W {mu_w:.0} N); energy error {:.3} %; {e:?}",
        before.len(),
        100.0 * e.relative_error()
    );
    assert!(
        mean_before.abs() < 0.1 * mu_w,
        "mean F_L {mean_before} N before the onset"
    );
    assert!(
        (mean_late - mu_w).abs() < 0.05 * mu_w,
        "mean F_L {mean_late} N"
    );
    assert!(e.torque_work_j > 0.0, "{e:?}");
    assert!(e.relative_error().abs() < 0.05, "{e:?}");
}
