//! The normal solver against Hertz, the series compliance of the normal contact, and the
//! normal solve on a fixed contact set.

use super::{reference_hertz, reference_hertz_input, rolling_config};
use crate::contact::{
    combined_modulus, influence, normal, report, shear_modulus, HertzGridParams, NormalInput,
    StepInputs, StepResult, TransientConfig, TransientRolling,
};
use std::f64::consts::PI;

fn normal_only(nx: usize, ny: usize, margin: f64) -> (StepResult, f64, f64, f64) {
    let cfg = rolling_config(nx, ny, margin);
    let mut eng = TransientRolling::new(cfg).unwrap();
    let r = eng.step(&StepInputs::force_creepage(100e3, 0.0)).unwrap();
    let (a, b) = report::equivalent_semi_axes(eng.x_m(), eng.y_m(), eng.pressure_pa());
    let pmax = eng.pressure_pa().iter().cloned().fold(0.0, f64::max);
    (r, a, b, pmax)
}

#[test]
fn grid_normal_solver_reproduces_hertz_and_converges() {
    // Closed form: Hertz (reference numbers of docs/theory.md §6.2, checked in hertz.rs).
    let h = reference_hertz();
    let mut errs = Vec::new();
    for &n in &[16usize, 32, 64] {
        let (r, a, b, pmax) = normal_only(n, n, 1.15);
        let e = [
            a / h.a_m - 1.0,
            b / h.b_m - 1.0,
            pmax / h.p0_pa - 1.0,
            r.approach_m / h.approach_m - 1.0,
        ];
        println!(
            "n={n}: a {:.4} mm b {:.4} mm p0 {:.1} MPa δ {:.2} µm, rel. errors {:?}",
            a * 1e3,
            b * 1e3,
            pmax / 1e6,
            r.approach_m * 1e6,
            e
        );
        errs.push(e);
    }
    for e in &errs[1..] {
        assert!(e.iter().all(|v| v.abs() < 0.01), "{e:?}");
    }
    // second-order convergence of p0 (ratio 4 per halving); at least 3
    assert!(errs[0][2].abs() / errs[1][2].abs() > 3.0 && errs[1][2].abs() / errs[2][2].abs() > 3.0);
    // approach at least first order
    assert!(errs[0][3].abs() / errs[1][3].abs() > 2.0 && errs[1][3].abs() / errs[2][3].abs() > 2.0);
}

#[test]
fn corrugated_rail_changes_patch_and_pressure() {
    // A rail bump under the contact (approach fixed) raises the force and the peak pressure and
    // shifts the patch centroid toward the bump: the profile enters the gap, not just the force.
    let cfg = rolling_config(24, 18, 1.4);
    let mut eng = TransientRolling::new(cfg).unwrap();
    let mut inp = StepInputs::force_creepage(100e3, 0.0);
    let r0 = eng.step(&inp).unwrap();
    let p0 = eng.pressure_pa().iter().cloned().fold(0.0, f64::max);
    let rail: Vec<f64> = eng
        .x_m()
        .iter()
        .map(|x| 10e-6 * (2.0 * PI * x / 0.03).sin())
        .collect();
    inp.normal = NormalInput::Approach(r0.approach_m);
    inp.rail_height_m = Some(&rail);
    let r1 = eng.step(&inp).unwrap();
    let p1 = eng.pressure_pa().iter().cloned().fold(0.0, f64::max);
    let (sx, s): (f64, f64) = eng
        .x_m()
        .iter()
        .enumerate()
        .fold((0.0, 0.0), |(a, b), (i, x)| {
            let row: f64 = eng.pressure_pa()[i * 18..(i + 1) * 18].iter().sum();
            (a + x * row, b + row)
        });
    println!(
        "flat: N {:.0}, pmax {:.1} MPa; corrugated: N {:.0}, pmax {:.1} MPa, centroid {:.3} mm",
        r0.normal_force_n,
        p0 / 1e6,
        r1.normal_force_n,
        p1 / 1e6,
        sx / s * 1e3
    );
    assert!(sx / s > 1e-5);
    assert!(r1.contact_elements != r0.contact_elements || (p1 / p0 - 1.0).abs() > 0.01);
}

