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
//! Stability: undamped modes need `Δt ω_max < 2`. The contact step `Δt_c = Δx / V` is fixed
//! by the contact grid, so when `Δt_c ω_max ≥ 1.9` (a basis with high modes, up to a
//! complete one) the integrator advances the modal system by `m` equal **sub-steps**
//! `h = Δt_c / m` inside each contact step, with `m = ⌈Δt_c ω_max / 1.8⌉` (`h ω_max ≤ 1.8`,
//! the explicit path's default safety 0.9 of the limit 2; [`substeps_for`]). The generalised
//! force is sampled at the contact steps: the force of `t_n` is held at every sub-step node
//! of `[t_n, t_{n+1})` and the last sub-step completes with the force of `t_{n+1}`. In the
//! central-difference sense of node loads (a node's load acting over `t_k ± h/2`) that is
//! the explicit path's held-force predictor over a contact step (docs/theory.md §8.4): with
//! `m = 1` it is the plain step above, unchanged. The held force acts like the sampled force
//! delayed by `(Δt_c − h)/2`. Interior sub-steps cost one product with `(I + ½h C_q)⁻¹`
//! each (a diagonal scaling when `C_q` is diagonal). The constructor refuses more than
//! [`MAX_SUBSTEPS`] sub-steps (lower f_max or refine the contact grid). The explicit coupling
//! through the contact force adds the contact stiffness to ω_max; the passage checks its
//! energy balance.
//!
//! References: Hairer, Lubich, Wanner, *Geometric Numerical Integration*, §I.1.4 (Störmer–
//! Verlet); Hughes, *The Finite Element Method*, §9.1 (Newmark family, β = 0 central
//! difference).

use faer::Mat;

use super::reduced::ModalSystem;
use super::DynamicsError;

/// Largest number of sub-steps per contact step ([`ModalVerlet::new`] refuses more: the
/// basis is then far above what the contact step can resolve; lower f_max).
pub const MAX_SUBSTEPS: usize = 4096;

/// `Δt ω_max` at and above which one step is refused (the limit is 2).
const STEP_LIMIT: f64 = 1.9;

/// `h ω_max` the sub-step count aims at (0.9 × the limit 2, the explicit path's default
/// safety).
const SUBSTEP_TARGET: f64 = 1.8;

/// Sub-steps per contact step `dt` (s) for a system whose highest frequency is `omega_max`
/// (rad/s): 1 when `dt ω_max < 1.9`, otherwise `⌈dt ω_max / 1.8⌉` (module doc).
pub fn substeps_for(omega_max: f64, dt: f64) -> usize {
    let x = dt * omega_max;
    if x < STEP_LIMIT {
        1
    } else {
        (x / SUBSTEP_TARGET).ceil().min(usize::MAX as f64) as usize
    }
}

/// How `(I + ½h C)⁻¹` is applied.
#[derive(Clone, Debug)]
enum DampingInverse {
    /// A full `C`: `E = (I + ½h C)⁻¹ − I`, the lower triangle packed by columns, in single
    /// precision ([`sym_packed_product_f32`]).
    Packed(Vec<f32>),
    /// A diagonal `C` (only with sub-steps): the diagonal.
    Diagonal(Vec<f64>),
}

/// Velocity-Verlet integrator of one modal system, sub-stepped inside the contact step
/// when the step is too long for the highest mode (module doc).
#[derive(Clone, Debug)]
pub struct ModalVerlet {
    /// The contact step (s).
    dt: f64,
    /// The sub-step `dt / substeps` (s).
    h: f64,
    /// Sub-steps per contact step (≥ 1).
    substeps: usize,
    omega2: Vec<f64>,
    /// (I + ½h C)⁻¹, symmetric.
    d_inv: DampingInverse,
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
    /// product after [`Self::set_state`], `(2/h)(rhs − v)` after [`Self::complete`].
    cv: Vec<f64>,
    /// The generalised force of the last contact-step boundary, held over the interior
    /// sub-steps (empty with one sub-step).
    f_held: Vec<f64>,
    /// The dampers' work over the last contact step, `Σ ½h(p_k + p_{k+1})` over its
    /// sub-steps (J).
    step_damper_work_j: f64,
}

impl ModalVerlet {
    /// An integrator with contact step `dt` (s), at rest, with the sub-step count of
    /// [`substeps_for`].
    pub fn new(sys: &ModalSystem, dt: f64) -> Result<Self, DynamicsError> {
        let m = substeps_for(omega_max(sys), dt);
        if m > MAX_SUBSTEPS {
            return Err(DynamicsError::OutOfRange {
                name: "modal sub-steps per contact step (time step × highest mode's ω / 1.8); lower run.fmax",
                value: m as f64,
                expected: "at most 4096",
            });
        }
        Self::with_substeps(sys, dt, m)
    }

