use super::{sym_packed_product_f32, Mat, ModalSystem, ModalVerlet};
use std::f64::consts::PI;

fn sdof(omega: f64, zeta: f64) -> ModalSystem {
    let mut c = Mat::zeros(1, 1);
    c[(0, 0)] = 2.0 * zeta * omega;
    ModalSystem {
        omega2: vec![omega * omega],
        damping: c,
    }
}

/// Free vibration of a damped oscillator vs the closed form
/// `q = e^{−ζωt}(cos ω_d t + ζω/ω_d sin ω_d t)`; second-order convergence in Δt.
#[test]
fn damped_oscillator_matches_closed_form_at_second_order() {
    let (w, z): (f64, f64) = (2.0 * PI * 1000.0, 0.05);
    let wd = w * (1.0 - z * z).sqrt();
    let t_end = 5e-3;
    let mut errs = Vec::new();
    for &n in &[500usize, 1000, 2000] {
        let dt = t_end / n as f64;
        let sys = sdof(w, z);
        let mut it = ModalVerlet::new(&sys, dt).unwrap();
        it.set_state(&[1.0], &[0.0], &[0.0]);
        for _ in 0..n {
            it.advance_displacement();
            it.complete(&[0.0]);
        }
        let exact = (-z * w * t_end).exp() * ((wd * t_end).cos() + z * w / wd * (wd * t_end).sin());
        errs.push((it.q[0] - exact).abs());
    }
    let r1 = errs[0] / errs[1];
    let r2 = errs[1] / errs[2];
    assert!(r1 > 3.6 && r2 > 3.6, "errors {errs:?}");
    assert!(errs[2] < 2e-3, "errors {errs:?}");
}

/// Undamped: the energy stays bounded (symplectic) over 10⁴ steps.
#[test]
fn undamped_energy_is_conserved() {
    let w = 2.0 * PI * 2000.0;
    let mut it = ModalVerlet::new(&sdof(w, 0.0), 1e-5).unwrap();
    it.set_state(&[1e-3], &[0.0], &[0.0]);
    let e0 = it.kinetic_energy() + it.strain_energy();
    let mut worst: f64 = 0.0;
    for _ in 0..10_000 {
        it.advance_displacement();
        it.complete(&[0.0]);
        let e = it.kinetic_energy() + it.strain_energy();
        worst = worst.max((e - e0).abs() / e0);
    }
    // Modified energy oscillates with amplitude ~ (ωΔt)²/4 ≈ 0.4 %; no drift.
    assert!(worst < 0.01, "energy error {worst}");
}

/// Static load: the response settles to f/ω² (steady state of a damped system).
#[test]
fn step_load_settles_at_static_deflection() {
    let w = 2.0 * PI * 500.0;
    let mut it = ModalVerlet::new(&sdof(w, 0.3), 2e-5).unwrap();
    it.set_state(&[0.0], &[0.0], &[1.0]);
    for _ in 0..5000 {
        it.advance_displacement();
        it.complete(&[1.0]);
    }
    assert!((it.q[0] * w * w - 1.0).abs() < 1e-9);
}

