//! Rolling contact: steady creep coefficients (Kalker), Carter's 2D problem,
//! Cattaneo–Mindlin, saturation, power balance and the transient response, the series
//! compliance in rolling, and the tangential solvers against each other.

use super::super::influence::strip::{half_space_kernel, StripInfluence};
use super::super::influence::Influence;
use super::{reference_hertz, rolling_config};
use crate::contact::{
    combined_modulus, load_response_curve, shear_modulus, solve_case, transient, ContactCase,
    ContactError, GridSpec, HertzContact, HertzGridParams, HertzInput, Longitudinal, NormalInput,
    StepInputs, TangentialAlgorithm, TransientConfig, TransientRolling, WearAccumulator,
};
use std::f64::consts::PI;

/// Kalker's table interpolated linearly in b/a between 0.7 and 0.8 at ν = 0.25.
fn kalker_table_nu025(ba: f64) -> (f64, f64, f64) {
    let t = (ba - 0.7) / 0.1;
    (
        4.54 + t * (4.36 - 4.54),
        4.21 + t * (3.99 - 4.21),
        1.95 + t * (1.75 - 1.95),
    )
}

#[test]
fn linear_creep_coefficients_match_kalker_32() {
    // Published table (Kalker 1990), reference ellipse b/a = 0.752 at ν = 0.25. On 32×32 the
    // first-order rolling discretisation is ~3.5 % high (measured: C11 +3.3 %, C22 +3.6 %,
    // C23 +1.1 %); the 48×48 test (ignored, slow) meets 2 %.
    let (c11, c22, c23, ba, _) = creep_coefficients(0.46, 0.3, 0.25, 32);
    let (k11, k22, k23) = kalker_table_nu025(ba);
    println!("32: C11 {c11:.3} ({k11:.3}) C22 {c22:.3} ({k22:.3}) C23 {c23:.3} ({k23:.3})");
    assert!((c11 / k11 - 1.0).abs() < 0.04);
    assert!((c22 / k22 - 1.0).abs() < 0.04);
    assert!((c23 / k23 - 1.0).abs() < 0.02);
}

#[test]
#[ignore = "slow (~15 s release): cargo test --release --lib contact::tests::linear_creep_coefficients_match_kalker_48 -- --ignored"]
fn linear_creep_coefficients_match_kalker_48() {
    // Measured: C11 4.523 vs 4.446 (+1.7 %), C22 4.171 vs 4.095 (+1.9 %), C23 1.842 vs 1.846.
    let (c11, c22, c23, ba, _) = creep_coefficients(0.46, 0.3, 0.25, 48);
    let (k11, k22, k23) = kalker_table_nu025(ba);
    assert!((c11 / k11 - 1.0).abs() < 0.02);
    assert!((c22 / k22 - 1.0).abs() < 0.02);
    assert!((c23 / k23 - 1.0).abs() < 0.02);
}

#[test]
fn carter_2d_rolling_50() {
    // Closed form (Carter; Johnson §8.2): F/µN = 1 − (1 − ξ/ξs)², ξs = µa/R, stick zone at the
    // leading edge with half-length a√(1 − F/µN). Measured on 50 cells: F/µN 0.7597 vs 0.75,
    // c/a 0.504 vs 0.5; on 200 cells 0.75008 and 0.498.
    let (f, c, lead, _) = carter(50, 0.5);
    assert!((-f / 0.75 - 1.0).abs() < 0.02, "F/µN = {f}");
    assert!((c - 0.5).abs() < 0.05, "c/a = {c}");
    assert!(lead > 0.9, "stick zone not at the leading edge: {lead}");
}

#[test]
#[ignore = "slow: cargo test --release --lib contact::tests::carter_2d_rolling_200 -- --ignored"]
fn carter_2d_rolling_200() {
    for (xf, tol) in [(0.25_f64, 0.003), (0.5, 0.003), (0.9, 0.003)] {
        let (f, c, _, _) = carter(200, xf);
        let exp = 1.0 - (1.0 - xf) * (1.0 - xf);
        assert!((-f / exp - 1.0).abs() < tol, "F/µN = {f} vs {exp}");
        assert!((c - (1.0 - exp).sqrt()).abs() < 0.02);
    }
}

