//! Shifted sparse LDLᵀ factorisation of `A(σ) = K − σ M`, its inertia (Sturm count) and
//! block solves.
//!
//! The pattern of `A` is the union of the patterns of `K` and `M`; only the lower triangle
//! (row ≥ column) is kept and handed to faer's low-level sparse Cholesky module
//! (`faer::sparse::linalg::cholesky`). The symbolic analysis (fill-reducing ordering,
//! elimination tree, supernodes) is done once per pattern; the numeric LDLᵀ is repeated per
//! shift σ (rad²/s²).
//!
//! **Sturm-sequence property / Sylvester's law of inertia** (Parlett, *The Symmetric
//! Eigenvalue Problem*, SIAM 1998, §3.3; Grimes, Lewis & Simon, SIAM J. Matrix Anal. Appl.
//! 15 (1994) 228–272, §2): if `P (K − σM) Pᵀ = L D Lᵀ` with `D` diagonal and `M` positive
//! definite, the number of negative entries of `D` equals the number of eigenvalues
//! `λ = ω²` of `K φ = λ M φ` with `λ < σ`.
//!
//! **Ordering and solves.** The fill-reducing ordering is METIS nested dissection
//! ([`crate::fe::ordering`]), AMD or the given numbering; `Auto` keeps the one with the smallest
//! factor. Block solves split their right-hand sides into concurrent column groups
//! (`column_groups`). Measured factor sizes and solve costs: docs/performance.md §3.1.
//!
//! The numeric factorisation is faer's supernodal/simplicial LDLᵀ *without pivoting*. That is
//! not backward stable for indefinite matrices in general; in practice (measured on this
//! project's matrices) it works for `K − σM` with σ inside the spectrum. A zero pivot (σ hits
//! an eigenvalue of a leading block) is handled by the caller by moving σ slightly, and the
//! accuracy of every computed eigenpair is verified afterwards by its true residual, so an
//! inaccurate factorisation cannot go unnoticed.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, supernodal::SupernodalLdltRef, CholeskySymbolicParams, LdltRef,
    SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, Mat, MatMut, Par, Side, Spec};
use std::sync::Arc;

use super::{EigenError, FillOrdering};

/// Symbolic structure of `K − σM` (lower triangle) plus the maps from the entries of K and M
/// into it. Built once per (K, M) pair.
pub struct ShiftedSystem {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// `(index into K.val, index into A values)` for every lower-triangle entry of K.
    k_map: Vec<(usize, usize)>,
    /// Same for M.
    m_map: Vec<(usize, usize)>,
    k_val: Vec<f64>,
    m_val: Vec<f64>,
    symbolic: Arc<SymbolicCholesky<usize>>,
    par: Par,
}

/// The symbolic analysis of a [`ShiftedSystem`] (fill-reducing ordering, elimination tree,
/// supernodes) with the pattern it was made for, to be shared by systems of the same
/// pattern ([`ShiftedSystem::with_analysis`]): the cases of a stiffness study change the
/// values of `K`, not its pattern.
#[derive(Clone)]
pub struct SharedAnalysis {
    col_ptr: Arc<Vec<usize>>,
    row_idx: Arc<Vec<usize>>,
    symbolic: Arc<SymbolicCholesky<usize>>,
}

/// The lower-triangle union pattern of `K` and `M` and the maps of their entries into it.
struct UnionPattern {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    k_map: Vec<(usize, usize)>,
    m_map: Vec<(usize, usize)>,
}

/// One numeric LDLᵀ factorisation of `K − σM`.
pub struct ShiftFactor {
    /// The shift σ actually used (rad²/s²).
    pub shift: f64,
    /// Number of negative pivots = number of eigenvalues λ < σ.
    pub negative_count: usize,
    /// Smallest |pivot| relative to the largest |pivot| (diagnostic for near-singularity).
    pub min_rel_pivot: f64,
    values: Vec<f64>,
}

impl ShiftedSystem {
    /// Builds the union pattern of `k` and `m` (both n × n, full symmetric storage) and runs
    /// the symbolic analysis with the requested fill-reducing ordering.
    pub fn new(
        k: SparseColMatRef<'_, usize, f64>,
        m: SparseColMatRef<'_, usize, f64>,
        ordering: FillOrdering,
        par: Par,
    ) -> Result<Self, EigenError> {
        let n = k.nrows();
        let pat = union_pattern(k, m);
        let sym = SymbolicSparseColMatRef::new_checked(n, n, &pat.col_ptr, None, &pat.row_idx);
        let symbolic = Self::choose_analysis(sym, ordering, n)?;
        Ok(Self::assemble(k, m, pat, Arc::new(symbolic), par))
    }

