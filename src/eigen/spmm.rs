//! Sparse (full symmetric storage, CSC) × dense block products, parallel over rows, and the
//! tall-skinny dense products of the block Gram–Schmidt, parallel over row ranges.
//!
//! Because the matrix is stored with both triangles, column i of the CSC arrays is also row i,
//! so `y[i, c] = Σ_k a_k x[row_k, c]` over column i is a gather dot product that needs no
//! atomics and parallelises over i. Up to `COLS` (8, one Lanczos block) columns of `x`,
//! packed row-major, are handled in one sweep over the matrix, so the (memory-bound) matrix
//! is read once per group instead of once per column.
//!
//! The dense products `Vᵀ Z` (j × b, a reduction over the n rows) and `Z −= V C` with a tall
//! `V` (n × j) and a thin `Z` (n × b) are split into `ROW_PARTS` contiguous row ranges, each
//! computed by a sequential gemm and run concurrently; the partial `Vᵀ Z` are summed in range
//! order. faer's own parallel gemm splits these shapes poorly (docs/performance.md §3.2); the
//! row split has one barrier per product. The number of ranges is fixed, not the number of
//! threads, so that the sums, and with them the modes, are bitwise the same whatever the
//! thread count (shards of a sweep run on different machines can be merged).

use faer::linalg::matmul::matmul;
use faer::sparse::SparseColMatRef;
use faer::{Accum, Mat, MatMut, MatRef, Par};
use rayon::prelude::*;

/// Columns of `x` handled in one sweep of the sparse matrix.
const COLS: usize = 8;

/// Rows per parallel task of the sparse product.
const ROW_CHUNK: usize = 2048;

/// Minimum rows per range of the row-split dense products (below: one range, sequential).
const MIN_ROWS_PER_PART: usize = 8192;

/// Row ranges of the row-split dense products of a tall block (at most; fewer when a range
/// would hold fewer than `MIN_ROWS_PER_PART` rows). A constant, not the thread count, so
/// that the order of the reductions does not depend on the machine: more threads than
/// ranges do not speed these products up.
pub(crate) const ROW_PARTS: usize = 2;

/// `y = A x` for symmetric `A` stored in full (both triangles).
///
/// The columns of `x` are taken `COLS` at a time and packed row-major (`COLS` values of
/// one row side by side, zero-padded), so every stored entry of `A` meets one contiguous
/// run of `x` (one cache line) and the inner product vectorises across the columns.
pub fn sym_spmm(a: SparseColMatRef<'_, usize, f64>, x: MatRef<'_, f64>, mut y: MatMut<'_, f64>) {
    let cp = a.symbolic().col_ptr();
    let ri = a.symbolic().row_idx();
    let nnz_per_col = a.symbolic().col_nnz();
    let v = a.val();
    let n = a.nrows();
    debug_assert_eq!(y.nrows(), n);
    let mut packed = vec![0.0f64; n * COLS];
    let mut c0 = 0;
    while c0 < x.ncols() {
        let w = COLS.min(x.ncols() - c0);
        packed
            .par_chunks_mut(ROW_CHUNK * COLS)
            .enumerate()
            .for_each(|(chunk, rows)| {
                let i0 = chunk * ROW_CHUNK;
                for (di, row) in rows.chunks_exact_mut(COLS).enumerate() {
                    for (c, slot) in row.iter_mut().enumerate() {
                        *slot = if c < w { x[(i0 + di, c0 + c)] } else { 0.0 };
                    }
                }
            });
        let xs = &packed;
        // Output: w disjoint columns, written chunk-wise in parallel.
        let mut outs: Vec<&mut [f64]> = Vec::with_capacity(w);
        let mut rest = y.as_mut().subcols_mut(c0, w);
        for _ in 0..w {
            let (first, tail) = rest.split_at_col_mut(1);
            rest = tail;
            let col = first
                .col_mut(0)
                .try_as_col_major_mut()
                .expect("output column is contiguous")
                .as_slice_mut();
            outs.push(col);
        }
        let n_chunks = n.div_ceil(ROW_CHUNK);
        // Split every output column into the same row chunks.
        let mut per_chunk: Vec<Vec<&mut [f64]>> = (0..n_chunks).map(|_| Vec::new()).collect();
        for col in outs {
            for (k, piece) in col.chunks_mut(ROW_CHUNK).enumerate() {
                per_chunk[k].push(piece);
            }
        }
        per_chunk
            .into_par_iter()
            .enumerate()
            .for_each(|(chunk, mut pieces)| {
                let i0 = chunk * ROW_CHUNK;
                let len = pieces[0].len();
                for di in 0..len {
                    let i = i0 + di;
                    let start = cp[i];
                    let end = match nnz_per_col {
                        Some(nz) => start + nz[i],
                        None => cp[i + 1],
                    };
                    let mut acc = [0.0f64; COLS];
                    for (&a_ip, &r) in v[start..end].iter().zip(&ri[start..end]) {
                        let xr: &[f64; COLS] = xs[r * COLS..(r + 1) * COLS]
                            .try_into()
                            .expect("a packed row holds COLS values");
                        for (acc_c, x_c) in acc.iter_mut().zip(xr) {
                            *acc_c += a_ip * x_c;
                        }
                    }
                    for (piece, a) in pieces.iter_mut().zip(acc) {
                        piece[di] = a;
                    }
                }
            });
        c0 += w;
    }
}

