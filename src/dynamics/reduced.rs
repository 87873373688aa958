//! Modal synthesis of the wheel–track system (docs/theory.md §7.1).
//!
//! Each substructure (track, wheel with the sprung mass) is reduced to its mass-normalised
//! modes below f_max: `q̈ + C_q q̇ + Ω² q = Φᵀ f`, with
//! - `Ω² = diag(ω_i²)` (rad²/s²),
//! - `C_q = Φᵀ C Φ` the **full** projected damping matrix of the discrete dampers (1/s): the
//!   railpad and ballast dampers are not proportional, so `C_q` is not diagonal
//!   (docs/theory.md §7.1),
//! - `Φᵀ f` the generalised force (N·m/√kg… i.e. N per unit modal coordinate).
//!
//! The two substructures are coupled only through the contact force, which acts at the
//! contact point on the rail running surface (moving) and on the wheel tread (fixed in the
//! non-rotating wheel frame). The contact frame, the rail's contact line and the wheel's
//! contact point live beneath both engines ([`crate::passage::contact_line`]).

use faer::sparse::SparseColMatRef;
use faer::Mat;

use super::DynamicsError;

pub(crate) use crate::passage::contact_line::dot;
pub use crate::passage::contact_line::{
    add_line_load, add_nodes_load, line_load_vector, modal_rows, ContactFrame, RailContactLine,
    WheelContact,
};

/// One substructure reduced to its modes.
#[derive(Clone, Debug)]
pub struct ModalSystem {
    /// Squared natural frequencies ω² (rad²/s²); rigid-body modes are set to exactly 0.
    pub omega2: Vec<f64>,
    /// Projected damping `Φᵀ C Φ` (1/s), m × m, symmetric.
    pub damping: Mat<f64>,
}

impl ModalSystem {
    /// Reduces a substructure: frequencies (Hz) of mass-normalised `modes` (n × m) and the
    /// sparse damping matrix `c` (N·s/m, n × n). Frequencies below `rigid_hz` are rigid-body
    /// modes (ω = 0 exactly).
    pub fn new(
        frequencies_hz: &[f64],
        modes: &Mat<f64>,
        c: SparseColMatRef<'_, usize, f64>,
        rigid_hz: f64,
    ) -> Result<Self, DynamicsError> {
        let m = frequencies_hz.len();
        if modes.ncols() != m || modes.nrows() != c.nrows() {
            return Err(DynamicsError::BasisShape {
                rows: modes.nrows(),
                cols: modes.ncols(),
                frequencies: m,
                dofs: c.nrows(),
            });
        }
        let omega2 = frequencies_hz
            .iter()
            .map(|&f| {
                if f < rigid_hz {
                    0.0
                } else {
                    (2.0 * std::f64::consts::PI * f).powi(2)
                }
            })
            .collect();
        let mut damping = project_damping(c, modes);
        // Symmetrise the round-off.
        for i in 0..m {
            for j in 0..i {
                let v = 0.5 * (damping[(i, j)] + damping[(j, i)]);
                damping[(i, j)] = v;
                damping[(j, i)] = v;
            }
        }
        Ok(ModalSystem { omega2, damping })
    }

    /// Adds modal damping of ratio `zeta` (−) to every mode with ω > 0: `C_ii += 2 ζ ω_i`
    /// (1/s). Rigid-body modes are left alone.
    pub(crate) fn add_modal_damping(&mut self, zeta: f64) {
        if zeta == 0.0 {
            return;
        }
        for i in 0..self.len() {
            let w2 = self.omega2[i];
            if w2 > 0.0 {
                self.damping[(i, i)] += 2.0 * zeta * w2.sqrt();
            }
        }
    }

    /// Number of modes.
    pub fn len(&self) -> usize {
        self.omega2.len()
    }

    /// True when there are no modes.
    pub fn is_empty(&self) -> bool {
        self.omega2.is_empty()
    }

    /// Largest |off-diagonal| / √(c_ii c_jj) of the damping matrix (−): how far from
    /// proportional (modal) damping the discrete dampers are.
    pub fn damping_coupling(&self) -> f64 {
        let m = self.len();
        let mut worst: f64 = 0.0;
        for i in 0..m {
            for j in 0..i {
                let d = (self.damping[(i, i)] * self.damping[(j, j)]).sqrt();
                if d > 0.0 {
                    worst = worst.max(self.damping[(i, j)].abs() / d);
                }
            }
        }
        worst
    }
}

