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

use super::basis::{BasisError, ModalBasis};
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
    /// The classification's rail planes or the passage's rows reach DOFs outside the
    /// components.
    #[error("{what}: the substructured basis cannot represent it; use basis = \"full\"")]
    Rows {
        /// Which rows, and where.
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
    /// Highest degree per coordinate of the attachment load patterns of the railpads and
    /// holds (−, 0 to 3; default 3: 16 patterns per group and direction).
    pub pattern_degree: usize,
    /// The same for the ballast's springs under each sleeper (−, 0 to 3; default 1,
    /// bilinear: soft springs under a stiff sleeper).
    #[serde(default = "default_ballast_pattern_degree")]
    pub ballast_pattern_degree: usize,
}

fn default_ballast_pattern_degree() -> usize {
    SubstructureOptions::default().ballast_pattern_degree
}

impl Default for SubstructureOptions {
    fn default() -> Self {
        Self {
            cutoff_factor: 1.5,
            sleeper_cutoff_factor: 1.0,
            pattern_degree: 3,
            ballast_pattern_degree: 1,
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
        for (name, d) in [
            ("pattern_degree", self.pattern_degree),
            ("ballast_pattern_degree", self.ballast_pattern_degree),
        ] {
            if d > 3 {
                return Err(SubstructureError::Option {
                    name,
                    value: d.to_string(),
                    allowed: "0 to 3",
                });
            }
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

    /// `ω̃²` (rad²/s²) of every coordinate of the assembled reduced system, in its order:
    /// the rail's, then each sleeper's.
    pub fn reduced_omega2(&self) -> impl Iterator<Item = f64> + '_ {
        let sleepers = self
            .sleeper_offsets
            .iter()
            .flat_map(|_| &self.sleeper.omega2);
        self.rail.omega2.iter().chain(sleepers).copied()
    }
}

/// Builds the component bases of a track (no cache).
pub(crate) fn build_components(
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
        patterns(&sleeper_groups, sp.sleeper_dofs, opts),
        opts.sleeper_cutoff_factor * fmax_hz,
    )?;
    let kr = sparse_block(mats.k.as_ref(), 0, sp.rail_dofs);
    let mr = sparse_block(mats.m.as_ref(), 0, sp.rail_dofs);
    drop(mats);
    let rail = rail_basis(
        kr.as_ref(),
        mr.as_ref(),
        patterns(&rail_groups, sp.rail_dofs, opts),
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

/// Wall time (s) of the steps of `substructured_track_basis_timed`, and the process's CPU
/// time (s, all threads; `NaN` where `/proc` is not available) during each: the CPU times
/// are the steps' own only while nothing else runs in the process.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BasisPhases {
    /// The reduced stiffness, the dense reduced eigenproblem and its refinement.
    pub reduced_s: f64,
    /// The expansion `Φ = ΨQ` to the track's free DOFs (for [`passage_track_basis_timed`],
    /// to the rows the passage reads).
    pub expand_s: f64,
    /// The classification of the modes (for [`passage_track_basis_timed`], with the energy
    /// shares, from the component coordinates).
    pub classify_s: f64,
    /// Process CPU time during the reduced step.
    pub reduced_cpu_s: f64,
    /// Process CPU time during the expansion.
    pub expand_cpu_s: f64,
    /// Process CPU time during the classification.
    pub classify_cpu_s: f64,
}

/// The process's CPU time (s, all threads), `NaN` where it is not available.
pub(crate) fn process_cpu_s() -> f64 {
    crate::progress::cpu_seconds().unwrap_or(f64::NAN)
}

/// The track's classified modes below `fmax_hz` from its component bases: the reduced
/// eigenproblem with the track's current spring stiffnesses, expanded and classified.
pub fn substructured_track_basis(
    track: &TrackStructure,
    comp: &TrackComponents,
    fmax_hz: f64,
) -> Result<ModalBasis<TrackModeClass>, SubstructureError> {
    substructured_track_basis_timed(track, comp, fmax_hz).map(|(b, _)| b)
}

/// [`substructured_track_basis`] with the wall time of each step.
pub(crate) fn substructured_track_basis_timed(
    track: &TrackStructure,
    comp: &TrackComponents,
    fmax_hz: f64,
) -> Result<(ModalBasis<TrackModeClass>, BasisPhases), SubstructureError> {
    timed_basis(
        track,
        comp,
        fmax_hz,
        |q| expand(comp, track.dofmap.n_free(), q),
        |q, modes| classify_modes(track, comp, q, modes),
    )
}

/// The reduced eigenproblem of `track` on `comp` below `fmax_hz`, its modes expanded by
/// `expand(Q)` and classified by `classify(Q, Φ)`, with each step's wall and CPU time.
fn timed_basis(
    track: &TrackStructure,
    comp: &TrackComponents,
    fmax_hz: f64,
    expand: impl FnOnce(&Mat<f64>) -> Mat<f64>,
    classify: impl FnOnce(&Mat<f64>, &Mat<f64>) -> Result<Vec<TrackModeClass>, SubstructureError>,
) -> Result<(ModalBasis<TrackModeClass>, BasisPhases), SubstructureError> {
    let (t, c0) = (Instant::now(), process_cpu_s());
    let k_red = reduced_stiffness(track, comp)?;
    let (freqs, q) = reduced_modes(&k_red, fmax_hz)?;
    let (reduced_s, c1) = (t.elapsed().as_secs_f64(), process_cpu_s());
    let modes = expand(&q);
    let (expand_s, c2) = (t.elapsed().as_secs_f64() - reduced_s, process_cpu_s());
    let classes = classify(&q, &modes)?;
    let (seconds, c3) = (t.elapsed().as_secs_f64(), process_cpu_s());
    let phases = BasisPhases {
        reduced_s,
        expand_s,
        classify_s: seconds - reduced_s - expand_s,
        reduced_cpu_s: c1 - c0,
        expand_cpu_s: c2 - c1,
        classify_cpu_s: c3 - c2,
    };
    let m = freqs.len();
    let basis = ModalBasis {
        frequencies_hz: freqs,
        modes,
        residuals: vec![f64::NAN; m],
        sturm_count: m,
        classes,
        cached: false,
        seconds,
    };
    Ok((basis, phases))
}

/// Classifies the expanded modes `Φ = ΨQ`, with the strain energies of the rail and of the
/// sleepers from the component coordinates: `Ψ_cᵀ K_c Ψ_c = diag(ω̃²)`, so a component's
/// energy in mode `j` is `½ Σ ω̃²_c Q_cj²`, equal to the element sum over its solids that
/// [`TrackClassifier::classify_many`] forms (one pass over every element per mode, most of
/// the classification's work); the springs' energies and the shape come from `Φ`.
fn classify_modes(
    track: &TrackStructure,
    comp: &TrackComponents,
    q: &Mat<f64>,
    modes: &Mat<f64>,
) -> Result<Vec<TrackModeClass>, SubstructureError> {
    use rayon::prelude::*;
    /// Modes classified per parallel task.
    const CHUNK: usize = 64;
    let classifier = TrackClassifier::new(track).map_err(BasisError::from)?;
    let solid = solid_energies(comp, q);
    let per_chunk: Vec<Vec<TrackModeClass>> = (0..q.ncols())
        .step_by(CHUNK)
        .collect::<Vec<_>>()
        .into_par_iter()
        .map(|c0| {
            let c1 = (c0 + CHUNK).min(q.ncols());
            let cols: Vec<Vec<f64>> = (c0..c1)
                .map(|j| modes.col(j).iter().copied().collect())
                .collect();
            let refs: Vec<&[f64]> = cols.iter().map(|c| c.as_slice()).collect();
            classifier
                .classify_many_with_solid_energy(track, &refs, &solid[c0..c1])
                .map_err(|e| SubstructureError::Basis(BasisError::from(e)))
        })
        .collect::<Result<_, _>>()?;
    Ok(per_chunk.into_iter().flatten().collect())
}

/// The rail's and the sleepers' strain energies `[rail, sleepers]` of every mode `Φ = ΨQ`
/// (J for the mode's amplitude): `½ Σ ω̃²_c Q_cj²` per component, since
/// `Ψ_cᵀ K_c Ψ_c = diag(ω̃²)`.
fn solid_energies(comp: &TrackComponents, q: &Mat<f64>) -> Vec<[f64; 2]> {
    let (nr, ns) = (comp.rail.omega2.len(), comp.sleeper.omega2.len());
    let energy = |j: usize, first: usize, w2: &[f64]| -> f64 {
        0.5 * w2
            .iter()
            .enumerate()
            .map(|(c, w)| w * q[(first + c, j)].powi(2))
            .sum::<f64>()
    };
    (0..q.ncols())
        .map(|j| {
            let sleepers = (0..comp.sleeper_offsets.len())
                .map(|i| energy(j, nr + i * ns, &comp.sleeper.omega2))
                .sum();
            [energy(j, 0, &comp.rail.omega2), sleepers]
        })
        .collect()
}

mod cache;
mod components;
mod reduced;
mod shapes;

pub use cache::component_key;
use cache::{load_component, store_component};
use components::{
    attachment_groups, identical_sleepers, patterns, rail_basis, sleeper_basis, solid_matrices,
    sparse_block, split,
};
use reduced::expand_sleepers;
pub use reduced::{expand, reduced_modes, reduced_stiffness};
pub use shapes::{passage_track_basis_timed, ReducedShapes};

#[cfg(test)]
mod tests;