#[test]
fn cattaneo_mindlin_stick_radius() {
    // Closed form (Johnson §7.2, exact for ν = 0): c/a = (1 − Q/µP)^(1/3), sphere on sphere.
    let (r, load, mu) = (0.1, 10e3, 0.3);
    let h = HertzContact::solve(&HertzInput {
        radius_x_m: r,
        radius_y_m: r,
        youngs_pa: 210e9,
        poisson: 0.0,
        load_n: load,
    })
    .unwrap();
    let cfg = TransientConfig::around_hertz(&HertzGridParams {
        radius_x_m: r,
        radius_y_m: r,
        poisson: 0.0,
        friction: mu,
        speed_m_per_s: 10.0,
        load_n: load,
        nx: 40,
        ny: 40,
        margin: 1.1,
        ..HertzGridParams::default()
    })
    .unwrap();
    let mut eng = TransientRolling::new(cfg).unwrap();
    for q in [0.3, 0.6] {
        eng.reset();
        // first step from rest = a static tangential shift (no rolling history)
        let res = eng
            .step(&StepInputs {
                normal: NormalInput::Force(load),
                longitudinal: Longitudinal::Force(q * mu * load),
                lateral_creepage: 0.0,
                spin_per_m: 0.0,
                rail_height_m: None,
            })
            .unwrap();
        let stick = eng
            .states()
            .iter()
            .filter(|&&s| s == transient::STATE_STICK)
            .count() as f64
            * eng.element_area_m2();
        let c = (stick / PI).sqrt() / h.a_m;
        let exp = (1.0 - q).cbrt();
        println!("Q/µP {q}: c/a {c:.4} vs {exp:.4}, Fx {:.1}", res.fx_n);
        assert!((res.fx_n / (q * mu * load) - 1.0).abs() < 1e-4);
        assert!((c / exp - 1.0).abs() < 0.04, "c/a {c} vs {exp}");
    }
}

#[test]
fn saturation_and_separation() {
    let cfg = rolling_config(20, 16, 1.2);
    let mut eng = TransientRolling::new(cfg).unwrap();
    let r = eng
        .solve_steady(&StepInputs::force_creepage(100e3, 0.05), 1e-8, 500)
        .unwrap();
    // full slip: |F| = µN (conservation of the friction bound), F opposite to ξ
    assert!((r.fx_n / (-0.4 * 100e3) - 1.0).abs() < 1e-4, "{r:?}");
    assert_eq!(r.slip_elements, r.contact_elements);
    // separation: zero load and negative approach give zero forces, not NaN
    let z = eng.step(&StepInputs::force_creepage(0.0, 0.01)).unwrap();
    assert_eq!(
        (z.fx_n, z.fy_n, z.normal_force_n, z.frictional_power_w),
        (0.0, 0.0, 0.0, 0.0)
    );
    let mut inp = StepInputs::force_creepage(0.0, 0.01);
    inp.normal = NormalInput::Approach(-1e-6);
    let z = eng.step(&inp).unwrap();
    assert_eq!((z.fx_n, z.normal_force_n), (0.0, 0.0));
    assert_eq!(z.slip_area_fraction(), 0.0);
    // prescribed force beyond friction is an error, not a NaN
    let mut inp = StepInputs::force_creepage(100e3, 0.0);
    inp.longitudinal = Longitudinal::Force(50e3);
    assert!(matches!(
        eng.step(&inp),
        Err(ContactError::TractionExceedsFriction { .. })
    ));
}

#[test]
fn frictional_power_matches_global_power_balance() {
    // Conservation law of steady rolling: −∫τ·s dA = −V ξ Fx. The step pairs the slip distance
    // of each material path x_{i+1} → x_i with the trapezoidal mean of the tractions at its
    // ends (τ_i now, τ_{i+1} one step ago), including the path on which the material leaves the
    // contact; by the symmetry of the influence operator this balance is then exact up to the
    // solver tolerance. Measured rel. error: −2.4e-6 (16×12), −3.9e-7 (32×24), +6e-8 (48×36).
    // Pairing with the end-of-step traction alone (backward Euler along the path) would lose
    // (V/Δx) τᵀ(C − C̄)τ, C̄ the one-cell-shifted operator: −41.5 %, −24.2 %, −16.5 %
    // on the same grids (first order in Δx; ≈ Δx µp0 / (G a ξ)): the balance below tells the
    // two pairings apart.
    for (nx, ny) in [(16usize, 12usize), (32, 24)] {
        let cfg = rolling_config(nx, ny, 1.2);
        let mut eng = TransientRolling::new(cfg).unwrap();
        let xi = -1.0e-3;
        let st = eng
            .solve_steady(&StepInputs::force_creepage(100e3, xi), 1e-9, 3000)
            .unwrap();
        let pw_global = -cfg.speed_m_per_s * xi * st.fx_n;
        let rel = st.frictional_power_w / pw_global - 1.0;
        println!(
            "{nx}x{ny}: Fx {:.1} N, slip fraction {:.3}, power {:.3} W vs global {:.3} W ({:+.2e})",
            st.fx_n,
            st.slip_area_fraction(),
            st.frictional_power_w,
            pw_global,
            rel
        );
        assert!(rel.abs() < 2e-5, "{rel}");
        assert!(st.slip_area_fraction() > 0.1);
    }
}

