//! Normal contact on the half-space grid: the Polonsky–Keer (1999) constrained conjugate
//! gradient method.
//!
//! Unknowns: element pressures `p_i ≥ 0` (Pa). Deformed gap `g_i = h_i − δ + (C p)_i ≥ 0`
//! (m) with `h` the undeformed gap, `δ` the rigid approach, `C` the normal influence
//! operator ([`NormalInfluence`]: the half-space's [`super::influence::Convolver`] or an FE
//! patch's kernel invariant along x, [`super::influence::strip::StripNormal`]); complementarity
//! `p_i g_i = 0`.
//! Either the total load `Σ p_i ΔA = P` is prescribed (δ is then the Lagrange multiplier,
//! Polonsky & Keer's algorithm, their eqs. 6–13) or the approach δ is prescribed (the same
//! CG without the load-balance step; a bound-constrained quadratic programme).
//! Warm start: the pressure passed in is the initial iterate; from the second consecutive
//! solve on, it is extrapolated linearly from the last two solutions (`2 p(t) − p(t − Δt)`,
//! clipped at 0; [`NormalSolver::extrapolate`]), which saves a third of the CG iterations of
//! a transient sequence.
//!
//! Series compliance ([`NormalSolver::series_compliance_m_per_n`], `c_z`, m/N): the rail
//! surface under the whole patch moves by the extra uniform displacement `c_z F_N`,
//! `F_N = Σ p_j ΔA`, so `g_i = h_i − δ + (C p)_i + c_z ΔA Σ_j p_j`. With the approach prescribed
//! this is the influence operator plus the rank-one term `c_z ΔA 1 1ᵀ` (m/Pa; in force
//! unknowns `f = p ΔA` it reads `c_z 1 1ᵀ`), still symmetric positive definite, so the same CG
//! solves it in one pass. With the load prescribed the term is a uniform gap shift absorbed
//! by the Lagrange multiplier: only the reported approach changes, by `+c_z F_N`.
//!
//! # Fixed contact set
//! While the contact set `A = {p > 0}` and the undeformed gap `h` stay the same (a smooth
//! rail: only the approach, the load or `c_z` change from step to step), the problem is
//! linear on `A`: `C_A p + c_z ΔA (Σ p) 1 = (δ − h)_A`. With the unit responses
//! `w = C_A⁻¹ 1` and `z = C_A⁻¹ h_A` (conjugate gradients on `A` to a relative residual of
//! 1e-12, once per set) the solution is `p = a w − z` with
//! `a = (δ + c_z ΔA Σz) / (1 + c_z ΔA Σw)` (approach prescribed) or
//! `a = (P/ΔA + Σz) / Σw = δ` (load prescribed). It is the solution of the contact problem
//! when every `p_i`, `i ∈ A`, is positive and the gap `h − δ + a C w − C z + c_z F_N` is
//! non-negative outside `A` (the complementarity problem has one solution, `C` being
//! positive definite); then the step needs no influence product. Otherwise the set changes:
//! Polonsky–Keer's CG solves the step, and the unit responses of its new set are computed
//! for the next steps. The superposed pressure is exact to the 1e-12 of the unit responses,
//! the CG's to its tolerance ([`NormalSolver::tol`]).

use super::influence::NormalInfluence;
use super::ContactError;

/// What is prescribed in the normal problem.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NormalMode {
    /// Total normal force (N).
    Load(f64),
    /// Rigid approach of the bodies (m), positive = into each other.
    Approach(f64),
}

/// Result of a normal solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NormalOutcome {
    /// Total normal force (N).
    pub load_n: f64,
    /// Rigid approach (m).
    pub approach_m: f64,
    /// CG iterations used.
    pub iterations: usize,
}

