//! Time integration of a reduced modal system `q̈ + C_q q̇ + Ω² q = f(t)` (docs/theory.md §7.2).
//!
//! **Scheme: velocity Verlet (Newmark β = 0, γ = ½) with the damping implicit.**
//!
//! ```text
//! q_{n+1} = q_n + Δt v_n + ½Δt² a_n
//! (I + ½Δt C_q) v_{n+1} = v_n + ½Δt a_n + ½Δt (f_{n+1} − Ω² q_{n+1})
//! a_{n+1} = (2/Δt)(v_{n+1} − v_n) − a_n          (= f_{n+1} − C_q v_{n+1} − Ω² q_{n+1})
//! ```
//!
//! Why this scheme:
//! - it is second-order accurate and symplectic for the undamped part (no numerical
//!   damping of the 0.5–3 kHz band that frequency selection is about; Newmark's average
//!   acceleration would also do, HHT-α would damp it);
//! - the displacement of step n+1 is explicit, so the contact force of step n+1 is computed
//!   from the structural state at that instant (the contact needs `q_{n+1}` and a velocity,
//!   for which the predictor `v_n + Δt a_n` is used — second-order consistent);
//! - with the full (non-diagonal) `C_q` the only matrix operation per step is one dense
//!   product with `(I + ½Δt C_q)⁻¹ = I + E`, factorised and inverted once. The product is
//!   memory-bound (at 750 modes the full matrix is 4.5 MB), so only the deviation `E` from
//!   the identity is stored, as the packed lower triangle (it is symmetric) in single
//!   precision, and applied in single precision: `v = rhs + E·rhs` reads a quarter of the
//!   full double-precision matrix ([`sym_packed_product_f32`]). `E = −½Δt C_q (I + ½Δt
//!   C_q)⁻¹` is small (‖E‖ ≤ ½Δt‖C_q‖, about 1e-2 on the default track), so the single
//!   precision changes `v` by at most about `m · 2⁻²⁴ · (|E| |rhs|)` per step, far below the
//!   scheme's own error (docs/theory.md §7.2).
//!   The damper force
//!   `C_q v_{n+1}` comes with it: the implicit equation says
//!   `½Δt C_q v_{n+1} = rhs − v_{n+1}`, so the dissipated power `v·C_q v` of the energy
//!   balance needs no second product ([`ModalVerlet::damping_power`]).
//!
//! Stability: undamped modes need `Δt ω_max < 2`; the constructor refuses `Δt ω_max ≥ 1.9`
//! with an error saying to lower f_max or refine the contact grid (Δt = Δx / V). The
//! explicit coupling through the contact force adds the contact stiffness to ω_max; the
//! passage checks its energy balance.
//!
//! References: Hairer, Lubich, Wanner, *Geometric Numerical Integration*, §I.1.4 (Störmer–
//! Verlet); Hughes, *The Finite Element Method*, §9.1 (Newmark family, β = 0 central
//! difference).

use faer::Mat;

use super::reduced::ModalSystem;
use super::DynamicsError;

/// Velocity-Verlet integrator of one modal system.
#[derive(Clone, Debug)]
pub struct ModalVerlet {
    dt: f64,
    omega2: Vec<f64>,
    /// `E = (I + ½Δt C)⁻¹ − I`, symmetric: the lower triangle packed by columns, in
    /// single precision ([`sym_packed_product_f32`]).
    e_packed: Vec<f32>,
    /// The damping matrix (for the initial acceleration and the dissipated power).
    c: Mat<f64>,
    /// Displacement q (modal coordinates).
    pub q: Vec<f64>,
    /// Velocity q̇.
    pub v: Vec<f64>,
    /// Acceleration q̈.
    pub a: Vec<f64>,
    v_old: Vec<f64>,
    rhs: Vec<f64>,
    /// `rhs` rounded to single precision, the input of the `E` product.
    rhs32: Vec<f32>,
    /// `E · rhs` in single precision.
    tmp32: Vec<f32>,
    /// The damper force `C_q v` (1/s · modal velocity) of the current velocity: an explicit
    /// product after [`Self::set_state`], `(2/Δt)(rhs − v)` after [`Self::complete`].
    cv: Vec<f64>,
}