#[test]
fn transient_rise_within_one_contact_length() {
    // Kalker (1990 §2.2 / ch. 5): from rest with constant creepage the force reaches its
    // steady value after about one contact length of rolling.
    let cfg = rolling_config(24, 18, 1.2);
    let h = reference_hertz();
    let mut eng = TransientRolling::new(cfg).unwrap();
    let xi = -1.0e-3;
    let st = eng
        .solve_steady(&StepInputs::force_creepage(100e3, xi), 1e-9, 3000)
        .unwrap();
    eng.reset();
    let steps_contact = (2.0 * h.a_m / cfg.grid.dx()).ceil() as usize;
    let mut reached = None;
    for k in 0..2 * steps_contact {
        let r = eng.step(&StepInputs::force_creepage(100e3, xi)).unwrap();
        if reached.is_none() && r.fx_n / st.fx_n > 0.95 {
            reached = Some(k + 1);
        }
    }
    let k = reached.expect("never reached 95 % of steady");
    println!(
        "95 % of steady Fx after {k} steps = {:.2} contact lengths",
        k as f64 / steps_contact as f64
    );
    // measured: 95 % after 1.75 contact lengths (24×18 grid)
    assert!(k <= 2 * steps_contact);
}

#[test]
fn load_response_long_wavelength_is_quasi_steady() {
    let cfg = rolling_config(16, 12, 1.35);
    let h = reference_hertz();
    let lams: Vec<f64> = [1.5, 3.0, 6.0, 30.0, 100.0]
        .iter()
        .map(|r| r * 2.0 * h.a_m)
        .collect();
    let curve = load_response_curve(&cfg, 100e3, 0.15, 0.05, &lams).unwrap();
    for p in &curve {
        println!(
            "λ/2a {:.2} f {:.0} Hz: |F|/|F_qs| {:.3}, lag {:.1}°",
            p.wavelength_over_contact_length,
            p.frequency_hz,
            p.amplitude_ratio,
            p.phase_lag_rad.to_degrees()
        );
    }
    let long = curve.last().unwrap();
    // measured: amplitude ratio 0.951, lag 0.8° at λ/2a = 100. The lag vanishes; the ~5 %
    // amplitude offset from the steady-state derivative is an open problem (see report).
    assert!(
        (long.amplitude_ratio - 1.0).abs() < 0.06 && long.phase_lag_rad.abs() < 0.03,
        "{long:?}"
    );
    // the response approaches the quasi-steady one monotonically as λ grows
    for w in curve.windows(2) {
        assert!(w[1].amplitude_ratio > w[0].amplitude_ratio);
    }
}

#[test]
fn wear_accumulator_conserves_work() {
    // Conservation: Σ_bins W_f ΔxΔy = Σ_steps P Δt when the patch stays inside the bins.
    let cfg = rolling_config(16, 12, 1.2);
    let mut eng = TransientRolling::new(cfg).unwrap();
    let mut acc = WearAccumulator::new(&eng, -0.02, 400);
    let mut total = 0.0;
    for k in 0..60 {
        let n = 100e3 * (1.0 + 0.1 * (k as f64 * 0.3).sin());
        let r = eng.step(&StepInputs::force_creepage(n, -2e-3)).unwrap();
        acc.add_step(&eng, k as f64 * cfg.grid.dx());
        total += r.frictional_power_w * eng.time_step_s();
    }
    assert!(total > 0.0);
    assert!((acc.total_j() / total - 1.0).abs() < 1e-12);
    let mut wx = vec![0.0; 400];
    acc.work_x(&mut wx);
    let sum: f64 = wx.iter().sum::<f64>() * cfg.grid.dx();
    assert!((sum / total - 1.0).abs() < 1e-12);
}

#[test]
fn solve_case_reference_and_fields() {
    let case = ContactCase {
        grid_nx: 24,
        grid_ny: 20,
        ..ContactCase::default()
    };
    let sol = solve_case(&case).unwrap();
    let s = sol.summary();
    println!("{}", serde_json::to_string(&s).unwrap());
    assert!((s.fx_n / 15e3 - 1.0).abs() < 1e-5);
    assert!(s.creepage < 0.0 && s.slip_area_fraction > 0.0 && s.slip_area_fraction < 1.0);
    assert!((s.a_mm / 7.162 - 1.0).abs() < 0.01 && (s.p0_mpa / 1237.6 - 1.0).abs() < 0.02);
    let json = serde_json::to_value(s).unwrap();
    for k in [
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
        assert!(json.get(k).is_some(), "missing key {k}");
    }
    let dir = std::env::temp_dir().join(format!("contact_fields_{}", std::process::id()));
    let files = sol.write_fields(&dir).unwrap();
    let csv = std::fs::read_to_string(&files[0]).unwrap();
    assert_eq!(csv.lines().count(), 1 + 24 * 20);
    assert!(csv.starts_with("x_mm,y_mm,pressure_mpa,tx_mpa,ty_mpa,slip_x,slip_y,state,power"));
    assert!(files.iter().all(|f| f.exists()));
    assert!(!dir.join("contact_fields.csv.tmp").exists());
    std::fs::remove_dir_all(&dir).ok();
}

