//! Direct sparse solution of `K u = f` for a symmetric positive definite stiffness.
//!
//! Sparse Cholesky `K = L Lᵀ` (faer supernodal/simplicial, fill-reducing ordering chosen
//! by faer): symbolic analysis, then numeric factorisation, then two triangular solves.
//! Used for static checks (deflections, reactions). Only the lower triangle of `K` is read.

use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::SparseColMat;
use faer::{Mat, Side};

use super::FeError;

/// Solves `K u = f` (K in N/m over free DOFs, f in N) and returns `u` (m). Fails with
/// [`FeError::NotPositiveDefinite`] when K is singular or indefinite (unconstrained
/// rigid-body motion), and [`FeError::DimensionMismatch`] on sizes.
pub fn static_solve(k: &SparseColMat<usize, f64>, f: &[f64]) -> Result<Vec<f64>, FeError> {
    let n = k.nrows();
    if k.ncols() != n {
        return Err(FeError::DimensionMismatch {
            what: "stiffness columns vs rows".into(),
            expected: n,
            got: k.ncols(),
        });
    }
    if f.len() != n {
        return Err(FeError::DimensionMismatch {
            what: "load vector".into(),
            expected: n,
            got: f.len(),
        });
    }
    let symbolic = SymbolicLlt::try_new(k.symbolic(), Side::Lower)?;
    let llt = Llt::try_new_with_symbolic(symbolic, k.as_ref(), Side::Lower).map_err(|e| {
        FeError::NotPositiveDefinite {
            detail: format!("{e:?}"),
        }
    })?;
    let mut rhs = Mat::<f64>::from_fn(n, 1, |i, _| f[i]);
    llt.solve_in_place(rhs.as_mut());
    let u: Vec<f64> = (0..n).map(|i| rhs[(i, 0)]).collect();
    if u.iter().any(|x| !x.is_finite()) {
        return Err(FeError::NotPositiveDefinite {
            detail: "solution is not finite".into(),
        });
    }
    Ok(u)
}

/// Every generalised eigenpair of dense symmetric `(K, M)` (`M` positive definite): the
/// eigenvalues `ω²` (1/s², ascending) and the M-orthonormal vectors (columns), by
/// `M = L Lᵀ`, the symmetric eigen-decomposition of `A = L⁻¹ K L⁻ᵀ` and `φ = L⁻ᵀ y`.
/// `O(n³)` time and `n²` memory: for verification and complete bases of a few thousand
/// DOFs. Fails with [`FeError::NotPositiveDefinite`] when `M` is not positive definite.
pub fn dense_generalised_eigen(
    k: &Mat<f64>,
    m: &Mat<f64>,
) -> Result<(Vec<f64>, Mat<f64>), FeError> {
    let l = m
        .llt(Side::Lower)
        .map_err(|e| FeError::NotPositiveDefinite {
            detail: format!("mass matrix of the dense eigenproblem: {e:?}"),
        })?
        .L()
        .to_owned();
    let mut a = k.clone();
    l.solve_lower_triangular_in_place(a.as_mut());
    let mut at = a.transpose().to_owned();
    l.solve_lower_triangular_in_place(at.as_mut());
    let n = k.nrows();
    let a = Mat::<f64>::from_fn(n, n, |i, j| 0.5 * (at[(i, j)] + at[(j, i)]));
    let evd = a
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| FeError::NotPositiveDefinite {
            detail: format!("dense symmetric eigensolver: {e:?}"),
        })?;
    let vals: Vec<f64> = (0..n).map(|i| evd.S().column_vector()[i]).collect();
    let mut phi = evd.U().to_owned();
    l.transpose().solve_upper_triangular_in_place(phi.as_mut());
    Ok((vals, phi))
}