// ---------------------------------------------------------------------------------------------
// Series compliance of the normal contact (TransientRolling::set_series_compliance)

#[test]
fn series_compliance_normal_matches_hertz_in_series() {
    // Closed form: sphere on plane (circular Hertz, R_e = 0.3 m), a spring c_z in series:
    // δ = δ_H(F) + c_z F, δ_H(F) = (9 F² / (16 E*² R_e))^(1/3). Prescribe δ for F = 100 kN.
    let (re, e, nu, load) = (0.3, 210e9, 0.3, 100e3);
    let es = combined_modulus(e, nu);
    let delta_h = (9.0 * load * load / (16.0 * es * es * re)).cbrt();
    let cz = 0.5e-9; // m/N: c_z F = 50 µm, comparable to δ_H
    let cfg = TransientConfig::around_hertz(&HertzGridParams {
        radius_x_m: re,
        radius_y_m: re,
        youngs_pa: e,
        poisson: nu,
        speed_m_per_s: 38.9,
        load_n: load,
        nx: 40,
        ny: 40,
        margin: 1.2,
        ..HertzGridParams::default()
    })
    .unwrap();
    let mut eng = TransientRolling::new(cfg).unwrap();
    eng.set_series_compliance([0.0, 0.0, cz]).unwrap();
    let mut inp = StepInputs::force_creepage(load, 0.0);
    inp.normal = NormalInput::Approach(delta_h + cz * load);
    let r = eng.step(&inp).unwrap();
    println!(
        "δ_H {:.3} µm + c F {:.3} µm → F {:.1} N ({:+.3e}), {} CG its",
        delta_h * 1e6,
        cz * load * 1e6,
        r.normal_force_n,
        r.normal_force_n / load - 1.0,
        r.normal_iterations
    );
    assert!((r.normal_force_n / load - 1.0).abs() < 0.01);
    // exact consistency with the grid's own compliance: the same force prescribed without c_z
    // needs the approach δ − c_z F (to solver tolerance), and with c_z (force mode) reports δ.
    let f = r.normal_force_n;
    let delta = delta_h + cz * load;
    eng.set_series_compliance([0.0; 3]).unwrap();
    let r0 = eng.step(&StepInputs::force_creepage(f, 0.0)).unwrap();
    assert!(
        (r0.approach_m - (delta - cz * f)).abs() < 1e-6 * delta,
        "{r0:?}"
    );
    eng.set_series_compliance([0.0, 0.0, cz]).unwrap();
    let r1 = eng.step(&StepInputs::force_creepage(f, 0.0)).unwrap();
    assert!((r1.approach_m - delta).abs() < 1e-6 * delta, "{r1:?}");
}

// ---------------------------------------------------------------------------------------------
// Normal solve on a fixed contact set (superposition of unit responses)

/// Normal solves of a smooth-rail sequence: approach and series compliance vary, the gap
/// does not. Returns per solve `(F_N, products)`.
fn normal_sequence(
    solver: &mut normal::NormalSolver,
    conv: &mut influence::Convolver,
    h: &[f64],
    da: f64,
) -> Vec<(f64, usize)> {
    let mut p = vec![0.0; h.len()];
    let mut out = Vec::new();
    let d0 = 60e-6;
    for k in 0..40 {
        let kf = k as f64;
        // small oscillation of the approach (the set stays), then a jump (the set grows)
        let d = if k < 30 {
            d0 * (1.0 + 0.002 * (0.7 * kf).sin())
        } else {
            1.3 * d0
        };
        solver.series_compliance_m_per_n = 1e-10 * (1.0 + 0.1 * (0.3 * kf).cos());
        let mode = if k == 0 {
            normal::NormalMode::Load(100e3)
        } else {
            normal::NormalMode::Approach(d)
        };
        let r = solver.solve(conv, h, da, mode, &mut p).unwrap();
        out.push((r.load_n, solver.products));
    }
    out
}

