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

/// Columns above the `f_max` bound kept in the Rayleigh–Ritz refinement of
/// [`reduced_modes`], so that a cluster straddling the bound is refined whole.
const REFINE_MARGIN: usize = 16;

/// Steps of subspace inverse iteration in [`reduced_modes`].
const INVERSE_ITERATIONS: usize = 2;

/// The shift α (rad²/s²) of the inverse iteration `(K_red + αI)⁻¹`: (2π · 1 Hz)², so that
/// the rigid-body modes of an ungrounded system keep it definite.
const INVERSE_ITERATION_SHIFT: f64 = 39.478_417_604_357_43;

/// Frequencies (Hz) and eigenvectors of the reduced system below `fmax_hz`.
///
/// `K_red` is badly scaled: the modes that matter have `ω² ≈ 10⁵–10⁹` rad²/s², the stiff
/// residual attachment vectors `10¹¹–10¹³`. The dense symmetric eigensolver's vectors
/// then mix within clusters of close eigenvalues: on the default track the sixteen
/// sleeper-on-ballast modes at 74–79 Hz came out with `‖K_red q − λ q‖ ≈ ‖K_red q‖` and a
/// returned eigenvalue 1.6 % above the Rayleigh quotient of its own vector, below the full
/// model's eigenvalues where a Ritz value cannot be. So the solver's lowest vectors (those
/// below the bound and [`REFINE_MARGIN`] more) only start a subspace iteration:
/// [`INVERSE_ITERATIONS`] steps of `U ← orth((K_red + αI)⁻¹ U)` (Cholesky, once) remove the
/// stiff directions' contamination, and a Rayleigh–Ritz step on the result (`Uᵀ K_red U`,
/// well scaled, solved again) gives the eigenpairs returned, each eigenvalue the Rayleigh
/// quotient of its vector (Parlett, *The Symmetric Eigenvalue Problem*, §11.2, §14.4; test
/// `refined_modes_resolve_a_cluster_under_stiff_directions`).
pub fn reduced_modes(
    k_red: &Mat<f64>,
    fmax_hz: f64,
) -> Result<(Vec<f64>, Mat<f64>), SubstructureError> {
    let dense_eigen = dense_symmetric_eigen;
    let n = k_red.nrows();
    let e = dense_eigen(k_red.as_ref(), "reduced track eigenproblem")?;
    let s = e.S().column_vector();
    let lam_max = hz_to_omega2(fmax_hz);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| s[a].total_cmp(&s[b]));
    let below = order.iter().filter(|&&i| s[i] < lam_max).count();
    let p = (below + REFINE_MARGIN).min(n);
    let mut u = Mat::from_fn(n, p, |i, j| e.U()[(i, order[j])]);
    // subspace inverse iteration with (K_red + αI)⁻¹: each step divides the stiff
    // directions' share by at least (λ_i + α)/(λ_max,kept + α)
    let shift = Mat::from_fn(n, n, |i, j| {
        k_red[(i, j)] + if i == j { INVERSE_ITERATION_SHIFT } else { 0.0 }
    });
    let chol = shift
        .llt(Side::Lower)
        .map_err(|e| SubstructureError::Eigen {
            what: "reduced track eigenproblem (inverse iteration)",
            source: EigenError::Factorization {
                shift_rad2_s2: -INVERSE_ITERATION_SHIFT,
                reason: format!("K_red + αI is not positive definite: {e:?}"),
            },
        })?;
    for _ in 0..INVERSE_ITERATIONS {
        use faer::linalg::solvers::Solve;
        let w = chol.solve(&u);
        u = w.qr().compute_thin_Q();
    }
    // Rayleigh–Ritz on span(U): B = Uᵀ K_red U
    let mut ku = Mat::<f64>::zeros(n, p);
    matmul(
        ku.as_mut(),
        Accum::Replace,
        k_red.as_ref(),
        u.as_ref(),
        1.0,
        Par::rayon(0),
    );
    let mut b = Mat::<f64>::zeros(p, p);
    matmul(
        b.as_mut(),
        Accum::Replace,
        u.transpose(),
        ku.as_ref(),
        1.0,
        Par::rayon(0),
    );
    let b = Mat::from_fn(p, p, |i, j| 0.5 * (b[(i, j)] + b[(j, i)]));
    let eb = dense_eigen(
        b.as_ref(),
        "reduced track eigenproblem (Rayleigh-Ritz refinement)",
    )?;
    let sb = eb.S().column_vector();
    let mut kept: Vec<usize> = (0..p).filter(|&i| sb[i] < lam_max).collect();
    kept.sort_by(|&a, &c| sb[a].total_cmp(&sb[c]));
    let f = kept
        .iter()
        .map(|&i| sb[i].max(0.0).sqrt() / (2.0 * std::f64::consts::PI))
        .collect();
    let v = Mat::from_fn(p, kept.len(), |i, j| eb.U()[(i, kept[j])]);
    let mut q = Mat::<f64>::zeros(n, kept.len());
    matmul(
        q.as_mut(),
        Accum::Replace,
        u.as_ref(),
        v.as_ref(),
        1.0,
        Par::rayon(0),
    );
    Ok((f, q))
}

/// The track's modes `Φ = Ψ Q` over its free DOFs (n × m).
pub fn expand(comp: &TrackComponents, n_free: usize, q: &Mat<f64>) -> Mat<f64> {
    let m = q.ncols();
    let nr = comp.rail.vectors.ncols();
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
    expand_sleepers(comp, q, &mut phi);
    phi
}

/// The sleepers' rows of `Φ = ΨQ`, written into `phi` (n_free × m).
pub(super) fn expand_sleepers(comp: &TrackComponents, q: &Mat<f64>, phi: &mut Mat<f64>) {
    let (nr, ns) = (comp.rail.vectors.ncols(), comp.sleeper.vectors.ncols());
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
}