/// Scratch of the Polonsky–Keer solver (allocated once).
#[derive(Clone)]
pub struct NormalSolver {
    gap: Vec<f64>,
    t: Vec<f64>,
    r: Vec<f64>,
    up: Vec<f64>,
    last_h: Vec<f64>,
    /// Solution of the solve before the last one (Pa), for the extrapolated warm start.
    prev_p: Vec<f64>,
    have_prev: bool,
    /// Warm start by linear extrapolation `2 p(t) − p(t − Δt)` (clipped at 0) from the last
    /// two solutions instead of `p(t)` alone.
    pub extrapolate: bool,
    last: Option<(NormalMode, f64, NormalOutcome)>,
    /// Uniform series compliance `c_z` (m/N, ≥ 0) of the rail surface under the patch (module
    /// doc); 0 = none.
    pub series_compliance_m_per_n: f64,
    /// Influence products (FFT pairs) used by the last solve.
    pub products: usize,
    /// Relative tolerance on the pressure change `Σ|Δp| / Σ p`.
    pub tol: f64,
    /// Maximum number of CG iterations.
    pub max_iterations: usize,
    /// Solve on a fixed contact set by superposition (module doc, "Fixed contact set");
    /// default on, off only to compare.
    pub fixed_set: bool,
    set: FixedSet,
}

/// Unit responses of a fixed contact set `A` for one undeformed gap `h` (module doc): `w =
/// C_A⁻¹ 1`, `z = C_A⁻¹ h_A` (Pa per m, Pa; zero outside `A`), their full-grid displacements
/// `C w`, `C z` and sums.
#[derive(Clone, Default)]
struct FixedSet {
    valid: bool,
    in_set: Vec<bool>,
    h: Vec<f64>,
    w: Vec<f64>,
    z: Vec<f64>,
    cw: Vec<f64>,
    cz: Vec<f64>,
    sum_w: f64,
    sum_z: f64,
    /// CG scratch: residual, direction, product.
    r: Vec<f64>,
    d: Vec<f64>,
    q: Vec<f64>,
}

impl NormalSolver {
    /// Scratch for `n` elements.
    pub fn new(n: usize) -> Self {
        NormalSolver {
            gap: vec![0.0; n],
            t: vec![0.0; n],
            r: vec![0.0; n],
            up: vec![0.0; n],
            last_h: vec![0.0; n],
            prev_p: vec![0.0; n],
            have_prev: false,
            extrapolate: true,
            last: None,
            series_compliance_m_per_n: 0.0,
            products: 0,
            tol: 1e-10,
            max_iterations: 2000,
            fixed_set: true,
            set: FixedSet {
                in_set: vec![false; n],
                h: vec![0.0; n],
                w: vec![0.0; n],
                z: vec![0.0; n],
                cw: vec![0.0; n],
                cz: vec![0.0; n],
                r: vec![0.0; n],
                d: vec![0.0; n],
                q: vec![0.0; n],
                ..FixedSet::default()
            },
        }
    }

    /// Forget the last solution (call when `p` was changed outside [`Self::solve`]).
    pub(crate) fn invalidate(&mut self) {
        self.last = None;
        self.have_prev = false;
        self.set.valid = false;
    }

    /// Solve for `p` (Pa, in/out: warm start) given the undeformed gap `h` (m), the element
    /// area `da` (m²) and the prescribed load or approach. On exit `gap` holds the deformed
    /// gap including the approach ([`Self::gap`]).
    ///
    /// If `h` and `mode` equal those of the previous solve (and `p` is its result, see
    /// `Self::invalidate`) the previous solution is returned without any product. Inside the
    /// CG the displacement `C p` is carried by the recurrence `C p ← C p − τ C t` while the
    /// contact set does not change (one FFT product per iteration), and recomputed exactly
    /// when it does.
    pub fn solve(
        &mut self,
        conv: &mut (impl NormalInfluence + ?Sized),
        h: &[f64],
        da: f64,
        mode: NormalMode,
        p: &mut [f64],
    ) -> Result<NormalOutcome, ContactError> {
        let c = self.series_compliance_m_per_n;
        if let Some((m, lc, out)) = self.last {
            if m == mode && lc == c && self.last_h[..] == h[..] {
                self.products = 0;
                return Ok(NormalOutcome {
                    iterations: 0,
                    ..out
                });
            }
        }
        let warm = self.last.is_some();
        self.last = None;
        let same_h = warm && self.last_h[..] == h[..];
        let positive = !matches!(mode, NormalMode::Load(w) if w <= 0.0);
        if self.fixed_set && positive && same_h && self.set.valid && self.set.h[..] == h[..] {
            if let Some((mut out, a)) = self.set.superpose(h, da, c, mode, &mut self.gap) {
                // accepted: the new pressure, with the extrapolation history kept
                self.prev_p.copy_from_slice(p);
                self.set.pressure(a, p);
                self.have_prev = true;
                self.products = 0;
                if let NormalMode::Load(_) = mode {
                    out.approach_m += c * out.load_n;
                }
                self.last_h.copy_from_slice(h);
                self.last = Some((mode, c, out));
                return Ok(out);
            }
        }
        if self.extrapolate && warm && self.have_prev {
            for (pi, q) in p.iter_mut().zip(self.prev_p.iter_mut()) {
                let x = (2.0 * *pi - *q).max(0.0);
                *q = *pi;
                *pi = x;
            }
        } else {
            self.prev_p.copy_from_slice(p);
        }
        self.have_prev = warm;
        let mut out = self.solve_inner(conv, h, da, mode, p)?;
        if self.fixed_set && same_h && out.load_n > 0.0 {
            // the undeformed gap did not change since the last step (smooth rail): the next
            // steps can superpose on this contact set
            self.products += self.set.build(conv, h, &*p)?;
        }
        if let NormalMode::Load(_) = mode {
            // the uniform displacement c_z F_N only shifts the Lagrange multiplier
            out.approach_m += c * out.load_n;
        }
        self.last_h.copy_from_slice(h);
        self.last = Some((mode, c, out));
        Ok(out)
    }

