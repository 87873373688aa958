//! Substructured modal model of the track (docs/theory.md §5.8): component bases of the rail
//! and of one sleeper, the railpad, ballast and elastic-hold springs as parameters of the
//! assembled reduced system.
//!
//! # Components
//! Without its springs the track falls apart into the rail (with the fastening's rigid holds,
//! which are constraints to the ground, not interfaces) and the half sleepers, which are
//! identical: one sleeper's basis serves all. Each component gets a Ritz basis:
//!
//! - its **free-interface modes** below the component cutoff `f_c` (= `cutoff_factor` ×
//!   f_max): shift-invert Lanczos for the rail, a dense eigensolution for the sleeper;
//! - **residual attachment vectors**: the static response `(K + αM)⁻¹ F` of the component to
//!   smooth load patterns over each group of spring attachment points (a group = one
//!   fastening's railpad, one elastic-hold region or one sleeper's ballast, in one direction;
//!   patterns = the tensor-product polynomials of degree ≤ `pattern_degree` in the points'
//!   coordinates), with the kept modes' part removed (MacNeal's residual flexibility,
//!   Craig & Kurdila 2006 §15.4). α > 0 makes `K + αM` definite for a component with
//!   rigid-body modes.
//!
//! A Rayleigh–Ritz step on each component's span makes the basis `Ψ_c` M-orthonormal and
//! K-orthogonal (`Ψ_cᵀ K_c Ψ_c = diag(ω̃²)`).
//!
//! # The assembled reduced system
//! `Ψ = blockdiag(Ψ_rail, Ψ_sleeper, …, Ψ_sleeper)`. The track's stiffness is the solids'
//! block-diagonal stiffness plus the springs `Σ_s k_s g_s g_sᵀ` ([`crate::fe::spring`]), so
//!
//! ```text
//! K_red(k) = diag(ω̃²) + Σ_s k_s (Ψᵀ g_s)(Ψᵀ g_s)ᵀ,    M_red = I,
//! ```
//!
//! exact for any spring stiffness on the span of `Ψ`: a new railpad, ballast or elastic-hold
//! stiffness needs only the dense eigenproblem of `K_red` (a few thousand unknowns), and
//! the track's modes are `Φ = Ψ Q` for the eigenvectors `Q` below f_max. Damping enters
//! neither K nor M: the passage projects the assembled C on `Φ` as for the full basis.
//!
//! # What it cannot represent
//! A change of the spring *layout* (which DOFs a spring joins: mesh, footprint, hold regions,
//! a stiffness switched between zero and non-zero with zero damping) or of a rigid hold is a
//! new component model (the component key holds the layout); non-identical sleepers are
//! refused ([`SubstructureError::SleepersDiffer`]). The full Lanczos basis
//! ([`super::basis::track_basis`]) stays the reference for everything.

use std::collections::BTreeMap;
use std::time::Instant;

use faer::linalg::matmul::matmul;
use faer::sparse::{SparseColMat, SparseColMatRef, Triplet};
use faer::{Accum, Mat, MatRef, Par, Side};

use super::basis::{classify_in_chunks, BasisError, ModalBasis};
use super::cache::{CacheKey, CacheLookup, CacheMeta, ModalCache};
use super::classify::{TrackClassifier, TrackModeClass};
use super::factor::ShiftedSystem;
use super::spmm::sym_spmm;
use super::{solve, EigenError, EigenOptions, FillOrdering};
use crate::fe::assembly::{assemble, AssemblyOptions, FeMatrices};
use crate::model::Model;
use crate::structure::track::SpringKind;
use crate::structure::TrackStructure;

/// Errors of the substructured track model.
#[derive(Debug, thiserror::Error)]
pub enum SubstructureError {
    /// Building, assembling or caching a basis failed.
    #[error(transparent)]
    Basis(#[from] BasisError),
    /// An eigensolution or factorisation failed.
    #[error("{what}: {source}")]
    Eigen {
        /// Which component or step.
        what: &'static str,
        /// The solver error.
        source: EigenError,
    },
    /// The half sleepers' matrices differ, so one sleeper's basis cannot serve all.
    #[error("sleeper {index} differs from sleeper 0 (max relative difference {difference:e} of its K or M): the substructured basis needs identical sleepers; use basis = \"full\"")]
    SleepersDiffer {
        /// The first differing sleeper.
        index: usize,
        /// Largest relative entry difference.
        difference: f64,
    },
    /// A spring joins DOFs the component split does not expect.
    #[error("spring {index} ({kind:?}) joins {what}: the substructured basis cannot represent it; use basis = \"full\"")]
    Layout {
        /// Spring index in the track structure.
        index: usize,
        /// Its kind.
        kind: SpringKind,
        /// What it joins.
        what: String,
    },
    /// Bad options.
    #[error("substructure option {name} = {value}: {allowed}")]
    Option {
        /// The option.
        name: &'static str,
        /// The value given.
        value: String,
        /// What is allowed.
        allowed: &'static str,
    },
}

/// Options of the component bases.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SubstructureOptions {
    /// Rail modes are kept below `cutoff_factor × f_max` (−, 1 to 4; default 1.5).
    pub cutoff_factor: f64,
    /// Sleeper modes are kept below `sleeper_cutoff_factor × f_max` (−, 1 to 4; default 1:
    /// the coarse sleeper mesh has a dense spectrum above f_max, and every sleeper mode is
    /// repeated once per sleeper in the reduced system).
    pub sleeper_cutoff_factor: f64,
    /// Highest degree per coordinate of the attachment load patterns (−, 0 to 3; default 3:
    /// 16 patterns per group and direction); the ballast's patterns (soft springs under a
    /// stiff sleeper) are at most bilinear.
    pub pattern_degree: usize,
}