    /// As [`Self::new`], reusing `shared` (made by [`Self::analysis`] of a system with the
    /// same union pattern) instead of a new symbolic analysis when the pattern of `k` and `m`
    /// is that one, entry for entry; otherwise analysed afresh with `ordering`. Either way the
    /// factorisations are those [`Self::new`] would give with the same ordering choice.
    pub fn with_analysis(
        k: SparseColMatRef<'_, usize, f64>,
        m: SparseColMatRef<'_, usize, f64>,
        shared: &SharedAnalysis,
        ordering: FillOrdering,
        par: Par,
    ) -> Result<Self, EigenError> {
        let n = k.nrows();
        let pat = union_pattern(k, m);
        if pat.col_ptr == *shared.col_ptr && pat.row_idx == *shared.row_idx {
            return Ok(Self::assemble(k, m, pat, shared.symbolic.clone(), par));
        }
        let sym = SymbolicSparseColMatRef::new_checked(n, n, &pat.col_ptr, None, &pat.row_idx);
        let symbolic = Self::choose_analysis(sym, ordering, n)?;
        Ok(Self::assemble(k, m, pat, Arc::new(symbolic), par))
    }

    /// This system's symbolic analysis and pattern, for [`Self::with_analysis`].
    pub fn analysis(&self) -> SharedAnalysis {
        SharedAnalysis {
            col_ptr: Arc::new(self.col_ptr.clone()),
            row_idx: Arc::new(self.row_idx.clone()),
            symbolic: self.symbolic.clone(),
        }
    }

    fn assemble(
        k: SparseColMatRef<'_, usize, f64>,
        m: SparseColMatRef<'_, usize, f64>,
        pat: UnionPattern,
        symbolic: Arc<SymbolicCholesky<usize>>,
        par: Par,
    ) -> Self {
        Self {
            n: k.nrows(),
            col_ptr: pat.col_ptr,
            row_idx: pat.row_idx,
            k_map: pat.k_map,
            m_map: pat.m_map,
            k_val: k.val().to_vec(),
            m_val: m.val().to_vec(),
            symbolic,
            par,
        }
    }

    /// The symbolic analysis with `ordering`; for `Auto` the sparsest of METIS, AMD and the
    /// given numbering.
    fn choose_analysis(
        sym: SymbolicSparseColMatRef<'_, usize>,
        ordering: FillOrdering,
        n: usize,
    ) -> Result<SymbolicCholesky<usize>, EigenError> {
        if ordering != FillOrdering::Auto {
            return Self::analyse(sym, ordering, n);
        }
        // The analyses are cheap next to one numeric factorisation; keep the sparsest.
        let mut best = Self::analyse(sym, FillOrdering::Metis, n)?;
        for o in [FillOrdering::Identity, FillOrdering::Amd] {
            let c = Self::analyse(sym, o, n)?;
            if c.len_val() < best.len_val() {
                best = c;
            }
        }
        Ok(best)
    }

