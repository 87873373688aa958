//! A substructured basis for the passage: the modes' rows that the passage reads (the
//! springs' DOFs and the rail's running surface) and the classification from the component
//! coordinates, without the modes' other rows (docs/theory.md §5.8).
//!
//! The expansion `Φ = ΨQ` to all 152,358 free DOFs of the default track costs about as much
//! as the reduced eigenproblem, and the passage reads a few per cent of its rows: the
//! damping projection `ΦᵀCΦ` the DOFs of the springs (the dampers are the springs'), the
//! contact line the running-surface nodes. The classification reads every rail row, but only
//! through linear functionals (the section sums of every node plane) and quadratic forms
//! (the rail's area- and length-weighted squared norm, the lumped-mass norms): on the
//! component basis these are `(AΨ)Q` and `qᵀ(ΨᵀWΨ)q`, with `AΨ` and `ΨᵀWΨ` formed once
//! per component set ([`ReducedShapes`]).

use rayon::prelude::*;

use super::{
    expand_sleepers, matmul, solid_energies, timed_basis, Accum, BasisError, BasisPhases, Mat,
    MatRef, ModalBasis, Par, SpringKind, SubstructureError, TrackClassifier, TrackComponents,
    TrackModeClass, TrackStructure,
};
use crate::eigen::classify::{SectionMotion, ShapeNorms, TrackEnergyShares, SECTION_SUMS};

/// Rows of the rail's basis per block of the Gram products in [`ReducedShapes::new`].
const GRAM_ROWS: usize = 8192;

/// One track's classification operators on its component bases and the rail rows its
/// passage reads; built once per component set and shared by the cases of a study (the
/// cases differ in spring values only, which enter none of them).
#[derive(Debug)]
pub struct ReducedShapes {
    classifier: TrackClassifier,
    /// Section sums of every node plane on the rail's basis (row `SECTION_SUMS·p + s`,
    /// column per rail basis vector).
    sums: Mat<f64>,
    /// `Ψ_railᵀ W Ψ_rail` with the rail's norm weights (m³·m²/kg).
    rail_norm: Mat<f64>,
    /// `Ψ_railᵀ M_l Ψ_rail` with the lumped node masses (−).
    rail_mass: Mat<f64>,
    /// `Ψ_sᵀ M_l Ψ_s` of each sleeper (−).
    sleeper_mass: Vec<Mat<f64>>,
    /// The rail's free DOFs the passage reads, ascending: the springs' and the
    /// running-surface nodes' of every plane.
    rail_rows: Vec<usize>,
    /// Free DOFs of the track.
    n_free: usize,
}

/// The weights of `(global DOF, weight)` summed per free DOF (n_free; constrained DOFs
/// dropped).
fn free_weights(track: &TrackStructure, weights: impl Iterator<Item = (usize, f64)>) -> Vec<f64> {
    let mut w = vec![0.0; track.dofmap.n_free()];
    for (dof, v) in weights {
        if let Some(f) = track.dofmap.free_index(dof) {
            w[f] += v;
        }
    }
    w
}

/// `Ψᵀ diag(w) Ψ` (N × N), the lower triangle by blocks of rows, then mirrored.
fn weighted_gram(psi: MatRef<'_, f64>, w: &[f64]) -> Mat<f64> {
    let n = psi.ncols();
    let mut g = Mat::<f64>::zeros(n, n);
    let mut r0 = 0;
    while r0 < psi.nrows() {
        let r1 = (r0 + GRAM_ROWS).min(psi.nrows());
        let block = psi.subrows(r0, r1 - r0);
        let wb = Mat::from_fn(r1 - r0, n, |i, c| w[r0 + i] * block[(i, c)]);
        faer::linalg::matmul::triangular::matmul(
            g.as_mut(),
            faer::linalg::matmul::triangular::BlockStructure::TriangularLower,
            Accum::Add,
            block.transpose(),
            faer::linalg::matmul::triangular::BlockStructure::Rectangular,
            wb.as_ref(),
            faer::linalg::matmul::triangular::BlockStructure::Rectangular,
            1.0,
            Par::rayon(0),
        );
        r0 = r1;
    }
    for j in 0..n {
        for i in 0..j {
            g[(i, j)] = g[(j, i)];
        }
    }
    g
}