/// Steady linear creep coefficients (C11, C22, C23, b/a, steps) on an n×n grid for relative
/// radii rx, ry (no slip: µ = 1000, ξ = 1e-4).
fn creep_coefficients(rx: f64, ry: f64, nu: f64, n: usize) -> (f64, f64, f64, f64, usize) {
    let load = 100e3;
    let mut cfg = TransientConfig::around_hertz(&HertzGridParams {
        radius_x_m: rx,
        radius_y_m: ry,
        poisson: nu,
        friction: 1e3,
        speed_m_per_s: 38.9,
        load_n: load,
        nx: n,
        ny: n,
        margin: 1.1,
        ..HertzGridParams::default()
    })
    .unwrap();
    cfg.tangential_tol = 1e-8;
    let h = HertzContact::solve(&HertzInput {
        radius_x_m: rx,
        radius_y_m: ry,
        youngs_pa: 210e9,
        poisson: nu,
        load_n: load,
    })
    .unwrap();
    let g = shear_modulus(210e9, nu);
    let c2 = h.a_m * h.b_m;
    let mut eng = TransientRolling::new(cfg).unwrap();
    let xi = 1e-4;
    let r = eng
        .solve_steady(&StepInputs::force_creepage(load, xi), 1e-7, 2000)
        .unwrap();
    let steps = eng.steps();
    let c11 = -r.fx_n / (g * c2 * xi);
    eng.reset();
    let mut inp = StepInputs::force_creepage(load, 0.0);
    inp.lateral_creepage = xi;
    let r = eng.solve_steady(&inp, 1e-7, 2000).unwrap();
    let c22 = -r.fy_n / (g * c2 * xi);
    eng.reset();
    let phi = xi / c2.sqrt();
    let mut inp = StepInputs::force_creepage(load, 0.0);
    inp.spin_per_m = phi;
    let r = eng.solve_steady(&inp, 1e-7, 2000).unwrap();
    let c23 = -r.fy_n / (g * c2 * c2.sqrt() * phi);
    (c11, c22, c23, h.b_m / h.a_m, steps)
}

/// Carter (Johnson §8.2): 2D steady rolling of identical cylinders (relative radius R), a strip
/// of length 200a. Returns (Fx/µN, stick half-length / a, stick leading edge / a, power W).
fn carter(nx: usize, xi_frac: f64) -> (f64, f64, f64, f64) {
    let (r, e, nu, mu, p_line) = (0.23, 210e9, 0.3, 0.3, 1.0e6);
    let es = combined_modulus(e, nu);
    let a = (4.0 * p_line * r / (PI * es)).sqrt();
    let len = 200.0 * a;
    let cfg = TransientConfig {
        grid: GridSpec {
            nx,
            ny: 1,
            half_length_x_m: 1.2 * a,
            half_length_y_m: 0.5 * len,
        },
        youngs_pa: e,
        poisson: nu,
        friction: mu,
        radius_x_m: r,
        radius_y_m: f64::INFINITY,
        speed_m_per_s: 30.0,
        normal_tol: 1e-10,
        tangential_tol: 1e-8,
    };
    let mut eng = TransientRolling::new(cfg).unwrap();
    let xi_s = mu * a / r;
    let res = eng
        .solve_steady(
            &StepInputs::force_creepage(p_line * len, xi_frac * xi_s),
            1e-8,
            5000,
        )
        .unwrap();
    let stick = eng
        .states()
        .iter()
        .filter(|&&s| s == transient::STATE_STICK)
        .count() as f64
        * cfg.grid.dx();
    let xs = eng.x_m();
    let lead = (0..nx)
        .filter(|&i| eng.states()[i] == transient::STATE_STICK)
        .map(|i| xs[i])
        .fold(f64::NEG_INFINITY, f64::max);
    (
        res.fx_n / (mu * res.normal_force_n),
        stick / 2.0 / a,
        lead / a,
        res.frictional_power_w,
    )
}

// ---------------------------------------------------------------------------------------------
// Series compliance in rolling (TransientRolling::set_series_compliance)