impl Default for SubstructureOptions {
    fn default() -> Self {
        Self {
            cutoff_factor: 1.5,
            sleeper_cutoff_factor: 1.0,
            pattern_degree: 3,
        }
    }
}

impl SubstructureOptions {
    /// Checks the ranges.
    pub fn validate(&self) -> Result<(), SubstructureError> {
        for (name, v) in [
            ("cutoff_factor", self.cutoff_factor),
            ("sleeper_cutoff_factor", self.sleeper_cutoff_factor),
        ] {
            if !(v.is_finite() && (1.0..=4.0).contains(&v)) {
                return Err(SubstructureError::Option {
                    name,
                    value: v.to_string(),
                    allowed: "1 to 4",
                });
            }
        }
        if self.pattern_degree > 3 {
            return Err(SubstructureError::Option {
                name: "pattern_degree",
                value: self.pattern_degree.to_string(),
                allowed: "0 to 3",
            });
        }
        Ok(())
    }
}

/// One component's Ritz basis: M-orthonormal columns with `Ψᵀ K Ψ = diag(omega2)`.
#[derive(Clone, Debug)]
pub struct ComponentBasis {
    /// Basis vectors over the component's free DOFs (n × N; m/√kg).
    pub vectors: Mat<f64>,
    /// `ω̃²` per vector (rad²/s²).
    pub omega2: Vec<f64>,
    /// How many leading vectors are component modes (the rest are attachment vectors).
    pub modes: usize,
}

/// The component bases of one track (see the module doc).
#[derive(Clone, Debug)]
pub struct TrackComponents {
    /// The rail's basis over the rail's free DOFs (the leading free DOFs of the track).
    pub rail: ComponentBasis,
    /// One sleeper's basis over its DOFs (node order of the sleeper mesh).
    pub sleeper: ComponentBasis,
    /// First free DOF of each sleeper.
    pub sleeper_offsets: Vec<usize>,
    /// Wall time to load or build (s).
    pub seconds: f64,
    /// True when both bases came from the cache.
    pub cached: bool,
}

impl TrackComponents {
    /// Size of the assembled reduced system.
    pub fn reduced_size(&self) -> usize {
        self.rail.omega2.len() + self.sleeper_offsets.len() * self.sleeper.omega2.len()
    }
}

/// Free-DOF split of the track: the rail's free DOFs `0..rail_dofs`, then the sleepers, each
/// `sleeper_dofs` long from its offset.
struct Split {
    rail_dofs: usize,
    sleeper_offsets: Vec<usize>,
    sleeper_dofs: usize,
}

fn split(track: &TrackStructure) -> Result<Split, SubstructureError> {
    let dm = &track.dofmap;
    let first_sleeper_node = track
        .sleepers
        .first()
        .map(|s| s.node_offset)
        .unwrap_or(track.mesh.nodes.len());
    let rail_dofs = (0..dm.n_free())
        .take_while(|&f| dm.global_dof(f) < 3 * first_sleeper_node)
        .count();
    let nodes_per = if track.sleepers.len() > 1 {
        track.sleepers[1].node_offset - track.sleepers[0].node_offset
    } else {
        track.mesh.nodes.len() - first_sleeper_node
    };
    let mut offsets = Vec::with_capacity(track.sleepers.len());
    for (i, s) in track.sleepers.iter().enumerate() {
        let f0 = dm.free_index(3 * s.node_offset);
        let f1 = dm.free_index(3 * (s.node_offset + nodes_per) - 1);
        match (f0, f1) {
            (Some(a), Some(b)) if b + 1 - a == 3 * nodes_per => offsets.push(a),
            _ => {
                return Err(SubstructureError::Layout {
                    index: i,
                    kind: SpringKind::Ballast,
                    what: format!(
                        "sleeper {i}, which has constrained DOFs or a different node count"
                    ),
                })
            }
        }
    }
    Ok(Split {
        rail_dofs,
        sleeper_offsets: offsets,
        sleeper_dofs: 3 * nodes_per,
    })
}

/// The track's solids without springs (K, M over the track's free DOFs, rigid holds applied).
fn solid_matrices(track: &TrackStructure) -> Result<FeMatrices, SubstructureError> {
    Ok(assemble(
        &track.mesh,
        &track.materials,
        &[],
        &[],
        &track.dofmap,
        AssemblyOptions { mass: track.mass },
    )
    .map_err(|e| BasisError::Structure(e.into()))?)
}

