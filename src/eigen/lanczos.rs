//! Shift-invert block Lanczos with thick restart and spectrum slicing (see the [`super`]
//! module doc for the method and references).
//!
//! Notation: `V` (n × j) is an M-orthonormal basis, `Q` (n × b) the pending block, and
//! `H` ((j + b) × j) satisfies `Op V = [V Q] H` with `Op = (K − σM)⁻¹M`. The leading j × j part
//! of `H` is the Rayleigh quotient `VᵀM Op V` (symmetric: `Op` is M-self-adjoint), the last
//! b rows `E` couple to `Q`, so a Ritz pair `(θ, V s)` has residual
//! `‖Op V s − θ V s‖_M = ‖E s‖₂` (Wu & Simon 2000, eq. 2.3, block form).
//!
//! Because `H` is formed from the *full* projection of every new block (not just the
//! tridiagonal recurrence coefficients) and `V` is re-orthogonalised twice, the method is a
//! block Krylov–Rayleigh–Ritz iteration that tolerates the arrow-shaped `H` after a thick
//! restart without special cases.

use std::sync::atomic::{AtomicUsize, Ordering as AtomicOrdering};
use std::time::Instant;

use faer::linalg::matmul::matmul;
use faer::sparse::{SparseColMat, SparseColMatRef};
use faer::{Accum, Mat, MatMut, MatRef, Par, Side};

use super::factor::{ShiftFactor, ShiftedSystem, SolveWorkspace};
use super::spmm::{
    sym_spmm, tall_mul_add, tall_right_mul_in_place, tall_t_mul, tall_update_then_t_mul,
};
use super::{
    hz_to_lambda, lambda_to_hz, EigenError, EigenOptions, EigenSolution, EigenTiming, SliceReport,
};

/// λ_floor = (2π · 1 Hz)² in the relative-residual denominator (rad²/s²).
const LAMBDA_FLOOR: f64 = 39.478_417_604_357_43;

/// Deterministic xorshift64* generator for start blocks.
struct Rng(u64);
impl Rng {
    fn next_f64(&mut self) -> f64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        let r = x.wrapping_mul(0x2545_f491_4f6c_dd1d);
        (r >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

fn dense_eig(a: MatRef<'_, f64>) -> Result<(Vec<f64>, Mat<f64>), EigenError> {
    let e = a
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| EigenError::Factorization {
            shift_rad2_s2: f64::NAN,
            reason: format!("dense symmetric eigensolver of a projected matrix failed: {e:?}"),
        })?;
    let s = e.S();
    let vals: Vec<f64> = (0..a.nrows()).map(|i| s[i]).collect();
    Ok((vals, e.U().to_owned()))
}

/// Adds the squared 2-norm of every column of `coef` to `total[i]` and `last[i]`.
fn add_squared_col_norms(coef: MatRef<'_, f64>, total: &mut [f64], last: &mut [f64]) {
    for (i, (t, l)) in total.iter_mut().zip(last.iter_mut()).enumerate() {
        let s2 = coef.col(i).squared_norm_l2();
        *t += s2;
        *l += s2;
    }
}

/// `out = diag(d) · z` (out: n × b, the same shape as z).
fn scale_rows(d: &[f64], z: MatRef<'_, f64>, mut out: MatMut<'_, f64>) {
    for c in 0..z.ncols() {
        for (r, &dr) in d.iter().enumerate() {
            out[(r, c)] = dr * z[(r, c)];
        }
    }
}

/// `y = M x`, by [`scale_rows`] when M is diagonal (`d = Some(diagonal)`), else by
/// [`sym_spmm`].
fn mul_m(
    m: SparseColMatRef<'_, usize, f64>,
    d: Option<&[f64]>,
    x: MatRef<'_, f64>,
    y: MatMut<'_, f64>,
) {
    match d {
        Some(d) => scale_rows(d, x, y),
        None => sym_spmm(m, x, y),
    }
}

/// The diagonal of `m` if `m` (without stored zeros) has exactly its diagonal entries.
fn diagonal_of(m: SparseColMatRef<'_, usize, f64>) -> Option<Vec<f64>> {
    (0..m.ncols())
        .map(
            |j| match (m.symbolic().row_idx_of_col_raw(j), m.val_of_col(j)) {
                ([i], [v]) if *i == j => Some(*v),
                _ => None,
            },
        )
        .collect()
}

/// `a · b` into a new matrix with the given parallelism.
fn mm(a: MatRef<'_, f64>, b: MatRef<'_, f64>, par: Par) -> Mat<f64> {
    let mut c = Mat::<f64>::zeros(a.nrows(), b.ncols());
    matmul(c.as_mut(), Accum::Replace, a, b, 1.0, par);
    c
}

/// Relative size (‖c₁‖ / ‖z‖_M per column) below which the second Gram–Schmidt pass's
/// update of a block is skipped (lumped mass, where its coefficients c₁ come out of the
/// first pass's sweep over V at no extra read). Skipping leaves z M-orthogonal to V to that
/// level instead of to round-off; a Ritz value then errs by at most about this fraction of
/// θ_max, two orders below the convergence floor `tolerance · θ_max / 100` for the default
/// tolerance. On the default track the pass is never needed (docs/performance.md §3.3).
const NEGLIGIBLE_SECOND_PASS: f64 = 1e-12;

/// Blocks between two convergence checks of a Lanczos cycle before its subspace is full (one
/// check costs a dense symmetric eigen-decomposition of the j × j projected matrix, ≈ 0.1 s
/// at j = 600, against ≈ 0.3 s per block of 8 solves and their re-orthogonalisation on the
/// default track).
const EARLY_CHECK_BLOCKS: usize = 4;

/// Work context of one solve.
struct Ctx<'a> {
    k: SparseColMatRef<'a, usize, f64>,
    m: SparseColMatRef<'a, usize, f64>,
    sys: &'a ShiftedSystem,
    /// The diagonal of M when M is diagonal (lumped mass): the Gram–Schmidt passes then need
    /// no stored `M·V` and the two passes share one read of V (see `orthonormalize`).
    m_diag: Option<&'a [f64]>,
    /// Parallelism of the solves, factorisations and dense products, see [`Ctx::par`].
    par: Par,
    /// Concurrent bands still running (see `solve`); `None` for a single band.
    running: Option<&'a AtomicUsize>,
    timing: EigenTiming,
    rng: Rng,
}

