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
//! ([`super::ordering`]), AMD or the given numbering; `Auto` keeps the one with the smallest
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
use faer::{Conj, MatMut, Par, Side, Spec};

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
    symbolic: SymbolicCholesky<usize>,
    par: Par,
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
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0usize);
        let mut row_idx: Vec<usize> = Vec::new();
        let mut k_map = Vec::new();
        let mut m_map = Vec::new();
        // marker[i] = position of row i in the current column of A, or usize::MAX.
        let mut marker = vec![usize::MAX; n];
        let mut touched: Vec<usize> = Vec::new();
        let (ks, kv) = (k.symbolic(), k.val());
        let (ms, mv) = (m.symbolic(), m.val());
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
        let sym = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
        let symbolic = if ordering == FillOrdering::Auto {
            // The analyses are cheap next to one numeric factorisation; keep the sparsest.
            let mut best = Self::analyse(sym, FillOrdering::Metis, n)?;
            for o in [FillOrdering::Identity, FillOrdering::Amd] {
                let c = Self::analyse(sym, o, n)?;
                if c.len_val() < best.len_val() {
                    best = c;
                }
            }
            best
        } else {
            Self::analyse(sym, ordering, n)?
        };
        Ok(Self {
            n,
            col_ptr,
            row_idx,
            k_map,
            m_map,
            k_val: kv.to_vec(),
            m_val: mv.to_vec(),
            symbolic,
            par,
        })
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
                super::ordering::nested_dissection(n, sym.col_ptr(), sym.row_idx())?
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
            .map_err(|e| EigenError::Factorization {
                shift_rad2_s2: f64::NAN,
                reason: format!("symbolic analysis failed: {e:?}"),
            })
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
    pub fn factorize_with(&self, shift: f64, par: Par) -> Result<Option<ShiftFactor>, EigenError> {
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
        let mut mem = MemBuffer::try_new(req).map_err(|_| EigenError::Factorization {
            shift_rad2_s2: shift,
            reason: "out of memory for the LDLᵀ workspace".into(),
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
    /// The columns are split into [`SOLVE_GROUPS`] contiguous groups, each solved sequentially
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
    pub fn solve_in_place_one_group(
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

/// Column groups of a block solve: independent groups, each solved sequentially, run
/// concurrently. A constant, not the thread count: a column's solution depends (in its last
/// bits) on the width of the group it is solved in, and a fixed split keeps the results the
/// same on every machine.
pub const SOLVE_GROUPS: usize = 2;

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