/// Row ranges of the row-split dense products of an n-row block: [`ROW_PARTS`] (at least
/// [`MIN_ROWS_PER_PART`] rows each) whatever `par` and the thread count, so that the partial
/// sums of the reductions, and with them the results, are bitwise the same for every `par`
/// and every machine; `par` only decides whether the ranges run concurrently
/// ([`run_concurrently`]).
fn row_parts(n: usize) -> usize {
    ROW_PARTS.min(n / MIN_ROWS_PER_PART).max(1)
}

/// Whether the row ranges of a product run concurrently.
fn run_concurrently(par: Par) -> bool {
    matches!(par, Par::Rayon(t) if t.get() > 1)
}

/// Row ranges `(start, len)` of `threads` nearly equal parts of `0..n`.
fn row_ranges(n: usize, threads: usize) -> Vec<(usize, usize)> {
    (0..threads)
        .map(|t| {
            let a = n * t / threads;
            let b = n * (t + 1) / threads;
            (a, b - a)
        })
        .collect()
}

/// `c = vᵀ z` (j × b) for tall `v` (n × j) and `z` (n × b).
pub(crate) fn tall_t_mul(v: MatRef<'_, f64>, z: MatRef<'_, f64>, par: Par) -> Mat<f64> {
    let (n, j, b) = (v.nrows(), v.ncols(), z.ncols());
    let mut c = Mat::<f64>::zeros(j, b);
    if j == 0 || b == 0 {
        return c;
    }
    let t = row_parts(n);
    if t == 1 {
        matmul(c.as_mut(), Accum::Replace, v.transpose(), z, 1.0, Par::Seq);
        return c;
    }
    let part = |(r0, len): (usize, usize)| {
        let mut p = Mat::<f64>::zeros(j, b);
        matmul(
            p.as_mut(),
            Accum::Replace,
            v.subrows(r0, len).transpose(),
            z.subrows(r0, len),
            1.0,
            Par::Seq,
        );
        p
    };
    let parts: Vec<Mat<f64>> = if run_concurrently(par) {
        row_ranges(n, t).into_par_iter().map(part).collect()
    } else {
        row_ranges(n, t).into_iter().map(part).collect()
    };
    for p in &parts {
        c += p;
    }
    c
}