impl Ctx<'_> {
    /// Parallelism of the next operation: `Par::Seq` while other concurrent bands run (one
    /// thread per band), `par` once this band is the last one running, so that the threads
    /// whose bands are done help it finish (rayon's work stealing picks up its row-split
    /// products, factorisations and the supernode-parallel parts of its one-group solves).
    fn par(&self) -> Par {
        match self.running {
            Some(r) if r.load(AtomicOrdering::Relaxed) > 1 => Par::Seq,
            _ => self.par,
        }
    }

    /// `z ← (K − σM)⁻¹ z`. A single band solves in column groups, one per thread (fastest).
    /// Concurrent bands solve every block as one group, whose result does not depend on the
    /// parallelism: a band's results then do not depend on when the other bands finish.
    fn solve(&self, fac: &ShiftFactor, z: MatMut<'_, f64>, buf: &mut SolveWorkspace) {
        match self.running {
            Some(_) => self.sys.solve_in_place_one_group(fac, z, buf, self.par()),
            None => self.sys.solve_in_place(fac, z, buf),
        }
    }

    /// Makes `z` M-orthonormal and M-orthogonal to `locked` and `basis` (both M-orthonormal),
    /// given `m_locked = M·locked` and `m_basis = M·basis`. Returns `(c, r)` with
    /// `z_in = locked·(…) + basis·c + z_out·r`; the `locked` part is dropped (it only removes
    /// round-off: `locked` spans eigenvectors, see module doc). Columns that vanish (rank
    /// deficiency) are replaced by random directions with a zero row in `r`. On return `mz`
    /// holds `M·z_out` (the caller keeps it as the next block's `M q` and column of `M V`).
    ///
    /// One round is two passes of block classical Gram–Schmidt ("twice is enough", Giraud et
    /// al., Numer. Math. 101 (2005) 87–100) with the coefficients `(M V)ᵀ z` formed from the
    /// stored `M V`, so the passes need no sparse product (for a diagonal M, `m_locked` and
    /// `m_basis` are empty and the coefficients are `Vᵀ(d∘z)`, the first pass's update and the
    /// second pass's coefficients sharing one sweep over V, and the second pass's update
    /// skipped when those coefficients are negligible, see [`NEGLIGIBLE_SECOND_PASS`]); then
    /// one sparse product `M z`, the
    /// Gram matrix `zᵀ M z` and the symmetric (Löwdin) orthonormalisation `z ← z G^{-1/2}`,
    /// whose `M z ← M z G^{-1/2}` is carried along. Another round follows while a column
    /// still shrank by more than half in the second pass (Kahan–Parlett criterion), the
    /// block's Gram matrix is ill-conditioned (κ(G) > 10⁴: the Löwdin step then leaves an
    /// orthogonality error ≈ u·κ(G)), or a column was replaced by a random vector.
    #[allow(clippy::too_many_arguments)]
    fn orthonormalize(
        &mut self,
        locked: MatRef<'_, f64>,
        m_locked: MatRef<'_, f64>,
        basis: MatRef<'_, f64>,
        m_basis: MatRef<'_, f64>,
        mut z: MatMut<'_, f64>,
        mut mz: MatMut<'_, f64>,
        scratch: &mut Mat<f64>,
    ) -> Result<(Mat<f64>, Mat<f64>), EigenError> {
        let b = z.ncols();
        let j = basis.ncols();
        let n = z.nrows();
        // Tall-skinny products, split over row ranges (see `spmm`).
        let par = self.par();
        if scratch.nrows() != n || scratch.ncols() != b {
            *scratch = Mat::<f64>::zeros(n, b);
        }
        let mut c = Mat::<f64>::zeros(j, b);
        let mut r_acc = Mat::<f64>::identity(b, b);
        let mut passes = 0;
        let mut rounds = 0;
        let mut replaced_last = false;
        let mut again = true;
        while again && rounds < 4 {
            rounds += 1;
            // ‖projected part‖²_M per column over the round, and in its last pass.
            let mut removed = vec![0.0f64; b];
            let mut removed_last = vec![0.0f64; b];
            // The locked vectors are eigenvectors: Op keeps a block M-orthogonal to them up to
            // round-off, so one projection per block suffices (again after a random
            // replacement, which is not orthogonal to them).
            if let Some(d) = self.m_diag {
                // Diagonal M: coefficients Vᵀ(d∘z) from V itself; the first pass's update
                // and the second pass's coefficients in one sweep over V (three reads of V
                // per block instead of four reads of V and M V, two when the second pass is
                // negligible).
                passes += 1;
                let reps = if replaced_last {
                    2
                } else {
                    usize::from(rounds == 1)
                };
                // First pass against the basis, which removes the bulk of z (the Lanczos
                // recurrence), then the locked vectors on what is left: projected before,
                // the round-off of the large z (≈ u‖z‖ along the locked vectors) would stay
                // in the much smaller result (grounded lattice: 1.8e-10 instead of 1e-15).
                let mut c01 = None;
                if j > 0 {
                    scale_rows(d, z.as_ref(), scratch.as_mut());
                    let c0 = tall_t_mul(basis, scratch.as_ref(), par);
                    let c1 = tall_update_then_t_mul(z.as_mut(), basis, c0.as_ref(), d, par);
                    add_squared_col_norms(c0.as_ref(), &mut removed, &mut removed_last);
                    c01 = Some((c0, c1));
                }
                for _ in 0..reps {
                    if locked.ncols() > 0 {
                        scale_rows(d, z.as_ref(), scratch.as_mut());
                        let cl = tall_t_mul(locked, scratch.as_ref(), par);
                        tall_mul_add(z.as_mut(), locked, cl.as_ref(), -1.0, par);
                        add_squared_col_norms(cl.as_ref(), &mut removed, &mut removed_last);
                    }
                }
                removed_last.fill(0.0);
                if let Some((mut c0, c1)) = c01 {
                    // The second pass's update changes z by at most ‖c1‖ (columns of V are
                    // M-orthonormal; the locked projection above is M-orthogonal to V and
                    // leaves c1 as it is): skip its read of V when that is below
                    // `NEGLIGIBLE_SECOND_PASS` of every column's M-norm.
                    let negligible = (0..b).all(|col| {
                        let zz: f64 = (0..n).map(|r| d[r] * z[(r, col)] * z[(r, col)]).sum();
                        c1.col(col).squared_norm_l2()
                            <= NEGLIGIBLE_SECOND_PASS * NEGLIGIBLE_SECOND_PASS * zz
                    });
                    if !negligible {
                        passes += 1;
                        tall_mul_add(z.as_mut(), basis, c1.as_ref(), -1.0, par);
                        add_squared_col_norms(c1.as_ref(), &mut removed, &mut removed_last);
                        c0 += &c1;
                    }
                    matmul(
                        c.as_mut(),
                        Accum::Add,
                        c0.as_ref(),
                        r_acc.as_ref(),
                        1.0,
                        Par::Seq,
                    );
                }
            } else {
                for pass in 0..2 {
                    passes += 1;
                    removed_last.fill(0.0);
                    // Locked vectors after the first basis pass (see the lumped case).
                    if locked.ncols() > 0 && ((rounds == 1 && pass == 1) || replaced_last) {
                        let cl = tall_t_mul(m_locked, z.as_ref(), par);
                        tall_mul_add(z.as_mut(), locked, cl.as_ref(), -1.0, par);
                        add_squared_col_norms(cl.as_ref(), &mut removed, &mut removed_last);
                    }
                    if j > 0 {
                        let cv = tall_t_mul(m_basis, z.as_ref(), par);
                        tall_mul_add(z.as_mut(), basis, cv.as_ref(), -1.0, par);
                        add_squared_col_norms(cv.as_ref(), &mut removed, &mut removed_last);
                        // c += cv · r_acc
                        matmul(
                            c.as_mut(),
                            Accum::Add,
                            cv.as_ref(),
                            r_acc.as_ref(),
                            1.0,
                            Par::Seq,
                        );
                    }
                }
            }
            replaced_last = false;
            let t = Instant::now();
            mul_m(self.m, self.m_diag, z.as_ref(), mz.as_mut());
            self.timing.orthogonalize_spmm_s += t.elapsed().as_secs_f64();
            // Symmetric (Löwdin) orthonormalisation of the block.
            let mut g = tall_t_mul(z.as_ref(), mz.as_ref(), par);
            let gt = g.transpose().to_owned();
            g += gt;
            g *= faer::Scale(0.5);
            // ‖z‖²_M before the round ≈ what was removed + what is left (Pythagoras).
            let before: Vec<f64> = (0..b).map(|i| removed[i] + g[(i, i)].max(0.0)).collect();
            let s_ref = before
                .iter()
                .copied()
                .fold(0.0f64, f64::max)
                .max(f64::MIN_POSITIVE);
            let shrink_last = (0..b)
                .map(|i| {
                    let left = g[(i, i)].max(0.0);
                    (left / (left + removed_last[i]).max(f64::MIN_POSITIVE)).sqrt()
                })
                .fold(f64::INFINITY, f64::min);
            let (lam, u) = dense_eig(g.as_ref())?;
            let mut scaled = u.clone();
            let mut r = Mat::<f64>::zeros(b, b);
            let mut deficient = Vec::new();
            for i in 0..b {
                if lam[i] > 1e-20 * s_ref {
                    let s = lam[i].sqrt();
                    for row in 0..b {
                        scaled[(row, i)] = u[(row, i)] / s;
                        r[(i, row)] = s * u[(row, i)];
                    }
                } else {
                    deficient.push(i);
                    for row in 0..b {
                        scaled[(row, i)] = 0.0;
                    }
                }
            }
            let kappa = lam[b - 1] / lam[0].max(f64::MIN_POSITIVE);
            // z ← z·S and M z ← M z·S.
            for mut x in [z.as_mut(), mz.as_mut()] {
                scratch.fill(0.0);
                tall_mul_add(scratch.as_mut(), x.as_ref(), scaled.as_ref(), 1.0, par);
                x.copy_from(&*scratch);
            }
            for &i in &deficient {
                for row in 0..n {
                    z[(row, i)] = self.rng.next_f64();
                }
                replaced_last = true;
            }
            r_acc = mm(r.as_ref(), r_acc.as_ref(), Par::Seq);
            again = replaced_last || shrink_last < 0.5 || kappa > 1e4;
        }
        if replaced_last {
            // Random columns of the last round (only after 4 rounds): M z is not carried.
            mul_m(self.m, self.m_diag, z.as_ref(), mz.as_mut());
        }
        self.timing.orthogonalization_passes += passes;
        self.timing.orthogonalized_blocks += 1;
        Ok((c, r_acc))
    }
}