/// The square block `[r0, r0 + n)` of a full-storage sparse matrix.
fn sparse_block(
    a: SparseColMatRef<'_, usize, f64>,
    r0: usize,
    n: usize,
) -> SparseColMat<usize, f64> {
    let mut trip = Vec::new();
    for j in r0..r0 + n {
        let rows = a.symbolic().row_idx_of_col_raw(j);
        let vals = a.val_of_col(j);
        for (&i, &v) in rows.iter().zip(vals) {
            if i >= r0 && i < r0 + n {
                trip.push(Triplet::new(i - r0, j - r0, v));
            }
        }
    }
    SparseColMat::try_new_from_triplets(n, n, &trip).expect("indices in range")
}

/// The dense block `[r0, r0 + n)` of a full-storage sparse matrix.
fn dense_block(a: SparseColMatRef<'_, usize, f64>, r0: usize, n: usize) -> Mat<f64> {
    let mut d = Mat::<f64>::zeros(n, n);
    for j in r0..r0 + n {
        let rows = a.symbolic().row_idx_of_col_raw(j);
        for (&i, &v) in rows.iter().zip(a.val_of_col(j)) {
            if i >= r0 && i < r0 + n {
                d[(i - r0, j - r0)] += v;
            }
        }
    }
    d
}

/// A group of attachment DOFs of one component (one direction): component-local DOF index
/// and the point's in-plane coordinates (m).
type Group = Vec<(usize, [f64; 2])>;

