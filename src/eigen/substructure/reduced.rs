//! The assembled reduced system of the substructured track: the springs and holds projected
//! on the component bases, the small reduced eigenproblem, and the expansion of its modes
//! to the full track DOFs (docs/theory.md §5.8).

use super::components::{dense_symmetric_eigen, hz_to_omega2, locate, Split};
use super::{
    matmul, Accum, BTreeMap, EigenError, Mat, MatRef, Par, Side, SubstructureError,
    TrackComponents, TrackStructure,
};

/// The component split of `comp` (rail rows first, then the sleepers').
fn comp_split(comp: &TrackComponents) -> Split {
    Split {
        rail_dofs: comp.rail.vectors.nrows(),
        sleeper_offsets: comp.sleeper_offsets.clone(),
        sleeper_dofs: comp.sleeper.vectors.nrows(),
    }
}

/// The non-zero entries of one spring's `g_s`: `(block, component-local row, weight)`.
type BlockEntries = Vec<(usize, usize, f64)>;

/// The non-zero parts of every spring's `g_s` by component block (block 0 the rail, block
/// `1 + i` sleeper `i`): `(block, component-local row, weight)`, side b with its weights
/// negated. Springs without stiffness contribute nothing to `K_red` and get no entries.
fn spring_block_entries(
    track: &TrackStructure,
    sp: &Split,
) -> Result<Vec<BlockEntries>, SubstructureError> {
    track
        .springs
        .iter()
        .enumerate()
        .map(|(j, s)| {
            if s.stiffness == 0.0 {
                return Ok(Vec::new());
            }
            let sides = s
                .side_a
                .iter()
                .copied()
                .chain(s.side_b.iter().map(|&(d, w)| (d, -w)));
            let mut e = Vec::new();
            for (dof, w) in sides {
                let Some(free) = track.dofmap.free_index(dof) else {
                    continue;
                };
                match locate(sp, free) {
                    (None, r) => e.push((0, r, w)),
                    (Some(i), r) if r < sp.sleeper_dofs => e.push((1 + i, r, w)),
                    _ => {
                        return Err(SubstructureError::Layout {
                            index: j,
                            kind: track.spring_kinds[j],
                            what: "a DOF outside the rail and the sleepers".into(),
                        })
                    }
                }
            }
            Ok(e)
        })
        .collect()
}

/// The assembled reduced stiffness `diag(ω̃²) + Σ k_s (Ψᵀg_s)(Ψᵀg_s)ᵀ` of a track whose springs
/// carry the current stiffnesses (`M_red = I`).
///
/// `Ψᵀg_s` is non-zero only on the blocks of the components the spring joins (a railpad
/// spring: the rail's and one sleeper's coordinates; a ballast spring: one sleeper's), so
/// the sum is formed block by block: for each pair of blocks `(a, b)` joined by some springs,
/// `P_b diag(k) P_aᵀ` over those springs only (`P_a`: their projections on block `a`), the
/// diagonal blocks as lower triangles, then mirrored. On the default track this is about a
/// tenth of the dense product over all springs (docs/log/performance.md §7.5); the result is
/// exactly symmetric.
pub fn reduced_stiffness(
    track: &TrackStructure,
    comp: &TrackComponents,
) -> Result<Mat<f64>, SubstructureError> {
    use faer::linalg::matmul::triangular::{matmul as tri_matmul, BlockStructure};
    let sp = comp_split(comp);
    let (nr, ns) = (comp.rail.vectors.ncols(), comp.sleeper.vectors.ncols());
    let block = |b: usize| -> (usize, MatRef<'_, f64>) {
        if b == 0 {
            (0, comp.rail.vectors.as_ref())
        } else {
            (nr + (b - 1) * ns, comp.sleeper.vectors.as_ref())
        }
    };
    let entries = spring_block_entries(track, &sp)?;
    // the springs joining each pair of blocks (a ≤ b)
    let mut pairs: BTreeMap<(usize, usize), Vec<usize>> = BTreeMap::new();
    for (j, e) in entries.iter().enumerate() {
        let mut blocks: Vec<usize> = e.iter().map(|&(b, _, _)| b).collect();
        blocks.sort_unstable();
        blocks.dedup();
        for (x, &a) in blocks.iter().enumerate() {
            for &b in &blocks[x..] {
                pairs.entry((a, b)).or_default().push(j);
            }
        }
    }
    // P (block size × springs): column t = Ψ_blockᵀ g_s restricted to the block, times `scale`
    let projection = |b: usize, springs: &[usize], scale: &dyn Fn(usize) -> f64| -> Mat<f64> {
        let (_, psi) = block(b);
        let mut p = Mat::<f64>::zeros(psi.ncols(), springs.len());
        for (t, &j) in springs.iter().enumerate() {
            let f = scale(j);
            let mut col = p.col_mut(t);
            for &(_, r, w) in entries[j].iter().filter(|e| e.0 == b) {
                let row = psi.row(r);
                for c in 0..psi.ncols() {
                    col[c] += f * w * row[c];
                }
            }
        }
        p
    };
    let n = comp.reduced_size();
    let mut k = Mat::<f64>::zeros(n, n);
    for ((a, b), springs) in &pairs {
        let pa = projection(*a, springs, &|_| 1.0);
        let pbk = projection(*b, springs, &|j| track.springs[j].stiffness);
        let (r0, ra) = (block(*a).0, pa.nrows());
        let (r1, rb) = (block(*b).0, pbk.nrows());
        let dst = k.as_mut().submatrix_mut(r1, r0, rb, ra);
        if a == b {
            tri_matmul(
                dst,
                BlockStructure::TriangularLower,
                Accum::Add,
                pbk.as_ref(),
                BlockStructure::Rectangular,
                pa.transpose(),
                BlockStructure::Rectangular,
                1.0,
                Par::rayon(0),
            );
        } else {
            matmul(
                dst,
                Accum::Add,
                pbk.as_ref(),
                pa.transpose(),
                1.0,
                Par::rayon(0),
            );
        }
    }
    for j in 0..n {
        for i in 0..j {
            k[(i, j)] = k[(j, i)];
        }
    }
    for (i, w) in comp.reduced_omega2().enumerate() {
        k[(i, i)] += w;
    }
    Ok(k)
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
/// below the bound and `REFINE_MARGIN` more) only start a subspace iteration:
/// `INVERSE_ITERATIONS` steps of `U ← orth((K_red + αI)⁻¹ U)` (Cholesky, once) remove the
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
        .map_err(|source| SubstructureError::Eigen {
            what: "reduced track eigenproblem (inverse iteration)",
            source: EigenError::DenseCholesky {
                what: "reduced stiffness K_red + αI",
                shift_rad2_s2: -INVERSE_ITERATION_SHIFT,
                source,
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
