//! The Rayleigh–Ritz repair across band bounds, the verification of the residuals and the
//! M-orthonormality, and the checks of the inputs.

use super::ctx::{dense_eig, mm, mul_m, LAMBDA_FLOOR};
use super::{
    sym_spmm, EigenError, EigenOptions, Mat, MatMut, Par, Problem, SparseColMat, SparseColMatRef,
};

/// Relative half-width in λ of the window of modes around a band bound that gets a joint
/// Rayleigh–Ritz step.
pub(super) const BOUND_WINDOW: f64 = 0.20;
/// At most this many modes on each side of a band bound enter that step.
pub(super) const BOUND_WINDOW_MAX: usize = 96;

/// Rayleigh–Ritz step on the columns `x` (approximate eigenvectors, λ ascending in
/// `lambdas`): with `K̂ = XᵀKX`, `M̂ = XᵀMX = Q D Qᵀ` and `W = Q D^{-1/2} Qᵀ`, the eigenpairs
/// `(λ̂, U)` of `W K̂ W` give `X ← X W U` (M-orthonormal) and `λ ← λ̂` (ascending).
pub(super) fn rayleigh_ritz_window(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    mut x: MatMut<'_, f64>,
    lambdas: &mut [f64],
    par: Par,
) -> Result<(), EigenError> {
    let (n, w) = (x.nrows(), x.ncols());
    let mut kx = Mat::<f64>::zeros(n, w);
    let mut mx = Mat::<f64>::zeros(n, w);
    sym_spmm(k, x.as_ref(), kx.as_mut());
    sym_spmm(m, x.as_ref(), mx.as_mut());
    let sym = |a: Mat<f64>| Mat::<f64>::from_fn(w, w, |r, c| 0.5 * (a[(r, c)] + a[(c, r)]));
    let kh = sym(mm(x.as_ref().transpose(), kx.as_ref(), par));
    let mh = sym(mm(x.as_ref().transpose(), mx.as_ref(), par));
    let (d, q) = dense_eig(mh.as_ref())?;
    if d[0] <= 0.5 {
        // The columns are M-orthonormal to ≈1e-7: a Gram matrix this far from I means the
        // band solves returned something else than eigenvectors.
        return Err(EigenError::Factorization {
            shift_rad2_s2: lambdas[0],
            reason: format!("modes at a band bound are not M-orthonormal (smallest Gram eigenvalue {:.3e}); set concurrent_bands = 1", d[0]),
        });
    }
    let qd = Mat::<f64>::from_fn(w, w, |r, c| q[(r, c)] / d[c].sqrt());
    let wm = mm(qd.as_ref(), q.as_ref().transpose(), par);
    let c = sym(mm(
        mm(wm.as_ref(), kh.as_ref(), par).as_ref(),
        wm.as_ref(),
        par,
    ));
    let (lam, u) = dense_eig(c.as_ref())?;
    let s = mm(wm.as_ref(), u.as_ref(), par);
    let y = mm(x.as_ref(), s.as_ref(), par);
    x.copy_from(&y);
    lambdas.copy_from_slice(&lam);
    Ok(())
}

/// A copy of `a` without its stored zero entries (same values, same shape).
pub(crate) fn drop_stored_zeros(a: SparseColMatRef<'_, usize, f64>) -> SparseColMat<usize, f64> {
    let n = a.ncols();
    let mut col_ptr = Vec::with_capacity(n + 1);
    col_ptr.push(0usize);
    let mut row_idx = Vec::new();
    let mut val = Vec::new();
    for j in 0..n {
        for (&i, &v) in a
            .symbolic()
            .row_idx_of_col_raw(j)
            .iter()
            .zip(a.val_of_col(j))
        {
            if v != 0.0 {
                row_idx.push(i);
                val.push(v);
            }
        }
        col_ptr.push(row_idx.len());
    }
    let sym = faer::sparse::SymbolicSparseColMat::new_checked(a.nrows(), n, col_ptr, None, row_idx);
    SparseColMat::new(sym, val)
}