/// Load patterns over the groups: for each group, the tensor-product polynomials of degree
/// ≤ `degree` in the coordinates scaled to [−1, 1] over the group's extent.
/// Ballast groups (kind 1) get at most degree 1.
fn patterns(groups: &BTreeMap<(u8, usize, usize), Group>, n: usize, max_degree: usize) -> Mat<f64> {
    let degree_of = |kind: u8| {
        if kind == 1 {
            max_degree.min(1)
        } else {
            max_degree
        }
    };
    let total: usize = groups
        .keys()
        .map(|k| (degree_of(k.0) + 1) * (degree_of(k.0) + 1))
        .sum();
    let mut f = Mat::<f64>::zeros(n, total);
    let mut col0 = 0;
    for (key, pts) in groups {
        let degree = degree_of(key.0);
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for (_, p) in pts {
            for a in 0..2 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        let scaled = |p: &[f64; 2], a: usize| {
            let h = 0.5 * (hi[a] - lo[a]);
            if h > 1e-9 {
                (p[a] - 0.5 * (hi[a] + lo[a])) / h
            } else {
                0.0
            }
        };
        for &(dof, p) in pts {
            let (s, t) = (scaled(&p, 0), scaled(&p, 1));
            for i in 0..=degree {
                for j in 0..=degree {
                    f[(dof, col0 + i * (degree + 1) + j)] = s.powi(i as i32) * t.powi(j as i32);
                }
            }
        }
        col0 += (degree + 1) * (degree + 1);
    }
    f
}

/// Which component a free DOF belongs to: `None` = rail, `Some(i)` = sleeper `i`; with its
/// component-local index.
fn locate(sp: &Split, free: usize) -> (Option<usize>, usize) {
    if free < sp.rail_dofs {
        return (None, free);
    }
    let i = sp
        .sleeper_offsets
        .partition_point(|&o| o <= free)
        .saturating_sub(1);
    (Some(i), free - sp.sleeper_offsets[i])
}

/// Attachment groups of the rail (kind, sleeper, direction) and of the sleeper (kind, 0,
/// direction; the union over all sleepers in sleeper-local coordinates).
#[allow(clippy::type_complexity)]
fn attachment_groups(
    track: &TrackStructure,
    sp: &Split,
) -> Result<
    (
        BTreeMap<(u8, usize, usize), Group>,
        BTreeMap<(u8, usize, usize), Group>,
    ),
    SubstructureError,
> {
    let mut rail: BTreeMap<(u8, usize, usize), Group> = BTreeMap::new();
    let mut sleeper: BTreeMap<(u8, usize, usize), Group> = BTreeMap::new();
    let xs = &track.layout.sleepers;
    let nearest = |x: f64| {
        (0..xs.len())
            .min_by(|&a, &b| (xs[a] - x).abs().total_cmp(&(xs[b] - x).abs()))
            .unwrap_or(0)
    };
    for (si, (s, &kind)) in track.springs.iter().zip(&track.spring_kinds).enumerate() {
        let kc = match kind {
            SpringKind::Fastening => 0u8,
            SpringKind::Ballast => 1,
            SpringKind::Hold => 2,
        };
        for &(dof, _) in s.side_a.iter().chain(&s.side_b) {
            let Some(free) = track.dofmap.free_index(dof) else {
                continue;
            };
            let [x, y, _] = track.mesh.nodes[dof / 3];
            let d = dof % 3;
            match locate(sp, free) {
                (None, local) => {
                    if kind == SpringKind::Ballast {
                        return Err(SubstructureError::Layout {
                            index: si,
                            kind,
                            what: "the rail".into(),
                        });
                    }
                    rail.entry((kc, nearest(x), d))
                        .or_default()
                        .push((local, [x, y]));
                }
                (Some(i), local) => {
                    if kind == SpringKind::Hold {
                        return Err(SubstructureError::Layout {
                            index: si,
                            kind,
                            what: "a sleeper".into(),
                        });
                    }
                    sleeper
                        .entry((kc, 0, d))
                        .or_default()
                        .push((local, [x - xs[i], y]));
                }
            }
        }
    }
    for g in rail.values_mut().chain(sleeper.values_mut()) {
        g.sort_by_key(|a| a.0);
        g.dedup_by(|a, b| a.0 == b.0);
    }
    Ok((rail, sleeper))
}

/// Removes the M-components along the M-orthonormal `phi` from `a` (twice, for round-off).
fn m_orthogonalise(
    a: &mut Mat<f64>,
    phi: MatRef<'_, f64>,
    m: &dyn Fn(MatRef<'_, f64>) -> Mat<f64>,
) {
    if phi.ncols() == 0 {
        return;
    }
    for _ in 0..2 {
        let ma = m(a.as_ref());
        let mut c = Mat::<f64>::zeros(phi.ncols(), a.ncols());
        matmul(
            c.as_mut(),
            Accum::Replace,
            phi.transpose(),
            ma.as_ref(),
            1.0,
            Par::rayon(0),
        );
        matmul(a.as_mut(), Accum::Add, phi, c.as_ref(), -1.0, Par::rayon(0));
    }
}

/// Relative size below which a direction of the attachment span is dropped as dependent.
const DEPENDENCE_TOLERANCE: f64 = 1e-10;

/// Rayleigh–Ritz on the span of `a` (already M-orthogonal to the kept modes): M-orthonormal,
/// K-orthogonal vectors and their `ω̃²`, dependent directions dropped.
fn ritz(
    a: &Mat<f64>,
    k: &dyn Fn(MatRef<'_, f64>) -> Mat<f64>,
    m: &dyn Fn(MatRef<'_, f64>) -> Mat<f64>,
) -> Result<(Mat<f64>, Vec<f64>), SubstructureError> {
    let q = a.ncols();
    if q == 0 {
        return Ok((Mat::zeros(a.nrows(), 0), vec![]));
    }
    let gram = |b: Mat<f64>| {
        let mut g = Mat::<f64>::zeros(q, q);
        matmul(
            g.as_mut(),
            Accum::Replace,
            a.transpose(),
            b.as_ref(),
            1.0,
            Par::rayon(0),
        );
        Mat::from_fn(q, q, |i, j| 0.5 * (g[(i, j)] + g[(j, i)]))
    };
    let ma = gram(m(a.as_ref()));
    let ka = gram(k(a.as_ref()));
    let eig = |x: MatRef<'_, f64>, what: &'static str| {
        x.self_adjoint_eigen(Side::Lower)
            .map_err(|e| SubstructureError::Eigen {
                what,
                source: EigenError::Factorization {
                    shift_rad2_s2: f64::NAN,
                    reason: format!("dense symmetric eigensolver failed: {e:?}"),
                },
            })
    };
    let em = eig(ma.as_ref(), "attachment Gram matrix")?;
    let d = em.S().column_vector();
    let dmax = (0..q).map(|i| d[i]).fold(0.0, f64::max);
    let keep: Vec<usize> = (0..q)
        .filter(|&i| d[i] > DEPENDENCE_TOLERANCE * dmax)
        .collect();
    let w = Mat::<f64>::from_fn(q, keep.len(), |i, j| {
        em.U()[(i, keep[j])] / d[keep[j]].sqrt()
    });
    let mut kw = Mat::<f64>::zeros(q, keep.len());
    matmul(
        kw.as_mut(),
        Accum::Replace,
        ka.as_ref(),
        w.as_ref(),
        1.0,
        Par::Seq,
    );
    let mut kt = Mat::<f64>::zeros(keep.len(), keep.len());
    matmul(
        kt.as_mut(),
        Accum::Replace,
        w.transpose(),
        kw.as_ref(),
        1.0,
        Par::Seq,
    );
    let kt = Mat::from_fn(kt.nrows(), kt.ncols(), |i, j| {
        0.5 * (kt[(i, j)] + kt[(j, i)])
    });
    let ek = eig(kt.as_ref(), "attachment Ritz problem")?;
    let mut t = Mat::<f64>::zeros(q, keep.len());
    matmul(
        t.as_mut(),
        Accum::Replace,
        w.as_ref(),
        ek.U(),
        1.0,
        Par::Seq,
    );
    let mut v = Mat::<f64>::zeros(a.nrows(), keep.len());
    matmul(
        v.as_mut(),
        Accum::Replace,
        a.as_ref(),
        t.as_ref(),
        1.0,
        Par::rayon(0),
    );
    let s = ek.S().column_vector();
    Ok((v, (0..keep.len()).map(|i| s[i].max(0.0)).collect()))
}

fn hz_to_omega2(f: f64) -> f64 {
    let w = 2.0 * std::f64::consts::PI * f;
    w * w
}

/// The shift α of the attachment solves `(K + αM)⁻¹`: (f_c / 10)² in rad²/s², small against
/// the truncated modes, large enough to keep rigid-body parts of the static response a
/// modest multiple of the residual part.
fn attachment_shift(cutoff_hz: f64) -> f64 {
    hz_to_omega2(0.1 * cutoff_hz)
}

/// The rail's basis: Lanczos modes below the cutoff plus the residual attachment vectors.
fn rail_basis(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    f: Mat<f64>,
    cutoff_hz: f64,
) -> Result<ComponentBasis, SubstructureError> {
    let sol = solve(k, m, &EigenOptions::new(cutoff_hz), None).map_err(|source| {
        SubstructureError::Eigen {
            what: "rail component modes",
            source,
        }
    })?;
    let alpha = attachment_shift(cutoff_hz);
    let sys = ShiftedSystem::new(k, m, FillOrdering::Auto, Par::rayon(0)).map_err(|source| {
        SubstructureError::Eigen {
            what: "rail attachment factorisation",
            source,
        }
    })?;
    let fac = sys
        .factorize(-alpha)
        .map_err(|source| SubstructureError::Eigen {
            what: "rail attachment factorisation",
            source,
        })?
        .ok_or(SubstructureError::Eigen {
            what: "rail attachment factorisation",
            source: EigenError::Factorization {
                shift_rad2_s2: -alpha,
                reason: "K + αM is singular".into(),
            },
        })?;
    let mut a = f;
    let mut ws = sys.solve_buffer(a.ncols());
    sys.solve_in_place(&fac, a.as_mut(), &mut ws);
    let kop = |x: MatRef<'_, f64>| {
        let mut y = Mat::<f64>::zeros(x.nrows(), x.ncols());
        sym_spmm(k, x, y.as_mut());
        y
    };
    let mop = |x: MatRef<'_, f64>| {
        let mut y = Mat::<f64>::zeros(x.nrows(), x.ncols());
        sym_spmm(m, x, y.as_mut());
        y
    };
    m_orthogonalise(&mut a, sol.modes.as_ref(), &mop);
    let (v, w2) = ritz(&a, &kop, &mop)?;
    let modes = sol.modes.ncols();
    Ok(ComponentBasis {
        vectors: concat_cols(&sol.modes, &v),
        omega2: sol
            .eigenvalues_rad2_s2
            .iter()
            .map(|&l| l.max(0.0))
            .chain(w2)
            .collect(),
        modes,
    })
}

/// One sleeper's basis: dense modes below the cutoff plus the residual attachment vectors.
fn sleeper_basis(
    k: &Mat<f64>,
    m: &Mat<f64>,
    f: Mat<f64>,
    cutoff_hz: f64,
) -> Result<ComponentBasis, SubstructureError> {
    let n = k.nrows();
    let eig_err = |what: &'static str, reason: String| SubstructureError::Eigen {
        what,
        source: EigenError::Factorization {
            shift_rad2_s2: f64::NAN,
            reason,
        },
    };
    // Generalised problem via M^{-1/2} (the lumped or consistent M is definite).
    let lm = m
        .llt(Side::Lower)
        .map_err(|e| eig_err("sleeper mass", format!("{e:?}")))?;
    let l = lm.L().to_owned();
    // A = L⁻¹ K L⁻ᵀ.
    use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
    let mut x = k.clone();
    solve_lower_triangular_in_place(l.as_ref(), x.as_mut(), Par::Seq);
    let mut a = x.transpose().to_owned();
    solve_lower_triangular_in_place(l.as_ref(), a.as_mut(), Par::Seq);
    let a = Mat::from_fn(n, n, |i, j| 0.5 * (a[(i, j)] + a[(j, i)]));
    let e = a
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| eig_err("sleeper modes", format!("{e:?}")))?;
    let lam_c = hz_to_omega2(cutoff_hz);
    let s = e.S().column_vector();
    let kept: Vec<usize> = (0..n).filter(|&i| s[i] < lam_c).collect();
    // φ = L⁻ᵀ y.
    let mut phi = Mat::<f64>::from_fn(n, kept.len(), |i, j| e.U()[(i, kept[j])]);
    use faer::linalg::triangular_solve::solve_upper_triangular_in_place;
    solve_upper_triangular_in_place(l.transpose(), phi.as_mut(), Par::Seq);
    let alpha = attachment_shift(cutoff_hz);
    let shifted = Mat::from_fn(n, n, |i, j| k[(i, j)] + alpha * m[(i, j)]);
    let ls = shifted
        .llt(Side::Lower)
        .map_err(|e| eig_err("sleeper attachment factorisation", format!("{e:?}")))?;
    use faer::linalg::solvers::Solve;
    let mut att = f;
    ls.solve_in_place(att.as_mut());
    let dense = |op: &Mat<f64>| {
        let op = op.clone();
        move |x: MatRef<'_, f64>| {
            let mut y = Mat::<f64>::zeros(x.nrows(), x.ncols());
            matmul(y.as_mut(), Accum::Replace, op.as_ref(), x, 1.0, Par::Seq);
            y
        }
    };
    let (kop, mop) = (dense(k), dense(m));
    m_orthogonalise(&mut att, phi.as_ref(), &mop);
    let (v, w2) = ritz(&att, &kop, &mop)?;
    Ok(ComponentBasis {
        vectors: concat_cols(&phi, &v),
        omega2: kept.iter().map(|&i| s[i].max(0.0)).chain(w2).collect(),
        modes: kept.len(),
    })
}

