//! The track's static flexibility at the contact for the cases of a design study, from one
//! factorisation of a reference stiffness (docs/theory.md §5.8, "Residual flexibility of a
//! case").
//!
//! The cases of a substructured study share the solids and the spring layout and differ in
//! spring stiffnesses only: `K = K₀ + G Δ Gᵀ`, with `G = [g_s]` the changed springs' DOF
//! vectors and `Δ = diag(k_s − k_{0,s})`. By the Sherman–Morrison–Woodbury identity
//! (Golub & Van Loan, *Matrix Computations*, 4th ed., §2.1.4)
//!
//! ```text
//! K⁻¹ = K₀⁻¹ − U (I + Δ A)⁻¹ Δ Uᵀ,    U = K₀⁻¹ G,   A = Gᵀ K₀⁻¹ G,
//! bᵀ K⁻¹ c = bᵀ K₀⁻¹ c − z_bᵀ (I + Δ A)⁻¹ Δ z_c,    z_b = Gᵀ K₀⁻¹ b,
//! ```
//!
//! exact for any stiffness change (`I + ΔA` is non-singular when `K₀` and `K` are positive
//! definite: `det(I + ΔA) = det K / det K₀`). The reference `K₀` is factorised once per
//! study; each changed spring costs one solve with it, once; a case costs one dense LU of
//! the changed springs' size instead of a sparse factorisation of the track and `3·n_planes`
//! solves.

use std::sync::Mutex;

use faer::Mat;

use crate::dynamics::reduced::{ContactFrame, RailContactLine};
use crate::dynamics::residual::{nodes_dot, PlaneFlexibility, StaticFlexibility, StiffnessFactor};
use crate::dynamics::DynamicsError;
use crate::structure::TrackStructure;

/// Springs solved per pass over the factor (memory: free DOFs × CHUNK × 8 bytes).
const CHUNK: usize = 96;

/// A spring's DOF vector over the free DOFs: `(free DOF, weight)`.
type SpringVector = Vec<(usize, f64)>;

/// The spring DOF vectors of a track over its free DOFs (constrained DOFs dropped).
fn spring_vectors(track: &TrackStructure) -> Vec<SpringVector> {
    track
        .springs
        .iter()
        .map(|s| {
            let a = s.side_a.iter().map(|&(d, w)| (d, w));
            let b = s.side_b.iter().map(|&(d, w)| (d, -w));
            a.chain(b)
                .filter_map(|(d, w)| track.dofmap.free_index(d).map(|i| (i, w)))
                .collect()
        })
        .collect()
}

/// The reference factorisation and what has been solved with it.
struct Reference {
    factor: StiffnessFactor,
    /// Reference stiffness of every spring (N/m).
    stiffness: Vec<f64>,
    /// Every spring's DOF vector (the layout the cases must share).
    vectors: Vec<SpringVector>,
    /// Free DOFs of the track.
    n: usize,
    /// The planes `(p0, p1)` of the stored plane values, and the line's node sets there.
    planes: Option<Planes>,
    /// Springs solved so far (indices into `vectors`), the order of `a`'s and `z`'s rows.
    solved: Vec<usize>,
    /// `g_sᵀ K₀⁻¹ g_t` for the solved springs.
    a: Mat<f64>,
    /// `g_sᵀ K₀⁻¹ b_{p,d}` for the solved springs (rows) and the planes' loads (columns,
    /// `3(p − p0) + d`).
    z: Mat<f64>,
}

/// The stored plane values of the reference.
struct Planes {
    p0: usize,
    p1: usize,
    nodes: Vec<Vec<(usize, f64)>>,
    axes: [[f64; 3]; 3],
    g: Vec<[f64; 3]>,
    cross: Vec<[f64; 3]>,
}

/// The reference factorisation shared by a study's cases (see the module doc); one per
/// spring layout.
pub(crate) struct StaticUpdater {
    reference: Mutex<Reference>,
}

impl StaticUpdater {
    /// Factorises the stiffness of `track` (the reference; N/m, free DOFs).
    pub fn new(track: &TrackStructure) -> Result<Self, DynamicsError> {
        let (mats, _) = track.assemble()?;
        let factor = StiffnessFactor::new(mats.k.as_ref())?;
        Ok(Self {
            reference: Mutex::new(Reference {
                factor,
                stiffness: track.springs.iter().map(|s| s.stiffness).collect(),
                vectors: spring_vectors(track),
                n: track.dofmap.n_free(),
                planes: None,
                solved: Vec::new(),
                a: Mat::zeros(0, 0),
                z: Mat::zeros(0, 0),
            }),
        })
    }

    /// The static flexibility source of a case's track (same solids and spring layout as
    /// the reference, any spring stiffnesses).
    pub(crate) fn for_track<'a>(&'a self, track: &TrackStructure) -> CaseStatic<'a> {
        CaseStatic {
            updater: self,
            stiffness: track.springs.iter().map(|s| s.stiffness).collect(),
            vectors: spring_vectors(track),
            n: track.dofmap.n_free(),
        }
    }
}