    /// `out = (C + c ΔA 1 1ᵀ) x` (m) for `x` in Pa: the influence product plus the uniform
    /// displacement of the series compliance (`c_da = c_z ΔA`, m/Pa; 0 in load mode).
    fn product(conv: &mut (impl NormalInfluence + ?Sized), c_da: f64, x: &[f64], out: &mut [f64]) {
        conv.normal(x, out);
        if c_da != 0.0 {
            let u = c_da * x.iter().sum::<f64>();
            out.iter_mut().for_each(|v| *v += u);
        }
    }

    /// Polonsky & Keer's constrained CG from the pressure `p` (Pa, in/out).
    ///
    /// Phases: the separation and zero-load shortcuts, the initial iterate, then per
    /// iteration the gap centred on its mean over the contact set (load mode) or on the
    /// approach, the conjugate direction, the step length, the pressure update (clipped at
    /// 0, overlapping elements entering the set), the scaling to the load and the
    /// displacement `C p` (by recurrence while the set holds).
    fn solve_inner(
        &mut self,
        conv: &mut (impl NormalInfluence + ?Sized),
        h: &[f64],
        da: f64,
        mode: NormalMode,
        p: &mut [f64],
    ) -> Result<NormalOutcome, ContactError> {
        self.products = 0;
        let c_da = match mode {
            NormalMode::Approach(_) => self.series_compliance_m_per_n * da,
            NormalMode::Load(_) => 0.0,
        };
        if let Some(out) = self.separated(h, mode, p) {
            return Ok(out);
        }
        Self::initial_iterate(conv, h, da, mode, p);
        let mut g_old = 1.0;
        let mut reuse_dir = false;
        self.t.fill(0.0);
        let mut last_change = 1.0;
        Self::product(conv, c_da, p, &mut self.up);
        self.products += 1;
        for it in 1..=self.max_iterations {
            let (delta, cnt, gg) = self.centred_gap(h, mode, p);
            let beta = if reuse_dir { gg / g_old } else { 0.0 };
            for i in 0..p.len() {
                self.t[i] = if p[i] > 0.0 {
                    self.gap[i] + beta * self.t[i]
                } else {
                    0.0
                };
            }
            g_old = gg;
            Self::product(conv, c_da, &self.t, &mut self.r);
            self.products += 1;
            let tau = self.step_length(conv, mode, p, cnt);
            let (change, any_overlap, clipped) = self.update_pressure(p, tau);
            reuse_dir = !any_overlap;
            let (tot, s_load) = scale_to_load(mode, da, p);
            if clipped || any_overlap {
                Self::product(conv, c_da, p, &mut self.up);
                self.products += 1;
            } else {
                for (u, r) in self.up.iter_mut().zip(&self.r) {
                    *u = s_load * (*u - tau * r);
                }
            }
            let scale = p.iter().sum::<f64>().max(1e-300);
            last_change = change / scale;
            if change / scale < self.tol && it > 1 {
                // final gap consistent with p (C p from the recurrence)
                for ((g, hv), u) in self.gap.iter_mut().zip(h).zip(&self.up) {
                    *g = u + hv - delta;
                }
                return Ok(NormalOutcome {
                    load_n: tot,
                    approach_m: delta,
                    iterations: it,
                });
            }
            if tot == 0.0 && matches!(mode, NormalMode::Approach(_)) && !any_overlap {
                return Ok(NormalOutcome {
                    load_n: 0.0,
                    approach_m: delta,
                    iterations: it,
                });
            }
        }
        Err(ContactError::NotConverged {
            solver: "Polonsky–Keer normal CG",
            iterations: self.max_iterations,
            residual: last_change,
        })
    }