fn concat_cols(a: &Mat<f64>, b: &Mat<f64>) -> Mat<f64> {
    let (p, q) = (a.ncols(), b.ncols());
    Mat::from_fn(a.nrows(), p + q, |i, j| {
        if j < p {
            a[(i, j)]
        } else {
            b[(i, j - p)]
        }
    })
}

/// Checks that every sleeper's K and M block equals sleeper 0's; returns sleeper 0's blocks.
fn identical_sleepers(
    mats: &FeMatrices,
    sp: &Split,
) -> Result<(Mat<f64>, Mat<f64>), SubstructureError> {
    let n = sp.sleeper_dofs;
    let k0 = dense_block(mats.k.as_ref(), sp.sleeper_offsets[0], n);
    let m0 = dense_block(mats.m.as_ref(), sp.sleeper_offsets[0], n);
    let scale = |a: &Mat<f64>| {
        (0..n)
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .map(|(i, j)| a[(i, j)].abs())
            .fold(0.0, f64::max)
    };
    let (sk, sm) = (scale(&k0), scale(&m0));
    for (idx, &o) in sp.sleeper_offsets.iter().enumerate().skip(1) {
        let ki = dense_block(mats.k.as_ref(), o, n);
        let mi = dense_block(mats.m.as_ref(), o, n);
        let mut diff: f64 = 0.0;
        for i in 0..n {
            for j in 0..n {
                diff = diff
                    .max((ki[(i, j)] - k0[(i, j)]).abs() / sk)
                    .max((mi[(i, j)] - m0[(i, j)]).abs() / sm);
            }
        }
        if diff > 1e-9 {
            return Err(SubstructureError::SleepersDiffer {
                index: idx,
                difference: diff,
            });
        }
    }
    Ok((k0, m0))
}

