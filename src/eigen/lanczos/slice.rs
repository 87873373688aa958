//! One Lanczos slice: block Lanczos with thick restart at one shift, deflating the modes
//! of the slices below, until its converged prefix holds the wanted pairs.

use super::ctx::{dense_eig, mm, mul_m, OrthoAgainst, EARLY_CHECK_BLOCKS};
use super::{
    lambda_to_hz, matmul, sym_spmm, tall_right_mul_in_place, Accum, Ctx, EigenError, EigenOptions,
    Instant, Mat, MatMut, MatRef, Par, ShiftFactor, SolveWorkspace,
};

/// Result of one slice.
pub(super) struct SliceOut {
    pub(super) lambdas: Vec<f64>,
    /// Per pair, whether its transformed residual meets `tol · θ` without the floor
    /// `θ_max/100` (pairs far from the shift may converge only to the floor): only these are
    /// accurate enough to carry into the next slice.
    pub(super) strict: Vec<bool>,
    pub(super) vecs: Mat<f64>,
    pub(super) restarts: usize,
    pub(super) solved: usize,
}

/// What one Lanczos slice looks for (see [`lanczos_slice`]).
pub(super) struct SliceParams<'a> {
    /// The factorisation of `K − σM` at the slice's shift σ (rad²/s²).
    pub(super) fac: &'a ShiftFactor,
    /// The deflated vectors (n × p, p ≥ 0): M-orthonormal eigenvectors found before.
    pub(super) locked: MatRef<'a, f64>,
    /// Converged pairs wanted (at least 1, raised to the `need` of `known`; cut to what fits
    /// in the problem beside `locked`).
    pub(super) want: usize,
    /// `Some((hi, need))`: the Sturm count puts exactly `need` eigenvalues in the slice below
    /// `hi` (rad²/s²), and the slice ends once its converged prefix holds them; `None`: an
    /// open-ended slice that ends at `want` converged pairs.
    pub(super) known: Option<(f64, usize)>,
    /// `Some(lo)`: a two-sided slice, whose wanted pairs lie in `[lo, hi)` (rad²/s²) on both
    /// sides of σ (about midway); `known` must then be given. `None`: one-sided, λ ≥ σ.
    pub(super) two_sided: Option<f64>,
}

