//! The static stiffness of a structure, factorised once, and its solutions for loads along the
//! rail's contact line: what both passage engines start from (the reduced engine's residual
//! flexibility, docs/theory.md §7.7; the explicit path's static start and local compliance,
//! §8.6).
//!
//! Assumptions: the track is supported (its `K` positive definite); loads are spread over a
//! node plane's contact nodes as [`crate::passage::contact_line`] spreads the contact force.

use faer::sparse::SparseColMatRef;
use faer::{Mat, Par};

use super::contact_line::{ContactFrame, RailContactLine};
use super::PassageError;
use crate::eigen::factor::{SharedAnalysis, ShiftFactor, ShiftedSystem, SolveWorkspace};
use crate::eigen::FillOrdering;
use crate::fe::assembly::DofMap;
use crate::structure::TrackStructure;

/// Right-hand sides solved together (memory n × BLOCK × 8 bytes).
pub(crate) const BLOCK: usize = 24;

/// `Σ_k w_k a · u(node_k)`: the weighted displacement of a node set along the unit vector `a`
/// from a free-DOF vector `u` (constrained DOFs are zero).
pub fn nodes_dot(
    nodes: &[(usize, f64)],
    dofmap: &DofMap,
    a: [f64; 3],
    u: impl Fn(usize) -> f64,
) -> f64 {
    let mut s = 0.0;
    for &(node, w) in nodes {
        for (c, &ac) in a.iter().enumerate() {
            if ac != 0.0 {
                if let Some(i) = dofmap.free_index(3 * node + c) {
                    s += w * ac * u(i);
                }
            }
        }
    }
    s
}

/// The sparse factor of the track stiffness `K` (N/m, free DOFs), for block solves.
///
/// The LDLᵀ of `K − σM` at σ = 0 from the eigensolver's [`ShiftedSystem`]: METIS ordering
/// and concurrent column-group solves (smaller and faster than a plain sparse Cholesky of
/// `K`: docs/performance.md §5). All pivots must be positive: `K` is positive definite when
/// the track is supported.
pub struct StiffnessFactor {
    sys: ShiftedSystem,
    factor: ShiftFactor,
}

impl StiffnessFactor {
    /// Factorises `K` once.
    pub fn new(k: SparseColMatRef<'_, usize, f64>) -> Result<Self, PassageError> {
        // At σ = 0 the mass matrix does not enter; K stands in for its pattern.
        let sys = ShiftedSystem::new(k, k, FillOrdering::Auto, Par::rayon(0))
            .map_err(PassageError::StiffnessFactor)?;
        Self::factorise(sys)
    }

    /// As [`Self::new`], reusing the symbolic analysis of an earlier factor of a `K` with
    /// the same pattern ([`Self::analysis`]; e.g. the cases of a stiffness study): only the
    /// numeric factorisation is done. The factor equals that of [`Self::new`]; a `K` of
    /// another pattern is analysed afresh.
    pub fn with_analysis(
        k: SparseColMatRef<'_, usize, f64>,
        shared: &SharedAnalysis,
    ) -> Result<Self, PassageError> {
        let sys = ShiftedSystem::with_analysis(k, k, shared, FillOrdering::Auto, Par::rayon(0))
            .map_err(PassageError::StiffnessFactor)?;
        Self::factorise(sys)
    }

    /// The symbolic analysis of this factor, for [`Self::with_analysis`].
    pub fn analysis(&self) -> SharedAnalysis {
        self.sys.analysis()
    }

    fn factorise(sys: ShiftedSystem) -> Result<Self, PassageError> {
        let factor = sys
            .factorize(0.0)
            .map_err(PassageError::StiffnessFactor)?
            .ok_or(PassageError::StiffnessIndefinite {
                negative_pivots: 0,
                min_rel_pivot: 0.0,
            })?;
        if factor.negative_count > 0 || factor.min_rel_pivot < 1e-14 {
            return Err(PassageError::StiffnessIndefinite {
                negative_pivots: factor.negative_count,
                min_rel_pivot: factor.min_rel_pivot,
            });
        }
        Ok(StiffnessFactor { sys, factor })
    }

    /// Overwrites the columns `b` of `rhs` (n × k) with vectors `z_b` such that
    /// `bᵀ K⁻¹ c = z_b · z_c` ([`ShiftedSystem::whiten_in_place`]: the forward substitution
    /// alone, over the factor's part a sparse load reaches).
    pub fn whiten_in_place(&self, rhs: faer::MatMut<'_, f64>) -> Result<(), PassageError> {
        self.sys
            .whiten_in_place(&self.factor, rhs)
            .map_err(PassageError::StiffnessFactor)
    }