    fn analyse(
        sym: SymbolicSparseColMatRef<'_, usize>,
        ordering: FillOrdering,
        n: usize,
    ) -> Result<SymbolicCholesky<usize>, EigenError> {
        // `Identity` is passed as an explicit identity permutation: faer's
        // `SymmetricOrdering::Identity` skips the conversion of the lower triangle to the
        // upper one that its symbolic analysis expects.
        let (fwd, inv): (Vec<usize>, Vec<usize>) = match ordering {
            FillOrdering::Identity => ((0..n).collect(), (0..n).collect()),
            FillOrdering::Metis => {
                crate::fe::ordering::nested_dissection(n, sym.col_ptr(), sym.row_idx())?
            }
            FillOrdering::Amd | FillOrdering::Auto => (Vec::new(), Vec::new()),
        };
        let ord = match ordering {
            FillOrdering::Amd | FillOrdering::Auto => SymmetricOrdering::Amd,
            FillOrdering::Identity | FillOrdering::Metis => {
                SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(&fwd, &inv, n))
            }
        };
        factorize_symbolic_cholesky(sym, Side::Lower, ord, CholeskySymbolicParams::default())
            .map_err(EigenError::Symbolic)
    }

    /// Dimension n.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Number of stored entries of the LDLᵀ factor (fill measure).
    pub fn factor_len(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Numeric LDLᵀ of `K − σM` (σ in rad²/s²) with the parallelism given at construction.
    /// Returns `None` on a zero pivot.
    pub fn factorize(&self, shift: f64) -> Result<Option<ShiftFactor>, EigenError> {
        self.factorize_with(shift, self.par)
    }

    /// [`Self::factorize`] with the parallelism `par` (e.g. `Par::Seq` while other
    /// factorisations or solves run on the other threads).
    pub(crate) fn factorize_with(
        &self,
        shift: f64,
        par: Par,
    ) -> Result<Option<ShiftFactor>, EigenError> {
        let mut a_val = vec![0.0f64; self.row_idx.len()];
        for &(p, q) in &self.k_map {
            a_val[q] += self.k_val[p];
        }
        for &(p, q) in &self.m_map {
            a_val[q] -= shift * self.m_val[p];
        }
        let sym = SymbolicSparseColMatRef::new_checked(
            self.n,
            self.n,
            &self.col_ptr,
            None,
            &self.row_idx,
        );
        let a = SparseColMatRef::new(sym, &a_val);
        let mut values = vec![0.0f64; self.symbolic.len_val()];
        let req = self
            .symbolic
            .factorize_numeric_ldlt_scratch::<f64>(par, Spec::default());
        let mut mem = MemBuffer::try_new(req).map_err(|source| EigenError::FactorWorkspace {
            shift_rad2_s2: shift,
            bytes: req.size_bytes(),
            source,
        })?;
        let res = self.symbolic.factorize_numeric_ldlt(
            &mut values,
            a,
            Side::Lower,
            LdltRegularization::default(),
            par,
            MemStack::new(&mut mem),
            Spec::default(),
        );
        if res.is_err() {
            return Ok(None);
        }
        let (neg, min_abs, max_abs) = self.inertia(&values);
        if min_abs.is_nan() || min_abs <= 0.0 || !max_abs.is_finite() {
            return Ok(None);
        }
        Ok(Some(ShiftFactor {
            shift,
            negative_count: neg,
            min_rel_pivot: min_abs / max_abs,
            values,
        }))
    }

    /// (negative pivots, min |d|, max |d|) of the diagonal D stored in `values`.
    fn inertia(&self, values: &[f64]) -> (usize, f64, f64) {
        let mut neg = 0usize;
        let mut min_abs = f64::INFINITY;
        let mut max_abs = 0.0f64;
        let mut visit = |d: f64| {
            if d < 0.0 {
                neg += 1;
            }
            if d.is_nan() {
                min_abs = f64::NAN;
            }
            min_abs = min_abs.min(d.abs());
            max_abs = max_abs.max(d.abs());
        };
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let f = s.factor();
                let cp = f.col_ptr();
                let ri = f.row_idx();
                for j in 0..self.n {
                    for p in cp[j]..cp[j + 1] {
                        if ri[p] == j {
                            visit(values[p]);
                        }
                    }
                }
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let l = SupernodalLdltRef::new(s, values);
                for sn in 0..s.n_supernodes() {
                    let v = l.supernode(sn).val();
                    for j in 0..v.ncols() {
                        visit(v[(j, j)]);
                    }
                }
            }
        }
        (neg, min_abs, max_abs)
    }

    /// Workspace for solving with up to `ncols` right-hand sides, with the parallelism given
    /// at construction or any less parallel one.
    pub fn solve_buffer(&self, ncols: usize) -> SolveWorkspace {
        let groups = column_groups(ncols, self.par);
        let width = ncols.div_ceil(groups.max(1)).max(1);
        SolveWorkspace {
            ncols,
            bufs: (0..groups.max(1))
                .map(|_| {
                    MemBuffer::new(
                        self.symbolic
                            .solve_in_place_scratch::<f64>(width, Par::Seq)
                            .or(self.symbolic.solve_in_place_scratch::<f64>(ncols, self.par))
                            .or(self.symbolic.solve_in_place_scratch::<f64>(ncols, Par::Seq)),
                    )
                })
                .collect(),
        }
    }

    /// Overwrites `rhs` with `(K − σM)⁻¹ rhs`, with the parallelism given at construction.
    ///
    /// The columns are split into `SOLVE_GROUPS` contiguous groups, each solved sequentially
    /// with its own workspace; with a parallel `par` the groups run concurrently. The result
    /// does not depend on `par` or the thread count.
    pub fn solve_in_place(
        &self,
        f: &ShiftFactor,
        mut rhs: MatMut<'_, f64>,
        ws: &mut SolveWorkspace,
    ) {
        let par = self.par;
        if rhs.ncols() > ws.ncols {
            *ws = self.solve_buffer(rhs.ncols());
        }
        let l = LdltRef::new(&self.symbolic, &f.values);
        let groups = column_groups(rhs.ncols(), par).min(ws.bufs.len());
        if groups <= 1 {
            l.solve_in_place_with_conj(Conj::No, rhs, par, MemStack::new(&mut ws.bufs[0]));
            return;
        }
        let width = rhs.ncols().div_ceil(groups);
        let mut parts: Vec<MatMut<'_, f64>> = Vec::with_capacity(groups);
        let mut rest = rhs.as_mut();
        while rest.ncols() > 0 {
            let w = width.min(rest.ncols());
            let (a, b) = rest.split_at_col_mut(w);
            parts.push(a);
            rest = b;
        }
        let solve = |(part, buf): (MatMut<'_, f64>, &mut MemBuffer)| {
            l.solve_in_place_with_conj(Conj::No, part, Par::Seq, MemStack::new(buf));
        };
        if matches!(par, Par::Seq) {
            parts.into_iter().zip(ws.bufs.iter_mut()).for_each(solve);
        } else {
            use rayon::prelude::*;
            parts
                .into_par_iter()
                .zip(ws.bufs.par_iter_mut())
                .for_each(solve);
        }
    }

    /// [`Self::solve_in_place`] as one column group whatever `par` (at most the parallelism
    /// given at construction): faer's supernodal solve then parallelises inside the supernodes
    /// only and gives bitwise the same result for every `par`, which the column groups do not
    /// (a solver switching its parallelism with the load stays reproducible).
    pub(crate) fn solve_in_place_one_group(
        &self,
        f: &ShiftFactor,
        rhs: MatMut<'_, f64>,
        ws: &mut SolveWorkspace,
        par: Par,
    ) {
        if rhs.ncols() > ws.ncols {
            *ws = self.solve_buffer(rhs.ncols());
        }
        let l = LdltRef::new(&self.symbolic, &f.values);
        l.solve_in_place_with_conj(Conj::No, rhs, par, MemStack::new(&mut ws.bufs[0]));
    }
}

