//! The assembled reduced system of the substructured track: the springs and holds projected
//! on the component bases, the small reduced eigenproblem, and the expansion of its modes
//! to the full track DOFs (docs/theory.md §5.8).

use super::*;

/// `Ψᵀ g_s` of every spring (N × n_springs, column per spring).
pub(super) fn spring_projections(
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
