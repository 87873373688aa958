//! The work context of a solve (matrices, factor solves, block Gram–Schmidt, timing), its
//! random start blocks, the dense helpers and the shift factorisation with zero-pivot moves.

use super::{
    matmul, sym_spmm, tall_mul_add, tall_t_mul, tall_update_then_t_mul, Accum, AtomicOrdering,
    AtomicUsize, EigenError, EigenTiming, Instant, Mat, MatMut, MatRef, Par, ShiftFactor,
    ShiftedSystem, Side, SolveWorkspace, SparseColMatRef,
};

/// λ_floor = (2π · [`crate::eigen::RESIDUAL_FLOOR_HZ`])² in the relative-residual
/// denominator (rad²/s²).
pub(super) const LAMBDA_FLOOR: f64 = (2.0 * std::f64::consts::PI * crate::eigen::RESIDUAL_FLOOR_HZ)
    * (2.0 * std::f64::consts::PI * crate::eigen::RESIDUAL_FLOOR_HZ);

/// Deterministic xorshift64* generator for start blocks.
pub(super) struct Rng(pub(super) u64);
impl Rng {
    pub(super) fn next_f64(&mut self) -> f64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        let r = x.wrapping_mul(0x2545_f491_4f6c_dd1d);
        (r >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

pub(super) fn dense_eig(a: MatRef<'_, f64>) -> Result<(Vec<f64>, Mat<f64>), EigenError> {
    let e = a
        .self_adjoint_eigen(Side::Lower)
        .map_err(|error| EigenError::DenseEigen {
            what: "projected Lanczos matrix",
            error,
        })?;
    let s = e.S();
    let vals: Vec<f64> = (0..a.nrows()).map(|i| s[i]).collect();
    Ok((vals, e.U().to_owned()))
}

/// Adds the squared 2-norm of every column of `coef` to `total[i]` and `last[i]`.
pub(super) fn add_squared_col_norms(coef: MatRef<'_, f64>, total: &mut [f64], last: &mut [f64]) {
    for (i, (t, l)) in total.iter_mut().zip(last.iter_mut()).enumerate() {
        let s2 = coef.col(i).squared_norm_l2();
        *t += s2;
        *l += s2;
    }
}

/// `out = diag(d) · z` (out: n × b, the same shape as z).
pub(super) fn scale_rows(d: &[f64], z: MatRef<'_, f64>, mut out: MatMut<'_, f64>) {
    for c in 0..z.ncols() {
        for (r, &dr) in d.iter().enumerate() {
            out[(r, c)] = dr * z[(r, c)];
        }
    }
}

/// `y = M x`, by [`scale_rows`] when M is diagonal (`d = Some(diagonal)`), else by
/// [`sym_spmm`].
pub(super) fn mul_m(
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
pub(super) fn diagonal_of(m: SparseColMatRef<'_, usize, f64>) -> Option<Vec<f64>> {
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
pub(super) fn mm(a: MatRef<'_, f64>, b: MatRef<'_, f64>, par: Par) -> Mat<f64> {
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
pub(super) const NEGLIGIBLE_SECOND_PASS: f64 = 1e-12;

/// Blocks between two convergence checks of a Lanczos cycle before its subspace is full (one
/// check costs a dense symmetric eigen-decomposition of the j × j projected matrix, ≈ 0.1 s
/// at j = 600, against ≈ 0.3 s per block of 8 solves and their re-orthogonalisation on the
/// default track).
pub(super) const EARLY_CHECK_BLOCKS: usize = 4;

/// Work context of one solve.
pub(super) struct Ctx<'a> {
    pub(super) k: SparseColMatRef<'a, usize, f64>,
    pub(super) m: SparseColMatRef<'a, usize, f64>,
    pub(super) sys: &'a ShiftedSystem,
    /// The diagonal of M when M is diagonal (lumped mass): the Gram–Schmidt passes then need
    /// no stored `M·V` and the two passes share one read of V (see `orthonormalize`).
    pub(super) m_diag: Option<&'a [f64]>,
    /// Parallelism of the solves, factorisations and dense products, see [`Ctx::par`].
    pub(super) par: Par,
    /// Concurrent bands still running (see `solve`); `None` for a single band.
    pub(super) running: Option<&'a AtomicUsize>,
    pub(super) timing: EigenTiming,
    pub(super) rng: Rng,
}

impl Ctx<'_> {
    /// Parallelism of the next operation: `Par::Seq` while other concurrent bands run (one
    /// thread per band), `par` once this band is the last one running, so that the threads
    /// whose bands are done help it finish (rayon's work stealing picks up its row-split
    /// products, factorisations and the supernode-parallel parts of its one-group solves).
    pub(super) fn par(&self) -> Par {
        match self.running {
            Some(r) if r.load(AtomicOrdering::Relaxed) > 1 => Par::Seq,
            _ => self.par,
        }
    }

    /// `z ← (K − σM)⁻¹ z`. A single band solves in column groups, one per thread (fastest).
    /// Concurrent bands solve every block as one group, whose result does not depend on the
    /// parallelism: a band's results then do not depend on when the other bands finish.
    pub(super) fn solve(&self, fac: &ShiftFactor, z: MatMut<'_, f64>, buf: &mut SolveWorkspace) {
        match self.running {
            Some(_) => self.sys.solve_in_place_one_group(fac, z, buf, self.par()),
            None => self.sys.solve_in_place(fac, z, buf),
        }
    }

    /// Makes `z` M-orthonormal and M-orthogonal to `against.locked` and `against.basis`
    /// (both M-orthonormal; see [`OrthoAgainst`]). Returns `(c, r)` with
    /// `z_in = locked·(…) + basis·c + z_out·r`; the `locked` part is dropped (it only removes
    /// round-off: `locked` spans eigenvectors, see module doc). Columns that vanish (rank
    /// deficiency) are replaced by random directions with a zero row in `r`. On return `mz`
    /// holds `M·z_out` (the caller keeps it as the next block's `M q` and column of `M V`).
    ///
    /// One round is two passes of block classical Gram–Schmidt ("twice is enough", Giraud et
    /// al., Numer. Math. 101 (2005) 87–100) with the coefficients `(M V)ᵀ z` formed from the
    /// stored `M V`, so the passes need no sparse product ([`GramSchmidt::project_consistent`];
    /// for a diagonal M the coefficients are `Vᵀ(d∘z)`, the first pass's update and the
    /// second pass's coefficients sharing one sweep over V, and the second pass's update
    /// skipped when those coefficients are negligible, see [`GramSchmidt::project_diagonal`]
    /// and [`NEGLIGIBLE_SECOND_PASS`]); then one sparse product `M z`, the Gram matrix
    /// `zᵀ M z` and the symmetric (Löwdin) orthonormalisation `z ← z G^{-1/2}`, whose
    /// `M z ← M z G^{-1/2}` is carried along ([`Ctx::lowdin`]). Another round follows while
    /// a column still shrank by more than half in the second pass (Kahan–Parlett
    /// criterion), the block's Gram matrix is ill-conditioned (κ(G) > 10⁴: the Löwdin step
    /// then leaves an orthogonality error ≈ u·κ(G)), or a column was replaced by a random
    /// vector.
    pub(super) fn orthonormalize(
        &mut self,
        against: &OrthoAgainst<'_>,
        mut z: MatMut<'_, f64>,
        mut mz: MatMut<'_, f64>,
        scratch: &mut Mat<f64>,
    ) -> Result<(Mat<f64>, Mat<f64>), EigenError> {
        let b = z.ncols();
        let j = against.basis.ncols();
        let n = z.nrows();
        // Tall-skinny products, split over row ranges (see `spmm`).
        let par = self.par();
        if scratch.nrows() != n || scratch.ncols() != b {
            *scratch = Mat::<f64>::zeros(n, b);
        }
        let mut gs = GramSchmidt {
            c: Mat::<f64>::zeros(j, b),
            r_acc: Mat::<f64>::identity(b, b),
            passes: 0,
            rounds: 0,
            replaced_last: false,
            removed: Vec::new(),
            removed_last: Vec::new(),
        };
        let mut again = true;
        while again && gs.rounds < 4 {
            gs.rounds += 1;
            gs.removed = vec![0.0f64; b];
            gs.removed_last = vec![0.0f64; b];
            // The locked vectors are eigenvectors: Op keeps a block M-orthogonal to them up to
            // round-off, so one projection per block suffices (again after a random
            // replacement, which is not orthogonal to them).
            match self.m_diag {
                Some(d) => gs.project_diagonal(d, against, z.as_mut(), scratch, par),
                None => gs.project_consistent(against, z.as_mut(), par),
            }
            gs.replaced_last = false;
            let t = Instant::now();
            mul_m(self.m, self.m_diag, z.as_ref(), mz.as_mut());
            self.timing.orthogonalize_spmm_s += t.elapsed().as_secs_f64();
            again = self.lowdin(&mut gs, z.as_mut(), mz.as_mut(), scratch, par)?;
        }
        if gs.replaced_last {
            // Random columns of the last round (only after 4 rounds): M z is not carried.
            mul_m(self.m, self.m_diag, z.as_ref(), mz.as_mut());
        }
        self.timing.orthogonalization_passes += gs.passes;
        self.timing.orthogonalized_blocks += 1;
        Ok((gs.c, gs.r_acc))
    }

    /// The symmetric (Löwdin) orthonormalisation of a round: `z ← z G^{-1/2}` and
    /// `M z ← M z G^{-1/2}` with the Gram matrix `G = zᵀ M z`; columns in its null space
    /// (eigenvalue below 10⁻²⁰ of the largest M-norm² before the round) are replaced by
    /// random directions. Accumulates the factor into `gs.r_acc`; returns whether another
    /// round is needed (a replaced column, a column that shrank by more than half in the
    /// round's last pass, or κ(G) > 10⁴).
    fn lowdin(
        &mut self,
        gs: &mut GramSchmidt,
        mut z: MatMut<'_, f64>,
        mut mz: MatMut<'_, f64>,
        scratch: &mut Mat<f64>,
        par: Par,
    ) -> Result<bool, EigenError> {
        let (n, b) = (z.nrows(), z.ncols());
        let mut g = tall_t_mul(z.as_ref(), mz.as_ref(), par);
        let gt = g.transpose().to_owned();
        g += gt;
        g *= faer::Scale(0.5);
        // ‖z‖²_M before the round ≈ what was removed + what is left (Pythagoras).
        let before: Vec<f64> = (0..b).map(|i| gs.removed[i] + g[(i, i)].max(0.0)).collect();
        let s_ref = before
            .iter()
            .copied()
            .fold(0.0f64, f64::max)
            .max(f64::MIN_POSITIVE);
        let shrink_last = (0..b)
            .map(|i| {
                let left = g[(i, i)].max(0.0);
                (left / (left + gs.removed_last[i]).max(f64::MIN_POSITIVE)).sqrt()
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
            gs.replaced_last = true;
        }
        gs.r_acc = mm(r.as_ref(), gs.r_acc.as_ref(), Par::Seq);
        Ok(gs.replaced_last || shrink_last < 0.5 || kappa > 1e4)
    }
}

/// The M-orthonormal vectors a block is made M-orthogonal to by [`Ctx::orthonormalize`].
pub(super) struct OrthoAgainst<'a> {
    /// Deflated eigenvectors (n × p, p ≥ 0).
    pub(super) locked: MatRef<'a, f64>,
    /// `M · locked` (n × p); empty (n × 0) for a diagonal M.
    pub(super) m_locked: MatRef<'a, f64>,
    /// The Krylov basis V (n × j, j ≥ 0).
    pub(super) basis: MatRef<'a, f64>,
    /// `M · basis` (n × j); empty (n × 0) for a diagonal M.
    pub(super) m_basis: MatRef<'a, f64>,
}

/// The running state of one [`Ctx::orthonormalize`].
struct GramSchmidt {
    /// Coefficients of the input block on the basis so far (j × b).
    c: Mat<f64>,
    /// Product of the rounds' Löwdin factors (b × b): `z_in = basis·c + z·r_acc` (plus the
    /// dropped locked part).
    r_acc: Mat<f64>,
    /// Gram–Schmidt passes over the basis so far.
    passes: usize,
    /// Rounds so far (at most 4).
    rounds: usize,
    /// The last round replaced a column by a random vector.
    replaced_last: bool,
    /// ‖projected part‖²_M per column over the current round.
    removed: Vec<f64>,
    /// The same in the round's last pass.
    removed_last: Vec<f64>,
}

impl GramSchmidt {
    /// One round's projections for a diagonal M (`d`): coefficients `Vᵀ(d∘z)` from V
    /// itself; the first pass's update and the second pass's coefficients in one sweep over
    /// V (three reads of V per block instead of four reads of V and M V, two when the
    /// second pass is negligible).
    fn project_diagonal(
        &mut self,
        d: &[f64],
        against: &OrthoAgainst<'_>,
        mut z: MatMut<'_, f64>,
        scratch: &mut Mat<f64>,
        par: Par,
    ) {
        let (locked, basis) = (against.locked, against.basis);
        let (n, b, j) = (z.nrows(), z.ncols(), basis.ncols());
        self.passes += 1;
        let reps = if self.replaced_last {
            2
        } else {
            usize::from(self.rounds == 1)
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
            add_squared_col_norms(c0.as_ref(), &mut self.removed, &mut self.removed_last);
            c01 = Some((c0, c1));
        }
        for _ in 0..reps {
            if locked.ncols() > 0 {
                scale_rows(d, z.as_ref(), scratch.as_mut());
                let cl = tall_t_mul(locked, scratch.as_ref(), par);
                tall_mul_add(z.as_mut(), locked, cl.as_ref(), -1.0, par);
                add_squared_col_norms(cl.as_ref(), &mut self.removed, &mut self.removed_last);
            }
        }
        self.removed_last.fill(0.0);
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
                self.passes += 1;
                tall_mul_add(z.as_mut(), basis, c1.as_ref(), -1.0, par);
                add_squared_col_norms(c1.as_ref(), &mut self.removed, &mut self.removed_last);
                c0 += &c1;
            }
            matmul(
                self.c.as_mut(),
                Accum::Add,
                c0.as_ref(),
                self.r_acc.as_ref(),
                1.0,
                Par::Seq,
            );
        }
    }

    /// One round's two projections for a general M, with the coefficients `(M V)ᵀ z` from
    /// the stored `M V` (and the locked vectors after the first basis pass, see
    /// [`GramSchmidt::project_diagonal`]).
    fn project_consistent(&mut self, against: &OrthoAgainst<'_>, mut z: MatMut<'_, f64>, par: Par) {
        let (locked, basis) = (against.locked, against.basis);
        for pass in 0..2 {
            self.passes += 1;
            self.removed_last.fill(0.0);
            if locked.ncols() > 0 && ((self.rounds == 1 && pass == 1) || self.replaced_last) {
                let cl = tall_t_mul(against.m_locked, z.as_ref(), par);
                tall_mul_add(z.as_mut(), locked, cl.as_ref(), -1.0, par);
                add_squared_col_norms(cl.as_ref(), &mut self.removed, &mut self.removed_last);
            }
            if basis.ncols() > 0 {
                let cv = tall_t_mul(against.m_basis, z.as_ref(), par);
                tall_mul_add(z.as_mut(), basis, cv.as_ref(), -1.0, par);
                add_squared_col_norms(cv.as_ref(), &mut self.removed, &mut self.removed_last);
                // c += cv · r_acc
                matmul(
                    self.c.as_mut(),
                    Accum::Add,
                    cv.as_ref(),
                    self.r_acc.as_ref(),
                    1.0,
                    Par::Seq,
                );
            }
        }
    }
}

/// Factorises `K − σM`; on a zero pivot moves σ by a small relative amount in `direction`
/// (±1) and retries (σ hit an eigenvalue of a leading block). `scale` (rad²/s²) sets the size
/// of the move.
pub(super) fn factorize(
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