/// Builds the component bases of a track (no cache).
pub fn build_components(
    track: &TrackStructure,
    fmax_hz: f64,
    opts: &SubstructureOptions,
) -> Result<TrackComponents, SubstructureError> {
    opts.validate()?;
    let t = Instant::now();
    let sp = split(track)?;
    if sp.sleeper_offsets.is_empty() {
        return Err(SubstructureError::Layout {
            index: 0,
            kind: SpringKind::Ballast,
            what: "no sleeper".into(),
        });
    }
    let mats = solid_matrices(track)?;
    let (rail_groups, sleeper_groups) = attachment_groups(track, &sp)?;
    let cutoff = opts.cutoff_factor * fmax_hz;
    let (ks, ms) = identical_sleepers(&mats, &sp)?;
    let sleeper = sleeper_basis(
        &ks,
        &ms,
        patterns(&sleeper_groups, sp.sleeper_dofs, opts.pattern_degree),
        opts.sleeper_cutoff_factor * fmax_hz,
    )?;
    let kr = sparse_block(mats.k.as_ref(), 0, sp.rail_dofs);
    let mr = sparse_block(mats.m.as_ref(), 0, sp.rail_dofs);
    drop(mats);
    let rail = rail_basis(
        kr.as_ref(),
        mr.as_ref(),
        patterns(&rail_groups, sp.rail_dofs, opts.pattern_degree),
        cutoff,
    )?;
    Ok(TrackComponents {
        rail,
        sleeper,
        sleeper_offsets: sp.sleeper_offsets,
        seconds: t.elapsed().as_secs_f64(),
        cached: false,
    })
}

/// Revision of the component construction (bump when the bases of an unchanged model change).
pub const COMPONENT_REVISION: u64 = 2;