/// The lower-triangle union pattern of `k` and `m` (both n × n, full symmetric storage) and
/// the maps of their lower-triangle entries into it.
fn union_pattern(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
) -> UnionPattern {
    let n = k.nrows();
    let mut col_ptr = Vec::with_capacity(n + 1);
    col_ptr.push(0usize);
    let mut row_idx: Vec<usize> = Vec::new();
    let mut k_map = Vec::new();
    let mut m_map = Vec::new();
    // marker[i] = position of row i in the current column of A, or usize::MAX.
    let mut marker = vec![usize::MAX; n];
    let mut touched: Vec<usize> = Vec::new();
    let (ks, ms) = (k.symbolic(), m.symbolic());
    for j in 0..n {
        let start = row_idx.len();
        touched.clear();
        // Collect the lower-triangle rows of column j of K and M.
        let mut rows: Vec<usize> = Vec::new();
        for sym in [ks, ms] {
            for &i in sym.row_idx_of_col_raw(j) {
                if i >= j && marker[i] == usize::MAX {
                    marker[i] = 0;
                    rows.push(i);
                }
            }
        }
        rows.sort_unstable();
        for (p, &i) in rows.iter().enumerate() {
            marker[i] = start + p;
            touched.push(i);
        }
        row_idx.extend_from_slice(&rows);
        let kr = ks.col_range(j);
        for (p, &i) in kr.clone().zip(ks.row_idx_of_col_raw(j)) {
            if i >= j {
                k_map.push((p, marker[i]));
            }
        }
        let mr = ms.col_range(j);
        for (p, &i) in mr.clone().zip(ms.row_idx_of_col_raw(j)) {
            if i >= j {
                m_map.push((p, marker[i]));
            }
        }
        for &i in &touched {
            marker[i] = usize::MAX;
        }
        col_ptr.push(row_idx.len());
    }
    UnionPattern {
        col_ptr,
        row_idx,
        k_map,
        m_map,
    }
}

