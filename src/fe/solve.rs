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