#[test]
fn series_compliance_leaves_steady_rolling_unchanged() {
    // Steady state: F(t) = F(t − Δt), the uniform slip term vanishes.
    let cfg = rolling_config(16, 12, 1.2);
    let mut eng = TransientRolling::new(cfg).unwrap();
    let mut inp = StepInputs::force_creepage(100e3, -1e-3);
    inp.lateral_creepage = 0.5e-3;
    let s0 = eng.solve_steady(&inp, 1e-10, 3000).unwrap();
    eng.reset();
    eng.set_series_compliance([2e-9, 1e-9, 0.0]).unwrap();
    let s1 = eng.solve_steady(&inp, 1e-10, 3000).unwrap();
    println!("steady: {s0:?}\nwith c: {s1:?}");
    let scale = 0.4 * 100e3;
    assert!((s1.fx_n - s0.fx_n).abs() < 1e-6 * scale);
    assert!((s1.fy_n - s0.fy_n).abs() < 1e-6 * scale);
    assert!((s1.frictional_power_w / s0.frictional_power_w - 1.0).abs() < 1e-5);
}

#[test]
fn series_compliance_transient_rise_matches_series_spring_model() {
    // Linear limit (µ = 1000: full adhesion, constant patch, so the step map is linear and
    // time-invariant). From rest, constant creepage ξ: the c_x = 0 run gives the response
    // F0(n) (n steps). Its increments R_k = (F0(k+1) − F0(k))/ξ are the impulse response of
    // the patch to the creepage of one step; R_0 = −k_t Δx with k_t the tangential stiffness
    // of the patch for a uniform shift (the first step from rest is a pure shift ξΔx). In
    // series with the compliance c_x the patch sees the effective creepage
    // ξ_eff(m) = ξ + c_x (F(m) − F(m−1)) / Δx, so
    //   F(n) = Σ_k R_k ξ_eff(n − k),
    // solved step by step for the implicit F(n) (the spring k_t in series with 1/c_x).
    let mut cfg = TransientConfig::around_hertz(&HertzGridParams {
        friction: 1e3,
        speed_m_per_s: 38.9,
        nx: 20,
        ny: 16,
        margin: 1.2,
        ..HertzGridParams::default()
    })
    .unwrap();
    // the tolerance is relative to µ p_max: tight, since µ = 1000
    cfg.tangential_tol = 1e-11;
    let mut eng = TransientRolling::new(cfg).unwrap();
    let xi = -1e-4;
    let dx = cfg.grid.dx();
    let nsteps = 40;
    let rise = |eng: &mut TransientRolling| -> Vec<f64> {
        let inp = StepInputs::force_creepage(100e3, xi);
        (0..nsteps).map(|_| eng.step(&inp).unwrap().fx_n).collect()
    };
    let f0 = rise(&mut eng);
    let k_t = -f0[0] / (xi * dx);
    let cx = 1.0 / k_t; // the series spring as stiff as the patch: a clear slow-down
    eng.reset();
    eng.set_series_compliance([cx, 0.0, 0.0]).unwrap();
    let fc = rise(&mut eng);
    let r: Vec<f64> = (0..nsteps)
        .map(|k| (f0[k] - if k > 0 { f0[k - 1] } else { 0.0 }) / xi)
        .collect();
    let mut model = vec![0.0; nsteps];
    let mut w_eff = vec![0.0; nsteps];
    for n in 0..nsteps {
        let fprev = if n > 0 { model[n - 1] } else { 0.0 };
        // F(n) = R_0 (ξ + c (F(n) − F(n−1))/Δx) + Σ_{k≥1} R_k ξ_eff(n−k)
        let hist: f64 = (1..=n).map(|k| r[k] * w_eff[n - k]).sum();
        let a = r[0] * cx / dx;
        model[n] = (r[0] * (xi - cx * fprev / dx) + hist) / (1.0 - a);
        w_eff[n] = xi + cx * (model[n] - fprev) / dx;
    }
    let fss = f0[nsteps - 1];
    let mut worst = 0.0_f64;
    for n in 0..nsteps {
        worst = worst.max((fc[n] - model[n]).abs() / fss.abs());
        if n < 10 {
            println!(
                "step {n}: F0 {:.2} N, F(c) {:.2} N, model {:.2} N",
                f0[n], fc[n], model[n]
            );
        }
    }
    println!("k_t = {k_t:.4e} N/m, c_x = {cx:.3e} m/N; max |F − model| / F_ss = {worst:.2e}");
    // the rise is slower with the series spring
    assert!(fc[0].abs() < 0.6 * f0[0].abs() && fc[5].abs() < f0[5].abs());
    // measured 2.2e-8 (the map is exactly linear; a few % would allow a scalar approximation)
    assert!(worst < 1e-5, "{worst}");
}