#[test]
fn fixed_set_normal_solve_equals_polonsky_keer() {
    // Independent solver: Polonsky–Keer's CG to 1e-12 (no superposition). The superposed
    // solution must agree to far better than the rolling tolerance (1e-6) and need no
    // product while the set stays.
    let cfg = rolling_config(24, 18, 1.4);
    let (nx, ny, g) = (cfg.grid.nx, cfg.grid.ny, cfg.grid);
    let es = combined_modulus(210e9, 0.3);
    let gm = shear_modulus(210e9, 0.3);
    let mut conv = influence::Convolver::new(nx, ny, g.dx(), g.dy(), es, gm, 0.3);
    let h: Vec<f64> = (0..nx * ny)
        .map(|e| {
            let (x, y) = (g.x(e / ny), g.y(e % ny));
            0.5 * x * x / 0.46 + 0.5 * y * y / 0.3
        })
        .collect();
    let da = g.dx() * g.dy();
    let mut fast = normal::NormalSolver::new(nx * ny);
    fast.tol = 1e-6;
    let mut exact = normal::NormalSolver::new(nx * ny);
    exact.tol = 1e-12;
    exact.fixed_set = false;
    let a = normal_sequence(&mut fast, &mut conv, &h, da);
    let b = normal_sequence(&mut exact, &mut conv, &h, da);
    let mut free_steps = 0;
    for (k, ((fa, pa), (fb, _))) in a.iter().zip(&b).enumerate() {
        // superposed (no product): exact to the unit responses; else the CG's tolerance
        let tol = if *pa == 0 { 1e-9 } else { 1e-6 };
        assert!((fa / fb - 1.0).abs() < tol, "solve {k}: {fa} vs {fb}");
        if *pa == 0 {
            free_steps += 1;
        }
    }
    println!("{free_steps} of {} solves without a product", a.len());
    assert!(free_steps >= 25, "{free_steps}");
    // the jump of the approach changes the set: solved (by the CG), still equal
    assert!(a[30].1 > 0);
}

/// The Hertz problem of the reference case on an `nx × ny` grid of elements `d` (m) centred
/// on the contact point: the element centres `(x, y)` (element `i · ny + j`) and the
/// undeformed gap (m) `x²/(2 R_x) + y²/(2 R_y)`.
fn hertz_gap(nx: usize, ny: usize, d: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let h = reference_hertz_input();
    let c = |i: usize, n: usize| (i as f64 - 0.5 * (n as f64 - 1.0)) * d;
    let (mut x, mut y, mut gap) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..nx {
        for j in 0..ny {
            let (xi, yj) = (c(i, nx), c(j, ny));
            x.push(xi);
            y.push(yj);
            gap.push(xi * xi / (2.0 * h.radius_x_m) + yj * yj / (2.0 * h.radius_y_m));
        }
    }
    (x, y, gap)
}

#[test]
fn strip_normal_operator_solves_as_the_half_space_convolver() {
    // The same half-space kernel through the FFT-along-x, dense-across products of an FE
    // patch and through the 2D FFT convolver: the same pressures (an independent product).
    use super::super::influence::strip::{half_space_kernel, StripNormal};
    let (nx, ny, d) = (24, 18, 0.8e-3);
    let inp = reference_hertz_input();
    let (e, nu) = (inp.youngs_pa, inp.poisson);
    let (e_star, g) = (combined_modulus(e, nu), shear_modulus(e, nu));
    let (_, _, gap) = hertz_gap(nx, ny, d);
    let mut conv = influence::Convolver::new(nx, ny, d, d, e_star, g, nu);
    let k = half_space_kernel((d, d), (e_star, g, nu), 1);
    let mut strip = StripNormal::new(nx, ny, |o, j, jp| k(o, j, jp)[0][0]);
    let mode = normal::NormalMode::Load(100e3);
    let (mut p1, mut p2) = (vec![0.0; nx * ny], vec![0.0; nx * ny]);
    let o1 = normal::NormalSolver::new(nx * ny)
        .solve(&mut conv, &gap, d * d, mode, &mut p1)
        .unwrap();
    let o2 = normal::NormalSolver::new(nx * ny)
        .solve(&mut strip, &gap, d * d, mode, &mut p2)
        .unwrap();
    let pmax = p1.iter().cloned().fold(0.0, f64::max);
    let diff = p1
        .iter()
        .zip(&p2)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(diff < 1e-8 * pmax, "{diff} of {pmax}");
    approx::assert_relative_eq!(o1.approach_m, o2.approach_m, max_relative = 1e-9);
}