/// The static flexibility of one case ([`StaticUpdater::for_track`]).
pub(crate) struct CaseStatic<'a> {
    updater: &'a StaticUpdater,
    stiffness: Vec<f64>,
    vectors: Vec<SpringVector>,
    n: usize,
}

fn layout_error(found: usize, expected: usize) -> DynamicsError {
    DynamicsError::SizeMismatch {
        what: "study static flexibility: the case's springs or DOFs vs the reference track's (the cases must share the spring layout)",
        found,
        expected,
    }
}

impl Reference {
    /// `K₀⁻¹ x` for the columns of `rhs` (one pass over the factor).
    fn solve(&self, rhs: faer::MatMut<'_, f64>) {
        let mut ws = self.factor.workspace(rhs.ncols().max(1));
        self.factor.solve_in_place(rhs, &mut ws);
    }

    /// The plane values of `p0..=p1` (solves once per range; a new range drops the solved
    /// springs, whose `z` rows belong to the old one).
    fn ensure_planes(
        &mut self,
        track: &TrackStructure,
        line: &RailContactLine,
        frame: &ContactFrame,
        p0: usize,
        p1: usize,
    ) -> Result<(), DynamicsError> {
        if self
            .planes
            .as_ref()
            .is_some_and(|p| p.p0 == p0 && p.p1 == p1)
        {
            return Ok(());
        }
        let (g, cross) = self.factor.plane_flexibility(track, line, frame, p0, p1)?;
        self.planes = Some(Planes {
            p0,
            p1,
            nodes: line.nodes[p0..=p1].to_vec(),
            axes: [frame.x, frame.t, frame.n],
            g,
            cross,
        });
        self.solved.clear();
        self.a = Mat::zeros(0, 0);
        self.z = Mat::zeros(0, 0);
        Ok(())
    }

    /// Solves with the springs in `springs` not solved yet and extends `a` and `z`.
    fn ensure_springs(&mut self, track: &TrackStructure, springs: &[usize]) {
        let new: Vec<usize> = springs
            .iter()
            .copied()
            .filter(|s| !self.solved.contains(s))
            .collect();
        if new.is_empty() {
            return;
        }
        let Some(planes) = self.planes.as_ref() else {
            return;
        };
        let all: Vec<usize> = self.solved.iter().chain(&new).copied().collect();
        let (old, tot) = (self.solved.len(), all.len());
        let ncol = 3 * planes.nodes.len();
        let mut a = Mat::<f64>::zeros(tot, tot);
        let mut z = Mat::<f64>::zeros(tot, ncol);
        for i in 0..old {
            for j in 0..old {
                a[(i, j)] = self.a[(i, j)];
            }
            for c in 0..ncol {
                z[(i, c)] = self.z[(i, c)];
            }
        }
        // K₀⁻¹ g_s for the new springs, CHUNK at a time (n × CHUNK of memory)
        let mut u = Mat::<f64>::zeros(self.n, CHUNK.min(new.len()));
        for (c0, chunk) in new.chunks(CHUNK).enumerate() {
            u.fill(0.0);
            for (j, &s) in chunk.iter().enumerate() {
                for &(i, w) in &self.vectors[s] {
                    u[(i, j)] += w;
                }
            }
            self.solve(u.as_mut().subcols_mut(0, chunk.len()));
            for j in 0..chunk.len() {
                let col = old + c0 * CHUNK + j;
                for (i, &t) in all.iter().enumerate() {
                    let v: f64 = self.vectors[t].iter().map(|&(r, w)| w * u[(r, j)]).sum();
                    a[(i, col)] = v;
                    a[(col, i)] = v;
                }
                for (p, nodes) in planes.nodes.iter().enumerate() {
                    for d in 0..3 {
                        z[(col, 3 * p + d)] =
                            nodes_dot(nodes, &track.dofmap, planes.axes[d], |r| u[(r, j)]);
                    }
                }
            }
        }
        // the pairs among the new springs were written from both sides; keep them symmetric
        for i in old..tot {
            for j in old..i {
                let v = 0.5 * (a[(i, j)] + a[(j, i)]);
                a[(i, j)] = v;
                a[(j, i)] = v;
            }
        }
        self.solved = all;
        self.a = a;
        self.z = z;
    }
}