impl ModalVerlet {
    /// An integrator with time step `dt` (s), at rest.
    pub fn new(sys: &ModalSystem, dt: f64) -> Result<Self, DynamicsError> {
        let m = sys.len();
        let w_max = sys.omega2.iter().copied().fold(0.0, f64::max).sqrt();
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(DynamicsError::OutOfRange {
                name: "time step (s)",
                value: dt,
                expected: "finite and > 0",
            });
        }
        if dt * w_max >= 1.9 {
            return Err(DynamicsError::UnstableTimeStep {
                dt_s: dt,
                f_max_hz: w_max / (2.0 * std::f64::consts::PI),
                dt_limit_s: 1.9 / w_max,
            });
        }
        let inv = implicit_damping_inverse(&sys.damping, dt)?;
        let mut e_packed = Vec::with_capacity(m * (m + 1) / 2);
        for j in 0..m {
            for i in j..m {
                let identity = if i == j { 1.0 } else { 0.0 };
                e_packed.push((inv[(i, j)] - identity) as f32);
            }
        }
        Ok(ModalVerlet {
            dt,
            omega2: sys.omega2.clone(),
            e_packed,
            c: sys.damping.clone(),
            q: vec![0.0; m],
            v: vec![0.0; m],
            a: vec![0.0; m],
            v_old: vec![0.0; m],
            rhs: vec![0.0; m],
            rhs32: vec![0.0; m],
            tmp32: vec![0.0; m],
            cv: vec![0.0; m],
        })
    }

    /// Time step (s).
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Number of modes.
    pub fn len(&self) -> usize {
        self.q.len()
    }

    /// True when there are no modes.
    pub fn is_empty(&self) -> bool {
        self.q.is_empty()
    }

    /// Sets the state and computes the consistent acceleration `a = f − C v − Ω² q`.
    pub fn set_state(&mut self, q: &[f64], v: &[f64], f: &[f64]) {
        let m = self.len();
        self.q.copy_from_slice(q);
        self.v.copy_from_slice(v);
        faer::linalg::matmul::matmul(
            faer::ColMut::from_slice_mut(&mut self.rhs),
            faer::Accum::Replace,
            self.c.as_ref(),
            faer::ColRef::from_slice(v),
            1.0,
            faer::Par::Seq,
        );
        for i in 0..m {
            self.cv[i] = self.rhs[i];
            self.a[i] = f[i] - self.rhs[i] - self.omega2[i] * q[i];
        }
    }

    /// First half of a step: advances the displacement to `t + Δt` and returns nothing; the
    /// predicted velocity for the contact is [`Self::predicted_velocity`].
    pub fn advance_displacement(&mut self) {
        let (dt, m) = (self.dt, self.len());
        for i in 0..m {
            self.q[i] += dt * self.v[i] + 0.5 * dt * dt * self.a[i];
        }
    }

    /// Predicted velocity at `t + Δt` (after [`Self::advance_displacement`]): `v_n + Δt a_n`.
    #[inline]
    pub fn predicted_velocity(&self, i: usize) -> f64 {
        self.v[i] + self.dt * self.a[i]
    }

    /// Second half of a step: the velocity and acceleration at `t + Δt` from the force
    /// `f_{n+1}` (generalised, per modal coordinate). No allocation.
    pub fn complete(&mut self, f: &[f64]) {
        let (dt, m) = (self.dt, self.len());
        for i in 0..m {
            self.rhs[i] =
                self.v[i] + 0.5 * dt * self.a[i] + 0.5 * dt * (f[i] - self.omega2[i] * self.q[i]);
        }
        self.v_old.copy_from_slice(&self.v);
        for (r32, r) in self.rhs32.iter_mut().zip(&self.rhs) {
            *r32 = *r as f32;
        }
        sym_packed_product_f32(&self.e_packed, &self.rhs32, &mut self.tmp32);
        for i in 0..m {
            // v = (I + E) rhs
            self.v[i] = self.rhs[i] + f64::from(self.tmp32[i]);
            self.a[i] = 2.0 / dt * (self.v[i] - self.v_old[i]) - self.a[i];
            // (I + ½Δt C) v = rhs  ⇒  C v = (2/Δt)(rhs − v)
            self.cv[i] = 2.0 / dt * (self.rhs[i] - self.v[i]);
        }
    }

    /// Kinetic energy ½ q̇ᵀq̇ (J).
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self.v.iter().map(|v| v * v).sum::<f64>()
    }

    /// Strain energy ½ Σ ω² q² (J).
    pub fn strain_energy(&self) -> f64 {
        0.5 * self
            .q
            .iter()
            .zip(&self.omega2)
            .map(|(q, w)| w * q * q)
            .sum::<f64>()
    }

    /// Power dissipated by the dampers at the current velocity, q̇ᵀ C q̇ (W). No product: the
    /// damper force `C q̇` is a by-product of [`Self::complete`] (module doc) or of
    /// [`Self::set_state`].
    pub fn damping_power(&self) -> f64 {
        self.v.iter().zip(&self.cv).map(|(v, c)| v * c).sum()
    }

    /// The damper force `C q̇` of the current velocity (module doc: from the implicit solve).
    pub fn damper_force(&self) -> &[f64] {
        &self.cv
    }
}