/// Block Lanczos at shift `fac.shift`, deflating `locked`, until the *converged prefix* (the
/// Ritz pairs of largest θ, i.e. λ just above σ, that are all converged) holds `want` pairs,
/// or — when `known = Some((hi, need))` (Sturm count) — until it holds `need` values below
/// `hi`. Returns the converged prefix, ascending λ.
///
/// `two_sided = Some(lo)`: the wanted pairs lie on both sides of σ, in `[lo, hi)` with σ
/// about midway (the first slice of a band whose lower neighbours are not deflated). The
/// prefix is then ordered by |θ| (nearest λ to σ first) and `known` must be given.
///
/// Every cycle extends the Krylov basis ([`Krylov::extend`]), solves the Rayleigh–Ritz
/// problem ([`rayleigh_ritz`]), counts the converged prefix ([`converged_prefix`]) and, once
/// the subspace is full without the wanted pairs, restarts ([`thick_restart`]).
pub(super) fn lanczos_slice(
    ctx: &mut Ctx<'_>,
    sp: &SliceParams<'_>,
    opts: &EigenOptions,
) -> Result<SliceOut, EigenError> {
    let n = ctx.sys.n();
    let locked = sp.locked;
    let p = locked.ncols();
    let sigma = sp.fac.shift;
    let two_sided = sp.two_sided;
    let need = sp.known.map_or(0, |k| k.1);
    let (b, want, m_max) = subspace_size(n, p, sp.want, need, opts)?;
    let round_up = |x: usize| x.div_ceil(b) * b;
    // Convergence is checked when the subspace is full and, from half of it (and at least
    // `want` + 2 blocks) on, every EARLY_CHECK_BLOCKS blocks.
    let early_from = round_up((want + 2 * b).max(m_max / 2));
    let mut kr = Krylov::new(ctx, locked, b, m_max, opts.refine_solves)?;
    let mut j = 0usize;
    let mut restarts = 0usize;
    loop {
        j = kr.extend(ctx, sp.fac, locked, j, early_from)?;
        let rr = rayleigh_ritz(ctx, kr.h.as_ref(), j, b)?;
        let theta = &rr.theta;
        let ritz = Ritz {
            sigma,
            theta,
            s: rr.s.as_ref(),
            es: rr.es.as_ref(),
        };
        // Indices by descending θ (wanted = largest θ = λ just above σ), or by descending |θ|
        // for a two-sided slice.
        let mut order: Vec<usize> = (0..j).rev().collect();
        if two_sided.is_some() {
            order.sort_by(|&a, &b| theta[b].abs().total_cmp(&theta[a].abs()));
        }
        let prefix = converged_prefix(&ritz, &order, two_sided.is_some(), opts.tolerance);
        let done = match sp.known {
            None => prefix >= want,
            Some((hi, need)) => {
                let lo = two_sided.unwrap_or(f64::NEG_INFINITY);
                let below = order[..prefix]
                    .iter()
                    .filter(|&&i| ritz.lambda(i) < hi && ritz.lambda(i) >= lo)
                    .count();
                // The Sturm count guarantees there are exactly `need` below hi: no need to wait
                // for a converged value above hi (that one converges slowly).
                below >= need
            }
        };
        if done {
            let (lambdas, strict, vecs) = ritz_pairs(
                ctx,
                &ritz,
                &order[..prefix],
                kr.v.as_ref().subcols(0, j),
                kr.q.as_ref(),
                opts.tolerance,
            );
            return Ok(SliceOut {
                lambdas,
                strict,
                vecs,
                restarts,
                solved: kr.solved,
            });
        }
        if j + b <= m_max {
            // An early check: the subspace is not full yet, keep extending it.
            continue;
        }
        if restarts >= opts.max_restarts {
            let (hi, expected) = sp
                .known
                .unwrap_or((ritz.lambda(order[want.min(j) - 1]), want));
            return Err(EigenError::MissedModes {
                lo_hz: lambda_to_hz(sigma),
                hi_hz: lambda_to_hz(hi),
                expected,
                found: prefix,
                restarts,
            });
        }
        j = thick_restart(
            ctx,
            &ritz,
            &order,
            (want, m_max, b),
            two_sided.is_some(),
            opts.restart_keep,
            (kr.v.as_mut(), kr.mv.as_mut(), kr.h.as_mut()),
        );
        restarts += 1;
    }
}

/// The Krylov basis of one slice and the work space of its extension.
struct Krylov {
    /// The M-orthonormal basis V (n × m_max; the first j columns are in use).
    v: Mat<f64>,
    /// M·V, kept alongside V so that the Gram–Schmidt passes need no sparse product (empty
    /// for a diagonal M).
    mv: Mat<f64>,
    /// M times the deflated vectors (empty for a diagonal M).
    m_locked: Mat<f64>,
    /// `Op V = [V Q] H`: the projected operator ((m_max + b) × m_max).
    h: Mat<f64>,
    /// The pending block Q (n × b) and `M Q`.
    q: Mat<f64>,
    mq: Mat<f64>,
    /// The next block being formed and its M product (n × b).
    z: Mat<f64>,
    mz: Mat<f64>,
    /// Work space of the Gram–Schmidt passes (n × b).
    scratch: Mat<f64>,
    /// Right-hand side and `K z` of the iterative refinement (n × b; empty without it).
    rhs: Mat<f64>,
    kz: Mat<f64>,
    /// One step of iterative refinement after every solve.
    refine: bool,
    buf: SolveWorkspace,
    /// Right-hand sides solved so far.
    solved: usize,
}