impl ReducedShapes {
    /// The operators of `track` on `comp` (one Gram product of the rail's basis per norm:
    /// about twice an expansion's work, once per component set).
    pub fn new(track: &TrackStructure, comp: &TrackComponents) -> Result<Self, SubstructureError> {
        let classifier = TrackClassifier::new(track).map_err(BasisError::from)?;
        let psi = comp.rail.vectors.as_ref();
        let nrail = psi.nrows();
        let np = classifier.n_planes();
        // section sums: (row, rail free DOF, coefficient)
        let mut terms = Vec::new();
        for p in 0..np {
            for (dof, s, a) in classifier.section_sum_terms(p) {
                match track.dofmap.free_index(dof) {
                    Some(f) if f < nrail => terms.push((SECTION_SUMS * p + s, f, a)),
                    Some(f) => {
                        return Err(SubstructureError::Rows {
                            what: format!(
                                "rail plane {p} at free DOF {f}, outside the rail's {nrail}"
                            ),
                        })
                    }
                    None => {}
                }
            }
        }
        let cols: Vec<Vec<f64>> = (0..psi.ncols())
            .into_par_iter()
            .map(|c| {
                let col = psi.col(c);
                let mut v = vec![0.0; SECTION_SUMS * np];
                for &(r, f, a) in &terms {
                    v[r] += a * col[f];
                }
                v
            })
            .collect();
        let sums = Mat::from_fn(SECTION_SUMS * np, psi.ncols(), |i, c| cols[c][i]);
        let norm_w = free_weights(track, classifier.rail_norm_weights().into_iter());
        let (mass, _) = classifier.node_masses();
        let mass_w = free_weights(
            track,
            mass.iter()
                .enumerate()
                .flat_map(|(n, &m)| (0..3).map(move |d| (3 * n + d, m))),
        );
        let (rail_norm, rail_mass) = rayon::join(
            || weighted_gram(psi, &norm_w[..nrail]),
            || weighted_gram(psi, &mass_w[..nrail]),
        );
        let sd = comp.sleeper.vectors.nrows();
        let sleeper_mass = comp
            .sleeper_offsets
            .iter()
            .map(|&o| weighted_gram(comp.sleeper.vectors.as_ref(), &mass_w[o..o + sd]))
            .collect();
        Ok(Self {
            rail_rows: passage_rail_rows(track, nrail)?,
            classifier,
            sums,
            rail_norm,
            rail_mass,
            sleeper_mass,
            n_free: track.dofmap.n_free(),
        })
    }

    /// The rail's free DOFs the passage reads (ascending).
    pub fn rail_rows(&self) -> &[usize] {
        &self.rail_rows
    }

    /// The classes of the modes `Φ = ΨQ` (`q`: reduced eigenvectors, one column per mode)
    /// with the given energy shares per mode: section motions and norms from the component
    /// coordinates.
    pub fn classify(
        &self,
        comp: &TrackComponents,
        q: &Mat<f64>,
        energy: &[TrackEnergyShares],
    ) -> Vec<crate::eigen::classify::TrackModeClass> {
        let (nr, ns) = (comp.rail.omega2.len(), comp.sleeper.omega2.len());
        let m = q.ncols();
        let qr = q.as_ref().subrows(0, nr);
        let product = |a: MatRef<'_, f64>, b: MatRef<'_, f64>| {
            let mut c = Mat::<f64>::zeros(a.nrows(), b.ncols());
            matmul(c.as_mut(), Accum::Replace, a, b, 1.0, Par::rayon(0));
            c
        };
        let sums = product(self.sums.as_ref(), qr);
        let (gn, gm) = (
            product(self.rail_norm.as_ref(), qr),
            product(self.rail_mass.as_ref(), qr),
        );
        let dot = |g: &Mat<f64>, a: MatRef<'_, f64>, j: usize| -> f64 {
            (0..a.nrows()).map(|i| a[(i, j)] * g[(i, j)]).sum()
        };
        let sleeper: Vec<Vec<f64>> = self
            .sleeper_mass
            .iter()
            .enumerate()
            .map(|(i, g)| {
                let qs = q.as_ref().subrows(nr + i * ns, ns);
                let gq = product(g.as_ref(), qs);
                (0..m).map(|j| dot(&gq, qs, j)).collect()
            })
            .collect();
        let np = self.classifier.n_planes();
        (0..m)
            .into_par_iter()
            .map(|j| {
                let sm: Vec<SectionMotion> = (0..np)
                    .map(|p| {
                        let s: [f64; SECTION_SUMS] =
                            std::array::from_fn(|k| sums[(SECTION_SUMS * p + k, j)]);
                        self.classifier.section_motion_from_sums(p, &s)
                    })
                    .collect();
                let sleeper_mass: f64 = sleeper.iter().map(|s| s[j]).sum();
                let norms = ShapeNorms {
                    rail: dot(&gn, qr, j),
                    sleeper_mass,
                    total_mass: dot(&gm, qr, j) + sleeper_mass,
                };
                self.classifier.classify_measured(&sm, norms, energy[j])
            })
            .collect()
    }
}