/// Natural frequencies (Hz) of M-orthonormal `modes` (n × m, `ΦᵀMΦ = I`) from their
/// Rayleigh quotients `ω² = φᵀKφ` with the stiffness `k` (N/m, full symmetric storage);
/// negative round-off gives 0. The quotient's error is of the order of the square of the
/// mode shape's error, so it is accurate where a shift-invert eigen-solver's eigenvalue is
/// not: a free body's rigid modes, whose shapes it finds to round-off but whose `λ ≈ 0` it
/// resolves only to the round-off of its shifts (on a coarse wheel mesh with
/// `run.fmax` ≥ 4.5 kHz, 1.8 Hz in place of 0, above [`super::passage::RIGID_HZ`]).
pub fn rayleigh_frequencies_hz(k: SparseColMatRef<'_, usize, f64>, modes: &Mat<f64>) -> Vec<f64> {
    let cols = k.symbolic().col_ptr();
    let rows = k.symbolic().row_idx();
    let vals = k.val();
    (0..modes.ncols())
        .map(|i| {
            let phi = modes.col(i);
            let mut w2 = 0.0;
            for (j, span) in cols.windows(2).enumerate() {
                let pj = phi[j];
                if pj == 0.0 {
                    continue;
                }
                for p in span[0]..span[1] {
                    w2 += phi[rows[p]] * vals[p] * pj;
                }
            }
            w2.max(0.0).sqrt() / (2.0 * std::f64::consts::PI)
        })
        .collect()
}

/// `Φᵀ C Φ` (m × m) over the DOFs that carry damping only. The assembled `C` shares the
/// sparsity pattern of `K`, but only the discrete dampers' DOFs (rail foot, sleeper faces)
/// hold nonzero values; the others are stored zeros. Gathering the active rows of `Φ` and the
/// nonzero entries of `C` first makes the projection cost `nnz(C≠0)·m + |A|·m²` instead of
/// `nnz(pattern)·m + n·m²` (default model, 5 kHz: seconds instead of tens of seconds).
fn project_damping(c: SparseColMatRef<'_, usize, f64>, modes: &Mat<f64>) -> Mat<f64> {
    let n = c.nrows();
    let m = modes.ncols();
    let cp = c.symbolic().col_ptr();
    let ri = c.symbolic().row_idx();
    let val = c.val();
    // Compact index of every DOF that appears in a nonzero entry.
    let mut compact = vec![usize::MAX; n];
    let mut active = Vec::new();
    let mut entries = Vec::new();
    for j in 0..c.ncols() {
        for p in cp[j]..cp[j + 1] {
            let v = val[p];
            if v != 0.0 {
                for d in [ri[p], j] {
                    if compact[d] == usize::MAX {
                        compact[d] = active.len();
                        active.push(d);
                    }
                }
                entries.push((compact[ri[p]], compact[j], v));
            }
        }
    }
    let na = active.len();
    // Φ_A (na × m) and C Φ_A restricted to the active rows.
    let phi_a = Mat::<f64>::from_fn(na, m, |r, k| modes[(active[r], k)]);
    let mut cphi = Mat::<f64>::zeros(na, m);
    for k in 0..m {
        let src = phi_a.col(k);
        let mut dst = cphi.col_mut(k);
        for &(i, j, v) in &entries {
            dst[i] += v * src[j];
        }
    }
    phi_a.transpose() * cphi.as_ref()
}

#[cfg(test)]
mod tests {
    use super::{project_damping, Mat};
    /// The projection over the damped DOFs equals the dense `Φᵀ C Φ` on a matrix whose
    /// pattern stores explicit zeros (as the assembled C does) and whose damped DOFs are
    /// scattered.
    #[test]
    fn damping_projection_equals_the_dense_product() {
        use faer::sparse::{SparseColMat, Triplet};
        let n: usize = 40;
        let m = 7;
        let mut trip = Vec::new();
        // Pattern: tridiagonal, values nonzero only in a few 2×2 damper blocks.
        for i in 0..n {
            for j in i.saturating_sub(1)..(i + 2).min(n) {
                trip.push(Triplet::new(i, j, 0.0));
            }
        }
        for &(a, b, c) in &[
            (3usize, 4usize, 2.5),
            (17, 18, 0.7),
            (31, 32, 4.0),
            (39, 38, 1.1),
        ] {
            trip.push(Triplet::new(a, a, c));
            trip.push(Triplet::new(b, b, c));
            trip.push(Triplet::new(a, b, -c));
            trip.push(Triplet::new(b, a, -c));
        }
        let cmat = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &trip).unwrap();
        let phi = Mat::<f64>::from_fn(n, m, |i, k| {
            ((i * 7 + k * 13) % 11) as f64 / 11.0 - 0.4 + 0.01 * k as f64
        });
        let got = project_damping(cmat.as_ref(), &phi);
        let dense = Mat::<f64>::from_fn(n, n, |i, j| {
            let mut v = 0.0;
            for t in &trip {
                if t.row == i && t.col == j {
                    v += t.val;
                }
            }
            v
        });
        let want = phi.transpose() * &dense * &phi;
        for i in 0..m {
            for j in 0..m {
                assert!((got[(i, j)] - want[(i, j)]).abs() < 1e-12, "{i} {j}");
            }
        }
    }
}
