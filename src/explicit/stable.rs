//! The stable time step of the central difference (docs/theory.md §8.2).
//!
//! Undamped, the central difference is stable for `Δt ≤ 2/ω_max`, `ω_max²` the largest
//! eigenvalue of `M⁻¹K` (equivalently of `A = M^{-½} K M^{-½}` with the lumped `M`). With a
//! damping ratio ξ in that mode the limit is `(2/ω_max)(√(1+ξ²) − ξ)` (Belytschko, Liu &
//! Moran 2000, §6.3). `ω_max` is estimated by a Lanczos iteration on `A` with full
//! reorthogonalisation: its largest Ritz value approaches `ω_max²` from below, so the step
//! keeps a safety factor; Gershgorin's row bound (an upper bound) is reported beside it.
//! The element-wise `h/c_d` rule is not used: it misses the element's true highest mode and
//! the springs that join the parts.

use super::operator::ExplicitOperator;
use super::ExplicitError;

/// Default safety factor on the estimated critical step (−).
pub(crate) const DEFAULT_SAFETY: f64 = 0.9;

/// Lanczos steps of the ω_max estimate (at most; it stops earlier when the largest Ritz
/// value changes by less than [`LANCZOS_TOL`] relative over 5 steps).
pub(crate) const LANCZOS_STEPS: usize = 120;

/// Relative convergence tolerance of the largest Ritz value (−).
pub(crate) const LANCZOS_TOL: f64 = 1e-6;

/// The stable step of one substructure.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct StableStep {
    /// Estimated highest natural angular frequency `ω_max` (rad/s): √ of the largest Ritz
    /// value of `M^{-½}KM^{-½}`.
    pub omega_max_estimate: f64,
    /// Gershgorin's upper bound on `ω_max` (rad/s).
    pub omega_max_bound: f64,
    /// Damping ratio of the highest Ritz vector, `zᵀC̃z / (2 ω_max)` (−).
    pub damping_ratio: f64,
    /// Critical step `(2/ω_max)(√(1+ξ²) − ξ)` (s) from the estimate.
    pub critical_s: f64,
    /// Lanczos steps used.
    pub lanczos_steps: usize,
}

impl StableStep {
    /// Estimates the stable step of `op` (no safety factor applied: see
    /// `Self::with_safety`).
    pub fn estimate(op: &ExplicitOperator) -> Result<Self, ExplicitError> {
        Ok(Self::with_ritz_vector(op)?.0)
    }

    /// The estimate and its Ritz vector `z` (of `M^{-½}KM^{-½}`, unit length).
    fn with_ritz_vector(op: &ExplicitOperator) -> Result<(Self, Vec<f64>), ExplicitError> {
        let (theta, z, steps) = lanczos_largest(op, LANCZOS_STEPS)?;
        let omega = theta.sqrt();
        let bound = op.gershgorin_omega2().sqrt();
        let two_xi_omega = op.scaled_damping_quotient(&z);
        let xi = if omega > 0.0 {
            (0.5 * two_xi_omega / omega).max(0.0)
        } else {
            0.0
        };
        let step = StableStep {
            omega_max_estimate: omega,
            omega_max_bound: bound,
            damping_ratio: xi,
            critical_s: critical_step(omega, xi),
            lanczos_steps: steps,
        };
        Ok((step, z))
    }

    /// The step to use (s): `safety × critical_s`, `safety` in (0, 1].
    pub(crate) fn with_safety(&self, safety: f64) -> f64 {
        safety * self.critical_s
    }
}

/// The highest mode as the estimate finds it: its [`StableStep`] and its displacement over
/// the free DOFs (m per unit `zᵀz`, `u = M^{-½} z` of the Ritz vector `z`), to see which part
/// of a structure sets the stable step (the mode's kinetic share of DOF `i` is `m_i u_i²`).
pub fn highest_mode(op: &ExplicitOperator) -> Result<(StableStep, Vec<f64>), ExplicitError> {
    let (step, z) = StableStep::with_ritz_vector(op)?;
    let u = z.iter().zip(op.mass()).map(|(z, m)| z / m.sqrt()).collect();
    Ok((step, u))
}

