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
//!   full double-precision matrix (`sym_packed_product_f32`). `E = −½Δt C_q (I + ½Δt
//!   C_q)⁻¹` is small (‖E‖ ≤ ½Δt‖C_q‖, about 1e-2 on the default track), so the single
//!   precision changes `v` by at most about `m · 2⁻²⁴ · (|E| |rhs|)` per step, far below the
//!   scheme's own error (docs/theory.md §7.2).
//!   The damper force
//!   `C_q v_{n+1}` comes with it: the implicit equation says
//!   `½Δt C_q v_{n+1} = rhs − v_{n+1}`, so the dissipated power `v·C_q v` of the energy
//!   balance needs no second product (`ModalVerlet::damping_power`).
//!
//! Stability: undamped modes need `Δt ω_max < 2`. The contact step `Δt_c = Δx / V` is fixed
//! by the contact grid, so when `Δt_c ω_max ≥ 1.9` (a basis with high modes, up to a
//! complete one) the integrator advances the modal system by `m` equal **sub-steps**
//! `h = Δt_c / m` inside each contact step, with `m = ⌈Δt_c ω_max / 1.8⌉` (`h ω_max ≤ 1.8`,
//! the explicit path's default safety 0.9 of the limit 2; `substeps_for`). The generalised
//! force is sampled at the contact steps: the force of `t_n` is held at every sub-step node
//! of `[t_n, t_{n+1})` and the last sub-step completes with the force of `t_{n+1}`. In the
//! central-difference sense of node loads (a node's load acting over `t_k ± h/2`) that is
//! the explicit path's held-force predictor over a contact step (docs/theory.md §8.4): with
//! `m = 1` it is the plain step above, unchanged. The held force acts like the sampled force
//! delayed by `(Δt_c − h)/2`. Interior sub-steps cost one product with `(I + ½h C_q)⁻¹`
//! each (a diagonal scaling when `C_q` is diagonal). The constructor refuses more than
//! `MAX_SUBSTEPS` sub-steps (lower f_max or refine the contact grid). The explicit coupling
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
pub(crate) const MAX_SUBSTEPS: usize = 4096;

/// `Δt ω_max` at and above which one step is refused (the limit is 2).
const STEP_LIMIT: f64 = 1.9;

/// `h ω_max` the sub-step count aims at (0.9 × the limit 2, the explicit path's default
/// safety).
const SUBSTEP_TARGET: f64 = 1.8;

/// Sub-steps per contact step `dt` (s) for a system whose highest frequency is `omega_max`
/// (rad/s): 1 when `dt ω_max < 1.9`, otherwise `⌈dt ω_max / 1.8⌉` (module doc).
pub(crate) fn substeps_for(omega_max: f64, dt: f64) -> usize {
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
    /// `substeps_for`.
    pub fn new(sys: &ModalSystem, dt: f64) -> Result<Self, DynamicsError> {
        let m = substeps_for(omega_max(sys), dt);
        if m > MAX_SUBSTEPS {
            return Err(DynamicsError::Passage(crate::passage::PassageError::OutOfRange {
                name: "modal sub-steps per contact step (time step × highest mode's ω / 1.8); lower run.fmax",
                value: m as f64,
                expected: "at most 4096",
            }));
        }
        Self::with_substeps(sys, dt, m)
    }

    /// An integrator with contact step `dt` (s) split into `substeps` equal sub-steps, at
    /// rest. Refuses a sub-step `h` with `h ω_max ≥ 1.9`.
    pub(crate) fn with_substeps(
        sys: &ModalSystem,
        dt: f64,
        substeps: usize,
    ) -> Result<Self, DynamicsError> {
        let n = sys.len();
        let w_max = omega_max(sys);
        if !(dt > 0.0 && dt.is_finite()) {
            return Err(DynamicsError::Passage(
                crate::passage::PassageError::OutOfRange {
                    name: "time step (s)",
                    value: dt,
                    expected: "finite and > 0",
                },
            ));
        }
        if !(1..=MAX_SUBSTEPS).contains(&substeps) {
            return Err(DynamicsError::Passage(
                crate::passage::PassageError::OutOfRange {
                    name: "modal sub-steps per contact step",
                    value: substeps as f64,
                    expected: "1 to 4096",
                },
            ));
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
    /// velocity for the contact is `Self::predicted_velocity`.
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
    pub(crate) fn predicted_velocity(&self, i: usize) -> f64 {
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
    /// the contact force and a correction (`Self::split_begin`, `Self::complete_split`):
    /// one sub-step per contact step and a full damping matrix.
    pub fn splits(&self) -> bool {
        self.substeps == 1 && matches!(self.d_inv, DampingInverse::Packed(_))
    }

    /// `y = E x` in single precision (`E = (I + ½h C)⁻¹ − I`, `x` rounded to `f32`, the
    /// product of `sym_packed_product_f32`), for [`Self::splits`] integrators; `x32` is
    /// scratch of the mode count. `y` (1/s · modal units, as `x`) gets the result in `f64`.
    pub(crate) fn damping_correction(
        &self,
        x: &[f64],
        x32: &mut [f32],
        y32: &mut [f32],
        y: &mut [f64],
    ) {
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
    pub(crate) fn split_begin(
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
    pub(crate) fn complete_split(&mut self, b: &[f64], e_b: &[f64], df: &[f64], e_df: &[f64]) {
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
    pub(crate) fn step_damper_work(&self) -> f64 {
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
    pub(crate) fn damping_power(&self) -> f64 {
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
    .map_err(DynamicsError::DampingIndefinite)?;
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
mod tests;