/// ‖A‖_∞ = max row sum of |a_ij| (≥ ‖A‖₂ for symmetric A).
pub(super) fn norm_inf(a: SparseColMatRef<'_, usize, f64>) -> f64 {
    (0..a.ncols())
        .map(|j| a.val_of_col(j).iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// The verification of a solution: per mode the relative residual and the backward error,
/// and the largest deviation of ΦᵀMΦ from I.
pub(super) struct Check {
    pub(super) residuals: Vec<f64>,
    pub(super) backward: Vec<f64>,
    pub(super) orthonormality: f64,
}

/// True residuals and M-orthonormality of the modes `phi` (n × total) with eigenvalues
/// `lambdas`, in chunks of 64 columns. The chunks are independent; with `parallel` they run
/// on all threads (the sparse products inside are sequential), each with its own K x and
/// M x buffers.
pub(super) fn verify(
    problem: &Problem<'_>,
    phi: &Mat<f64>,
    lambdas: &[f64],
    opts: &EigenOptions,
) -> Check {
    let (k, m, m_diag) = (problem.k, problem.m, problem.m_diag);
    let (n, total) = (phi.nrows(), phi.ncols());
    let target = opts.modes_per_slice;
    let (k_norm, m_norm) = (norm_inf(k), norm_inf(m));
    let chunk = 64usize;
    let full = opts.full_orthogonality_check || (n as f64) * (total as f64).powi(2) <= 2e10;
    // One chunk of columns: (relative residuals, backward errors, orthonormality error).
    let check_chunk = |(kx, mx): &mut (Mat<f64>, Mat<f64>), c0: usize| {
        let w = chunk.min(total - c0);
        let x = phi.as_ref().subcols(c0, w);
        sym_spmm(k, x, kx.as_mut().subcols_mut(0, w));
        mul_m(m, m_diag, x, mx.as_mut().subcols_mut(0, w));
        let mut res = Vec::with_capacity(w);
        let mut back = Vec::with_capacity(w);
        for c in 0..w {
            let lam = lambdas[c0 + c];
            let kc = kx.as_ref().col(c);
            let mc = mx.as_ref().col(c);
            let mut num = 0.0;
            for r in 0..n {
                let d = kc[r] - lam * mc[r];
                num += d * d;
            }
            let num = num.sqrt();
            let den = kc.norm_l2() + lam.abs().max(LAMBDA_FLOOR) * mc.norm_l2();
            res.push(num / den);
            let xn = x.col(c).norm_l2();
            back.push(num / ((k_norm + lam.abs() * m_norm) * xn));
        }
        // Orthonormality against this chunk: all columns (full) or a window of neighbours;
        // ΦᵀMΦ is symmetric, so only the columns up to the chunk's last are needed (every
        // pair is met once, by the chunk of its later column).
        let (a0, a1) = if full {
            (0, c0 + w)
        } else {
            let span = 2 * target.max(chunk);
            (c0.saturating_sub(span), c0 + w)
        };
        let g = mm(
            phi.as_ref().subcols(a0, a1 - a0).transpose(),
            mx.as_ref().subcols(0, w),
            Par::Seq,
        );
        let mut orth = 0.0f64;
        for c in 0..w {
            for r in 0..(a1 - a0) {
                let expect = if a0 + r == c0 + c { 1.0 } else { 0.0 };
                orth = orth.max((g[(r, c)] - expect).abs());
            }
        }
        (res, back, orth)
    };
    let width = chunk.min(total.max(1));
    let bufs = || (Mat::<f64>::zeros(n, width), Mat::<f64>::zeros(n, width));
    let starts: Vec<usize> = (0..total).step_by(chunk).collect();
    let parts: Vec<(Vec<f64>, Vec<f64>, f64)> = if opts.parallel {
        use rayon::prelude::*;
        starts
            .par_iter()
            .map_init(bufs, |b, &c0| check_chunk(b, c0))
            .collect()
    } else {
        let mut b = bufs();
        starts.iter().map(|&c0| check_chunk(&mut b, c0)).collect()
    };
    let mut out = Check {
        residuals: Vec::with_capacity(total),
        backward: Vec::with_capacity(total),
        orthonormality: 0.0,
    };
    for (r, bw, o) in parts {
        out.residuals.extend(r);
        out.backward.extend(bw);
        out.orthonormality = out.orthonormality.max(o);
    }
    out
}

pub(super) fn validate(o: &EigenOptions) -> Result<(), EigenError> {
    let bad = |name: &'static str, value: String, reason: &'static str| {
        Err(EigenError::InvalidOption {
            name,
            value,
            reason,
        })
    };
    if !(o.f_max_hz.is_finite() && o.f_max_hz > 0.0) {
        return bad("f_max_hz", o.f_max_hz.to_string(), "must be finite and > 0");
    }
    if !(o.f_min_hz.is_finite() && o.f_min_hz >= 0.0 && o.f_min_hz < o.f_max_hz) {
        return bad(
            "f_min_hz",
            o.f_min_hz.to_string(),
            "must satisfy 0 ≤ f_min < f_max",
        );
    }
    if !(o.tolerance > 0.0 && o.tolerance <= 1e-3) {
        return bad("tolerance", o.tolerance.to_string(), "must be in (0, 1e-3]");
    }
    if o.block_size == 0 || o.block_size > 256 {
        return bad("block_size", o.block_size.to_string(), "must be in 1..=256");
    }
    if !(o.restart_keep >= 0.0 && o.restart_keep <= 0.9) {
        return bad(
            "restart_keep",
            o.restart_keep.to_string(),
            "must be in [0, 0.9]",
        );
    }
    if !(o.subspace_ratio >= 1.5 && o.subspace_ratio <= 10.0) {
        return bad(
            "subspace_ratio",
            o.subspace_ratio.to_string(),
            "must be in [1.5, 10]",
        );
    }
    if let Some(b) = o.concurrent_bands {
        if b == 0 || b > 64 {
            return bad(
                "concurrent_bands",
                b.to_string(),
                "must be in 1..=64 (or unset for one band per thread)",
            );
        }
    }
    if o.modes_per_slice == 0 {
        return bad("modes_per_slice", "0".into(), "must be ≥ 1");
    }
    if let Some(r) = o.rigid_shift_hz {
        if !(r.is_finite() && r > 0.0) {
            return bad("rigid_shift_hz", r.to_string(), "must be finite and > 0");
        }
    }
    Ok(())
}