/// `z += alpha · v c` for tall `v` (n × j), `c` (j × b), `z` (n × b).
pub(crate) fn tall_mul_add(
    mut z: MatMut<'_, f64>,
    v: MatRef<'_, f64>,
    c: MatRef<'_, f64>,
    alpha: f64,
    par: Par,
) {
    let n = v.nrows();
    if v.ncols() == 0 || c.ncols() == 0 {
        return;
    }
    let t = row_parts(n);
    if t == 1 || !run_concurrently(par) {
        // No reduction over rows: the row split does not change the result.
        matmul(z, Accum::Add, v, c, alpha, Par::Seq);
        return;
    }
    // Split z into the row ranges (disjoint mutable views).
    let ranges = row_ranges(n, t);
    let mut views: Vec<(MatMut<'_, f64>, usize, usize)> = Vec::with_capacity(t);
    let mut rest = z.as_mut();
    for &(r0, len) in &ranges {
        let (head, tail) = rest.split_at_row_mut(len);
        views.push((head, r0, len));
        rest = tail;
    }
    views.into_par_iter().for_each(|(zv, r0, len)| {
        matmul(zv, Accum::Add, v.subrows(r0, len), c, alpha, Par::Seq);
    });
}

/// `v[:, 0..k] = v[:, 0..j] · s` in place for tall `v` (n × ≥j) and `s` (j × k, k ≤ j), one
/// row block at a time (parallel over row blocks), so no n × k temporary is allocated.
pub(crate) fn tall_right_mul_in_place(mut v: MatMut<'_, f64>, s: MatRef<'_, f64>, par: Par) {
    let (j, k) = (s.nrows(), s.ncols());
    debug_assert!(k <= j && j <= v.ncols());
    if j == 0 || k == 0 {
        return;
    }
    /// Rows per block: the j-wide input rows and the k-wide product of a block stay in cache.
    const ROWS: usize = 256;
    let n = v.nrows();
    let mut blocks: Vec<MatMut<'_, f64>> = Vec::with_capacity(n.div_ceil(ROWS));
    let mut rest = v.as_mut().subcols_mut(0, j);
    while rest.nrows() > 0 {
        let len = ROWS.min(rest.nrows());
        let (head, tail) = rest.split_at_row_mut(len);
        blocks.push(head);
        rest = tail;
    }
    let work = |blk: MatMut<'_, f64>| {
        let mut tmp = Mat::<f64>::zeros(blk.nrows(), k);
        matmul(tmp.as_mut(), Accum::Replace, blk.as_ref(), s, 1.0, Par::Seq);
        blk.subcols_mut(0, k).copy_from(&tmp);
    };
    if row_parts(n) == 1 || !run_concurrently(par) {
        blocks.into_iter().for_each(work);
    } else {
        blocks.into_par_iter().for_each(work);
    }
}

/// Rows per block of [`tall_update_then_t_mul`]: a block of a 600-column basis (1.2 MB) stays
/// in cache between its two products.
const FUSE_ROWS: usize = 256;

/// For a diagonal `M = diag(d)`: `z ← z − v c`, then returns `vᵀ M z` of the updated `z`, in
/// one sweep over `v` (n × j) by row blocks, so `v` is read from memory once for both
/// products instead of twice (the first pass's update and the second pass's coefficients of
/// the block Gram–Schmidt). Parallel over row ranges like [`tall_mul_add`].
pub(crate) fn tall_update_then_t_mul(
    mut z: MatMut<'_, f64>,
    v: MatRef<'_, f64>,
    c: MatRef<'_, f64>,
    d: &[f64],
    par: Par,
) -> Mat<f64> {
    let (n, j, b) = (v.nrows(), v.ncols(), z.ncols());
    debug_assert_eq!(d.len(), n);
    if j == 0 || b == 0 {
        return Mat::<f64>::zeros(j, b);
    }
    let ranges = row_ranges(n, row_parts(n));
    let mut views: Vec<(MatMut<'_, f64>, usize)> = Vec::with_capacity(ranges.len());
    let mut rest = z.as_mut();
    for &(r0, len) in &ranges {
        let (head, tail) = rest.split_at_row_mut(len);
        views.push((head, r0));
        rest = tail;
    }
    let work = |(mut zv, r0): (MatMut<'_, f64>, usize)| {
        let mut acc = Mat::<f64>::zeros(j, b);
        let mut dz = Mat::<f64>::zeros(FUSE_ROWS.min(zv.nrows()), b);
        let mut i = 0;
        while i < zv.nrows() {
            let len = FUSE_ROWS.min(zv.nrows() - i);
            let vb = v.subrows(r0 + i, len);
            let mut zb = zv.as_mut().subrows_mut(i, len);
            matmul(zb.as_mut(), Accum::Add, vb, c, -1.0, Par::Seq);
            for col in 0..b {
                for r in 0..len {
                    dz[(r, col)] = d[r0 + i + r] * zb[(r, col)];
                }
            }
            matmul(
                acc.as_mut(),
                Accum::Add,
                vb.transpose(),
                dz.as_ref().subrows(0, len),
                1.0,
                Par::Seq,
            );
            i += len;
        }
        acc
    };
    let parts: Vec<Mat<f64>> = if views.len() == 1 || !run_concurrently(par) {
        views.into_iter().map(work).collect()
    } else {
        views.into_par_iter().map(work).collect()
    };
    let mut out = Mat::<f64>::zeros(j, b);
    for p in &parts {
        out += p;
    }
    out
}