/// The damper force `C v = (2/Δt)(rhs − v)` taken from the implicit solve equals the
/// explicit product of the damping matrix with the velocity (a full, non-proportional
/// `C` with the spread of the track's modal damping), and so does the power `vᵀC v`.
#[test]
fn free_damper_force_equals_the_explicit_product() {
    let m = 40;
    let dt = 1.6e-5;
    // C = Bᵀ B + diag: positive definite, entries from 0.1 to ~300 1/s, not proportional
    let mut b = Mat::<f64>::zeros(12, m);
    for r in 0..12 {
        for c in 0..m {
            b[(r, c)] = (((r * 31 + c * 17) % 23) as f64 - 11.0) * 0.6;
        }
    }
    let mut c = b.transpose() * &b;
    for i in 0..m {
        c[(i, i)] += 0.1 + i as f64;
    }
    let omega2 = (0..m)
        .map(|i| (2.0 * PI * (50.0 + 120.0 * i as f64)).powi(2))
        .collect();
    let sys = ModalSystem {
        omega2,
        damping: c.clone(),
    };
    let mut it = ModalVerlet::new(&sys, dt).unwrap();
    let q0: Vec<f64> = (0..m).map(|i| 1e-6 * ((i % 7) as f64 - 3.0)).collect();
    let v0: Vec<f64> = (0..m).map(|i| 1e-3 * ((i % 5) as f64 - 2.0)).collect();
    let f: Vec<f64> = (0..m).map(|i| ((i % 3) as f64 - 1.0) * 10.0).collect();
    it.set_state(&q0, &v0, &f);
    for step in 0..50 {
        it.advance_displacement();
        it.complete(&f);
        if step % 10 != 9 {
            continue;
        }
        let exact: Vec<f64> = (0..m)
            .map(|i| (0..m).map(|j| c[(i, j)] * it.v[j]).sum())
            .collect();
        let scale = exact.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
        // the single-precision E product leaves `(I + ½Δt C) v = rhs + D δ` with
        // |δ| ≤ the rounding bound, so `C v = (2/Δt)(rhs − v) + (2/Δt) D δ`
        let bound = damper_force_rounding_bound(&c, dt, &it.v);
        for (i, (x, e)) in it.damper_force().iter().zip(&exact).enumerate() {
            assert!(
                (x - e).abs() <= bound[i] + 1e-12 * scale,
                "mode {i}: {x} vs {e} (bound {})",
                bound[i]
            );
        }
        let p_exact: f64 = it.v.iter().zip(&exact).map(|(v, c)| v * c).sum();
        let p = it.damping_power();
        let p_bound: f64 = it.v.iter().zip(&bound).map(|(v, b)| v.abs() * b).sum();
        assert!(
            (p - p_exact).abs() <= p_bound + 1e-12 * p_exact.abs(),
            "{p} vs {p_exact}"
        );
        // the bound is a few parts per million of the force here: the test is not empty
        assert!(bound.iter().fold(0.0_f64, |a, b| a.max(*b)) < 1e-4 * scale);
    }
}

/// One step with a full, non-proportional damping matrix: the velocity equals the
/// solution of the implicit equation `(I + ½Δt C) v₁ = v₀ + ½Δt a₀ + ½Δt (f − Ω² q₁)` by
/// an independent dense LU (nalgebra) within the single-precision rounding bound of the
/// `E` product, and the packed symmetric product equals the plain dense product within
/// its rounding bound for sizes around the 8-wide blocks.
#[test]
fn implicit_velocity_equals_a_dense_lu_solve() {
    for m in [1usize, 3, 4, 5, 8, 9, 16, 17, 37] {
        let a = nalgebra::DMatrix::from_fn(m, m, |i, j| {
            1.0 / (1.0 + i as f64 + j as f64) + if i == j { 2.0 } else { 0.0 }
        });
        let mut packed = Vec::new();
        for j in 0..m {
            for i in j..m {
                packed.push(a[(i, j)]);
            }
        }
        let x: Vec<f32> = (0..m).map(|i| ((i * 7) % 5) as f32 - 2.0).collect();
        let mut y = vec![0.0; m];
        let packed32: Vec<f32> = packed.iter().map(|&a| a as f32).collect();
        sym_packed_product_f32(&packed32, &x, &mut y);
        let xd = nalgebra::DVector::from_iterator(m, x.iter().map(|&x| f64::from(x)));
        let yd = &a * &xd;
        // γ_{m+1}: m products summed, and A rounded to single precision
        let g = gamma_f32(m + 1);
        let abs_ax = a.abs() * xd.abs();
        for i in 0..m {
            let err = (f64::from(y[i]) - yd[i]).abs();
            assert!(err <= g * abs_ax[i], "m {m} row {i}: {err}");
        }
    }
    let m = 29;
    let dt = 1.6e-5;
    let (c, omega2, sys) = full_damping_system(m, [40.0, 1.0], [80.0, 150.0]);
    let mut it = ModalVerlet::new(&sys, dt).unwrap();
    let (q0, v0) = test_state(m);
    let f: Vec<f64> = (0..m).map(|i| ((i % 3) as f64 - 1.0) * 10.0).collect();
    it.set_state(&q0, &v0, &f);
    let a0 = it.a.clone();
    it.advance_displacement();
    let q1 = it.q.clone();
    it.complete(&f);
    let lhs = nalgebra::DMatrix::from_fn(m, m, |i, j| {
        0.5 * dt * c[(i, j)] + if i == j { 1.0 } else { 0.0 }
    });
    let rhs = nalgebra::DVector::from_fn(m, |i, _| {
        v0[i] + 0.5 * dt * a0[i] + 0.5 * dt * (f[i] - omega2[i] * q1[i])
    });
    let v1 = lhs.clone().lu().solve(&rhs).unwrap();
    // v = rhs + E rhs with E = (I + ½Δt C)⁻¹ − I applied in single precision: E and rhs
    // rounded, m products summed (γ_{m+2} of |E| |rhs|)
    let e = lhs.try_inverse().unwrap() - nalgebra::DMatrix::<f64>::identity(m, m);
    let bound = e.abs() * rhs.abs() * gamma_f32(m + 2);
    for i in 0..m {
        assert!(
            (it.v[i] - v1[i]).abs() <= bound[i] + 1e-14 * v1.amax(),
            "mode {i}: {} vs {} (bound {})",
            it.v[i],
            v1[i],
            bound[i]
        );
    }
}