/// The cache key of a track's component `part` (`rail-component` or `sleeper-component`):
/// the track's key ([`super::basis::structure_key_value`]) without any spring stiffness, but
/// with the railpad directions that have springs at all (a direction with zero stiffness and
/// zero damping has none, which changes the spring layout), f_max and the options. Hold and
/// ballast springs exist whatever their stiffness.
pub fn component_key(
    m: &Model,
    fmax_hz: f64,
    opts: &SubstructureOptions,
    part: &str,
) -> Result<CacheKey, BasisError> {
    let mut v = super::basis::structure_key_value(m, "track")?;
    if let Some(o) = v.as_object_mut() {
        for p in ["fastening", "ballast"] {
            if let Some(f) = o.get_mut(p).and_then(|r| r.as_object_mut()) {
                f.retain(|k, _| !k.ends_with("stiffness"));
                if let Some(c) = f.get_mut("custom").and_then(|r| r.as_object_mut()) {
                    for h in c.values_mut() {
                        if let Some(h) = h.as_object_mut() {
                            h.remove("stiffness");
                        }
                    }
                }
            }
        }
    }
    let (k, c) = (m.fastening.stiffness(), m.fastening.damping());
    let active: u64 = (0..3)
        .filter(|&d| k[d] != 0.0 || c[d] != 0.0)
        .map(|d| 1u64 << d)
        .sum();
    let bytes = serde_json::to_vec(&v).map_err(BasisError::Json)?;
    Ok(CacheKey::new()
        .u64("physics_revision", super::basis::PHYSICS_REVISION)
        .u64("component_revision", COMPONENT_REVISION)
        .bytes("model", &bytes)
        .u64("railpad_directions", active)
        .f64("f_max_hz", fmax_hz)
        .f64("cutoff_factor", opts.cutoff_factor)
        .f64("sleeper_cutoff_factor", opts.sleeper_cutoff_factor)
        .u64("pattern_degree", opts.pattern_degree as u64)
        .str("substructure", part))
}

fn store_component(cache: &ModalCache, key: &CacheKey, c: &ComponentBasis, fmax: f64) {
    let freqs: Vec<f64> = c
        .omega2
        .iter()
        .map(|&w| w.sqrt() / (2.0 * std::f64::consts::PI))
        .collect();
    let meta = CacheMeta {
        key: String::new(),
        crate_version: String::new(),
        n_dofs: c.vectors.nrows(),
        n_modes: c.vectors.ncols(),
        f_min_hz: 0.0,
        f_max_hz: fmax,
        sturm_count: c.modes,
        relative_residuals: vec![],
        m_orthonormality_error: 0.0,
        frequencies_blake3: String::new(),
        modes_blake3: String::new(),
        classification: serde_json::json!({ "component_modes": c.modes, "omega2": c.omega2 }),
    };
    if let Err(e) = cache.store(key, &freqs, &c.vectors, meta) {
        eprintln!("warning: could not store a track component basis in the cache: {e}");
    }
}

fn load_component(cache: &ModalCache, key: &CacheKey, n: usize) -> Option<ComponentBasis> {
    let CacheLookup::Hit(c) = cache.load(key) else {
        return None;
    };
    let modes = c.meta.classification.get("component_modes")?.as_u64()? as usize;
    let omega2: Vec<f64> =
        serde_json::from_value(c.meta.classification.get("omega2")?.clone()).ok()?;
    (c.modes.nrows() == n && omega2.len() == c.modes.ncols() && modes <= omega2.len()).then_some(
        ComponentBasis {
            vectors: c.modes,
            omega2,
            modes,
        },
    )
}

/// The component bases of a track, loaded from the cache or built and stored.
pub fn track_components(
    m: &Model,
    track: &TrackStructure,
    cache: &ModalCache,
    fmax_hz: f64,
    opts: &SubstructureOptions,
) -> Result<TrackComponents, SubstructureError> {
    let t = Instant::now();
    let sp = split(track)?;
    let rk = component_key(m, fmax_hz, opts, "rail-component")?;
    let sk = component_key(m, fmax_hz, opts, "sleeper-component")?;
    if let (Some(rail), Some(sleeper)) = (
        load_component(cache, &rk, sp.rail_dofs),
        load_component(cache, &sk, sp.sleeper_dofs),
    ) {
        return Ok(TrackComponents {
            rail,
            sleeper,
            sleeper_offsets: sp.sleeper_offsets,
            seconds: t.elapsed().as_secs_f64(),
            cached: true,
        });
    }
    let c = build_components(track, fmax_hz, opts)?;
    let cutoff = opts.cutoff_factor * fmax_hz;
    store_component(cache, &rk, &c.rail, cutoff);
    store_component(cache, &sk, &c.sleeper, opts.sleeper_cutoff_factor * fmax_hz);
    Ok(c)
}

/// `Ψᵀ g_s` of every spring (N × n_springs, column per spring).
fn spring_projections(
    track: &TrackStructure,
    comp: &TrackComponents,
) -> Result<Mat<f64>, SubstructureError> {
    let sp = Split {
        rail_dofs: comp.rail.vectors.nrows(),
        sleeper_offsets: comp.sleeper_offsets.clone(),
        sleeper_dofs: comp.sleeper.vectors.nrows(),
    };
    let (nr, ns) = (comp.rail.vectors.ncols(), comp.sleeper.vectors.ncols());
    let mut g = Mat::<f64>::zeros(comp.reduced_size(), track.springs.len());
    for (j, s) in track.springs.iter().enumerate() {
        let sides = s
            .side_a
            .iter()
            .map(|&(d, w)| (d, w))
            .chain(s.side_b.iter().map(|&(d, w)| (d, -w)));
        for (dof, w) in sides {
            let Some(free) = track.dofmap.free_index(dof) else {
                continue;
            };
            match locate(&sp, free) {
                (None, r) => {
                    for c in 0..nr {
                        g[(c, j)] += w * comp.rail.vectors[(r, c)];
                    }
                }
                (Some(i), r) => {
                    if r >= sp.sleeper_dofs {
                        return Err(SubstructureError::Layout {
                            index: j,
                            kind: track.spring_kinds[j],
                            what: "a DOF outside the rail and the sleepers".into(),
                        });
                    }
                    let base = nr + i * ns;
                    for c in 0..ns {
                        g[(base + c, j)] += w * comp.sleeper.vectors[(r, c)];
                    }
                }
            }
        }
    }
    Ok(g)
}