    /// Workspace for [`Self::solve_in_place`] with up to `ncols` right-hand sides (allocate
    /// once, reuse for every block).
    pub fn workspace(&self, ncols: usize) -> SolveWorkspace {
        self.sys.solve_buffer(ncols)
    }

    /// Overwrites the columns of `rhs` (n × k) with `K⁻¹ rhs`, using `ws` (replaced by a
    /// larger one if it was sized for fewer than k columns).
    pub fn solve_in_place(&self, rhs: faer::MatMut<'_, f64>, ws: &mut SolveWorkspace) {
        self.sys.solve_in_place(&self.factor, rhs, ws);
    }

    /// Number of rows (free DOFs).
    pub fn n(&self) -> usize {
        self.sys.n()
    }
}

/// The symbolic analysis of the first `K` factorised through it, reused for every later
/// `K` of the same pattern (the cases of a stiffness study): each factorisation is then
/// numeric only, with the same factor as [`StiffnessFactor::new`].
#[derive(Default)]
pub struct SharedStiffnessAnalysis {
    analysis: std::sync::Mutex<Option<SharedAnalysis>>,
}

impl SharedStiffnessAnalysis {
    /// Factorises `k`, with the stored analysis when there is one (and its pattern is
    /// that of `k`), else analysing `k` and storing its analysis.
    pub fn factor(
        &self,
        k: SparseColMatRef<'_, usize, f64>,
    ) -> Result<StiffnessFactor, PassageError> {
        let stored = self.analysis.lock().ok().and_then(|a| a.clone());
        match stored {
            Some(a) => StiffnessFactor::with_analysis(k, &a),
            None => {
                let f = StiffnessFactor::new(k)?;
                if let Ok(mut a) = self.analysis.lock() {
                    *a = Some(f.analysis());
                }
                Ok(f)
            }
        }
    }
}

/// Index range of the node planes that a contact travelling over `[x_lo, x_hi]` (m) uses:
/// the planes around both ends included.
pub fn plane_range(
    line: &RailContactLine,
    x_lo: f64,
    x_hi: f64,
) -> Result<(usize, usize), PassageError> {
    let off = |x: f64| line.off_rail("residual flexibility point", x);
    let (p0, _) = line.locate(x_lo).ok_or_else(|| off(x_lo))?;
    let (p1, _) = line.locate(x_hi).ok_or_else(|| off(x_hi))?;
    Ok((p0, p1 + 1))
}

/// Receives `(plane offset, direction, u)` with `u(i)` the free DOF `i` of a solution.
pub(crate) type PlaneVisitor<'a> = dyn FnMut(usize, usize, &dyn Fn(usize) -> f64) + 'a;

/// Solves `K u = b_{p,d}` for the unit contact loads of the planes `p0..=p1` of `line` and
/// the three frame directions, in blocks of right-hand sides, and hands each solution to
/// `visit(p − p0, d, u)` with `u(i)` the free DOF `i` of the solution.
pub fn for_each_plane_solution(
    track: &TrackStructure,
    factor: &StiffnessFactor,
    line: &RailContactLine,
    frame: &ContactFrame,
    p0: usize,
    p1: usize,
    visit: &mut PlaneVisitor<'_>,
) {
    let total = 3 * (p1 - p0 + 1);
    let n = factor.n();
    let mut rhs = Mat::<f64>::zeros(n, BLOCK.min(total));
    let mut b = vec![0.0; n];
    let mut ws = factor.workspace(BLOCK.min(total));
    let mut start = 0;
    while start < total {
        let k = BLOCK.min(total - start);
        for j in 0..k {
            let (i, d) = ((start + j) / 3, (start + j) % 3);
            let mut force = [0.0; 3];
            force[d] = 1.0;
            b.iter_mut().for_each(|v| *v = 0.0);
            super::contact_line::add_nodes_load(
                &line.nodes[p0 + i],
                &track.dofmap,
                frame,
                1.0,
                force,
                &mut b,
            );
            for (r, &v) in b.iter().enumerate() {
                rhs[(r, j)] = v;
            }
        }
        factor.solve_in_place(rhs.as_mut().subcols_mut(0, k), &mut ws);
        for j in 0..k {
            let (i, d) = ((start + j) / 3, (start + j) % 3);
            visit(i, d, &|r: usize| rhs[(r, j)]);
        }
        start += k;
    }
}