/// `γ_n = n u / (1 − n u)` with the single-precision unit round-off `u = 2⁻²⁴` (Higham,
/// §3.1): the relative bound of a sum of `n` rounded products.
#[test]
fn split_velocity_step_equals_a_dense_lu_solve() {
    // Independent check of the split step (`split_begin` + `complete_split`): the force
    // f = f_known + df with E df formed separately (by linearity) against the dense LU
    // solve of (I + ½Δt C) v = rhs(f) in f64. Each single-precision product adds at most
    // γ_{m+2} |E| |x| of its input x (b, and ½Δt df), so the bound is their sum.
    let m = 31;
    let dt = 1.6e-5;
    let (c, omega2, sys) = full_damping_system(m, [60.0, 2.0], [90.0, 140.0]);
    let mut it = ModalVerlet::new(&sys, dt).unwrap();
    assert!(it.splits());
    let (q0, v0) = test_state(m);
    let f_known: Vec<f64> = (0..m).map(|i| ((i % 3) as f64 - 1.0) * 1e3).collect();
    let df: Vec<f64> = (0..m).map(|i| ((i % 4) as f64 - 1.5) * 2.0).collect();
    it.set_state(&q0, &v0, &f_known);
    let a0 = it.a.clone();
    it.advance_displacement();
    let q1 = it.q.clone();
    let (mut b, mut e_b, mut e_df) = (vec![0.0; m], vec![0.0; m], vec![0.0; m]);
    let (mut x32, mut y32) = (vec![0.0f32; m], vec![0.0f32; m]);
    it.split_begin(&f_known, &mut b, (&mut x32, &mut y32), &mut e_b);
    it.damping_correction(&df, &mut x32, &mut y32, &mut e_df);
    it.complete_split(&b, &e_b, &df, &e_df);
    let lhs = nalgebra::DMatrix::from_fn(m, m, |i, j| {
        0.5 * dt * c[(i, j)] + if i == j { 1.0 } else { 0.0 }
    });
    let bd = nalgebra::DVector::from_fn(m, |i, _| {
        v0[i] + 0.5 * dt * a0[i] + 0.5 * dt * (f_known[i] - omega2[i] * q1[i])
    });
    let dd = nalgebra::DVector::from_fn(m, |i, _| 0.5 * dt * df[i]);
    let v1 = lhs.clone().lu().solve(&(&bd + &dd)).unwrap();
    let e = lhs.try_inverse().unwrap() - nalgebra::DMatrix::<f64>::identity(m, m);
    let bound = (e.abs() * (bd.abs() + dd.abs())) * gamma_f32(m + 2);
    for i in 0..m {
        let err = (it.v[i] - v1[i]).abs();
        assert!(
            err <= bound[i] + 1e-14 * v1.amax(),
            "mode {i}: {} vs {} (bound {})",
            it.v[i],
            v1[i],
            bound[i]
        );
    }
    // the damping acts: the dense solution differs from the undamped rhs by far more
    // than the bound, so the test would see a wrong correction
    let undamped = (&bd + &dd - &v1).amax();
    assert!(
        undamped > 100.0 * bound.amax(),
        "{undamped} vs {}",
        bound.amax()
    );
}