impl StaticFlexibility for CaseStatic<'_> {
    fn n(&self) -> usize {
        self.n
    }

    fn plane_flexibility(
        &self,
        track: &TrackStructure,
        line: &RailContactLine,
        frame: &ContactFrame,
        p0: usize,
        p1: usize,
    ) -> Result<PlaneFlexibility, DynamicsError> {
        let mut r = self
            .updater
            .reference
            .lock()
            .map_err(|_| layout_error(0, 0))?;
        if r.n != self.n || r.vectors != self.vectors {
            return Err(layout_error(self.vectors.len(), r.vectors.len()));
        }
        r.ensure_planes(track, line, frame, p0, p1)?;
        let changed: Vec<usize> = (0..self.stiffness.len())
            .filter(|&s| self.stiffness[s] != r.stiffness[s])
            .collect();
        r.ensure_springs(track, &changed);
        let planes = r.planes.as_ref().ok_or_else(|| layout_error(0, 1))?;
        let (mut g, mut cross) = (planes.g.clone(), planes.cross.clone());
        if changed.is_empty() {
            return Ok((g, cross));
        }
        // rows of the solved springs that changed, with Δ
        let rows: Vec<(usize, f64)> = changed
            .iter()
            .map(|&s| {
                let i = r.solved.iter().position(|&t| t == s).unwrap_or(usize::MAX);
                (i, self.stiffness[s] - r.stiffness[s])
            })
            .collect();
        if rows.iter().any(|&(i, _)| i == usize::MAX) {
            return Err(layout_error(rows.len(), r.solved.len()));
        }
        let m = rows.len();
        let ncol = r.z.ncols();
        // (I + ΔA) X = Δ Z
        let lhs = Mat::<f64>::from_fn(m, m, |i, j| {
            let (ri, di) = rows[i];
            let diag = if i == j { 1.0 } else { 0.0 };
            diag + di * r.a[(ri, rows[j].0)]
        });
        let rhs = Mat::<f64>::from_fn(m, ncol, |i, c| rows[i].1 * r.z[(rows[i].0, c)]);
        let x = {
            use faer::linalg::solvers::Solve;
            lhs.partial_piv_lu().solve(&rhs)
        };
        let zx = |ca: usize, cb: usize| -> f64 {
            (0..m).map(|i| r.z[(rows[i].0, ca)] * x[(i, cb)]).sum()
        };
        let np = planes.nodes.len();
        for p in 0..np {
            for d in 0..3 {
                g[p][d] -= zx(3 * p + d, 3 * p + d);
                if p + 1 < np {
                    cross[p][d] -= zx(3 * p + d, 3 * (p + 1) + d);
                }
            }
        }
        if g.iter()
            .flatten()
            .chain(cross.iter().flatten())
            .any(|v| !v.is_finite())
        {
            return Err(DynamicsError::Passage(
                crate::passage::PassageError::StiffnessIndefinite {
                    negative_pivots: 0,
                    min_rel_pivot: 0.0,
                },
            ));
        }
        Ok((g, cross))
    }
}

#[cfg(test)]
mod tests {
    use super::{
        ContactFrame, Mat, RailContactLine, StaticFlexibility, StaticUpdater, StiffnessFactor,
        TrackStructure,
    };
    use crate::model::test_problems::small_model;

    /// The updated reference against an independent factorisation of each case's own `K`
    /// (the small track): a 4× softer and a 2× stiffer vertical railpad, then a stiffer
    /// ballast (new springs solved on the way), then the reference itself again.
    #[test]
    fn updated_flexibility_matches_a_factorisation_of_the_case_stiffness() {
        let reference = TrackStructure::build(&small_model(&[]).unwrap()).unwrap();
        let updater = StaticUpdater::new(&reference).unwrap();
        let cases: [&[&str]; 4] = [
            &["fastening.vertical_stiffness=0.325e9"],
            &["fastening.vertical_stiffness=2.6e9"],
            &[
                "fastening.vertical_stiffness=2.6e9",
                "ballast.vertical_stiffness=90e6",
            ],
            &[],
        ];
        for set in cases {
            let m = small_model(set).unwrap();
            let track = TrackStructure::build(&m).unwrap();
            let frame = ContactFrame::for_inclination(m.rail.inclination);
            let none = Mat::<f64>::zeros(track.dofmap.n_free(), 0);
            let line = RailContactLine::new(&track, &none, &frame, 0.006).unwrap();
            let p0 = line.planes_x_m.len() / 2 - 4;
            let (p1, case) = (p0 + 8, updater.for_track(&track));
            let (g, cross) = case
                .plane_flexibility(&track, &line, &frame, p0, p1)
                .unwrap();
            let (mats, _) = track.assemble().unwrap();
            let own = StiffnessFactor::new(mats.k.as_ref()).unwrap();
            let (g0, cross0) = own
                .plane_flexibility(&track, &line, &frame, p0, p1)
                .unwrap();
            let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
            let worst = g
                .iter()
                .zip(&g0)
                .chain(cross.iter().zip(&cross0))
                .flat_map(|(a, b)| (0..3).map(move |d| rel(a[d], b[d])))
                .fold(0.0, f64::max);
            eprintln!(
                "{set:?}: worst relative difference {worst:e}, G_n {:e}",
                g0[4][2]
            );
            assert!(worst < 1e-8, "{set:?}: {worst:e}");
        }
        let r = updater.reference.lock().unwrap();
        let pads = reference
            .spring_kinds
            .iter()
            .zip(&reference.springs)
            .filter(|(k, s)| {
                **k == crate::structure::track::SpringKind::Fastening && s.side_a[0].0 % 3 == 2
            })
            .count();
        assert!(
            r.solved.len() > pads,
            "{} solved, {pads} vertical pads",
            r.solved.len()
        );
    }
}