impl Krylov {
    /// The work space of a slice with block size `b` and subspace size `m_max`, deflating
    /// `locked`; the first block Q is random, made M-orthonormal and M-orthogonal to
    /// `locked`.
    fn new(
        ctx: &mut Ctx<'_>,
        locked: MatRef<'_, f64>,
        b: usize,
        m_max: usize,
        refine: bool,
    ) -> Result<Self, EigenError> {
        let n = ctx.sys.n();
        let p = locked.ncols();
        let v = Mat::<f64>::zeros(n, m_max);
        let lumped = ctx.m_diag.is_some();
        let mv = Mat::<f64>::zeros(n, if lumped { 0 } else { m_max });
        let mut m_locked = Mat::<f64>::zeros(n, if lumped { 0 } else { p });
        if p > 0 && !lumped {
            let t = Instant::now();
            sym_spmm(ctx.m, locked, m_locked.as_mut());
            ctx.timing.orthogonalize_spmm_s += t.elapsed().as_secs_f64();
        }
        let scratch = Mat::<f64>::zeros(n, b);
        let h = Mat::<f64>::zeros(m_max + b, m_max);
        let q = Mat::<f64>::from_fn(n, b, |_, _| ctx.rng.next_f64());
        let z = Mat::<f64>::zeros(n, b);
        let mz = Mat::<f64>::zeros(n, b);
        let (rhs, kz) = if refine {
            (Mat::<f64>::zeros(n, b), Mat::<f64>::zeros(n, b))
        } else {
            (Mat::<f64>::zeros(0, 0), Mat::<f64>::zeros(0, 0))
        };
        let buf = ctx.sys.solve_buffer(b);
        // mq = M q throughout (returned by every orthonormalisation).
        let mq = Mat::<f64>::zeros(n, b);
        let mut kr = Krylov {
            v,
            mv,
            m_locked,
            h,
            q,
            mq,
            z,
            mz,
            scratch,
            rhs,
            kz,
            refine,
            buf,
            solved: 0,
        };
        let against = OrthoAgainst {
            locked,
            m_locked: kr.m_locked.as_ref(),
            basis: kr.v.as_ref().subcols(0, 0),
            m_basis: kr.mv.as_ref().subcols(0, 0),
        };
        ctx.orthonormalize(&against, kr.q.as_mut(), kr.mq.as_mut(), &mut kr.scratch)?;
        Ok(kr)
    }

    /// Extends the basis from `j` columns block by block (solve with `fac`, optional
    /// refinement, orthonormalisation against `locked` and V) until it is full or an early
    /// convergence check is due from `early_from` columns on; returns the new size.
    fn extend(
        &mut self,
        ctx: &mut Ctx<'_>,
        fac: &ShiftFactor,
        locked: MatRef<'_, f64>,
        mut j: usize,
        early_from: usize,
    ) -> Result<usize, EigenError> {
        let (n, b) = (self.q.nrows(), self.q.ncols());
        let m_max = self.v.ncols();
        let sigma = fac.shift;
        let lumped = ctx.m_diag.is_some();
        while j + b <= m_max {
            self.v.as_mut().subcols_mut(j, b).copy_from(&self.q);
            if !lumped {
                self.mv.as_mut().subcols_mut(j, b).copy_from(&self.mq);
            }
            self.z.copy_from(&self.mq);
            let t = Instant::now();
            if self.refine {
                self.rhs.copy_from(&self.z);
            }
            ctx.solve(fac, self.z.as_mut(), &mut self.buf);
            ctx.timing.solved_vectors += b;
            self.solved += b;
            if self.refine {
                // One step of iterative refinement: z += A⁻¹ (rhs − (K − σM) z).
                sym_spmm(ctx.k, self.z.as_ref(), self.kz.as_mut());
                mul_m(ctx.m, ctx.m_diag, self.z.as_ref(), self.mz.as_mut());
                for c in 0..b {
                    for r in 0..n {
                        self.rhs[(r, c)] -= self.kz[(r, c)] - sigma * self.mz[(r, c)];
                    }
                }
                ctx.solve(fac, self.rhs.as_mut(), &mut self.buf);
                self.z += &self.rhs;
                ctx.timing.solved_vectors += b;
                self.solved += b;
            }
            ctx.timing.solve_s += t.elapsed().as_secs_f64();
            let t = Instant::now();
            let against = OrthoAgainst {
                locked,
                m_locked: self.m_locked.as_ref(),
                basis: self.v.as_ref().subcols(0, j + b),
                m_basis: self.mv.as_ref().subcols(0, if lumped { 0 } else { j + b }),
            };
            let (c, r) = ctx.orthonormalize(
                &against,
                self.z.as_mut(),
                self.mz.as_mut(),
                &mut self.scratch,
            )?;
            ctx.timing.orthogonalize_s += t.elapsed().as_secs_f64();
            self.h.as_mut().submatrix_mut(0, j, j + b, b).copy_from(&c);
            self.h.as_mut().submatrix_mut(j + b, j, b, b).copy_from(&r);
            std::mem::swap(&mut self.q, &mut self.z);
            std::mem::swap(&mut self.mq, &mut self.mz);
            j += b;
            if j < m_max
                && j >= early_from
                && ((j - early_from) / b).is_multiple_of(EARLY_CHECK_BLOCKS)
            {
                break;
            }
        }
        Ok(j)
    }
}