#[test]
fn series_compliance_rejects_invalid_values() {
    let cfg = rolling_config(8, 6, 1.2);
    let mut eng = TransientRolling::new(cfg).unwrap();
    for bad in [
        [-1e-9, 0.0, 0.0],
        [0.0, f64::NAN, 0.0],
        [0.0, 0.0, f64::INFINITY],
        [0.0, 0.0, -0.0 - 1e-30],
    ] {
        assert!(matches!(
            eng.set_series_compliance(bad),
            Err(ContactError::InvalidParameter { .. })
        ));
    }
    assert_eq!(eng.series_compliance(), [0.0; 3]);
    eng.set_series_compliance([1e-9, 2e-9, 3e-9]).unwrap();
    assert_eq!(eng.series_compliance(), [1e-9, 2e-9, 3e-9]);
}

// ---------------------------------------------------------------------------------------------
// Tangential solvers

#[test]
fn newton_tangential_solver_matches_element_test_solver() {
    // Independent solver: the former active-set method (slip directions by Kalker's element
    // test only) on the same transient sequence, with varying load, corrugated rail, lateral
    // creepage and spin (slip directions far from the rolling direction).
    let cfg = rolling_config(20, 16, 1.3);
    let dx = cfg.grid.dx();
    let mut runs = Vec::new();
    // the third run, Newton at a 1000× tighter tolerance, is the reference
    for (alg, tol) in [
        (TangentialAlgorithm::Newton, cfg.tangential_tol),
        (TangentialAlgorithm::ElementTest, cfg.tangential_tol),
        (TangentialAlgorithm::Newton, 1e-3 * cfg.tangential_tol),
    ] {
        let mut eng = TransientRolling::new(TransientConfig {
            tangential_tol: tol,
            ..cfg
        })
        .unwrap();
        eng.set_tangential_algorithm(alg);
        runs.push(transient_sequence(&mut eng, dx, 60, 0, |_| -1.5e-3));
    }
    let diff = |a: usize, b: usize| force_power_difference(&runs[a].0, &runs[b].0);
    let (newton, element, between) = (diff(0, 2), diff(1, 2), diff(0, 1));
    println!(
        "tangential FFT pairs: Newton {}, element test {} (reference {}); vs reference \
         (force/µN, power rel.): Newton {newton:?}, element test {element:?}; \
         between {between:?}",
        runs[0].1, runs[1].1, runs[2].1
    );
    // measured vs the reference: Newton (3.0e-8 µN, power 2.9e-6), element test (1.1e-5 µN,
    // power 1.0e-4): at equal tolerance the Newton directions are the more accurate ones
    assert!(newton.0 < 1e-6 && newton.1 < 1e-5, "{newton:?}");
    assert!(newton.0 <= element.0, "{newton:?} {element:?}");
    assert!(between.0 < 1e-4 && between.1 < 1e-3, "{between:?}");
    assert!(runs[0].1 * 5 < runs[1].1);
}

#[test]
fn jacobi_preconditioned_tangential_solver_matches_the_plain_one() {
    // The same transient sequence (varying load, corrugated rail, lateral creepage, spin) with
    // the inner CG preconditioned and plain, and the reference: the plain CG at a 1000×
    // tighter tolerance. The preconditioner changes the path, not the solution.
    let runs = switch_runs(|eng, on| eng.set_tangential_jacobi(on));
    let diff = |a: usize, b: usize| force_power_difference(&runs[a].0, &runs[b].0);
    let (pre, plain) = (diff(0, 2), diff(1, 2));
    println!(
        "tangential FFT pairs (steps 20..80): Jacobi {}, plain {} (reference {}); vs reference \
         (force/µN, power rel.): Jacobi {pre:?}, plain {plain:?}",
        runs[0].1, runs[1].1, runs[2].1
    );
    assert!(pre.0 < 1e-6 && pre.1 < 1e-5, "{pre:?}");
    assert!(plain.0 < 1e-6 && plain.1 < 1e-5, "{plain:?}");
    assert!(
        runs[0].1 * 4 < runs[1].1 * 3,
        "{} vs {}",
        runs[0].1,
        runs[1].1
    );
}