/// A modal system of `m` modes with a full damping matrix
/// `C_ij = c[0] / (1 + |i − j|) + c[1] i δ_ij` (1/s) and `ω_i = 2π (f[0] + f[1] i)`
/// (rad/s): `(C, ω², system)`.
fn full_damping_system(m: usize, c: [f64; 2], f: [f64; 2]) -> (Mat<f64>, Vec<f64>, ModalSystem) {
    let mut cm = Mat::<f64>::zeros(m, m);
    for i in 0..m {
        for j in 0..m {
            cm[(i, j)] = c[0] / (1.0 + (i as f64 - j as f64).abs())
                + if i == j { c[1] * i as f64 } else { 0.0 };
        }
    }
    let omega2: Vec<f64> = (0..m)
        .map(|i| (2.0 * PI * (f[0] + f[1] * i as f64)).powi(2))
        .collect();
    let sys = ModalSystem {
        omega2: omega2.clone(),
        damping: cm.clone(),
    };
    (cm, omega2, sys)
}

/// A displacement and velocity of `m` modes for the implicit-step tests.
fn test_state(m: usize) -> (Vec<f64>, Vec<f64>) {
    (
        (0..m).map(|i| 1e-6 * ((i % 7) as f64 - 3.0)).collect(),
        (0..m).map(|i| 1e-3 * ((i % 5) as f64 - 2.0)).collect(),
    )
}

fn gamma_f32(n: usize) -> f64 {
    let nu = n as f64 * 2f64.powi(-24);
    nu / (1.0 - nu)
}

/// Per mode, the bound on `|(2/Δt)(rhs − v) − C v|` that the single-precision `E`
/// product allows: `(2/Δt) |D| γ_{m+2} |E| |rhs|` with `D = I + ½Δt C` and `rhs ≈ D v`.
fn damper_force_rounding_bound(c: &Mat<f64>, dt: f64, v: &[f64]) -> Vec<f64> {
    let m = v.len();
    let d = nalgebra::DMatrix::from_fn(m, m, |i, j| {
        0.5 * dt * c[(i, j)] + if i == j { 1.0 } else { 0.0 }
    });
    let e = d.clone().try_inverse().unwrap() - nalgebra::DMatrix::<f64>::identity(m, m);
    let rhs = &d * nalgebra::DVector::from_column_slice(v);
    let delta = e.abs() * rhs.abs() * (gamma_f32(m + 2) * 1.01);
    let b = d.abs() * delta * (2.0 / dt);
    b.iter().copied().collect()
}

/// Response of `q̈ + 2ζω q̇ + ω² q = f` from rest to a unit step load at t = 0 (closed
/// form): `q = (1 − e^{−ζωt}(cos ω_d t + ζω/ω_d sin ω_d t))/ω²`.
fn step_response(w: f64, z: f64, t: f64) -> f64 {
    let wd = w * (1.0 - z * z).sqrt();
    (1.0 - (-z * w * t).exp() * ((wd * t).cos() + z * w / wd * (wd * t).sin())) / (w * w)
}

/// A step load on a damped oscillator with the contact step 4/ω (one step refused):
/// sub-stepped, the response follows the closed form with the sub-step's second-order
/// convergence (a constant force is the same held or sampled), and `new` picks
/// ⌈4/1.8⌉ = 3 sub-steps.
#[test]
fn substepped_step_load_matches_the_closed_form_at_second_order() {
    let (w, z) = (2.0 * PI * 1000.0, 0.05);
    let dt = 4.0 / w;
    let sys = sdof(w, z);
    assert!(ModalVerlet::with_substeps(&sys, dt, 1).is_err());
    assert_eq!(ModalVerlet::new(&sys, dt).unwrap().substeps(), 3);
    let steps = 40; // 25 ms
    let mut errs = Vec::new();
    for m in [8usize, 16, 32] {
        let mut it = ModalVerlet::with_substeps(&sys, dt, m).unwrap();
        it.set_state(&[0.0], &[0.0], &[1.0]);
        let mut worst: f64 = 0.0;
        for n in 1..=steps {
            it.advance_displacement();
            it.complete(&[1.0]);
            let exact = step_response(w, z, n as f64 * dt);
            worst = worst.max((it.q[0] - exact).abs() * w * w);
        }
        errs.push(worst);
    }
    eprintln!("step load, worst error × ω² at 8, 16, 32 sub-steps: {errs:?}");
    assert!(
        errs[0] / errs[1] > 3.6 && errs[1] / errs[2] > 3.6,
        "{errs:?}"
    );
    assert!(errs[2] < 1e-2, "{errs:?}");
}