/// The central difference's critical step `(2/ω)(√(1+ξ²) − ξ)` (s) for a mode of angular
/// frequency `omega` (rad/s) and damping ratio `xi` (−).
pub fn critical_step(omega: f64, xi: f64) -> f64 {
    2.0 / omega * ((1.0 + xi * xi).sqrt() - xi)
}

/// A fixed pseudo-random start vector (so that the estimate is reproducible).
fn start_vector(n: usize) -> Vec<f64> {
    let mut s: u64 = 0x9E37_79B9_7F4A_7C15;
    (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        })
        .collect()
}

/// Largest eigenvalue of `M^{-½}KM^{-½}` by Lanczos with full reorthogonalisation:
/// `(θ_max (1/s²), its Ritz vector, steps)`.
fn lanczos_largest(
    op: &ExplicitOperator,
    max_steps: usize,
) -> Result<(f64, Vec<f64>, usize), ExplicitError> {
    let n = op.n();
    let m = max_steps.min(n);
    let norm = |x: &[f64]| x.iter().map(|a| a * a).sum::<f64>().sqrt();
    let mut q = start_vector(n);
    let nq = norm(&q);
    q.iter_mut().for_each(|x| *x /= nq);
    let mut basis: Vec<Vec<f64>> = vec![q];
    let (mut alpha, mut beta) = (Vec::<f64>::new(), Vec::<f64>::new());
    let mut w = vec![0.0; n];
    let mut history: Vec<f64> = Vec::new();
    let mut best = (0.0, vec![0.0; 1]);
    for j in 0..m {
        op.apply_scaled(&basis[j], &mut w);
        let a: f64 = w.iter().zip(&basis[j]).map(|(x, y)| x * y).sum();
        alpha.push(a);
        // Full reorthogonalisation (twice is enough).
        for _ in 0..2 {
            for b in &basis {
                let c: f64 = w.iter().zip(b).map(|(x, y)| x * y).sum();
                w.iter_mut().zip(b).for_each(|(x, y)| *x -= c * y);
            }
        }
        let (theta, y) = tridiagonal_largest(&alpha, &beta);
        history.push(theta);
        best = (theta, y);
        let bnorm = norm(&w);
        let k = history.len();
        let converged = k > 6 && {
            let old = history[k - 6];
            (theta - old).abs() <= LANCZOS_TOL * theta.abs()
        };
        if converged || bnorm <= 1e-12 * theta.abs().max(f64::MIN_POSITIVE) || j + 1 == m {
            break;
        }
        beta.push(bnorm);
        basis.push(w.iter().map(|x| x / bnorm).collect());
    }
    let (theta, y) = best;
    if !(theta.is_finite() && theta > 0.0) {
        return Err(ExplicitError::NoStableStep { omega2: theta });
    }
    let mut z = vec![0.0; n];
    for (c, b) in y.iter().zip(&basis) {
        z.iter_mut().zip(b).for_each(|(x, v)| *x += c * v);
    }
    Ok((theta, z, alpha.len()))
}

/// Largest eigenvalue and eigenvector of the symmetric tridiagonal matrix with diagonal
/// `alpha` and off-diagonal `beta` (len = alpha.len() − 1, or shorter: missing = 0).
fn tridiagonal_largest(alpha: &[f64], beta: &[f64]) -> (f64, Vec<f64>) {
    let k = alpha.len();
    let t = nalgebra::DMatrix::from_fn(k, k, |r, c| {
        if r == c {
            alpha[r]
        } else if r + 1 == c && r < beta.len() {
            beta[r]
        } else if c + 1 == r && c < beta.len() {
            beta[c]
        } else {
            0.0
        }
    });
    let e = nalgebra::SymmetricEigen::new(t);
    let (i, &theta) = e
        .eigenvalues
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .expect("k ≥ 1");
    (theta, e.eigenvectors.column(i).iter().copied().collect())
}