/// Column groups of a block solve: independent groups, each solved sequentially, run
/// concurrently. A constant, not the thread count: a column's solution depends (in its last
/// bits) on the width of the group it is solved in, and a fixed split keeps the results the
/// same on every machine.
pub(crate) const SOLVE_GROUPS: usize = 2;

/// Number of column groups of a block of `ncols` right-hand sides: [`SOLVE_GROUPS`], at most
/// one per column, whatever `par` (which only decides whether they run concurrently). faer's
/// supernodal triangular solves parallelise inside the dense supernode blocks only, which a
/// block of 8 right-hand sides does not fill; independent column groups, each solved
/// sequentially, keep the cores busy (measured: docs/performance.md §3.1).
fn column_groups(ncols: usize, _par: Par) -> usize {
    SOLVE_GROUPS.min(ncols).max(1)
}

/// Scratch memory of [`ShiftedSystem::solve_in_place`]: one buffer per concurrently solved
/// column group.
pub struct SolveWorkspace {
    /// Right-hand sides it was sized for (a wider block gets a new workspace).
    ncols: usize,
    bufs: Vec<MemBuffer>,
}

impl ShiftedSystem {
    /// Overwrites the columns `b` of `rhs` (n × k) with `z = Pᵀ D^{-1/2} L⁻¹ P b`, from the
    /// factor `P (K − σM) Pᵀ = L D Lᵀ` with all pivots positive (σ below the spectrum, e.g.
    /// σ = 0 for a supported `K`), so that `bᵀ (K − σM)⁻¹ c = z_b · z_c` for any two
    /// columns: the quadratic forms of a block of loads from the forward substitution alone.
    ///
    /// The forward substitution of a sparse load only reaches the load's rows and their
    /// ancestors in the elimination tree (Gilbert & Peierls, SIAM J. Sci. Stat. Comput. 9
    /// (1988) 862–874; Davis, *Direct Methods for Sparse Linear Systems*, SIAM 2006, §3.2):
    /// the supernodes off those paths are skipped, which for loads concentrated on a few
    /// nodes is most of the factor. The columns are solved in `SOLVE_GROUPS` fixed groups
    /// (concurrently with a parallel `par` given at construction), so the result does not
    /// depend on the thread count.
    ///
    /// # Errors
    /// [`EigenError::Factorization`] when `f` has a non-positive pivot (the quadratic form is
    /// not a sum of squares) or `rhs` has the wrong number of rows.
    pub fn whiten_in_place(&self, f: &ShiftFactor, rhs: MatMut<'_, f64>) -> Result<(), EigenError> {
        if f.negative_count > 0 || rhs.nrows() != self.n {
            return Err(EigenError::Factorization {
                shift_rad2_s2: f.shift,
                reason: format!(
                    "whitening needs positive pivots ({} negative) and {} rows ({} given)",
                    f.negative_count,
                    self.n,
                    rhs.nrows()
                ),
            });
        }
        let groups = column_groups(rhs.ncols(), self.par);
        let width = rhs.ncols().div_ceil(groups).max(1);
        let mut parts: Vec<MatMut<'_, f64>> = Vec::with_capacity(groups);
        let mut rest = rhs;
        while rest.ncols() > 0 {
            let w = width.min(rest.ncols());
            let (a, b) = rest.split_at_col_mut(w);
            parts.push(a);
            rest = b;
        }
        let one = |part: MatMut<'_, f64>| self.whiten_group(&f.values, part);
        if matches!(self.par, Par::Seq) {
            parts.into_iter().for_each(one);
        } else {
            use rayon::prelude::*;
            parts.into_par_iter().for_each(one);
        }
        Ok(())
    }