/// A harmonic load sampled at the contact steps and held over the sub-steps acts as the
/// sampled load delayed by `(Δt_c − h)/2` (module doc): the steady response of a damped
/// oscillator equals the closed form `|H| sin(ω_f (t − τ) − φ)` with that delay within
/// 1 % of its amplitude (the hold's amplitude factor `sinc(ω_f Δt_c/2)` and its ripple
/// at the sampling rate are below 0.4 % here), and is several times further from the
/// undelayed one.
#[test]
fn held_harmonic_load_acts_with_half_a_contact_step_of_delay() {
    let (w, z) = (2.0 * PI * 1000.0, 0.2);
    let wf = 2.0 * PI * 300.0;
    let dt = 1.0 / w; // 0.16 ms: ω_f Δt_c = 0.3
    let m = 20;
    let sys = sdof(w, z);
    let mut it = ModalVerlet::with_substeps(&sys, dt, m).unwrap();
    let tau = 0.5 * (dt - it.substep_s());
    // steady state of q̈ + 2ζω q̇ + ω² q = sin(ω_f t)
    let (re, im) = (w * w - wf * wf, 2.0 * z * w * wf);
    let amp = 1.0 / (re * re + im * im).sqrt();
    let phi = im.atan2(re);
    let steady = |t: f64| amp * (wf * t - phi).sin();
    it.set_state(&[0.0], &[0.0], &[0.0]);
    let (mut err_delayed, mut err_plain): (f64, f64) = (0.0, 0.0);
    for n in 1..=1000 {
        let t = n as f64 * dt;
        it.advance_displacement();
        it.complete(&[(wf * t).sin()]);
        if t > 0.1 {
            // the transient has decayed by e^{−ζωt} < 1e-50
            err_delayed = err_delayed.max((it.q[0] - steady(t - tau)).abs() / amp);
            err_plain = err_plain.max((it.q[0] - steady(t)).abs() / amp);
        }
    }
    eprintln!("held harmonic load: error delayed {err_delayed:.2e}, undelayed {err_plain:.2e}");
    assert!(
        err_delayed < 0.01,
        "delayed {err_delayed}, plain {err_plain}"
    );
    assert!(
        err_plain > 5.0 * err_delayed,
        "delayed {err_delayed}, plain {err_plain}"
    );
}

/// Stability at `Δt_c ω_max = 10`: `new` splits the contact step into ⌈10/1.8⌉ = 6
/// sub-steps; an undamped two-mode system (ω_max and ω_max/7) keeps its energy within
/// the modified-energy oscillation of the sub-step over 10⁴ contact steps, where one step
/// is refused.
#[test]
fn substeps_by_the_rule_are_stable_at_ten_times_the_step_limit() {
    let w = 2.0 * PI * 5000.0;
    let dt = 10.0 / w;
    let sys = ModalSystem {
        omega2: vec![w * w, (w / 7.0).powi(2)],
        damping: Mat::zeros(2, 2),
    };
    let mut it = ModalVerlet::new(&sys, dt).unwrap();
    assert_eq!(it.substeps(), 6);
    assert!(it.substep_s() * w <= 1.8);
    it.set_state(&[1e-6, 1e-6], &[0.0, 0.0], &[0.0, 0.0]);
    let e0 = it.kinetic_energy() + it.strain_energy();
    let mut worst: f64 = 0.0;
    for _ in 0..10_000 {
        it.advance_displacement();
        it.complete(&[0.0, 0.0]);
        let e = it.kinetic_energy() + it.strain_energy();
        worst = worst.max((e - e0).abs() / e0);
    }
    eprintln!("Δt_c ω_max = 10, 6 sub-steps: worst relative energy error {worst:.3}");
    // velocity Verlet's energy oscillates by up to (hω)²/(4 − (hω)²) ≈ 2.3 at hω = 1.67
    // for the top mode alone; bounded, no drift (measured: 0.68 with both modes)
    assert!(worst < 1.0, "energy error {worst}");
    let one = ModalVerlet::with_substeps(&sys, dt, 1).unwrap_err();
    assert!(one.to_string().contains("fmax"), "{one}");
}