/// The assembled reduced stiffness `diag(ω̃²) + Σ k_s (Ψᵀg_s)(Ψᵀg_s)ᵀ` of a track whose springs
/// carry the current stiffnesses (`M_red = I`).
pub fn reduced_stiffness(
    track: &TrackStructure,
    comp: &TrackComponents,
) -> Result<Mat<f64>, SubstructureError> {
    let g = spring_projections(track, comp)?;
    let n = g.nrows();
    let gk = Mat::<f64>::from_fn(n, g.ncols(), |i, j| g[(i, j)] * track.springs[j].stiffness);
    let mut k = Mat::<f64>::zeros(n, n);
    matmul(
        k.as_mut(),
        Accum::Replace,
        gk.as_ref(),
        g.transpose(),
        1.0,
        Par::rayon(0),
    );
    let diag = comp.rail.omega2.iter().chain(
        comp.sleeper_offsets
            .iter()
            .flat_map(|_| comp.sleeper.omega2.iter()),
    );
    for (i, &w) in diag.enumerate() {
        k[(i, i)] += w;
    }
    Ok(Mat::from_fn(n, n, |i, j| 0.5 * (k[(i, j)] + k[(j, i)])))
}

/// Frequencies (Hz) and eigenvectors of the reduced system below `fmax_hz`.
pub fn reduced_modes(
    k_red: &Mat<f64>,
    fmax_hz: f64,
) -> Result<(Vec<f64>, Mat<f64>), SubstructureError> {
    let e = k_red
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| SubstructureError::Eigen {
            what: "reduced track eigenproblem",
            source: EigenError::Factorization {
                shift_rad2_s2: f64::NAN,
                reason: format!("dense symmetric eigensolver failed: {e:?}"),
            },
        })?;
    let s = e.S().column_vector();
    let lam_max = hz_to_omega2(fmax_hz);
    let kept: Vec<usize> = (0..k_red.nrows()).filter(|&i| s[i] < lam_max).collect();
    let f = kept
        .iter()
        .map(|&i| s[i].max(0.0).sqrt() / (2.0 * std::f64::consts::PI))
        .collect();
    let q = Mat::from_fn(k_red.nrows(), kept.len(), |i, j| e.U()[(i, kept[j])]);
    Ok((f, q))
}

/// The track's modes `Φ = Ψ Q` over its free DOFs (n × m).
pub fn expand(comp: &TrackComponents, n_free: usize, q: &Mat<f64>) -> Mat<f64> {
    let m = q.ncols();
    let (nr, ns) = (comp.rail.vectors.ncols(), comp.sleeper.vectors.ncols());
    let mut phi = Mat::<f64>::zeros(n_free, m);
    let rows = comp.rail.vectors.nrows();
    matmul(
        phi.as_mut().subrows_mut(0, rows),
        Accum::Replace,
        comp.rail.vectors.as_ref(),
        q.as_ref().subrows(0, nr),
        1.0,
        Par::rayon(0),
    );
    let sd = comp.sleeper.vectors.nrows();
    for (i, &o) in comp.sleeper_offsets.iter().enumerate() {
        matmul(
            phi.as_mut().subrows_mut(o, sd),
            Accum::Replace,
            comp.sleeper.vectors.as_ref(),
            q.as_ref().subrows(nr + i * ns, ns),
            1.0,
            Par::rayon(0),
        );
    }
    phi
}

/// The track's classified modes below `fmax_hz` from its component bases: the reduced
/// eigenproblem with the track's current spring stiffnesses, expanded and classified.
pub fn substructured_track_basis(
    track: &TrackStructure,
    comp: &TrackComponents,
    fmax_hz: f64,
) -> Result<ModalBasis<TrackModeClass>, SubstructureError> {
    let t = Instant::now();
    let k_red = reduced_stiffness(track, comp)?;
    let (freqs, q) = reduced_modes(&k_red, fmax_hz)?;
    let modes = expand(comp, track.dofmap.n_free(), &q);
    let classifier = TrackClassifier::new(track).map_err(BasisError::from)?;
    let classes = classify_in_chunks(&modes, &freqs, "track", |u, _| {
        Ok(classifier.classify_many(track, u)?)
    })?;
    let m = freqs.len();
    Ok(ModalBasis {
        frequencies_hz: freqs,
        modes,
        residuals: vec![f64::NAN; m],
        sturm_count: m,
        classes,
        cached: false,
        seconds: t.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests;