/// The rail's free DOFs (below `nrail`) of the springs and of the running-surface nodes of
/// every node plane, ascending.
fn passage_rail_rows(
    track: &TrackStructure,
    nrail: usize,
) -> Result<Vec<usize>, SubstructureError> {
    let rail = &track.rail;
    let surface = (0..rail.n_planes()).flat_map(|p| {
        rail.section
            .running_surface
            .iter()
            .flat_map(move |&j| (0..3).map(move |d| 3 * rail.node(p, j) + d))
    });
    let mut rows = Vec::new();
    for dof in surface {
        match track.dofmap.free_index(dof) {
            Some(f) if f < nrail => rows.push(f),
            Some(f) => {
                return Err(SubstructureError::Rows {
                    what: format!("running surface at free DOF {f}, outside the rail's {nrail}"),
                })
            }
            None => {}
        }
    }
    let springs = track
        .springs
        .iter()
        .flat_map(|s| s.side_a.iter().chain(&s.side_b).map(|&(d, _)| d));
    rows.extend(
        springs
            .filter_map(|d| track.dofmap.free_index(d))
            .filter(|&f| f < nrail),
    );
    rows.sort_unstable();
    rows.dedup();
    Ok(rows)
}

/// The modes `Φ = ΨQ` at the rail rows `rail_rows` and at every sleeper DOF, the other rows
/// `NaN` (n_free × m): a consumer that reads a row not expanded gets `NaN`, never a
/// plausible number.
pub(crate) fn expand_rows(
    comp: &TrackComponents,
    n_free: usize,
    q: &Mat<f64>,
    rail_rows: &[usize],
) -> Mat<f64> {
    let m = q.ncols();
    let nr = comp.rail.vectors.ncols();
    let mut phi = Mat::<f64>::full(n_free, m, f64::NAN);
    let psi = comp.rail.vectors.as_ref();
    let gathered = Mat::from_fn(rail_rows.len(), nr, |i, c| psi[(rail_rows[i], c)]);
    let mut rows = Mat::<f64>::zeros(rail_rows.len(), m);
    matmul(
        rows.as_mut(),
        Accum::Replace,
        gathered.as_ref(),
        q.as_ref().subrows(0, nr),
        1.0,
        Par::rayon(0),
    );
    for j in 0..m {
        for (i, &r) in rail_rows.iter().enumerate() {
            phi[(r, j)] = rows[(i, j)];
        }
    }
    expand_sleepers(comp, q, &mut phi);
    phi
}

/// The energy shares of the modes: the rail's and the sleepers' strain energies from the
/// component coordinates ([`solid_energies`]), the springs' from the modes' rows at their
/// DOFs (`modes` needs those rows only).
fn energy_shares(
    track: &TrackStructure,
    comp: &TrackComponents,
    q: &Mat<f64>,
    modes: &Mat<f64>,
) -> Vec<TrackEnergyShares> {
    let solid = solid_energies(comp, q);
    (0..q.ncols())
        .into_par_iter()
        .map(|j| {
            let col = modes.col(j);
            let (mut ef, mut eb) = (0.0, 0.0);
            for (s, k) in track.springs.iter().zip(&track.spring_kinds) {
                let u =
                    |&(d, w): &(usize, f64)| track.dofmap.free_index(d).map_or(0.0, |f| w * col[f]);
                let r = s.side_a.iter().map(u).sum::<f64>() - s.side_b.iter().map(u).sum::<f64>();
                let e = 0.5 * s.stiffness * r * r;
                match k {
                    // An elastic hold is part of the fastening.
                    SpringKind::Fastening | SpringKind::Hold => ef += e,
                    SpringKind::Ballast => eb += e,
                    // damping only: no strain energy
                    SpringKind::EndDashpot => {}
                }
            }
            TrackEnergyShares::from_energies([solid[j][0], solid[j][1], ef, eb])
        })
        .collect()
}

/// The track's classified modes below `fmax_hz` for a passage: the reduced eigenproblem as in
/// `substructured_track_basis_timed`, the modes expanded only at the rows the passage reads
/// (`expand_rows`; the other rows `NaN`) and classified from the component coordinates
/// ([`ReducedShapes::classify`]). For a basis whose every row is read (output, cache) use
/// `substructured_track_basis`.
pub fn passage_track_basis_timed(
    track: &TrackStructure,
    comp: &TrackComponents,
    shapes: &ReducedShapes,
    fmax_hz: f64,
) -> Result<(ModalBasis<TrackModeClass>, BasisPhases), SubstructureError> {
    if shapes.n_free != track.dofmap.n_free() {
        return Err(SubstructureError::Rows {
            what: format!(
                "classification operators of a track with {} free DOFs applied to one with {}",
                shapes.n_free,
                track.dofmap.n_free()
            ),
        });
    }
    timed_basis(
        track,
        comp,
        fmax_hz,
        |q| expand_rows(comp, shapes.n_free, q, &shapes.rail_rows),
        |q, modes| {
            let energy = energy_shares(track, comp, q, modes);
            Ok(shapes.classify(comp, q, &energy))
        },
    )
}
