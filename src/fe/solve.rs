//! Direct sparse solution of `K u = f` for a symmetric positive definite stiffness.
//!
//! Sparse Cholesky `K = L Lᵀ` (faer's supernodal/simplicial factorisation): a symbolic
//! analysis under the sparser of two fill-reducing orderings — METIS nested dissection
//! ([`super::ordering`]) and faer's approximate minimum degree (below 200,000 DOFs; above,
//! nested dissection alone) — then the numeric factorisation,
//! then two triangular solves per right-hand side. Used for static checks (deflections,
//! reactions) and for the contact patch's submodels, whose factors are the largest this
//! program builds (tens of GB at the contact's element size: the ordering matters). Only the
//! lower triangle of `K` is read.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymmetricOrdering,
};
use faer::sparse::SparseColMat;
use faer::{Conj, Mat, Side, Spec};

use super::FeError;

/// From this many free DOFs on, minimum degree is not tried beside nested dissection: on the
/// contact patch's submodels (0.52 and 0.59 M DOFs) its factor had 2.9 and 2.2 times the
/// entries of nested dissection's, and its analysis alone took 3.4 and 3.7 s.
const ND_ONLY_DOFS: usize = 200_000;

/// A sparse Cholesky factorisation `K = L Lᵀ` of a stiffness over free DOFs, kept for many
/// right-hand sides (the unit loads of a contact patch's influence coefficients).
pub struct Cholesky {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
    n: usize,
}

/// The lower triangle's pattern (rows ≥ column) of `k` in CSC: what the ordering reads.
fn lower_pattern(k: &SparseColMat<usize, f64>) -> (Vec<usize>, Vec<usize>) {
    let n = k.ncols();
    let (cp, ri) = (k.symbolic().col_ptr(), k.symbolic().row_idx());
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut row_idx = Vec::with_capacity(ri.len() / 2 + n);
    col_ptr.push(0);
    for j in 0..n {
        row_idx.extend(ri[cp[j]..cp[j + 1]].iter().filter(|&&r| r >= j));
        col_ptr.push(row_idx.len());
    }
    (col_ptr, row_idx)
}

impl Cholesky {
    /// Factorises `K` (N/m, square, symmetric; only the lower triangle is read). Fails with
    /// [`FeError::NotPositiveDefinite`] when K is singular or indefinite (unconstrained
    /// rigid-body motion), and [`FeError::DimensionMismatch`] when K is not square. The
    /// ordering is whichever of nested dissection and minimum degree gives the smaller factor
    /// below 200,000 free DOFs, nested dissection above (minimum degree alone when METIS cannot
    /// order the graph).
    pub fn new(k: &SparseColMat<usize, f64>) -> Result<Self, FeError> {
        let n = k.nrows();
        if k.ncols() != n {
            return Err(FeError::DimensionMismatch {
                what: "stiffness columns vs rows".into(),
                expected: n,
                got: k.ncols(),
            });
        }
        let analyse = |ordering| {
            factorize_symbolic_cholesky(
                k.symbolic(),
                Side::Lower,
                ordering,
                CholeskySymbolicParams::default(),
            )
        };
        let (cp, ri) = lower_pattern(k);
        let symbolic = match super::ordering::nested_dissection(n, &cp, &ri) {
            Ok((fwd, inv)) => {
                let perm = faer::perm::PermRef::new_checked(&fwd, &inv, n);
                let nd = analyse(SymmetricOrdering::Custom(perm))?;
                if n >= ND_ONLY_DOFS {
                    nd
                } else {
                    let amd = analyse(SymmetricOrdering::Amd)?;
                    if nd.len_val() < amd.len_val() {
                        nd
                    } else {
                        amd
                    }
                }
            }
            Err(_) => analyse(SymmetricOrdering::Amd)?,
        };
        drop((cp, ri));
        let par = faer::get_global_parallelism();
        let mut values = Vec::new();
        values
            .try_reserve_exact(symbolic.len_val())
            .map_err(|_| faer::sparse::FaerError::OutOfMemory)?;
        values.resize(symbolic.len_val(), 0.0);
        let req = symbolic.factorize_numeric_llt_scratch::<f64>(par, Spec::default());
        let mut mem = MemBuffer::try_new(req).map_err(|_| faer::sparse::FaerError::OutOfMemory)?;
        symbolic
            .factorize_numeric_llt(
                &mut values,
                k.as_ref(),
                Side::Lower,
                LltRegularization::default(),
                par,
                MemStack::new(&mut mem),
                Spec::default(),
            )
            .map_err(|e| {
                FeError::NotPositiveDefinite(faer::sparse::linalg::LltError::Numeric(e))
            })?;
        Ok(Cholesky {
            symbolic,
            values,
            n,
        })
    }