    /// [`Self::whiten_in_place`] of one column group, sequentially.
    fn whiten_group(&self, values: &[f64], mut rhs: MatMut<'_, f64>) {
        let (n, k) = (self.n, rhs.ncols());
        let perm = self.symbolic.perm().map(|p| p.arrays());
        // x = P b: row i of x is row fwd[i] of b
        let mut x = Mat::<f64>::zeros(n, k);
        let mut nonzero_rows = Vec::new();
        for i in 0..n {
            let src = perm.map_or(i, |(fwd, _)| fwd[i]);
            let mut any = false;
            for j in 0..k {
                let v = rhs[(src, j)];
                x[(i, j)] = v;
                any |= v != 0.0;
            }
            if any {
                nonzero_rows.push(i);
            }
        }
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                whiten_simplicial(s.factor(), values, x.as_mut());
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                whiten_supernodal(s, values, &nonzero_rows, x.as_mut());
            }
        }
        for i in 0..n {
            let dst = perm.map_or(i, |(fwd, _)| fwd[i]);
            for j in 0..k {
                rhs[(dst, j)] = x[(i, j)];
            }
        }
    }
}

/// `x ← D^{-1/2} L⁻¹ x` with the simplicial LDLᵀ factor (`L` unit lower, `D` on its
/// diagonal entries).
fn whiten_simplicial(
    l: SymbolicSparseColMatRef<'_, usize>,
    values: &[f64],
    mut x: MatMut<'_, f64>,
) {
    let (cp, ri) = (l.col_ptr(), l.row_idx());
    for c in 0..l.ncols() {
        let mut d = f64::NAN;
        for p in cp[c]..cp[c + 1] {
            let r = ri[p];
            if r == c {
                d = values[p];
            } else if r > c {
                for j in 0..x.ncols() {
                    let v = x[(c, j)];
                    x[(r, j)] -= values[p] * v;
                }
            }
        }
        let s = d.sqrt().recip();
        for j in 0..x.ncols() {
            x[(c, j)] *= s;
        }
    }
}