    /// The shortcuts without contact: zero load (the bodies touch at the lowest point of `h`)
    /// or an approach that leaves every gap open. Sets `p = 0` and the gap.
    fn separated(&mut self, h: &[f64], mode: NormalMode, p: &mut [f64]) -> Option<NormalOutcome> {
        let (approach_m, gap_shift) = match mode {
            NormalMode::Load(w) if w <= 0.0 => {
                let hmin = h.iter().cloned().fold(f64::INFINITY, f64::min);
                (hmin, hmin)
            }
            NormalMode::Approach(d) if h.iter().all(|&hv| hv - d >= 0.0) => (d, d),
            _ => return None,
        };
        p.fill(0.0);
        for (g, hv) in self.gap.iter_mut().zip(h) {
            *g = hv - gap_shift;
        }
        Some(NormalOutcome {
            load_n: 0.0,
            approach_m,
            iterations: 0,
        })
    }

    /// The initial iterate: the warm start `p` as it is (scaled to the load in load mode),
    /// or from rest the overlap of the undeformed bodies (below the approach, or the lowest
    /// 30 % of `h` in load mode) scaled to the load or to a plausible magnitude.
    fn initial_iterate(
        conv: &(impl NormalInfluence + ?Sized),
        h: &[f64],
        da: f64,
        mode: NormalMode,
        p: &mut [f64],
    ) {
        let mut total: f64 = p.iter().sum::<f64>() * da;
        let cold = total <= 0.0 || !total.is_finite();
        if cold {
            // start from where the undeformed bodies would overlap (or the lowest point)
            let hmin = h.iter().cloned().fold(f64::INFINITY, f64::min);
            let hmax = h.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            let thr = match mode {
                NormalMode::Approach(d) => d,
                NormalMode::Load(_) => hmin + 0.3 * (hmax - hmin) + 1e-15,
            };
            for (pi, &hv) in p.iter_mut().zip(h) {
                *pi = (thr - hv).max(0.0);
            }
            total = p.iter().sum::<f64>() * da;
        }
        if let NormalMode::Load(w) = mode {
            let s = w / total;
            p.iter_mut().for_each(|v| *v *= s);
        } else if cold {
            // scale to a plausible magnitude: mean overlap / self-influence (a warm start,
            // the previous pressure, is kept as it is)
            let d = match mode {
                NormalMode::Approach(d) => d,
                _ => 0.0,
            };
            let s = h.iter().map(|hv| (d - hv).max(0.0)).fold(0.0, f64::max)
                / conv.diag_n().max(1e-300)
                / p.iter().cloned().fold(0.0, f64::max).max(1e-300);
            p.iter_mut().for_each(|v| *v *= s * 0.3);
        }
    }

    /// The gap `h + C p` centred on `ḡ`: its mean over the contact set (load mode) or the
    /// approach. Returns `ḡ` (the approach of the iterate, m), the contact elements and the
    /// squared norm of the centred gap over the contact set.
    fn centred_gap(&mut self, h: &[f64], mode: NormalMode, p: &[f64]) -> (f64, usize, f64) {
        for ((g, hv), u) in self.gap.iter_mut().zip(h).zip(&self.up) {
            *g = hv + u;
        }
        let (mut sum, mut cnt) = (0.0, 0usize);
        for (g, pi) in self.gap.iter().zip(p.iter()) {
            if *pi > 0.0 {
                sum += g;
                cnt += 1;
            }
        }
        let gbar = match mode {
            NormalMode::Load(_) => {
                if cnt == 0 {
                    0.0
                } else {
                    sum / cnt as f64
                }
            }
            NormalMode::Approach(d) => d,
        };
        let mut gg = 0.0;
        for (g, pi) in self.gap.iter_mut().zip(p.iter()) {
            *g -= gbar;
            if *pi > 0.0 {
                gg += *g * *g;
            }
        }
        (gbar, cnt, gg)
    }