    /// Number of free DOFs.
    pub(crate) fn dim(&self) -> usize {
        self.n
    }

    /// Entries of the factor `L` (its memory is eight bytes each).
    pub fn factor_len(&self) -> usize {
        self.values.len()
    }

    /// Overwrites each column of `rhs` (loads, N; `dim()` rows) with the displacements (m).
    /// Fails with [`FeError::DimensionMismatch`] on the row count and
    /// [`FeError::NotFinite`] when a solution is not finite.
    pub fn solve_in_place(&self, rhs: &mut Mat<f64>) -> Result<(), FeError> {
        if rhs.nrows() != self.n {
            return Err(FeError::DimensionMismatch {
                what: "load vectors".into(),
                expected: self.n,
                got: rhs.nrows(),
            });
        }
        let par = faer::get_global_parallelism();
        let req = self
            .symbolic
            .solve_in_place_scratch::<f64>(rhs.ncols(), par);
        let mut mem = MemBuffer::try_new(req).map_err(|_| faer::sparse::FaerError::OutOfMemory)?;
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            rhs.as_mut(),
            par,
            MemStack::new(&mut mem),
        );
        let finite = (0..rhs.ncols()).all(|c| (0..self.n).all(|i| rhs[(i, c)].is_finite()));
        if !finite {
            return Err(FeError::NotFinite);
        }
        Ok(())
    }
}

/// Solves `K u = f` (K in N/m over free DOFs, f in N) and returns `u` (m). Fails with
/// [`FeError::NotPositiveDefinite`] when K is singular or indefinite (unconstrained
/// rigid-body motion), and [`FeError::DimensionMismatch`] on sizes.
pub fn static_solve(k: &SparseColMat<usize, f64>, f: &[f64]) -> Result<Vec<f64>, FeError> {
    let factor = Cholesky::new(k)?;
    if f.len() != factor.dim() {
        return Err(FeError::DimensionMismatch {
            what: "load vector".into(),
            expected: factor.dim(),
            got: f.len(),
        });
    }
    let mut rhs = Mat::<f64>::from_fn(f.len(), 1, |i, _| f[i]);
    factor.solve_in_place(&mut rhs)?;
    Ok((0..f.len()).map(|i| rhs[(i, 0)]).collect())
}

/// Every generalised eigenpair of dense symmetric `(K, M)` (`K` positive semi-definite, `M`
/// positive definite): the eigenvalues `ω²` (1/s², ascending) and the M-orthonormal vectors
/// (columns). `O(n³)` time and `n²` memory: for verification and complete bases of a few
/// thousand DOFs.
///
/// It solves the inverse problem: with the shift `σ = 1e-8 · max_i K_ii/M_ii` (1/s², about
/// 1e-8 of `ω_max²`) and `K + σM = L Lᵀ`, the symmetric eigen-decomposition of
/// `B = L⁻¹ M L⁻ᵀ` gives `μ = 1/(ω² + σ)` and `φ = L⁻ᵀ y / √μ`. A symmetric eigen-solver's
/// eigenvalues carry an absolute error of order `ε‖A‖` (Golub & Van Loan 2013, §8.1.2), so
/// on `A = L_M⁻¹ K L_M⁻ᵀ` the low modes, which carry the flexibility `Σ φφᵀ/ω²`, lose
/// `ε ω_max²/ω²` relative (on a stiff FE structure, `ω_max²/ω_1²` ≈ 1e7–1e10); on `B` the
/// error sits on the high modes, where it is `ε ω_max²/σ` ≈ 1e-8 relative, and the low ones
/// keep `ε (ω² + σ)²/(σω²)`. With a complete basis `Σ φφᵀ/ω²` then reproduces `K⁻¹` of a
/// supported structure to round-off. The shift keeps `K + σM` positive definite when `K`
/// has rigid-body modes (their `ω²` come out within `ε σ` of zero, either sign). Fails with
/// [`FeError::DenseShiftNotPositiveDefinite`] when `K + σM` is not positive definite,
/// [`FeError::DenseMassNotPositive`] when `M` is not, and [`FeError::DenseEigen`] when the
/// eigensolver fails.
pub fn dense_generalised_eigen(
    k: &Mat<f64>,
    m: &Mat<f64>,
) -> Result<(Vec<f64>, Mat<f64>), FeError> {
    let n = k.nrows();
    let sigma = 1e-8
        * (0..n)
            .filter(|&i| m[(i, i)] > 0.0)
            .map(|i| k[(i, i)] / m[(i, i)])
            .fold(0.0_f64, f64::max);
    let shifted = Mat::<f64>::from_fn(n, n, |i, j| k[(i, j)] + sigma * m[(i, j)]);
    let l = shifted
        .llt(Side::Lower)
        .map_err(|source| FeError::DenseShiftNotPositiveDefinite { sigma, source })?
        .L()
        .to_owned();
    let mut a = m.clone();
    l.solve_lower_triangular_in_place(a.as_mut());
    let mut at = a.transpose().to_owned();
    l.solve_lower_triangular_in_place(at.as_mut());
    let b = Mat::<f64>::from_fn(n, n, |i, j| 0.5 * (at[(i, j)] + at[(j, i)]));
    drop((a, at));
    let evd = b
        .self_adjoint_eigen(Side::Lower)
        .map_err(|error| FeError::DenseEigen { error })?;
    let mu = evd.S().column_vector();
    if let Some(i) = (0..n).find(|&i| mu[i].is_nan() || mu[i] <= 0.0) {
        return Err(FeError::DenseMassNotPositive { eigenvalue: mu[i] });
    }
    let mut y = evd.U().to_owned();
    l.transpose().solve_upper_triangular_in_place(y.as_mut());
    // μ ascending is ω² descending: reverse the order.
    let vals: Vec<f64> = (0..n).map(|j| 1.0 / mu[n - 1 - j] - sigma).collect();
    let phi = Mat::<f64>::from_fn(n, n, |r, j| {
        let c = n - 1 - j;
        y[(r, c)] / mu[c].sqrt()
    });
    Ok((vals, phi))
}