#[test]
fn circle_start_gives_the_solution_of_the_plain_warm_start() {
    // The same transient sequence with the last step's slip elements started on their new
    // circle and without, and the reference: the plain warm start at a 1000× tighter
    // tolerance. The start changes the path, not the solution.
    let runs = switch_runs(|eng, on| eng.set_circle_start(on));
    let diff = |a: usize, b: usize| force_power_difference(&runs[a].0, &runs[b].0);
    let (circle, plain) = (diff(0, 2), diff(1, 2));
    println!(
        "tangential FFT pairs (steps 20..80): circle start {}, plain {} (reference {}); vs \
         reference (force/µN, power rel.): circle {circle:?}, plain {plain:?}",
        runs[0].1, runs[1].1, runs[2].1
    );
    assert!(circle.0 < 1e-6 && circle.1 < 1e-5, "{circle:?}");
    assert!(plain.0 < 1e-6 && plain.1 < 1e-5, "{plain:?}");
    assert!(runs[0].1 < runs[1].1, "{} vs {}", runs[0].1, runs[1].1);
}

#[test]
fn linear_start_gives_the_solution_of_the_whole_grid_start() {
    // The same transient sequence with the start's slip by linearity from the last step's
    // exact product and with the whole-grid product of the start, and the reference: the
    // whole-grid start at a 1000× tighter tolerance. The start's product changes the path
    // (single-precision box product of the traction's change), not the solution.
    let runs = switch_runs(|eng, on| eng.set_linear_start(on));
    let diff = |a: usize, b: usize| force_power_difference(&runs[a].0, &runs[b].0);
    let (linear, whole) = (diff(0, 2), diff(1, 2));
    println!(
        "tangential FFT pairs (steps 20..80): linear start {}, whole grid {} (reference {}); \
         vs reference (force/µN, power rel.): linear {linear:?}, whole grid {whole:?}",
        runs[0].1, runs[1].1, runs[2].1
    );
    assert!(linear.0 < 1e-6 && linear.1 < 1e-5, "{linear:?}");
    assert!(whole.0 < 1e-6 && whole.1 < 1e-5, "{whole:?}");
    // the start's product is replaced, not added to: at most one confirming product more in
    // a step whose start already meets the tolerance
    assert!(
        runs[0].1 <= runs[1].1 + 60,
        "{} vs {}",
        runs[0].1,
        runs[1].1
    );
}

/// The result of [`transient_sequence`]: `(F_x, F_y, frictional power)` per step and the
/// tangential influence products counted.
type SequenceRun = (Vec<(f64, f64, f64)>, usize);

/// Three runs of [`transient_sequence`] (80 steps, products counted from step 20 on: the
/// warm-started regime of a passage; longitudinal creepage `−1.5e-3 + 2e-4 sin(0.3 k)`) on a
/// 24 × 18 grid: with a solver switch `set` on, off, and off at a 1000× tighter tolerance
/// (the reference).
fn switch_runs(set: impl Fn(&mut TransientRolling, bool)) -> Vec<SequenceRun> {
    let cfg = rolling_config(24, 18, 1.4);
    let dx = cfg.grid.dx();
    let mut runs = Vec::new();
    for (on, tol) in [
        (true, cfg.tangential_tol),
        (false, cfg.tangential_tol),
        (false, 1e-3 * cfg.tangential_tol),
    ] {
        let mut eng = TransientRolling::new(TransientConfig {
            tangential_tol: tol,
            ..cfg
        })
        .unwrap();
        set(&mut eng, on);
        runs.push(transient_sequence(&mut eng, dx, 80, 20, |k| {
            -1.5e-3 + 2e-4 * (0.3 * k as f64).sin()
        }));
    }
    runs
}

/// Drives `eng` through `steps` transient steps of the tangential-solver comparisons: normal
/// load 100 kN ± 10 %, a 30 mm rail corrugation of 5 µm, longitudinal creepage `creep(k)`,
/// lateral creepage 0.8e-3 and spin 0.3 1/m. Returns `(F_x, F_y, frictional power)` per step
/// and the tangential influence products of the steps from `count_from` on.
fn transient_sequence(
    eng: &mut TransientRolling,
    dx: f64,
    steps: usize,
    count_from: usize,
    creep: impl Fn(usize) -> f64,
) -> (Vec<(f64, f64, f64)>, usize) {
    let xs = eng.x_m().to_vec();
    let mut rail = vec![0.0; xs.len()];
    let mut out = Vec::new();
    let mut prods = 0usize;
    for k in 0..steps {
        let xc = k as f64 * dx;
        for (r, x) in rail.iter_mut().zip(&xs) {
            *r = 5e-6 * (2.0 * PI * (xc + x) / 0.03).sin();
        }
        let r = eng
            .step(&StepInputs {
                normal: NormalInput::Force(100e3 * (1.0 + 0.1 * (0.4 * k as f64).sin())),
                longitudinal: Longitudinal::Creepage(creep(k)),
                lateral_creepage: 0.8e-3,
                spin_per_m: 0.3,
                rail_height_m: Some(&rail),
            })
            .unwrap();
        if k >= count_from {
            prods += r.tangential_iterations;
        }
        out.push((r.fx_n, r.fy_n, r.frictional_power_w));
    }
    (out, prods)
}