/// Result of one slice.
struct SliceOut {
    lambdas: Vec<f64>,
    /// Per pair, whether its transformed residual meets `tol · θ` without the floor
    /// `θ_max/100` (pairs far from the shift may converge only to the floor): only these are
    /// accurate enough to carry into the next slice.
    strict: Vec<bool>,
    vecs: Mat<f64>,
    restarts: usize,
    solved: usize,
}

/// Block Lanczos at shift `fac.shift`, deflating `locked`, until the *converged prefix* (the
/// Ritz pairs of largest θ, i.e. λ just above σ, that are all converged) holds `want` pairs,
/// or — when `known = Some((hi, need))` (Sturm count) — until it holds `need` values below
/// `hi`. Returns the converged prefix, ascending λ.
///
/// `two_sided = Some(lo)`: the wanted pairs lie on both sides of σ, in `[lo, hi)` with σ
/// about midway (the first slice of a band whose lower neighbours are not deflated). The
/// prefix is then ordered by |θ| (nearest λ to σ first) and `known` must be given.
#[allow(clippy::too_many_arguments)]
fn lanczos_slice(
    ctx: &mut Ctx<'_>,
    fac: &ShiftFactor,
    locked: MatRef<'_, f64>,
    want: usize,
    known: Option<(f64, usize)>,
    two_sided: Option<f64>,
    opts: &EigenOptions,
) -> Result<SliceOut, EigenError> {
    let n = ctx.sys.n();
    let p = locked.ncols();
    let sigma = fac.shift;
    let avail = n.saturating_sub(p);
    let need = known.map_or(0, |k| k.1);
    let mut want = want.max(need).max(1);
    let b = opts.block_size.min(avail.saturating_sub(want) / 2).max(1);
    let round_up = |x: usize| x.div_ceil(b) * b;
    let cap = (avail.saturating_sub(b) / b) * b;
    let m_max =
        round_up(((opts.subspace_ratio * want as f64).ceil() as usize).max(want + 4 * b)).min(cap);
    if m_max < want + b {
        want = m_max.saturating_sub(b);
    }
    if want == 0 || want < need {
        return Err(EigenError::InvalidOption {
            name: "block_size / modes_per_slice",
            value: format!("block {b}, {need} modes in slice, {n} DOFs"),
            reason: "the Krylov subspace does not fit in the problem: lower block_size or modes_per_slice",
        });
    }
    // Convergence is checked when the subspace is full and, from half of it (and at least
    // `want` + 2 blocks) on, every EARLY_CHECK_BLOCKS blocks.
    let early_from = round_up((want + 2 * b).max(m_max / 2));
    let mut v = Mat::<f64>::zeros(n, m_max);
    // M·V, kept alongside V so that the Gram–Schmidt passes need no sparse product (not
    // needed for a diagonal M).
    let lumped = ctx.m_diag.is_some();
    let mut mv = Mat::<f64>::zeros(n, if lumped { 0 } else { m_max });
    let mut m_locked = Mat::<f64>::zeros(n, if lumped { 0 } else { p });
    if p > 0 && !lumped {
        let t = Instant::now();
        sym_spmm(ctx.m, locked, m_locked.as_mut());
        ctx.timing.orthogonalize_spmm_s += t.elapsed().as_secs_f64();
    }
    let mut scratch = Mat::<f64>::zeros(n, b);
    let mut h = Mat::<f64>::zeros(m_max + b, m_max);
    let mut q = Mat::<f64>::from_fn(n, b, |_, _| ctx.rng.next_f64());
    let mut z = Mat::<f64>::zeros(n, b);
    let mut mz = Mat::<f64>::zeros(n, b);
    let (mut rhs, mut kz) = if opts.refine_solves {
        (Mat::<f64>::zeros(n, b), Mat::<f64>::zeros(n, b))
    } else {
        (Mat::<f64>::zeros(0, 0), Mat::<f64>::zeros(0, 0))
    };
    let mut buf = ctx.sys.solve_buffer(b);
    // mq = M q throughout (returned by every orthonormalisation).
    let mut mq = Mat::<f64>::zeros(n, b);
    ctx.orthonormalize(
        locked,
        m_locked.as_ref(),
        v.as_ref().subcols(0, 0),
        mv.as_ref().subcols(0, 0),
        q.as_mut(),
        mq.as_mut(),
        &mut scratch,
    )?;
    let mut j = 0usize;
    let mut restarts = 0usize;
    let mut solved = 0usize;
    loop {
        while j + b <= m_max {
            v.as_mut().subcols_mut(j, b).copy_from(&q);
            if !lumped {
                mv.as_mut().subcols_mut(j, b).copy_from(&mq);
            }
            z.copy_from(&mq);
            let t = Instant::now();
            if opts.refine_solves {
                rhs.copy_from(&z);
            }
            ctx.solve(fac, z.as_mut(), &mut buf);
            ctx.timing.solved_vectors += b;
            solved += b;
            if opts.refine_solves {
                // One step of iterative refinement: z += A⁻¹ (rhs − (K − σM) z).
                sym_spmm(ctx.k, z.as_ref(), kz.as_mut());
                mul_m(ctx.m, ctx.m_diag, z.as_ref(), mz.as_mut());
                for c in 0..b {
                    for r in 0..n {
                        rhs[(r, c)] -= kz[(r, c)] - sigma * mz[(r, c)];
                    }
                }
                ctx.solve(fac, rhs.as_mut(), &mut buf);
                z += &rhs;
                ctx.timing.solved_vectors += b;
                solved += b;
            }
            ctx.timing.solve_s += t.elapsed().as_secs_f64();
            let t = Instant::now();
            let (c, r) = ctx.orthonormalize(
                locked,
                m_locked.as_ref(),
                v.as_ref().subcols(0, j + b),
                mv.as_ref().subcols(0, if lumped { 0 } else { j + b }),
                z.as_mut(),
                mz.as_mut(),
                &mut scratch,
            )?;
            ctx.timing.orthogonalize_s += t.elapsed().as_secs_f64();
            h.as_mut().submatrix_mut(0, j, j + b, b).copy_from(&c);
            h.as_mut().submatrix_mut(j + b, j, b, b).copy_from(&r);
            std::mem::swap(&mut q, &mut z);
            std::mem::swap(&mut mq, &mut mz);
            j += b;
            if j < m_max && j >= early_from && ((j - early_from) / b) % EARLY_CHECK_BLOCKS == 0 {
                break;
            }
        }
        // Rayleigh–Ritz on the symmetric part.
        let t_rr = Instant::now();
        let hj = h.as_ref().submatrix(0, 0, j, j);
        let t = Mat::<f64>::from_fn(j, j, |r, c| 0.5 * (hj[(r, c)] + hj[(c, r)]));
        let (theta, s) = dense_eig(t.as_ref())?;
        let e = h.as_ref().submatrix(j, 0, b, j);
        let es = mm(e, s.as_ref(), Par::Seq);
        ctx.timing.rayleigh_ritz_s += t_rr.elapsed().as_secs_f64();
        // Indices by descending θ (wanted = largest θ = λ just above σ), or by descending |θ|
        // for a two-sided slice.
        let mut order: Vec<usize> = (0..j).rev().collect();
        if two_sided.is_some() {
            order.sort_by(|&a, &b| theta[b].abs().total_cmp(&theta[a].abs()));
        }
        // Convergence: ‖Op x − θx‖_M ≤ tol · max(θ, θ_max/100). The floor reflects the
        // attainable accuracy: solves and re-orthogonalisation err by O(u κ)·‖Op‖ with
        // ‖Op‖ = θ_max, so Ritz values far from the shift (θ ≪ θ_max) cannot be resolved to
        // tol relative to their own θ. The true residual of every pair is checked afterwards.
        let theta_abs_max = theta[0].abs().max(theta[j - 1].abs());
        let converged = |idx: usize| -> bool {
            let res = es.as_ref().col(idx).norm_l2();
            (theta[idx] > 0.0 || two_sided.is_some())
                && res <= opts.tolerance * theta[idx].abs().max(1e-2 * theta_abs_max)
        };
        let lambda_of = |idx: usize| sigma + 1.0 / theta[idx];
        let prefix = order.iter().take_while(|&&i| converged(i)).count();
        let done = match known {
            None => prefix >= want,
            Some((hi, need)) => {
                let lo = two_sided.unwrap_or(f64::NEG_INFINITY);
                let below = order[..prefix]
                    .iter()
                    .filter(|&&i| lambda_of(i) < hi && lambda_of(i) >= lo)
                    .count();
                // The Sturm count guarantees there are exactly `need` below hi: no need to wait
                // for a converged value above hi (that one converges slowly).
                below >= need
            }
        };
        if done {
            let t_x = Instant::now();
            let mut sel: Vec<usize> = order[..prefix].to_vec();
            // Ascending λ (for a one-sided slice the prefix is in that order already).
            sel.sort_by(|&a, &b| lambda_of(a).total_cmp(&lambda_of(b)));
            let s_sel = Mat::<f64>::from_fn(j, prefix, |r, c| s[(r, sel[c])]);
            let mut vecs = mm(v.as_ref().subcols(0, j), s_sel.as_ref(), ctx.par());
            // One free inverse-iteration step: x' = Op x / θ = x + Q (E s)/θ (Op V = V T + Q E).
            // Then K x' − λ M x' = −M r/θ² with r = Op x − θx: the high-frequency content
            // of r is no longer amplified by K − σM (Ericsson & Ruhe 1980, §3).
            let es_sel = Mat::<f64>::from_fn(b, prefix, |r, c| es[(r, sel[c])] / theta[sel[c]]);
            matmul(
                vecs.as_mut(),
                Accum::Add,
                q.as_ref(),
                es_sel.as_ref(),
                1.0,
                ctx.par(),
            );
            let lambdas = sel.iter().map(|&i| lambda_of(i)).collect();
            let strict = sel
                .iter()
                .map(|&i| es.as_ref().col(i).norm_l2() <= opts.tolerance * theta[i].abs())
                .collect();
            ctx.timing.restart_s += t_x.elapsed().as_secs_f64();
            return Ok(SliceOut {
                lambdas,
                strict,
                vecs,
                restarts,
                solved,
            });
        }
        if j + b <= m_max {
            // An early check: the subspace is not full yet, keep extending it.
            continue;
        }
        if restarts >= opts.max_restarts {
            let (hi, expected) = known.unwrap_or((lambda_of(order[want.min(j) - 1]), want));
            return Err(EigenError::MissedModes {
                lo_hz: lambda_to_hz(sigma),
                hi_hz: lambda_to_hz(hi),
                expected,
                found: prefix,
                restarts,
            });
        }
        // Thick restart: keep the Ritz vectors with the largest θ, plus those at the other
        // end (θ < 0: eigenvalues below σ that are not deflated) whose |θ| exceeds the
        // smallest wanted θ. Purging the latter would let them grow back every cycle and
        // pollute the wanted ones; keeping them acts as a soft deflation.
        let t_x = Instant::now();
        // Thick restart keeps the wanted Ritz vectors plus a fraction of the rest of the
        // subspace (measured on the track: keeping 30 % instead of half gives every cycle a
        // longer Krylov sequence and needs ~20 % fewer solves in all).
        let extra = ((m_max - want) as f64 * opts.restart_keep) as usize;
        let kkeep = (want + extra).min(j - b);
        let theta_thr = theta[order[want.min(j) - 1]].max(0.0);
        // (A two-sided slice keeps both ends through its |θ| order already.)
        let neg: Vec<usize> = (0..j)
            .take_while(|&i| two_sided.is_none() && theta[i] < 0.0 && -theta[i] >= theta_thr)
            .take((kkeep - want.min(kkeep)) / 2)
            .collect();
        let mut sel: Vec<usize> = order[..kkeep - neg.len()].to_vec();
        sel.extend_from_slice(&neg);
        let s_sel = Mat::<f64>::from_fn(j, kkeep, |r, c| s[(r, sel[c])]);
        tall_right_mul_in_place(v.as_mut(), s_sel.as_ref(), ctx.par());
        if !lumped {
            tall_right_mul_in_place(mv.as_mut(), s_sel.as_ref(), ctx.par());
        }
        let ek = Mat::<f64>::from_fn(b, kkeep, |r, c| es[(r, sel[c])]);
        h.fill(0.0);
        for (i, &idx) in sel.iter().enumerate() {
            h[(i, i)] = theta[idx];
        }
        h.as_mut().submatrix_mut(kkeep, 0, b, kkeep).copy_from(&ek);
        j = kkeep;
        restarts += 1;
        ctx.timing.restart_s += t_x.elapsed().as_secs_f64();
    }
}