/// The Rayleigh–Ritz solution of one cycle, owned (borrowed as a [`Ritz`]).
struct RitzSolution {
    /// Ritz values θ = 1/(λ − σ) (s²/rad²), ascending.
    theta: Vec<f64>,
    /// Their eigenvectors in the Krylov basis (j × j).
    s: Mat<f64>,
    /// `E·s` (b × j), whose column norms are the Ritz residuals.
    es: Mat<f64>,
}

/// Rayleigh–Ritz on the symmetric part of the leading `j × j` block of `h` (block size
/// `b`): the Ritz values θ (ascending), their eigenvectors `s` and `E·s` (E: the `b` rows of
/// `h` below that block).
fn rayleigh_ritz(
    ctx: &mut Ctx<'_>,
    h: MatRef<'_, f64>,
    j: usize,
    b: usize,
) -> Result<RitzSolution, EigenError> {
    let t_rr = Instant::now();
    let hj = h.submatrix(0, 0, j, j);
    let t = Mat::<f64>::from_fn(j, j, |r, c| 0.5 * (hj[(r, c)] + hj[(c, r)]));
    let (theta, s) = dense_eig(t.as_ref())?;
    let e = h.submatrix(j, 0, b, j);
    let es = mm(e, s.as_ref(), Par::Seq);
    ctx.timing.rayleigh_ritz_s += t_rr.elapsed().as_secs_f64();
    Ok(RitzSolution { theta, s, es })
}

/// The length of the converged prefix of `order`: the pairs, in that order, up to the first
/// that has not converged. Convergence: ‖Op x − θx‖_M ≤ `tol` · max(θ, θ_max/100) (and θ > 0
/// for a one-sided slice). The floor reflects the attainable accuracy: solves and
/// re-orthogonalisation err by O(u κ)·‖Op‖ with ‖Op‖ = θ_max, so Ritz values far from the
/// shift (θ ≪ θ_max) cannot be resolved to tol relative to their own θ. The true residual of
/// every pair is checked afterwards.
fn converged_prefix(ritz: &Ritz<'_>, order: &[usize], two_sided: bool, tol: f64) -> usize {
    let (theta, es) = (ritz.theta, ritz.es);
    let j = theta.len();
    let theta_abs_max = theta[0].abs().max(theta[j - 1].abs());
    let converged = |idx: usize| -> bool {
        let res = es.col(idx).norm_l2();
        (theta[idx] > 0.0 || two_sided) && res <= tol * theta[idx].abs().max(1e-2 * theta_abs_max)
    };
    order.iter().take_while(|&&i| converged(i)).count()
}

/// Block size `b`, number of wanted pairs and Krylov subspace size `m_max` (a multiple of
/// `b`) of a slice in an `n`-DOF problem with `p` deflated vectors: `want` raised to the
/// Sturm-known `need` (and at least 1), the subspace `subspace_ratio · want` (at least
/// `want + 4b`), both cut to what fits beside the deflated vectors.
fn subspace_size(
    n: usize,
    p: usize,
    want: usize,
    need: usize,
    opts: &EigenOptions,
) -> Result<(usize, usize, usize), EigenError> {
    let avail = n.saturating_sub(p);
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
    Ok((b, want, m_max))
}

/// The Rayleigh–Ritz solution of one Lanczos cycle at shift `sigma` (rad²/s²): Ritz values
/// `theta` (ascending; θ = 1/(λ − σ), s²/rad²), their eigenvectors `s` in the Krylov basis,
/// and `es` = E·s, whose column norms are the Ritz residuals (E: the last block row of H).
struct Ritz<'a> {
    sigma: f64,
    theta: &'a [f64],
    s: MatRef<'a, f64>,
    es: MatRef<'a, f64>,
}

impl Ritz<'_> {
    /// Eigenvalue λ = σ + 1/θ (rad²/s²) of Ritz pair `idx`.
    fn lambda(&self, idx: usize) -> f64 {
        self.sigma + 1.0 / self.theta[idx]
    }
}