/// max |ΔF_x|, |ΔF_y| / µN (µN = 0.4 · 100 kN) and the max relative difference of the
/// frictional power between two runs of [`transient_sequence`].
fn force_power_difference(a: &[(f64, f64, f64)], b: &[(f64, f64, f64)]) -> (f64, f64) {
    let (mut f, mut p) = (0.0_f64, 0.0_f64);
    for (x, y) in a.iter().zip(b) {
        f = f.max((x.0 - y.0).abs().max((x.1 - y.1).abs()) / (0.4 * 100e3));
        p = p.max((x.2 - y.2).abs() / y.2.abs().max(1.0));
    }
    (f, p)
}

/// The 24 × 18 grid of the solver comparisons and the strip operators of the quasi-identical
/// half-space's kernel on it, `extra_rows` rows longer (0: the same grid).
fn half_space_strip(extra_rows: usize) -> (TransientConfig, StripInfluence) {
    let cfg = rolling_config(24, 18, 1.4);
    let (nx, ny, dx, dy) = (cfg.grid.nx, cfg.grid.ny, cfg.grid.dx(), cfg.grid.dy());
    let (es, gm) = (
        combined_modulus(cfg.youngs_pa, cfg.poisson),
        shear_modulus(cfg.youngs_pa, cfg.poisson),
    );
    let kernel = half_space_kernel((dx, dy), (es, gm, cfg.poisson), 3);
    (cfg, StripInfluence::new(nx + extra_rows, ny, kernel))
}

/// The transient sequence of the solver comparisons (60 steps) on the half-space engine with
/// series compliance `c` and on `fe`: (max |ΔF|/µN, max relative Δ power).
fn against_the_half_space(c: [f64; 3], fe: &mut TransientRolling) -> (f64, f64) {
    let cfg = *fe.config();
    let creep = |k: usize| -1.5e-3 + 2e-4 * (0.3 * k as f64).sin();
    let mut half = TransientRolling::new(cfg).unwrap();
    half.set_series_compliance(c).unwrap();
    let a = transient_sequence(&mut half, cfg.grid.dx(), 60, 0, creep);
    let b = transient_sequence(fe, cfg.grid.dx(), 60, 0, creep);
    force_power_difference(&b.0, &a.0)
}

#[test]
fn strip_operators_of_the_half_space_kernel_give_the_half_space_solution() {
    // The same transient sequence (normal load varying ±10 %, a 5 µm corrugation, creepage,
    // lateral creepage and spin) on the half-space's 2D FFT operators and on the strip
    // operators (FFT along x, dense blocks across: an independent product) built from the
    // same half-space coefficients: the solvers take either through one interface, so the
    // forces and the frictional power agree to the solvers' tolerance.
    let (cfg, strip) = half_space_strip(0);
    assert_eq!(strip.coupling_ratio(), 0.0);
    assert!(strip.asymmetry() < 1e-12, "{}", strip.asymmetry());
    let mut fe = TransientRolling::with_influence(cfg, Influence::Strip(strip)).unwrap();
    let (f, p) = against_the_half_space([0.0; 3], &mut fe);
    println!("strip vs half-space: force/µN {f:.2e}, power rel. {p:.2e}");
    assert!(f < 2e-6 && p < 2e-5, "{f:e} {p:e}");
    // an operator on another grid is refused
    let (_, other) = half_space_strip(1);
    assert!(TransientRolling::with_influence(cfg, Influence::Strip(other)).is_err());
}

#[test]
fn a_negative_uniform_term_of_the_operators_adds_to_the_series_compliance() {
    // The fe-patch's split is a negative uniform compliance beside its kernel: the solvers
    // must see the sum. Half-space with series compliance c against the strip operators of
    // the half-space kernel with the uniform term −u and series compliance c + u.
    let c = [2e-10, 2.5e-10, 3e-10];
    let u = [1.5e-10, 1.0e-10, 2e-10];
    let (cfg, strip) = half_space_strip(0);
    let strip = strip.with_uniform(u.map(|v| -v));
    let mut fe = TransientRolling::with_influence(cfg, Influence::Strip(strip)).unwrap();
    fe.set_series_compliance([0, 1, 2].map(|d| c[d] + u[d]))
        .unwrap();
    let (f, p) = against_the_half_space(c, &mut fe);
    println!(
        "strip with −u, series c + u vs half-space with c: force/µN {f:.2e}, power rel. {p:.2e}"
    );
    assert!(f < 2e-6 && p < 2e-5, "{f:e} {p:e}");
}