/// The lower triangle of `(I + ½Δt C)⁻¹` (`C` the m × m damping matrix, symmetric positive
/// semi-definite, so the matrix is symmetric positive definite): Cholesky factor `L`, `L⁻¹`,
/// and `L⁻ᵀ L⁻¹` by triangular products (about m³ flops instead of the 2m³ of solving for
/// the identity). Sequential on purpose: results do not depend on the thread count (a sweep
/// runs its passages in parallel and must give the same answer on any number of threads).
fn implicit_damping_inverse(c: &Mat<f64>, dt: f64) -> Result<Mat<f64>, DynamicsError> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::cholesky::llt;
    let m = c.nrows();
    let par = faer::Par::Seq;
    let mut l = Mat::<f64>::from_fn(m, m, |i, j| {
        if i >= j {
            f64::from(u8::from(i == j)) + 0.5 * dt * c[(i, j)]
        } else {
            0.0
        }
    });
    let mut mem = MemBuffer::new(
        llt::factor::cholesky_in_place_scratch::<f64>(m, par, Default::default())
            .or(llt::inverse::inverse_scratch::<f64>(m, par)),
    );
    llt::factor::cholesky_in_place(
        l.as_mut(),
        Default::default(),
        par,
        MemStack::new(&mut mem),
        Default::default(),
    )
    .map_err(|_| DynamicsError::DampingIndefinite)?;
    for j in 1..m {
        for i in 0..j {
            l[(i, j)] = 0.0;
        }
    }
    let mut inv = Mat::<f64>::zeros(m, m);
    llt::inverse::inverse(inv.as_mut(), l.as_ref(), par, MemStack::new(&mut mem));
    Ok(inv)
}

/// `y = A x` in single precision for a symmetric `m × m` matrix `A` given by its lower
/// triangle packed by columns (`packed[off_j + (i − j)] = A[i][j]`, `i ≥ j`,
/// `off_j = Σ_{k<j} (m − k)`): each stored entry is read once and used twice (the column's
/// axpy and the row's dot product), in one pass. `x`, `y` of length `m`, `packed` of length
/// `m(m+1)/2`. No allocation. Rounding: each `y_i` is a sum of `m` products, so
/// `|y_i − (A x)_i| ≤ γ_m (|A| |x|)_i` with `γ_m = m u/(1 − m u)`, `u = 2⁻²⁴` (Higham,
/// *Accuracy and Stability of Numerical Algorithms*, §3.1).
fn sym_packed_product_f32(packed: &[f32], x: &[f32], y: &mut [f32]) {
    debug_assert!(y.len() == x.len() && packed.len() == x.len() * (x.len() + 1) / 2);
    // explicit SIMD (8 or 16 lanes: AVX2/FMA or AVX-512 when the CPU has them), dispatched
    // at run time
    pulp::Arch::new().dispatch(SymPacked { packed, x, y })
}

struct SymPacked<'a> {
    packed: &'a [f32],
    x: &'a [f32],
    y: &'a mut [f32],
}

impl pulp::WithSimd for SymPacked<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, simd: S) {
        let (packed, x, y) = (self.packed, self.x, self.y);
        let m = x.len();
        y.fill(0.0);
        let mut off = 0;
        for j in 0..m {
            let col = &packed[off..off + (m - j)];
            off += m - j;
            let xj = x[j];
            // column j below the diagonal: y += A[j+1.., j] x_j and the dot A[j+1.., j]·x
            let (c_head, c_tail) = S::as_simd_f32s(&col[1..]);
            let (x_head, x_tail) = S::as_simd_f32s(&x[j + 1..]);
            let (y_head, y_tail) = S::as_mut_simd_f32s(&mut y[j + 1..]);
            let sx = simd.splat_f32s(xj);
            let mut acc = simd.splat_f32s(0.0);
            for ((c, xv), yv) in c_head.iter().zip(x_head).zip(y_head.iter_mut()) {
                *yv = simd.mul_add_f32s(*c, sx, *yv);
                acc = simd.mul_add_f32s(*c, *xv, acc);
            }
            let mut dot = simd.reduce_sum_f32s(acc);
            for ((c, xv), yv) in c_tail.iter().zip(x_tail).zip(y_tail.iter_mut()) {
                *yv += c * xj;
                dot += c * xv;
            }
            y[j] += col[0] * xj + dot;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
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
            let exact =
                (-z * w * t_end).exp() * ((wd * t_end).cos() + z * w / wd * (wd * t_end).sin());
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
        let mut c = Mat::<f64>::zeros(m, m);
        for i in 0..m {
            for j in 0..m {
                c[(i, j)] = 40.0 / (1.0 + (i as f64 - j as f64).abs())
                    + if i == j { i as f64 } else { 0.0 };
            }
        }
        let omega2: Vec<f64> = (0..m)
            .map(|i| (2.0 * PI * (80.0 + 150.0 * i as f64)).powi(2))
            .collect();
        let sys = ModalSystem {
            omega2: omega2.clone(),
            damping: c.clone(),
        };
        let mut it = ModalVerlet::new(&sys, dt).unwrap();
        let q0: Vec<f64> = (0..m).map(|i| 1e-6 * ((i % 7) as f64 - 3.0)).collect();
        let v0: Vec<f64> = (0..m).map(|i| 1e-3 * ((i % 5) as f64 - 2.0)).collect();
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

    #[test]
    fn unstable_step_is_an_error_naming_the_limit() {
        let e = ModalVerlet::new(&sdof(2.0 * PI * 5000.0, 0.0), 1e-4).unwrap_err();
        let s = e.to_string();
        assert!(s.contains("time step") && s.contains("fmax"), "{s}");
    }
}