/// The converged Ritz pairs `prefix` (indices into `ritz`) as eigenpairs in ascending λ:
/// eigenvalues (rad²/s²), whether each meets `tol · θ` without the floor (strict), and the
/// eigenvectors (n × prefix) after one free inverse-iteration step with the next block `q`
/// of the Krylov basis `v`.
fn ritz_pairs(
    ctx: &mut Ctx<'_>,
    ritz: &Ritz<'_>,
    prefix: &[usize],
    v: MatRef<'_, f64>,
    q: MatRef<'_, f64>,
    tol: f64,
) -> (Vec<f64>, Vec<bool>, Mat<f64>) {
    let t_x = Instant::now();
    let (theta, s, es) = (ritz.theta, ritz.s, ritz.es);
    let j = v.ncols();
    let b = q.ncols();
    let lambda_of = |idx: usize| ritz.lambda(idx);
    let mut sel: Vec<usize> = prefix.to_vec();
    // Ascending λ (for a one-sided slice the prefix is in that order already).
    sel.sort_by(|&a, &b| lambda_of(a).total_cmp(&lambda_of(b)));
    let s_sel = Mat::<f64>::from_fn(j, sel.len(), |r, c| s[(r, sel[c])]);
    let mut vecs = mm(v, s_sel.as_ref(), ctx.par());
    // One free inverse-iteration step: x' = Op x / θ = x + Q (E s)/θ (Op V = V T + Q E).
    // Then K x' − λ M x' = −M r/θ² with r = Op x − θx: the high-frequency content
    // of r is no longer amplified by K − σM (Ericsson & Ruhe 1980, §3).
    let es_sel = Mat::<f64>::from_fn(b, sel.len(), |r, c| es[(r, sel[c])] / theta[sel[c]]);
    matmul(
        vecs.as_mut(),
        Accum::Add,
        q,
        es_sel.as_ref(),
        1.0,
        ctx.par(),
    );
    let lambdas: Vec<f64> = sel.iter().map(|&i| lambda_of(i)).collect();
    let strict: Vec<bool> = sel
        .iter()
        .map(|&i| es.col(i).norm_l2() <= tol * theta[i].abs())
        .collect();
    ctx.timing.restart_s += t_x.elapsed().as_secs_f64();
    (lambdas, strict, vecs)
}

/// Thick restart of a slice's Krylov basis after a full cycle: keeps the `want` Ritz vectors
/// first in `order` plus a fraction `restart_keep` of the rest of the `m_max`-column subspace
/// (block size `b`), among them, for a one-sided slice, the Ritz vectors of undeflated
/// eigenvalues below σ (θ < 0) whose |θ| exceeds the smallest wanted θ. Rewrites V, M·V
/// (`mv`, not kept for a diagonal M) and H (the Ritz values on the diagonal, E·s below) and
/// returns the kept size.
fn thick_restart(
    ctx: &mut Ctx<'_>,
    ritz: &Ritz<'_>,
    order: &[usize],
    (want, m_max, b): (usize, usize, usize),
    two_sided: bool,
    restart_keep: f64,
    (mut v, mut mv, mut h): (MatMut<'_, f64>, MatMut<'_, f64>, MatMut<'_, f64>),
) -> usize {
    let (theta, s, es) = (ritz.theta, ritz.s, ritz.es);
    let j = theta.len();
    let lumped = ctx.m_diag.is_some();
    // Thick restart: keep the Ritz vectors with the largest θ, plus those at the other
    // end (θ < 0: eigenvalues below σ that are not deflated) whose |θ| exceeds the
    // smallest wanted θ. Purging the latter would let them grow back every cycle and
    // pollute the wanted ones; keeping them acts as a soft deflation.
    let t_x = Instant::now();
    // Thick restart keeps the wanted Ritz vectors plus a fraction of the rest of the
    // subspace (measured on the track: keeping 30 % instead of half gives every cycle a
    // longer Krylov sequence and needs ~20 % fewer solves in all).
    let extra = ((m_max - want) as f64 * restart_keep) as usize;
    let kkeep = (want + extra).min(j - b);
    let theta_thr = theta[order[want.min(j) - 1]].max(0.0);
    // (A two-sided slice keeps both ends through its |θ| order already.)
    let neg: Vec<usize> = (0..j)
        .take_while(|&i| !two_sided && theta[i] < 0.0 && -theta[i] >= theta_thr)
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
    ctx.timing.restart_s += t_x.elapsed().as_secs_f64();
    kkeep
}