/// Computes all eigenpairs of `K φ = λ M φ` with `f_min ≤ f < f_max` (see module doc).
///
/// `k`, `m`: n × n, full symmetric storage (both triangles), K PSD, M PD.
/// `progress`: optional bar; its length is set to the Sturm count and its position to the
/// modes found so far.
pub fn solve(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    opts: &EigenOptions,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<EigenSolution, EigenError> {
    let t_total = Instant::now();
    if k.nrows() != k.ncols() || m.nrows() != m.ncols() || k.nrows() != m.nrows() {
        return Err(EigenError::DimensionMismatch {
            k_rows: k.nrows(),
            k_cols: k.ncols(),
            m_rows: m.nrows(),
            m_cols: m.ncols(),
        });
    }
    validate(opts)?;
    let n = k.nrows();
    if n == 0 {
        return Err(EigenError::InvalidOption {
            name: "K, M",
            value: "0 × 0".into(),
            reason: "the model has no free DOFs",
        });
    }
    let par = if opts.parallel {
        Par::rayon(0)
    } else {
        Par::Seq
    };
    let t = Instant::now();
    let sys = ShiftedSystem::new(k, m, opts.ordering, par)?;
    // Every product with M below uses a copy without the stored zeros: the assembled matrices
    // share one pattern of 3 × 3 DOF blocks, a consistent mass `m_ab I` fills only the
    // diagonal of each block (two thirds of M's stored entries are zeros) and a lumped mass
    // (the default model's) only the diagonal of M (default track to 5 kHz: the M products
    // took 18.4 s, now 0.6 s).
    let m_compact = drop_stored_zeros(m);
    let m = m_compact.as_ref();
    let m_diag_vec = diagonal_of(m);
    let m_diag = m_diag_vec.as_deref();
    let mut ctx = Ctx {
        k,
        m,
        sys: &sys,
        m_diag,
        par,
        running: None,
        timing: EigenTiming {
            symbolic_s: t.elapsed().as_secs_f64(),
            factor_entries: sys.factor_len(),
            ..Default::default()
        },
        rng: Rng(opts.seed | 1),
    };
    let lam_max = hz_to_lambda(opts.f_max_hz);
    // The factorisations at the band's ends are independent: with `parallel` they run
    // side by side.
    let s_first = if opts.f_min_hz == 0.0 {
        let rb = opts
            .rigid_shift_hz
            .unwrap_or((opts.f_max_hz / 100.0).max(1.0));
        -hz_to_lambda(rb)
    } else {
        hz_to_lambda(opts.f_min_hz)
    };
    let end_factor = |shift: f64, direction: f64| {
        let mut c = Ctx {
            k,
            m,
            sys: &sys,
            m_diag,
            par,
            running: None,
            timing: EigenTiming::default(),
            rng: Rng(1),
        };
        factorize(&mut c, shift, direction, lam_max).map(|f| (f, c.timing))
    };
    // Bands the solve will most likely use (it decides once the Sturm counts are known):
    // with two or more, the count probe of `choose_splits` is factorised alongside the ends.
    let likely_bands = match opts.concurrent_bands {
        Some(b) => b,
        None if opts.parallel && n >= AUTO_BANDS_MIN_DOFS => AUTO_BANDS,
        None => 1,
    };
    let probe_x = (likely_bands >= 2).then(|| split_probe_x(likely_bands));
    let probe_factor = || {
        probe_x
            .map(|x| end_factor(lambda_at(s_first, lam_max, x), 1.0))
            .transpose()
    };
    // From 0 Hz: the Sturm count at GROUNDED_TEST · |σ₀| says whether the structure is
    // grounded far enough above σ₀ for the probe of `run_band` to pay (default track: its
    // lowest mode, 74.7 Hz, is below that point, 105 Hz, and this factorisation, beside the
    // others, replaces a probe of 176 solved vectors that could not move the shift).
    let ground_factor = || {
        (opts.f_min_hz == 0.0)
            .then(|| end_factor(GROUNDED_TEST * s_first.abs(), 1.0))
            .transpose()
    };
    let ((top, ground), (first, probe)) = if opts.parallel {
        rayon::join(
            || rayon::join(|| end_factor(lam_max, 1.0), ground_factor),
            || rayon::join(|| end_factor(s_first, -1.0), probe_factor),
        )
    } else {
        (
            (end_factor(lam_max, 1.0), ground_factor()),
            (end_factor(s_first, -1.0), probe_factor()),
        )
    };
    let ((top, t_top), (first, t_first)) = (top?, first?);
    ctx.timing.absorb(&t_top);
    ctx.timing.absorb(&t_first);
    let grounded = match ground? {
        Some((f, t)) => {
            ctx.timing.absorb(&t);
            f.negative_count == 0
        }
        None => false,
    };
    let probe = match (probe?, probe_x) {
        (Some((f, t)), Some(x)) => {
            ctx.timing.absorb(&t);
            Some((x, f))
        }
        _ => None,
    };
    let nu_max = top.negative_count;
    if opts.f_min_hz == 0.0 && first.negative_count != 0 {
        return Err(EigenError::NotSemiDefinite {
            shift_rad2_s2: first.shift,
            negative_pivots: first.negative_count,
        });
    }
    let nu0 = first.negative_count;
    let first_shift = first.shift;
    let total = nu_max.saturating_sub(nu0);
    if let Some(pb) = progress {
        pb.set_length(total as u64);
        pb.set_position(0);
    }
    let from_zero = opts.f_min_hz == 0.0;
    let top_bound = (top.shift, nu_max);
    drop(top);
    let wanted_bands = match opts.concurrent_bands {
        Some(b) => b,
        // Small models: one band (faster, and exactly M-orthogonal across all slices).
        None if opts.parallel && n >= AUTO_BANDS_MIN_DOFS => {
            AUTO_BANDS.min(total / opts.modes_per_slice)
        }
        None => 1,
    };
    // Band bounds: (factorisation at the lower bound, starts at 0 Hz, (upper shift, count)).
    let mut jobs: Vec<(ShiftFactor, bool, (f64, usize))> = Vec::new();
    let mut band_bounds: Vec<f64> = Vec::new();
    if wanted_bands >= 2 && total >= 2 {
        let splits = choose_splits(&mut ctx, &first, top_bound, wanted_bands, lam_max, probe)?;
        let mut lower = first;
        let mut lower_from_zero = from_zero;
        for s in splits {
            let bound = (s.shift, s.negative_count);
            band_bounds.push(s.shift);
            jobs.push((lower, lower_from_zero, bound));
            lower = s;
            lower_from_zero = false;
        }
        jobs.push((lower, lower_from_zero, top_bound));
    } else {
        jobs.push((first, from_zero, top_bound));
    }
    let mut timing = std::mem::take(&mut ctx.timing);
    let bands = jobs.len();
    timing.bands = bands;
    let sys = &sys;
    // One thread per band while several run: the bands' solves then each read their own
    // factor once per block instead of once per column group (see module doc). The last band
    // running goes parallel again (`Ctx::par`).
    let running = AtomicUsize::new(bands);
    // Every band writes its modes into its own columns of one n × total matrix (no copies).
    let mut phi = Mat::<f64>::zeros(n, total);
    let mut views: Vec<MatMut<'_, f64>> = Vec::with_capacity(bands);
    let mut rest = phi.as_mut();
    for (first, _, top) in &jobs {
        let (head, tail) = rest.split_at_col_mut(top.1 - first.negative_count);
        views.push(head);
        rest = tail;
    }
    let run = |i: usize,
               ((first, from_zero, top), view): (
        (ShiftFactor, bool, (f64, usize)),
        MatMut<'_, f64>,
    )| {
        let mut ctx = Ctx {
            k,
            m,
            sys,
            m_diag,
            par,
            running: (bands > 1).then_some(&running),
            timing: EigenTiming::default(),
            // Band 0 keeps the seed of the single-band solver (reproducible results).
            rng: Rng((opts.seed ^ (i as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)) | 1),
        };
        let out = run_band(
            &mut ctx, view, first, from_zero, grounded, top, lam_max, opts, progress,
        );
        running.fetch_sub(1, AtomicOrdering::Relaxed);
        out.map(|out| (out, ctx.timing))
    };
    let outs: Vec<Result<(BandOut, EigenTiming), EigenError>> = if bands > 1 && opts.parallel {
        use rayon::prelude::*;
        jobs.into_par_iter()
            .zip(views)
            .enumerate()
            .map(|(i, job)| run(i, job))
            .collect()
    } else {
        jobs.into_iter()
            .zip(views)
            .enumerate()
            .map(|(i, job)| run(i, job))
            .collect()
    };
    let mut lambdas: Vec<f64> = Vec::with_capacity(total);
    let mut slices: Vec<SliceReport> = Vec::new();
    for out in outs {
        let (band, t) = out?;
        timing.absorb(&t);
        lambdas.extend_from_slice(&band.lambdas);
        slices.extend(band.slices);
    }
    if lambdas.len() != total {
        return Err(EigenError::MissedModes {
            lo_hz: lambda_to_hz(first_shift.max(0.0)),
            hi_hz: opts.f_max_hz,
            expected: total,
            found: lambdas.len(),
            restarts: 0,
        });
    }
    // Sort ascending (slices and bands are ascending already; keep it robust).
    let mut idx: Vec<usize> = (0..lambdas.len()).collect();
    idx.sort_by(|&a, &b| lambdas[a].total_cmp(&lambdas[b]));
    if idx.iter().enumerate().any(|(i, &j)| i != j) {
        let sorted = Mat::<f64>::from_fn(n, idx.len(), |r, c| phi[(r, idx[c])]);
        phi = sorted;
        lambdas = idx.iter().map(|&i| lambdas[i]).collect();
    }
    // Across a band bound the modes were found without deflating each other: their mutual
    // M-orthogonality is only ≈ residual / gap. A Rayleigh–Ritz step on the modes near each
    // bound restores it (and cannot make them worse: the Ritz vectors of a subspace are its
    // best approximations).
    let t_rr = Instant::now();
    for &b in &band_bounds {
        let mid = lambdas.partition_point(|&l| l < b);
        let lo = lambdas
            .partition_point(|&l| l < b - BOUND_WINDOW * b.abs())
            .max(mid.saturating_sub(BOUND_WINDOW_MAX));
        let hi = lambdas
            .partition_point(|&l| l < b + BOUND_WINDOW * b.abs())
            .min(mid + BOUND_WINDOW_MAX);
        if hi > lo + 1 {
            rayleigh_ritz_window(
                k,
                m,
                phi.as_mut().subcols_mut(lo, hi - lo),
                &mut lambdas[lo..hi],
                par,
            )?;
        }
    }
    timing.restart_s += t_rr.elapsed().as_secs_f64();
    let target = opts.modes_per_slice;
    // Verification: true residuals and M-orthonormality.
    let t = Instant::now();
    let (k_norm, m_norm) = (norm_inf(k), norm_inf(m));
    let chunk = 64usize;
    let full = opts.full_orthogonality_check || (n as f64) * (total as f64).powi(2) <= 2e10;
    // One chunk of columns: (relative residuals, backward errors, orthonormality error).
    // The chunks are independent; with `parallel` they run on all threads (the sparse
    // products inside are sequential), each with its own K x and M x buffers.
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
    let mut residuals = Vec::with_capacity(total);
    let mut backward = Vec::with_capacity(total);
    let mut orth_err = 0.0f64;
    for (r, bw, o) in parts {
        residuals.extend(r);
        backward.extend(bw);
        orth_err = orth_err.max(o);
    }
    timing.check_s = t.elapsed().as_secs_f64();
    timing.total_s = t_total.elapsed().as_secs_f64();
    Ok(EigenSolution {
        frequencies_hz: lambdas.iter().map(|&l| lambda_to_hz(l)).collect(),
        eigenvalues_rad2_s2: lambdas,
        modes: phi,
        relative_residuals: residuals,
        backward_errors: backward,
        m_orthonormality_error: orth_err,
        sturm_count: nu_max,
        sturm_count_below_min: nu0,
        slices,
        timing,
    })
}

/// What one band `[lower bound of first, top)` found besides its eigenvectors (written into
/// the band's columns of the solution).
struct BandOut {
    /// Eigenvalues (rad²/s²) in the order of the band's columns.
    lambdas: Vec<f64>,
    /// The band's slices, ascending.
    slices: Vec<SliceReport>,
}

/// Spectrum slicing over one band: from the factorisation `first` at the band's lower bound
/// (`from_zero`: the negative rigid-body shift σ₀ of a band that starts at 0 Hz, with the
/// grounded-structure probe if `grounded`, i.e. no eigenvalue below `GROUNDED_TEST · |σ₀|`;
/// otherwise a bound λ_lo > 0, where the band starts with a two-sided slice) up to
/// `top = (shift, Sturm count)`. The eigenvectors go into `phi` (n × the band's Sturm count)
/// in the order of the returned eigenvalues. `lam_max` (rad²/s²) scales the small moves of a
/// shift that hits a zero pivot.
#[allow(clippy::too_many_arguments)]
fn run_band(
    ctx: &mut Ctx<'_>,
    mut phi: MatMut<'_, f64>,
    first: ShiftFactor,
    from_zero: bool,
    grounded: bool,
    top: (f64, usize),
    lam_max: f64,
    opts: &EigenOptions,
    progress: Option<&indicatif::ProgressBar>,
) -> Result<BandOut, EigenError> {
    let n = ctx.sys.n();
    let (top_shift, nu_max) = top;
    let nu0 = first.negative_count;
    let total = nu_max.saturating_sub(nu0);
    let mut reported = 0usize;
    debug_assert_eq!((phi.nrows(), phi.ncols()), (n, total));
    let mut lambdas: Vec<f64> = Vec::with_capacity(total);
    let mut slices: Vec<SliceReport> = Vec::new();
    let mut cur = first;
    if from_zero && grounded && total > 0 {
        // If the structure is grounded, the lowest eigenvalue λ₁ can lie far above the
        // negative shift σ₀; Lanczos at σ₀ would then see a tightly clustered θ = 1/(λ − σ₀)
        // and converge slowly. A short probe at σ₀ finds λ₁ (a Ritz value ≥ λ₁); if
        // 0.9 λ₁ ≫ |σ₀| and the Sturm count at 0.9 λ₁ is still 0, the first slice starts there.
        // The caller's Sturm count at `GROUNDED_TEST · |σ₀|` has shown that λ₁ lies that
        // high (`grounded`); otherwise the probe could not move the shift and is skipped.
        let probe = {
            let empty = phi.as_ref().subcols(0, 0);
            // Loose tolerance and one wanted value: any Ritz value bounds λ₁ from above
            // (θ_Ritz ≤ θ₁), and the Sturm count at 0.9·l1 decides whether the shift moves.
            let mut popts = opts.clone();
            popts.tolerance = 1e-4;
            lanczos_slice(ctx, &cur, empty, 1, None, None, &popts)?
        };
        let l1 = probe.lambdas.first().copied().unwrap_or(0.0);
        let moved = GROUNDED_SHIFT * l1;
        // (True whenever the probe returned a value: l1 ≥ λ₁ > GROUNDED_TEST · |σ₀|.)
        if moved > GROUNDED_MOVE * cur.shift.abs() {
            let f = factorize(ctx, moved, -1.0, lam_max)?;
            if f.negative_count == 0 {
                cur = f;
            }
        }
    }
    // Converged pairs above the last boundary (λ ≥ τ, from the converged prefix of the
    // previous slice): their vectors sit in phi right after the committed columns, their λ in
    // `carried`. They are eigenpairs of the next slice already, so it deflates them (with all
    // modes found so far) and needs that many fewer new ones; discarding them would make the
    // next slice converge them again. Measured on the default track to 5 kHz with all earlier
    // slices deflated: 3064 solved vectors with carrying, 3120 without (−2 %, within the
    // run-to-run spread of the wall time).
    let mut carried: Vec<f64> = Vec::new();
    // Lower bound of a band above 0 Hz: the modes below it are never deflated here.
    let band_lo = (!from_zero).then_some(cur.shift);
    // Eigenvalues per rad²/s² in the previous slice.
    let mut last_density: Option<f64> = None;
    loop {
        let nu_cur = cur.negative_count;
        if nu_cur >= nu_max {
            break;
        }
        let remaining = nu_max - nu_cur;
        let lo = cur.shift;
        let target = opts.modes_per_slice;
        // A remainder of up to 1.5 targets is one last slice (default track to 5 kHz: a
        // 170-mode last slice instead of a 152-mode one and an 18-mode tail costing a
        // factorisation and ~4 s).
        let last = remaining <= target + target / 2;
        let t_slice = Instant::now();
        // The first slice of a band above 0 Hz cannot deflate the modes below its bound lo
        // (another band's, or below f_min): with the shift at lo they would converge at the
        // negative end of θ as unwanted pairs, about as many as the slice wants and denser
        // in λ (default track to 2 kHz in two bands: 872 solved vectors for the upper band's
        // first 93 modes, against ~3 per mode otherwise). So that slice is two-sided: it
        // wants every eigenvalue in [lo, hi) (Sturm count known) with the Lanczos shift at
        // the midpoint, where the undeflated ones below lo are farther from the shift than
        // every wanted one.
        let two_sided = !from_zero && slices.is_empty();
        let mut sided = two_sided;
        let col0 = lambdas.len();
        let nc = carried.len();
        // Deflated: every mode found so far and the carried pairs (contiguous in phi). The
        // modes of earlier slices lie below σ at θ = 1/(λ − σ) < 0; left in, the ones of the
        // slices before the last compete with the far end of the wanted θ and converge as
        // unwanted Ritz values (default track to 5 kHz, subspace ratio 3: deflating only the
        // previous slice solved 3592 vectors, deflating all 2880, and the M-orthonormality
        // error of the whole basis fell from 1.3e-8 to 2.5e-14).
        let locked_range = (0, col0 + nc);
        let mut mid: Option<ShiftFactor> = None;
        // In a band above 0 Hz a slice whose width exceeds CAP_RATIO × its distance from the
        // band's lower bound would meet the undeflated modes below that bound at the far end
        // of θ. Such a slice ends at the cap instead, with the Sturm count known there
        // (default track to 5 kHz in two bands: the upper band's second slice, as wide as
        // that distance, needed 4 restarts and 5.8 solved vectors per mode). The band's last
        // slice is two-sided (shift at its midpoint m, half-width h): the same margin,
        // h ≤ CAP_RATIO · (m − bound), allows it a width of up to
        // 2·CAP_RATIO/(1 − CAP_RATIO) = 4.7 times that distance (default track to 5 kHz:
        // a 183-mode last slice of 536 vectors instead of a capped 97-mode one of 464 and
        // an 86-mode last one of 264).
        let capped = match (band_lo, last_density) {
            (Some(b), Some(rho))
                if !(two_sided || (last && top_shift - lo <= TWO_SIDED_CAP_RATIO * (lo - b))) =>
            {
                let cap = lo + CAP_RATIO * (lo - b);
                if cap < top_shift && rho * (cap - lo) <= (target + target / 4) as f64 {
                    let f = factorize(ctx, cap, 1.0, lam_max)?;
                    (f.negative_count > nu_cur && f.negative_count < nu_max && f.shift < top_shift)
                        .then_some(f)
                } else {
                    None
                }
            }
            _ => None,
        };
        let mut out;
        // A slice to a bound whose Sturm count is known: the cap, or the band top.
        let known_end = match capped {
            Some(f) => Some((f.shift, f.negative_count, Some(f))),
            None if last && !two_sided => Some((top_shift, nu_max, None)),
            None => None,
        };
        let (hi, nu_hi, next) = if let Some((hi, nu_hi, next)) = known_end {
            let carried_below = carried.iter().filter(|&&x| x < hi).count();
            let need_new = (nu_hi - nu_cur).saturating_sub(carried_below);
            let want = need_new + opts.block_size.max((nu_hi - nu_cur) / 5);
            let locked = phi.as_ref().subcols(locked_range.0, locked_range.1);
            // The band's last slice is two-sided (deflating everything below lo): with the
            // shift midway, its modes near the band top lie half as far from the shift as
            // with the shift at lo, so they converge sooner and more accurately (default
            // track to 5 kHz: 416 instead of 536 solved vectors in the upper band's last
            // slice, and the M-orthogonality across the band bound 5e-8 instead of 2e-7).
            out = if next.is_none() {
                let m = factorize(ctx, 0.5 * (lo + hi), 1.0, lam_max)?;
                let o = lanczos_slice(ctx, &m, locked, want, Some((hi, need_new)), Some(lo), opts)?;
                mid = Some(m);
                sided = true;
                o
            } else {
                lanczos_slice(ctx, &cur, locked, want, Some((hi, need_new)), None, opts)?
            };
            (hi, nu_hi, next)
        } else if two_sided {
            // Width of about `target` modes (count model ν ∝ λ^{3/2} up to the band top),
            // corrected once if the Sturm count says it holds more than 1.2 targets: this
            // slice deflates nothing and needs more solves per mode than any other
            // (default track to 5 kHz: 185 modes, 616 vectors; corrected to 100 modes, 320
            // vectors, and the band's two-sided last slice, which deflates them, 183 modes
            // in 536 vectors).
            let mut w = if last {
                top_shift - lo
            } else {
                (top_shift * ((nu_cur + target) as f64 / nu_max as f64).powf(2.0 / 3.0) - lo)
                    .max(1e-3 * top_shift)
            };
            let mut bound = None;
            for _ in 0..2 {
                if lo + w >= top_shift {
                    bound = None;
                    break;
                }
                let f = factorize(ctx, lo + w, 1.0, lam_max)?;
                let count = f.negative_count - nu_cur;
                let too_many = count > target + target / 5;
                bound = Some(f);
                if !too_many {
                    break;
                }
                w *= target as f64 / count as f64;
            }
            let (hi, nu_hi, next) = match bound {
                Some(f) if f.negative_count < nu_max && f.shift < top_shift => {
                    (f.shift, f.negative_count, Some(f))
                }
                _ => (top_shift, nu_max, None),
            };
            let need = nu_hi - nu_cur;
            let m = factorize(ctx, 0.5 * (lo + hi), 1.0, lam_max)?;
            let want = need + opts.block_size.max(need / 5);
            out = lanczos_slice(
                ctx,
                &m,
                phi.as_ref().subcols(0, 0),
                want,
                Some((hi, need)),
                Some(lo),
                opts,
            )?;
            mid = Some(m);
            (hi, nu_hi, next)
        } else {
            // The slice stops once `want` pairs converged (early convergence checks) and
            // the boundary below keeps 2/3 or more of them: 1.25 targets keep about one.
            let want = (target + target / 4).saturating_sub(nc).max(target / 2);
            out = {
                let locked = phi.as_ref().subcols(locked_range.0, locked_range.1);
                lanczos_slice(ctx, &cur, locked, want, None, None, opts)?
            };
            // Boundary in the widest relative gap of the last third of the converged λ
            // (carried and new; everything below it has converged; a wide gap keeps K − τM
            // well conditioned).
            let mut l: Vec<f64> = out.lambdas.iter().copied().filter(|&x| x >= lo).collect();
            l.extend_from_slice(&carried);
            l.sort_by(f64::total_cmp);
            let tau = if l.len() >= 2 {
                let k0 = (2 * l.len() / 3).min(l.len() - 2);
                let kbest = (k0..l.len() - 1)
                    .max_by(|&a, &b| {
                        let ga = (l[a + 1] - l[a]) / l[a + 1].abs().max(1e-300);
                        let gb = (l[b + 1] - l[b]) / l[b + 1].abs().max(1e-300);
                        ga.total_cmp(&gb)
                    })
                    .unwrap_or(k0);
                0.5 * (l[kbest] + l[kbest + 1])
            } else {
                top_shift
            };
            if tau >= top_shift {
                (top_shift, nu_max, None)
            } else {
                let f = factorize(ctx, tau, 1.0, lam_max)?;
                (f.shift, f.negative_count, Some(f))
            }
        };
        let need = nu_hi - nu_cur;
        let carried_in = carried.iter().filter(|&&x| x < hi).count();
        let select = |o: &SliceOut| -> Vec<usize> {
            (0..o.lambdas.len())
                .filter(|&i| o.lambdas[i] >= lo && o.lambdas[i] < hi)
                .collect()
        };
        let mut keep = select(&out);
        if keep.len() + carried_in != need {
            // The Sturm count says the converged prefix skipped an eigenvalue (e.g. a
            // multiplicity larger than the block): iterate again with the count known.
            out = {
                let locked = phi.as_ref().subcols(locked_range.0, locked_range.1);
                let nl = need.saturating_sub(carried_in);
                let lf = mid.as_ref().unwrap_or(&cur);
                let wide = if sided { 2 * nl } else { nl };
                lanczos_slice(
                    ctx,
                    lf,
                    locked,
                    wide + opts.block_size,
                    Some((hi, nl)),
                    sided.then_some(lo),
                    opts,
                )?
            };
            keep = select(&out);
            if keep.len() + carried_in != need {
                return Err(EigenError::MissedModes {
                    lo_hz: lambda_to_hz(lo),
                    hi_hz: lambda_to_hz(hi),
                    expected: need,
                    found: keep.len() + carried_in,
                    restarts: out.restarts,
                });
            }
        }
        drop(mid);
        // Layout from col0: the slice's modes (carried ones below hi, then the new ones), then
        // the pairs carried on (carried ones at or above hi, then new converged ones between
        // hi and λ_max, as many as fit).
        let old_carried = phi.as_ref().subcols(col0, nc).to_owned();
        let mut next_carried: Vec<(f64, usize, bool)> = Vec::new(); // (λ, index, from old)
        let mut c = col0;
        for (i, &x) in carried.iter().enumerate() {
            if x < hi {
                phi.as_mut().col_mut(c).copy_from(old_carried.col(i));
                lambdas.push(x);
                c += 1;
            } else {
                next_carried.push((x, i, true));
            }
        }
        for &i in &keep {
            phi.as_mut().col_mut(c).copy_from(out.vecs.col(i));
            lambdas.push(out.lambdas[i]);
            c += 1;
        }
        if next.is_some() {
            // Carried: the strictly converged pairs above hi, up to the first that is not
            // (the next slice must find every eigenvalue above the carried ones itself).
            for (i, &x) in out.lambdas.iter().enumerate() {
                if x >= hi && x < top_shift {
                    if !out.strict[i] {
                        break;
                    }
                    next_carried.push((x, i, false));
                }
            }
        }
        next_carried.sort_by(|a, b| a.0.total_cmp(&b.0));
        next_carried.truncate(total.saturating_sub(c));
        carried.clear();
        for &(x, i, from_old) in &next_carried {
            let src = if from_old {
                old_carried.col(i)
            } else {
                out.vecs.col(i)
            };
            phi.as_mut().col_mut(c).copy_from(src);
            carried.push(x);
            c += 1;
        }
        last_density = Some((nu_hi - nu_cur) as f64 / (hi - lo).max(f64::MIN_POSITIVE));
        slices.push(SliceReport {
            shift_lo_rad2_s2: lo,
            shift_hi_rad2_s2: hi,
            sturm_lo: nu_cur,
            sturm_hi: nu_hi,
            modes_found: need,
            carried: carried_in,
            restarts: out.restarts,
            solved_vectors: out.solved,
            lanczos_s: t_slice.elapsed().as_secs_f64(),
        });
        if let Some(pb) = progress {
            pb.inc((lambdas.len() - reported) as u64);
            reported = lambdas.len();
        }
        match next {
            Some(f) => cur = f,
            None => break,
        }
    }
    Ok(BandOut { lambdas, slices })
}

/// Fraction of the probed λ₁ (an upper bound of it) where the grounded-structure probe of
/// `run_band` puts the first shift (kept only if the Sturm count there is 0).
const GROUNDED_SHIFT: f64 = 0.9;

/// The probe moves the first shift from σ₀ < 0 up to `GROUNDED_SHIFT` · λ₁ only if that
/// exceeds `GROUNDED_MOVE` · |σ₀|.
const GROUNDED_MOVE: f64 = 4.0;

/// Where the caller counts eigenvalues before that probe, as a multiple of |σ₀|: no
/// eigenvalue below it ⇔ λ₁ > GROUNDED_MOVE / GROUNDED_SHIFT · |σ₀|, the condition under
/// which the probe can move the shift.
const GROUNDED_TEST: f64 = GROUNDED_MOVE / GROUNDED_SHIFT;

/// λ (rad²/s²) at the fraction `x` of the way from `lo` to `hi` in √λ (i.e. in frequency),
/// `x = (√λ − √λ_lo)/(√λ_hi − √λ_lo)` with a negative `lo` (rigid-body shift) taken as 0.
fn lambda_at(lo: f64, hi: f64, x: f64) -> f64 {
    let (a, b) = (lo.max(0.0).sqrt(), hi.max(0.0).sqrt());
    (a + x * (b - a)).powi(2)
}

/// Work of the modes up to `x` (see [`choose_splits`]) for the count exponent `alpha`.
fn band_work(x: f64, alpha: f64) -> f64 {
    x.powf(alpha) + 2.0 * alpha / (alpha + 2.0) * x.powf(alpha + 2.0)
}

/// `x` in [0, 1] where `band_work(x, alpha)` reaches `goal` (bisection; the work increases).
fn work_point(goal: f64, alpha: f64) -> f64 {
    let (mut x0, mut x1) = (0.0f64, 1.0f64);
    for _ in 0..60 {
        let xm = 0.5 * (x0 + x1);
        if band_work(xm, alpha) < goal {
            x0 = xm;
        } else {
            x1 = xm;
        }
    }
    0.5 * (x0 + x1)
}

/// Where the count probe of [`choose_splits`] goes, for `bands` bands: the first split of
/// the prior α = 1 (the default track's exponent), so that on such a model the probe is the
/// bound itself and no further factorisation is needed. Known before any Sturm count, so the
/// probe is factorised alongside the band's ends.
fn split_probe_x(bands: usize) -> f64 {
    work_point(band_work(1.0, 1.0) / bands.max(2) as f64, 1.0)
}

/// Tolerance in x within which the probe serves as a band bound.
const PROBE_AS_BOUND: f64 = 0.03;

/// Band bounds for `bands` concurrent bands between the factorisations `first` (lower bound)
/// and `top = (shift, Sturm count)`: factorisations of `K − λ_i M`, ascending, chosen so that
/// every band has about the same *work*. With `x = (√λ − √λ_lo)/(√λ_top − √λ_lo)` the count
/// model is `ν(λ) − ν₀ ≈ N·x^α`, fitted to one probe `(x_p, factorisation at x_p)` (the
/// default track has α ≈ 1: its rail and sleepers are slender; without a probe one is
/// factorised at x = ½), and a mode at x costs `1 + 2x²` units (the slices near f_max take
/// longer per mode: denser spectrum in θ, more deflated modes; docs/performance.md §3.3).
/// Band i then ends where the work `W(x) = x^α + 2α/(α+2)·x^{α+2}` reaches
/// `i/bands · W(1)`; the probe is that bound if it lies within [`PROBE_AS_BOUND`] of it. A split whose count does not lie
/// strictly between its neighbours' is dropped (fewer, non-empty bands).
fn choose_splits(
    ctx: &mut Ctx<'_>,
    first: &ShiftFactor,
    top: (f64, usize),
    bands: usize,
    lam_max: f64,
    probe: Option<(f64, ShiftFactor)>,
) -> Result<Vec<ShiftFactor>, EigenError> {
    let nu0 = first.negative_count;
    let total = top.1.saturating_sub(nu0).max(1) as f64;
    let lam_at = |x: f64| lambda_at(first.shift, top.0, x);
    let (xp, probe) = match probe {
        Some(p) => p,
        None => (0.5, factorize(ctx, lam_at(0.5), 1.0, lam_max)?),
    };
    let frac = probe.negative_count.saturating_sub(nu0) as f64 / total;
    let alpha = if frac <= 0.0 {
        4.0
    } else if frac >= 1.0 {
        0.25
    } else {
        (frac.ln() / xp.ln()).clamp(0.25, 4.0)
    };
    let mut probe = Some(probe);
    let mut out: Vec<ShiftFactor> = Vec::new();
    for i in 1..bands {
        let x = work_point(i as f64 / bands as f64 * band_work(1.0, alpha), alpha);
        let f = match probe.take() {
            Some(p) if (x - xp).abs() <= PROBE_AS_BOUND => p,
            other => {
                probe = other;
                factorize(ctx, lam_at(x), 1.0, lam_max)?
            }
        };
        let above_last = out.last().map_or(nu0, |l| l.negative_count);
        if f.negative_count > above_last && f.negative_count < top.1 && f.shift < top.0 {
            out.push(f);
        }
    }
    Ok(out)
}

/// Smallest model (free DOFs) that is split into concurrent bands by default: below it the
/// solves are cheap and not memory-bound, and one band is as fast.
const AUTO_BANDS_MIN_DOFS: usize = 20_000;

/// Concurrent bands of a model of at least [`AUTO_BANDS_MIN_DOFS`] free DOFs by default. A
/// constant, not the thread count: the band bounds decide which slice finds which mode, so
/// they must not depend on the machine for the modes to be bitwise reproducible everywhere.
const AUTO_BANDS: usize = 2;

/// Largest width of a slice in a band above 0 Hz, as a multiple of its distance from the
/// band's lower bound (see `run_band`).
const CAP_RATIO: f64 = 0.7;

/// Widest two-sided last slice of a band above 0 Hz, as a multiple of its distance from the
/// band's lower bound: the margin of [`CAP_RATIO`] for a shift at the slice's midpoint.
const TWO_SIDED_CAP_RATIO: f64 = 2.0 * CAP_RATIO / (1.0 - CAP_RATIO);

/// Relative half-width in λ of the window of modes around a band bound that gets a joint
/// Rayleigh–Ritz step.
const BOUND_WINDOW: f64 = 0.20;
/// At most this many modes on each side of a band bound enter that step.
const BOUND_WINDOW_MAX: usize = 96;

/// Rayleigh–Ritz step on the columns `x` (approximate eigenvectors, λ ascending in
/// `lambdas`): with `K̂ = XᵀKX`, `M̂ = XᵀMX = Q D Qᵀ` and `W = Q D^{-1/2} Qᵀ`, the eigenpairs
/// `(λ̂, U)` of `W K̂ W` give `X ← X W U` (M-orthonormal) and `λ ← λ̂` (ascending).
fn rayleigh_ritz_window(
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
fn drop_stored_zeros(a: SparseColMatRef<'_, usize, f64>) -> SparseColMat<usize, f64> {
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
fn norm_inf(a: SparseColMatRef<'_, usize, f64>) -> f64 {
    (0..a.ncols())
        .map(|j| a.val_of_col(j).iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// Factorises `K − σM`; on a zero pivot moves σ by a small relative amount in `direction`
/// (±1) and retries (σ hit an eigenvalue of a leading block). `scale` (rad²/s²) sets the size
/// of the move.
fn factorize(
    ctx: &mut Ctx<'_>,
    shift: f64,
    direction: f64,
    scale: f64,
) -> Result<ShiftFactor, EigenError> {
    let mut s = shift;
    for attempt in 0..6 {
        let t = Instant::now();
        let f = ctx.sys.factorize_with(s, ctx.par())?;
        ctx.timing.factorize_s += t.elapsed().as_secs_f64();
        ctx.timing.factorizations += 1;
        if let Some(f) = f {
            if f.min_rel_pivot > 1e-14 {
                return Ok(f);
            }
        }
        s = shift + direction * scale * 1e-6 * 10f64.powi(attempt);
    }
    Err(EigenError::Factorization {
        shift_rad2_s2: shift,
        reason: "zero or tiny pivots in LDLᵀ even after moving the shift; check that M is positive definite and K has no NaN".into(),
    })
}

fn validate(o: &EigenOptions) -> Result<(), EigenError> {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Closed form: a two-sided slice `[lo, lo + w)` with `w = TWO_SIDED_CAP_RATIO · (lo − b)`
    /// has its shift at `m = lo + w/2`, and its half-width is exactly `CAP_RATIO` times the
    /// distance from `m` down to the band bound `b` (the one-sided margin), for any `lo > b`.
    #[test]
    fn two_sided_cap_keeps_the_one_sided_margin() {
        for (b, lo) in [(0.0, 1.0), (4.1e8, 4.2e8), (1e3, 9e9)] {
            let w = TWO_SIDED_CAP_RATIO * (lo - b);
            let (h, m) = (0.5 * w, lo + 0.5 * w);
            approx::assert_relative_eq!(h / (m - b), CAP_RATIO, max_relative = 1e-12);
        }
    }
}