#[cfg(test)]
mod tests {
    use super::{dense_generalised_eigen, Mat};
    /// A chain of `n` masses alternating between 1 kg and 1 mg, joined by springs of
    /// 1e4 N/m (spring 0 to the ground when `grounded`): `ω_max²/ω_1²` ≈ 1e9, the
    /// conditioning of a stiff FE structure on soft supports, with every matrix entry exact.
    fn chain(n: usize, grounded: bool) -> (Mat<f64>, Mat<f64>) {
        let s = 1e4;
        let mut k = Mat::<f64>::zeros(n, n);
        if grounded {
            k[(0, 0)] += s;
        }
        for i in 1..n {
            k[(i, i)] += s;
            k[(i - 1, i - 1)] += s;
            k[(i, i - 1)] -= s;
            k[(i - 1, i)] -= s;
        }
        let m = Mat::<f64>::from_fn(n, n, |i, j| match (i == j, i % 2) {
            (false, _) => 0.0,
            (true, 0) => 1.0,
            (true, _) => 1e-6,
        });
        (k, m)
    }

    /// Closed forms: the complete basis of the grounded chain sums to its static
    /// flexibility at the free end, `Σ φ_tip²/ω² = n/k` (springs in series), to 1e-12
    /// relative (an eigen-solver on `L_M⁻¹ K L_M⁻ᵀ` loses about `ε ω_max²/ω_1²` ≈ 1e-7
    /// here); the basis is M-orthonormal and `Kφ = ω²Mφ` to the round-off of the top modes;
    /// the free chain has one rigid mode, its `ω²` within 1e-6 of zero (1/s²), and the next
    /// one elastic.
    #[test]
    fn a_complete_dense_basis_sums_to_the_static_flexibility() {
        let n = 40;
        let (k, m) = chain(n, true);
        let (w2, phi) = dense_generalised_eigen(&k, &m).unwrap();
        assert!(w2.windows(2).all(|p| p[0] <= p[1]));
        let exact = n as f64 / 1e4;
        let modal: f64 = (0..n).map(|i| phi[(n - 1, i)].powi(2) / w2[i]).sum();
        assert!(
            ((modal - exact) / exact).abs() < 1e-12,
            "tip flexibility {modal:e} vs n/k {exact:e} m/N"
        );
        let g = phi.transpose() * &m * &phi;
        let lam = Mat::<f64>::from_fn(n, n, |i, j| if i == j { w2[i] } else { 0.0 });
        let r = &k * &phi - &m * &phi * lam;
        let (mut orth, mut res) = (0.0_f64, 0.0_f64);
        for i in 0..n {
            for j in 0..n {
                let t = if i == j { 1.0 } else { 0.0 };
                orth = orth.max((g[(i, j)] - t).abs());
                res = res.max(r[(i, j)].abs() / w2[n - 1]);
            }
        }
        assert!(
            orth < 1e-8 && res < 1e-8,
            "ΦᵀMΦ − I {orth:e}, residual {res:e}"
        );
        let (k, m) = chain(n, false);
        let (w2, _) = dense_generalised_eigen(&k, &m).unwrap();
        assert!(w2[0].abs() < 1e-6, "rigid mode ω² = {:e}", w2[0]);
        assert!(w2[1] > 1.0, "first elastic ω² = {:e}", w2[1]);
    }
}
