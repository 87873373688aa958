//! Nested-dissection fill-reducing ordering (METIS `METIS_NodeND`) for the sparse
//! factorisations of both the eigen-solver (the LDLᵀ of `K − σM`, `crate::eigen::factor`) and
//! the static solves ([`super::solve::Cholesky`]: the contact patch's submodels).
//!
//! George's nested dissection (SIAM J. Numer. Anal. 10 (1973) 345–363) in the multilevel form
//! of Karypis & Kumar (SIAM J. Sci. Comput. 20 (1998) 359–392): recursively remove a small
//! vertex separator of the matrix graph and number it last. On the slender rail the
//! separators are rail cross-sections and sleepers, and the factor of the default track holds
//! 17 % fewer entries than with AMD (figures in `crate::eigen::factor`).
//!
//! METIS (Apache-2.0) is compiled from the sources vendored in the `metis-sys` crate (C, built
//! with `cc`; no system library needed). METIS compresses vertices with identical closed
//! adjacency (the three DOFs of one node) before ordering, so the DOF graph is passed as it is.
//!
//! The crate's only `unsafe` outside the contact step's AVX2 kernels (`contact::avx2` and
//! their call sites after the run-time CPU check) and the passage's spinning worker
//! (`dynamics::passage::spin`): one FFI call with buffers whose lengths are checked here. Calls are serialised (METIS keeps its random generator in process-wide
//! state).

/// Why a nested-dissection ordering could not be computed.
#[derive(Debug, thiserror::Error)]
pub enum OrderingError {
    /// `col_ptr` and `row_idx` do not describe an n × n pattern.
    #[error("pattern arrays are inconsistent")]
    InconsistentPattern,
    /// The graph exceeds METIS' 32-bit indices.
    #[error("graph with {vertices} vertices and {adjacency} adjacency entries exceeds METIS' 32-bit indices")]
    TooLarge {
        /// Vertices (matrix columns).
        vertices: usize,
        /// Adjacency entries (off-diagonal entries, both directions).
        adjacency: usize,
    },
    /// METIS_NodeND returned an error status.
    #[error("METIS_NodeND returned status {0}")]
    Metis(i64),
    /// METIS returned something that is not a permutation.
    #[error("METIS returned an invalid permutation")]
    InvalidPermutation,
}

/// Nested-dissection ordering of the symmetric pattern given by its lower triangle in CSC
/// (`col_ptr`, `row_idx`, rows ≥ column; the diagonal may be present).
///
/// Returns `(fwd, inv)` with `fwd[new] = old` (elimination order) and `inv[old] = new`, the
/// convention of faer's `PermRef::new_checked(fwd, inv, n)`. Errors when the graph is too
/// large for METIS' 32-bit indices or METIS reports a failure.
pub fn nested_dissection(
    n: usize,
    col_ptr: &[usize],
    row_idx: &[usize],
) -> Result<(Vec<usize>, Vec<usize>), OrderingError> {
    if n == 0 {
        return Ok((Vec::new(), Vec::new()));
    }
    if col_ptr.len() != n + 1 || *col_ptr.last().unwrap_or(&0) != row_idx.len() {
        return Err(OrderingError::InconsistentPattern);
    }
    // Full adjacency without the diagonal (CSR of a symmetric graph: both directions).
    let mut deg = vec![0usize; n];
    for j in 0..n {
        for &i in &row_idx[col_ptr[j]..col_ptr[j + 1]] {
            if i != j {
                deg[i] += 1;
                deg[j] += 1;
            }
        }
    }
    let total: usize = deg.iter().sum();
    if total >= i32::MAX as usize || n >= i32::MAX as usize {
        return Err(OrderingError::TooLarge {
            vertices: n,
            adjacency: total,
        });
    }
    let mut xadj = vec![0i32; n + 1];
    for v in 0..n {
        xadj[v + 1] = xadj[v] + deg[v] as i32;
    }
    let mut fill: Vec<usize> = xadj[..n].iter().map(|&x| x as usize).collect();
    let mut adjncy = vec![0i32; total];
    for j in 0..n {
        for &i in &row_idx[col_ptr[j]..col_ptr[j + 1]] {
            if i != j {
                adjncy[fill[i]] = j as i32;
                fill[i] += 1;
                adjncy[fill[j]] = i as i32;
                fill[j] += 1;
            }
        }
    }
    // METIS seeds and draws from a process-wide random generator: calls from concurrent
    // threads would interleave its state (different orderings for the same graph), so they
    // are serialised; each call re-seeds it, which makes the ordering reproducible.
    static METIS_LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _guard = METIS_LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let mut nvtxs = n as i32;
    let mut perm = vec![0i32; n];
    let mut iperm = vec![0i32; n];
    // SAFETY: METIS_NodeND reads `nvtxs`, `xadj` (n + 1 entries) and `adjncy` (xadj[n]
    // entries, all in 0..n, built above) and writes n entries into `perm` and `iperm`; vwgt
    // and options are null (unit weights, default options). The buffers outlive the call.
    let status = unsafe {
        metis_sys::METIS_NodeND(
            &mut nvtxs,
            xadj.as_mut_ptr(),
            adjncy.as_mut_ptr(),
            std::ptr::null_mut(),
            std::ptr::null_mut(),
            perm.as_mut_ptr(),
            iperm.as_mut_ptr(),
        )
    };
    if status != metis_sys::rstatus_et_METIS_OK {
        return Err(OrderingError::Metis(status as i64));
    }
    // METIS: row i of the permuted matrix is row perm[i] of the original (perm[new] = old),
    // iperm[old] = new.
    let fwd: Vec<usize> = perm.iter().map(|&p| p as usize).collect();
    let inv: Vec<usize> = iperm.iter().map(|&p| p as usize).collect();
    let ok = fwd.iter().all(|&p| p < n) && (0..n).all(|i| inv[fwd[i]] == i);
    if !ok {
        return Err(OrderingError::InvalidPermutation);
    }
    Ok((fwd, inv))
}

#[cfg(test)]
mod tests {
    use super::nested_dissection;
    /// Lower-triangle CSC of the 5-point Laplacian pattern on an nx × ny grid.
    fn grid(nx: usize, ny: usize) -> (usize, Vec<usize>, Vec<usize>) {
        let n = nx * ny;
        let mut cp = vec![0usize];
        let mut ri = Vec::new();
        for j in 0..n {
            let (x, y) = (j % nx, j / nx);
            ri.push(j);
            if x + 1 < nx {
                ri.push(j + 1);
            }
            if y + 1 < ny {
                ri.push(j + nx);
            }
            cp.push(ri.len());
        }
        (n, cp, ri)
    }

    #[test]
    fn nested_dissection_is_a_valid_permutation() {
        let (n, cp, ri) = grid(30, 20);
        let (fwd, inv) = nested_dissection(n, &cp, &ri).unwrap();
        let mut seen = vec![false; n];
        for &p in &fwd {
            assert!(!seen[p]);
            seen[p] = true;
        }
        for (old, &new) in inv.iter().enumerate() {
            assert_eq!(fwd[new], old);
        }
        assert!(nested_dissection(0, &[0], &[]).unwrap().0.is_empty());
        assert!(nested_dissection(3, &[0, 1], &[0]).is_err());
    }
}