    /// The step length `τ` along the direction `t` with its product `r = C t` (its mean
    /// over the `cnt` contact elements removed in load mode); `1/C_ii` when the curvature
    /// is not positive.
    fn step_length(
        &self,
        conv: &(impl NormalInfluence + ?Sized),
        mode: NormalMode,
        p: &[f64],
        cnt: usize,
    ) -> f64 {
        let n = p.len();
        let rbar = match mode {
            NormalMode::Load(_) => {
                let mut s = 0.0;
                for i in 0..n {
                    if p[i] > 0.0 {
                        s += self.r[i];
                    }
                }
                if cnt == 0 {
                    0.0
                } else {
                    s / cnt as f64
                }
            }
            NormalMode::Approach(_) => 0.0,
        };
        let (mut num, mut den) = (0.0, 0.0);
        for i in 0..n {
            if p[i] > 0.0 {
                num += self.gap[i] * self.t[i];
                den += (self.r[i] - rbar) * self.t[i];
            }
        }
        if den > 0.0 {
            num / den
        } else {
            1.0 / conv.diag_n()
        }
    }

    /// The pressure update `p − τ t` on the contact set, clipped at 0, and `−τ g` where an
    /// element outside the set overlaps. Returns `Σ|Δp|` (Pa), whether an element entered
    /// the set and whether one was clipped.
    fn update_pressure(&self, p: &mut [f64], tau: f64) -> (f64, bool, bool) {
        let mut change = 0.0;
        let mut any_overlap = false;
        let mut clipped = false;
        for i in 0..p.len() {
            let old = p[i];
            if old > 0.0 {
                let v = old - tau * self.t[i];
                if v < 0.0 {
                    clipped = true;
                }
                p[i] = v.max(0.0);
            } else if self.gap[i] < 0.0 {
                p[i] = old - tau * self.gap[i];
                any_overlap = true;
            }
            change += (p[i] - old).abs();
        }
        (change, any_overlap, clipped)
    }

    /// Deformed gap (m) of the last solve, `h − δ + C p`.
    pub fn gap(&self) -> &[f64] {
        &self.gap
    }
}

/// The total force of `p` (Pa) on elements of area `da` (m²) and, in load mode with a
/// positive total, `p` scaled to the load. Returns the total (N) and the scale (−).
fn scale_to_load(mode: NormalMode, da: f64, p: &mut [f64]) -> (f64, f64) {
    let mut tot = p.iter().sum::<f64>() * da;
    let mut s_load = 1.0;
    if let NormalMode::Load(w) = mode {
        if tot > 0.0 {
            s_load = w / tot;
            for v in p.iter_mut() {
                *v *= s_load;
            }
            tot = w;
        }
    }
    (tot, s_load)
}

/// Relative residual `‖C_A x − b‖ / ‖b‖` at which the unit responses of a fixed contact set
/// are accepted: far below the pressure tolerance of the Polonsky–Keer CG (1e-6 in rolling).
const FIXED_SET_TOL: f64 = 1e-12;

impl FixedSet {
    /// The unit responses of the contact set `{p > 0}` for the gap `h` (Polonsky–Keer's
    /// solution `p`). Returns the influence products used.
    fn build(
        &mut self,
        conv: &mut (impl NormalInfluence + ?Sized),
        h: &[f64],
        p: &[f64],
    ) -> Result<usize, ContactError> {
        let was_valid = self.valid;
        self.valid = false;
        for (s, &pi) in self.in_set.iter_mut().zip(p) {
            *s = pi > 0.0;
        }
        // warm start from the responses of the previous set (restricted to the new one)
        if !was_valid {
            self.w.fill(0.0);
            self.z.fill(0.0);
        }
        let mut products = 0;
        let mut x = std::mem::take(&mut self.w);
        products += self.solve_on_set(conv, |_| 1.0, &mut x)?;
        self.w = x;
        let mut x = std::mem::take(&mut self.z);
        products += self.solve_on_set(conv, |i| h[i], &mut x)?;
        self.z = x;
        conv.normal(&self.w, &mut self.cw);
        conv.normal(&self.z, &mut self.cz);
        self.sum_w = self.w.iter().sum();
        self.sum_z = self.z.iter().sum();
        self.h.copy_from_slice(h);
        self.valid = true;
        Ok(products + 2)
    }

