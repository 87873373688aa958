//! Sparse (full symmetric storage, CSC) × dense block products, parallel over rows.
//!
//! Because the matrix is stored with both triangles, column i of the CSC arrays is also row i,
//! so `y[i, c] = Σ_k a_k x[row_k, c]` over column i is a gather dot product that needs no
//! atomics and parallelises over i.

use faer::sparse::SparseColMatRef;
use faer::{MatMut, MatRef};
use rayon::prelude::*;

/// `y = A x` for symmetric `A` stored in full (both triangles).
pub fn sym_spmm(a: SparseColMatRef<'_, usize, f64>, x: MatRef<'_, f64>, mut y: MatMut<'_, f64>) {
    let cp = a.symbolic().col_ptr();
    let ri = a.symbolic().row_idx();
    let nnz_per_col = a.symbolic().col_nnz();
    let v = a.val();
    let n = a.nrows();
    for c in 0..x.ncols() {
        let xc = x.col(c);
        let xs: Vec<f64>;
        let xsl: &[f64] = match xc.try_as_col_major() {
            Some(s) => s.as_slice(),
            None => {
                xs = xc.iter().copied().collect();
                &xs
            }
        };
        let yc = y
            .as_mut()
            .col_mut(c)
            .try_as_col_major_mut()
            .expect("output column is contiguous")
            .as_slice_mut();
        yc.par_chunks_mut(2048)
            .enumerate()
            .for_each(|(chunk, out)| {
                let i0 = chunk * 2048;
                for (di, o) in out.iter_mut().enumerate() {
                    let i = i0 + di;
                    let start = cp[i];
                    let end = match nnz_per_col {
                        Some(nz) => start + nz[i],
                        None => cp[i + 1],
                    };
                    let mut acc = 0.0;
                    for p in start..end {
                        acc += v[p] * xsl[ri[p]];
                    }
                    *o = acc;
                }
            });
        debug_assert_eq!(yc.len(), n);
    }
}