    /// An integrator with contact step `dt` (s) split into `substeps` equal sub-steps, at
    /// rest. Refuses a sub-step `h` with `h ω_max ≥ 1.9`.
    pub fn with_substeps(
        sys: &ModalSystem,
        dt: f64,
        substeps: usize,
    ) -> Result<Self, DynamicsError> {
        let n = sys.len();
        let w_max = omega_max(sys);
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(DynamicsError::OutOfRange {
                name: "time step (s)",
                value: dt,
                expected: "finite and > 0",
            });
        }
        if !(1..=MAX_SUBSTEPS).contains(&substeps) {
            return Err(DynamicsError::OutOfRange {
                name: "modal sub-steps per contact step",
                value: substeps as f64,
                expected: "1 to 4096",
            });
        }
        let h = dt / substeps as f64;
        if h * w_max >= STEP_LIMIT {
            return Err(DynamicsError::UnstableTimeStep {
                dt_s: h,
                f_max_hz: w_max / (2.0 * std::f64::consts::PI),
                dt_limit_s: STEP_LIMIT / w_max,
            });
        }
        let c = &sys.damping;
        let diagonal = (0..n).all(|j| (0..n).all(|i| i == j || c[(i, j)] == 0.0));
        let d_inv = if substeps > 1 && diagonal {
            DampingInverse::Diagonal((0..n).map(|i| 1.0 / (1.0 + 0.5 * h * c[(i, i)])).collect())
        } else {
            let inv = implicit_damping_inverse(c, h)?;
            let mut packed = Vec::with_capacity(n * (n + 1) / 2);
            for j in 0..n {
                for i in j..n {
                    let identity = if i == j { 1.0 } else { 0.0 };
                    packed.push((inv[(i, j)] - identity) as f32);
                }
            }
            DampingInverse::Packed(packed)
        };
        Ok(ModalVerlet {
            dt,
            h,
            substeps,
            omega2: sys.omega2.clone(),
            d_inv,
            c: sys.damping.clone(),
            q: vec![0.0; n],
            v: vec![0.0; n],
            a: vec![0.0; n],
            v_old: vec![0.0; n],
            rhs: vec![0.0; n],
            rhs32: vec![0.0; n],
            tmp32: vec![0.0; n],
            cv: vec![0.0; n],
            f_held: vec![0.0; if substeps > 1 { n } else { 0 }],
            step_damper_work_j: 0.0,
        })
    }

    /// Contact time step (s).
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Sub-steps per contact step (1: the plain velocity-Verlet step).
    pub fn substeps(&self) -> usize {
        self.substeps
    }

    /// Sub-step `dt / substeps` (s).
    pub fn substep_s(&self) -> f64 {
        self.h
    }

    /// Number of modes.
    pub fn len(&self) -> usize {
        self.q.len()
    }

    /// True when there are no modes.
    pub fn is_empty(&self) -> bool {
        self.q.is_empty()
    }

    /// Sets the state and computes the consistent acceleration `a = f − C v − Ω² q`; `f` is
    /// also the force held over the next contact step's interior sub-steps.
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
        if self.substeps > 1 {
            self.f_held.copy_from_slice(f);
        }
        self.step_damper_work_j = 0.0;
    }

    /// First half of a contact step: the interior sub-steps under the held force (none with
    /// one sub-step), then the last sub-step's displacement, to `t + Δt`; the predicted
    /// velocity for the contact is [`Self::predicted_velocity`].
    pub fn advance_displacement(&mut self) {
        self.step_damper_work_j = 0.0;
        if self.substeps > 1 {
            let f = std::mem::take(&mut self.f_held);
            for _ in 1..self.substeps {
                self.drift();
                self.kick(&f);
            }
            self.f_held = f;
        }
        self.drift();
    }

    /// `q ← q + h v + ½h² a`.
    fn drift(&mut self) {
        let (dt, m) = (self.h, self.len());
        for i in 0..m {
            self.q[i] += dt * self.v[i] + 0.5 * dt * dt * self.a[i];
        }
    }

    /// Predicted velocity at `t + Δt` (after [`Self::advance_displacement`]): `v + h a` of
    /// the last sub-step.
    #[inline]
    pub fn predicted_velocity(&self, i: usize) -> f64 {
        self.v[i] + self.h * self.a[i]
    }

    /// Second half of a contact step: the velocity and acceleration at `t + Δt` from the
    /// force `f_{n+1}` (generalised, per modal coordinate), which is then held over the next
    /// step's interior sub-steps. No allocation.
    pub fn complete(&mut self, f: &[f64]) {
        self.kick(f);
        if self.substeps > 1 {
            self.f_held.copy_from_slice(f);
        }
    }

    /// The velocity half of a sub-step with the force `f` at its end.
    fn kick(&mut self, f: &[f64]) {
        let (dt, m) = (self.h, self.len());
        let p_old = self.damping_power();
        for i in 0..m {
            self.rhs[i] =
                self.v[i] + 0.5 * dt * self.a[i] + 0.5 * dt * (f[i] - self.omega2[i] * self.q[i]);
        }
        self.v_old.copy_from_slice(&self.v);
        match &self.d_inv {
            DampingInverse::Packed(e) => {
                for (r32, r) in self.rhs32.iter_mut().zip(&self.rhs) {
                    *r32 = *r as f32;
                }
                sym_packed_product_f32(e, &self.rhs32, &mut self.tmp32);
                // v = (I + E) rhs
                for i in 0..m {
                    self.v[i] = self.rhs[i] + f64::from(self.tmp32[i]);
                }
            }
            DampingInverse::Diagonal(d) => {
                for i in 0..m {
                    self.v[i] = d[i] * self.rhs[i];
                }
            }
        }
        for i in 0..m {
            self.a[i] = 2.0 / dt * (self.v[i] - self.v_old[i]) - self.a[i];
            // (I + ½Δt C) v = rhs  ⇒  C v = (2/Δt)(rhs − v)
            self.cv[i] = 2.0 / dt * (self.rhs[i] - self.v[i]);
        }
        self.step_damper_work_j += 0.5 * dt * (p_old + self.damping_power());
    }

    /// Whether the velocity half of a contact step can be split into a part known before
    /// the contact force and a correction ([`Self::split_begin`], [`Self::complete_split`]):
    /// one sub-step per contact step and a full damping matrix.
    pub fn splits(&self) -> bool {
        self.substeps == 1 && matches!(self.d_inv, DampingInverse::Packed(_))
    }

    /// `y = E x` in single precision (`E = (I + ½h C)⁻¹ − I`, `x` rounded to `f32`, the
    /// product of [`sym_packed_product_f32`]), for [`Self::splits`] integrators; `x32` is
    /// scratch of the mode count. `y` (1/s · modal units, as `x`) gets the result in `f64`.
    pub fn damping_correction(&self, x: &[f64], x32: &mut [f32], y32: &mut [f32], y: &mut [f64]) {
        let DampingInverse::Packed(e) = &self.d_inv else {
            y.fill(0.0);
            return;
        };
        for (r32, r) in x32.iter_mut().zip(x) {
            *r32 = *r as f32;
        }
        sym_packed_product_f32(e, x32, y32);
        for (v, v32) in y.iter_mut().zip(y32.iter()) {
            *v = f64::from(*v32);
        }
    }

    /// The first part of a split velocity half-step (after [`Self::advance_displacement`],
    /// before the contact force is known): `b = v + ½h a + ½h (f_known − Ω² q)` (the
    /// velocity right-hand side with the force `f_known`, e.g. the last contact force on the
    /// new rows) and its damping correction `e_b = E b` ([`Self::damping_correction`]).
    /// Reads the state only, so it can run beside the contact step.
    pub fn split_begin(
        &self,
        f_known: &[f64],
        b: &mut [f64],
        (x32, y32): (&mut [f32], &mut [f32]),
        e_b: &mut [f64],
    ) {
        let h = self.h;
        for i in 0..self.len() {
            b[i] = self.v[i]
                + 0.5 * h * self.a[i]
                + 0.5 * h * (f_known[i] - self.omega2[i] * self.q[i]);
        }
        self.damping_correction(b, x32, y32, e_b);
    }

    /// The second part of a split velocity half-step: the force is `f_known + df`, with
    /// `e_df = E df` given (by linearity, e.g. from the damping corrections of the rows that
    /// `df` combines): `rhs = b + ½h df`, `v = rhs + e_b + ½h e_df`, then the acceleration,
    /// the damper force and the dampers' work as [`Self::complete`]. The same implicit step
    /// as [`Self::complete`] with `f = f_known + df` up to the rounding of the single
    /// precision products. For [`Self::splits`] integrators; no allocation.
    pub fn complete_split(&mut self, b: &[f64], e_b: &[f64], df: &[f64], e_df: &[f64]) {
        debug_assert!(self.splits());
        let (dt, m) = (self.h, self.len());
        let p_old = self.damping_power();
        self.v_old.copy_from_slice(&self.v);
        for i in 0..m {
            self.rhs[i] = b[i] + 0.5 * dt * df[i];
            self.v[i] = self.rhs[i] + e_b[i] + 0.5 * dt * e_df[i];
        }
        for i in 0..m {
            self.a[i] = 2.0 / dt * (self.v[i] - self.v_old[i]) - self.a[i];
            self.cv[i] = 2.0 / dt * (self.rhs[i] - self.v[i]);
        }
        self.step_damper_work_j += 0.5 * dt * (p_old + self.damping_power());
    }

    /// The dampers' work over the last contact step (J): the trapezoidal rule over its
    /// sub-steps, `Σ ½h(q̇ᵀC q̇ |_k + q̇ᵀC q̇ |_{k+1})`.
    pub fn step_damper_work(&self) -> f64 {
        self.step_damper_work_j
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

/// The highest natural frequency of a modal system (rad/s).
fn omega_max(sys: &ModalSystem) -> f64 {
    sys.omega2.iter().copied().fold(0.0, f64::max).sqrt()
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
    fn full_damping_system(
        m: usize,
        c: [f64; 2],
        f: [f64; 2],
    ) -> (Mat<f64>, Vec<f64>, ModalSystem) {
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
}