/// One sub-step is the plain step: `new` keeps one step below `Δt ω_max = 1.9`, and with
/// sub-steps a full damping matrix and its diagonal special case give the same state
/// (the diagonal path is only an economy). The damper work over a contact step equals
/// the trapezoidal rule of the plain step when there is one sub-step.
#[test]
fn one_substep_is_the_plain_step_and_diagonal_damping_is_an_economy() {
    let w = 2.0 * PI * 3000.0;
    assert_eq!(
        ModalVerlet::new(&sdof(w, 0.1), 1.85 / w)
            .unwrap()
            .substeps(),
        1
    );
    assert_eq!(
        ModalVerlet::new(&sdof(w, 0.1), 1.95 / w)
            .unwrap()
            .substeps(),
        2
    );
    let sys = sdof(w, 0.1);
    let mut it = ModalVerlet::new(&sys, 1e-5).unwrap();
    it.set_state(&[1e-6], &[1e-3], &[0.5]);
    let p0 = it.damping_power();
    it.advance_displacement();
    it.complete(&[0.5]);
    let p1 = it.damping_power();
    assert_eq!(it.step_damper_work(), 0.5 * 1e-5 * (p0 + p1));
    // diagonal vs packed: a 2 × 2 C with a zero coupling, and one with 1e-300 (packed)
    let mut c = Mat::<f64>::zeros(2, 2);
    c[(0, 0)] = 30.0;
    c[(1, 1)] = 70.0;
    let mut cp = c.clone();
    cp[(0, 1)] = 1e-300;
    cp[(1, 0)] = 1e-300;
    let omega2 = vec![w * w, (2.0 * w).powi(2)];
    let runs: Vec<Vec<f64>> = [c, cp]
        .into_iter()
        .map(|damping| {
            let sys = ModalSystem {
                omega2: omega2.clone(),
                damping,
            };
            let mut it = ModalVerlet::with_substeps(&sys, 4e-5, 5).unwrap();
            it.set_state(&[1e-6, -1e-6], &[0.0, 1e-3], &[1.0, 2.0]);
            for n in 0..100 {
                it.advance_displacement();
                let g = (n as f64 * 0.3).sin();
                it.complete(&[g, -g]);
            }
            vec![it.q[0], it.q[1], it.v[0], it.v[1], it.step_damper_work()]
        })
        .collect();
    // the packed path applies E = (I + ½hC)⁻¹ − I in single precision (module doc): per
    // sub-step a relative γ_4 ‖E‖ ≈ 2.4e-7 · 2.8e-4 ≈ 7e-11 of the velocity, so < 1e-7 over
    // the 500 sub-steps
    for (a, b) in runs[0].iter().zip(&runs[1]) {
        assert!((a - b).abs() <= 1e-7 * a.abs().max(1e-30), "{a} vs {b}");
    }
}

/// A sub-step above the limit, and more sub-steps than [`MAX_SUBSTEPS`], are errors
/// that say to lower f_max.
#[test]
fn unstable_step_is_an_error_naming_the_limit() {
    let sys = sdof(2.0 * PI * 5000.0, 0.0);
    let e = ModalVerlet::with_substeps(&sys, 1e-4, 1).unwrap_err();
    let s = e.to_string();
    assert!(s.contains("time step") && s.contains("fmax"), "{s}");
    // 1 s × 3.1e4 rad/s / 1.8 = 17,453 sub-steps
    let s = ModalVerlet::new(&sys, 1.0).unwrap_err().to_string();
    assert!(s.contains("sub-steps") && s.contains("fmax"), "{s}");
}