/// `x ← D^{-1/2} L⁻¹ x` with the supernodal LDLᵀ factor, visiting only the supernodes that
/// hold a nonzero row of `x` (`nonzero_rows`, factor numbering) and their ancestors: a
/// supernode's parent is the one holding the smallest row of its below-diagonal pattern.
fn whiten_supernodal(
    s: &faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky<usize>,
    values: &[f64],
    nonzero_rows: &[usize],
    mut x: MatMut<'_, f64>,
) {
    let (ns, k) = (s.n_supernodes(), x.ncols());
    let (begin, end) = (s.supernode_begin(), s.supernode_end());
    let mut owner = vec![0usize; s.nrows()];
    for t in 0..ns {
        owner[begin[t]..end[t]].iter_mut().for_each(|o| *o = t);
    }
    let mut reached = vec![false; ns];
    for &r in nonzero_rows {
        let mut t = owner[r];
        while !reached[t] {
            reached[t] = true;
            match s.supernode(t).pattern().iter().min() {
                Some(&p) => t = owner[p],
                None => break,
            }
        }
    }
    let l = SupernodalLdltRef::new(s, values);
    let longest = (0..ns)
        .filter(|&t| reached[t])
        .map(|t| s.supernode(t).pattern().len())
        .max()
        .unwrap_or(0);
    let mut tmp = Mat::<f64>::zeros(longest, k);
    for t in (0..ns).filter(|&t| reached[t]) {
        let sn = l.supernode(t);
        let size = sn.val().ncols();
        let (top, bot) = sn.val().split_at_row(size);
        let mut xt = x.as_mut().subrows_mut(sn.start(), size);
        faer::linalg::triangular_solve::solve_unit_lower_triangular_in_place(
            top,
            xt.as_mut(),
            Par::Seq,
        );
        let pattern = sn.pattern();
        let mut tm = tmp.as_mut().subrows_mut(0, pattern.len());
        faer::linalg::matmul::matmul(
            tm.as_mut(),
            faer::Accum::Replace,
            bot,
            xt.as_ref(),
            1.0,
            Par::Seq,
        );
        for j in 0..k {
            for (idx, &i) in pattern.iter().enumerate() {
                x[(i, j)] -= tm[(idx, j)];
            }
        }
        for idx in 0..size {
            let sc = top[(idx, idx)].sqrt().recip();
            for j in 0..k {
                x[(sn.start() + idx, j)] *= sc;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{Arc, FillOrdering, Mat, Par, ShiftedSystem, SymbolicCholeskyRaw};
    use faer::sparse::{SparseColMat, Triplet};

    /// The 7-point Laplacian of an `a × b × c` grid plus `shift` on the diagonal (SPD).
    fn grid(a: usize, b: usize, c: usize, shift: f64) -> SparseColMat<usize, f64> {
        let id = |i: usize, j: usize, l: usize| (l * b + j) * a + i;
        let mut t = Vec::new();
        for l in 0..c {
            for j in 0..b {
                for i in 0..a {
                    let p = id(i, j, l);
                    t.push(Triplet::new(p, p, 6.0 + shift + 0.01 * (p % 7) as f64));
                    let mut link = |q: usize| {
                        t.push(Triplet::new(p, q, -1.0));
                        t.push(Triplet::new(q, p, -1.0));
                    };
                    if i + 1 < a {
                        link(id(i + 1, j, l));
                    }
                    if j + 1 < b {
                        link(id(i, j + 1, l));
                    }
                    if l + 1 < c {
                        link(id(i, j, l + 1));
                    }
                }
            }
        }
        let n = a * b * c;
        SparseColMat::try_new_from_triplets(n, n, &t).unwrap()
    }

    /// Sparse loads (a few rows each) whose quadratic forms `bᵀK⁻¹c`, from the whitened
    /// columns, must equal those from full solves to round-off (independent path: faer's
    /// forward and backward substitution); both factor kinds.
    fn check_whitening(k: &SparseColMat<usize, f64>, expect_supernodal: bool) {
        let n = k.nrows();
        let sys =
            ShiftedSystem::new(k.as_ref(), k.as_ref(), FillOrdering::Auto, Par::rayon(2)).unwrap();
        assert_eq!(
            matches!(sys.symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_)),
            expect_supernodal
        );
        let f = sys.factorize(0.0).unwrap().unwrap();
        let cols = 5;
        let b = Mat::<f64>::from_fn(n, cols, |i, j| {
            if (i * 7 + 3 * j) % (n / 3).max(3) == 0 || i == (j * 11) % n {
                1.0 + 0.25 * j as f64 - 0.1 * (i % 3) as f64
            } else {
                0.0
            }
        });
        let mut x = b.clone();
        let mut ws = sys.solve_buffer(cols);
        sys.solve_in_place(&f, x.as_mut(), &mut ws);
        let mut z = b.clone();
        sys.whiten_in_place(&f, z.as_mut()).unwrap();
        for p in 0..cols {
            for q in 0..cols {
                let want: f64 = (0..n).map(|i| b[(i, p)] * x[(i, q)]).sum();
                let got: f64 = (0..n).map(|i| z[(i, p)] * z[(i, q)]).sum();
                assert!(
                    (got - want).abs() <= 1e-12 * want.abs().max(1e-3),
                    "({p},{q}): {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn whitened_loads_give_the_quadratic_forms_of_the_solves() {
        check_whitening(&grid(9, 1, 1, 0.5), false);
        check_whitening(&grid(14, 12, 10, 0.0), true);
    }

    /// A system sharing another's analysis factorises to the same values as one analysed
    /// afresh (same pattern); a different pattern is analysed afresh.
    #[test]
    fn a_shared_analysis_gives_the_factor_of_a_fresh_one() {
        let k0 = grid(8, 7, 6, 0.0);
        let k1 = grid(8, 7, 6, 2.0);
        let s0 =
            ShiftedSystem::new(k0.as_ref(), k0.as_ref(), FillOrdering::Auto, Par::Seq).unwrap();
        let shared = s0.analysis();
        let fresh =
            ShiftedSystem::new(k1.as_ref(), k1.as_ref(), FillOrdering::Auto, Par::Seq).unwrap();
        let reused = ShiftedSystem::with_analysis(
            k1.as_ref(),
            k1.as_ref(),
            &shared,
            FillOrdering::Auto,
            Par::Seq,
        )
        .unwrap();
        assert!(Arc::ptr_eq(&reused.symbolic, &s0.symbolic));
        let (a, b) = (
            fresh.factorize(0.0).unwrap().unwrap(),
            reused.factorize(0.0).unwrap().unwrap(),
        );
        assert_eq!(a.values, b.values);
        let other = grid(5, 4, 3, 0.0);
        let s2 = ShiftedSystem::with_analysis(
            other.as_ref(),
            other.as_ref(),
            &shared,
            FillOrdering::Auto,
            Par::Seq,
        )
        .unwrap();
        assert!(!Arc::ptr_eq(&s2.symbolic, &s0.symbolic));
        assert_eq!(s2.n(), 60);
        assert!(s2.factorize(0.0).unwrap().is_some());
    }
}