    /// Conjugate gradients for `C_A x = b` on the set `A` (`x` zero outside it; in/out: the
    /// start). Returns the influence products used.
    fn solve_on_set(
        &mut self,
        conv: &mut (impl NormalInfluence + ?Sized),
        b: impl Fn(usize) -> f64,
        x: &mut [f64],
    ) -> Result<usize, ContactError> {
        let n = x.len();
        for i in 0..n {
            if !self.in_set[i] {
                x[i] = 0.0;
            }
        }
        conv.normal(x, &mut self.q);
        let (mut rr, mut bb) = (0.0, 0.0);
        for i in 0..n {
            let (r, bi) = if self.in_set[i] {
                let bi = b(i);
                (bi - self.q[i], bi)
            } else {
                (0.0, 0.0)
            };
            self.r[i] = r;
            self.d[i] = r;
            rr += r * r;
            bb += bi * bi;
        }
        let stop = FIXED_SET_TOL * FIXED_SET_TOL * bb;
        let mut products = 1;
        while rr > stop {
            if products > n + 10 {
                return Err(ContactError::NotConverged {
                    solver: "normal unit responses on a fixed contact set (CG)",
                    iterations: products,
                    residual: (rr / bb).sqrt(),
                });
            }
            conv.normal(&self.d, &mut self.q);
            products += 1;
            let mut dq = 0.0;
            for i in 0..n {
                if self.in_set[i] {
                    dq += self.d[i] * self.q[i];
                }
            }
            let alpha = rr / dq;
            let mut rr_new = 0.0;
            for i in 0..n {
                if self.in_set[i] {
                    x[i] += alpha * self.d[i];
                    self.r[i] -= alpha * self.q[i];
                    rr_new += self.r[i] * self.r[i];
                }
            }
            let beta = rr_new / rr;
            rr = rr_new;
            for i in 0..n {
                self.d[i] = self.r[i] + beta * self.d[i];
            }
        }
        Ok(products)
    }

    /// The solution on the fixed set for `mode` and the series compliance `c` (m/N), if it is
    /// the solution of the contact problem (every pressure of the set positive, no overlap
    /// outside it): the outcome (approach without the series share in load mode, as
    /// [`NormalSolver::solve_inner`]) and the factor `a` of `p = a w − z`; the deformed gap
    /// is written to `gap`. `None` (gap unspecified) when the set must change.
    fn superpose(
        &self,
        h: &[f64],
        da: f64,
        c: f64,
        mode: NormalMode,
        gap: &mut [f64],
    ) -> Option<(NormalOutcome, f64)> {
        let (a, delta, c_da) = match mode {
            NormalMode::Approach(d) => {
                let c_da = c * da;
                let den = 1.0 + c_da * self.sum_w;
                if den <= 0.0 {
                    // a negative uniform compliance (the fe-patch's split) larger than the
                    // set's own: not positive definite; the CG decides
                    return None;
                }
                ((d + c_da * self.sum_z) / den, d, c_da)
            }
            NormalMode::Load(f) => {
                let a = (f / da + self.sum_z) / self.sum_w;
                (a, a, 0.0)
            }
        };
        let s = a * self.sum_w - self.sum_z;
        let uniform = c_da * s - delta;
        for i in 0..h.len() {
            if self.in_set[i] {
                if a * self.w[i] - self.z[i] <= 0.0 {
                    return None;
                }
                gap[i] = 0.0;
            } else {
                let g = h[i] + a * self.cw[i] - self.cz[i] + uniform;
                if g < 0.0 {
                    return None;
                }
                gap[i] = g;
            }
        }
        let out = NormalOutcome {
            load_n: s * da,
            approach_m: delta,
            iterations: 0,
        };
        Some((out, a))
    }

    /// `p = a w − z` on the set, 0 outside (Pa).
    fn pressure(&self, a: f64, p: &mut [f64]) {
        for i in 0..p.len() {
            p[i] = if self.in_set[i] {
                a * self.w[i] - self.z[i]
            } else {
                0.0
            };
        }
    }
}
