//! The component bases of the substructured track: the rail and one sleeper (all sleepers
//! are identical), each with its free-interface modes below the cut-off and the residual
//! attachment vectors of its spring attachment points, M-orthonormalised and Ritz-reduced
//! (docs/theory.md §5.8).

use super::{
    assemble, matmul, solve, sym_spmm, Accum, AssemblyOptions, BTreeMap, BasisError,
    ComponentBasis, EigenError, EigenOptions, FeMatrices, FillOrdering, Mat, MatRef, Par,
    ShiftedSystem, Side, SparseColMat, SparseColMatRef, SpringKind, SubstructureError,
    TrackStructure, Triplet,
};

/// Free-DOF split of the track: the rail's free DOFs `0..rail_dofs`, then the sleepers, each
/// `sleeper_dofs` long from its offset.
pub(super) struct Split {
    pub(super) rail_dofs: usize,
    pub(super) sleeper_offsets: Vec<usize>,
    pub(super) sleeper_dofs: usize,
}

pub(super) fn split(track: &TrackStructure) -> Result<Split, SubstructureError> {
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
pub(super) fn solid_matrices(track: &TrackStructure) -> Result<FeMatrices, SubstructureError> {
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
pub(super) fn sparse_block(
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
pub(super) fn dense_block(a: SparseColMatRef<'_, usize, f64>, r0: usize, n: usize) -> Mat<f64> {
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
/// ≤ `opts.pattern_degree` (ballast groups, kind 1: `opts.ballast_pattern_degree`) in the
/// coordinates scaled to [−1, 1] over the group's extent.
pub(super) fn patterns(
    groups: &BTreeMap<(u8, usize, usize), Group>,
    n: usize,
    opts: &super::SubstructureOptions,
) -> Mat<f64> {
    let degree_of = |kind: u8| {
        if kind == 1 {
            opts.ballast_pattern_degree
        } else {
            opts.pattern_degree
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
pub(super) fn locate(sp: &Split, free: usize) -> (Option<usize>, usize) {
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
pub(super) fn attachment_groups(
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
            SpringKind::EndDashpot => 3,
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
pub(super) fn m_orthogonalise(
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

/// The dense symmetric eigen-decomposition of `a` (lower triangle), its failure named by
/// `what`.
pub(super) fn dense_symmetric_eigen(
    a: MatRef<'_, f64>,
    what: &'static str,
) -> Result<faer::linalg::solvers::SelfAdjointEigen<f64>, SubstructureError> {
    a.self_adjoint_eigen(Side::Lower)
        .map_err(|error| SubstructureError::Eigen {
            what,
            source: EigenError::DenseEigen { what, error },
        })
}

/// Relative size below which a direction of the attachment span is dropped as dependent.
pub(super) const DEPENDENCE_TOLERANCE: f64 = 1e-10;

/// Rayleigh–Ritz on the span of `a` (already M-orthogonal to the kept modes): M-orthonormal,
/// K-orthogonal vectors and their `ω̃²`, dependent directions dropped.
pub(super) fn ritz(
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
    let eig = dense_symmetric_eigen;
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

pub(super) fn hz_to_omega2(f: f64) -> f64 {
    let w = 2.0 * std::f64::consts::PI * f;
    w * w
}

/// The shift α of the attachment solves `(K + αM)⁻¹`: (f_c / 10)² in rad²/s², small against
/// the truncated modes, large enough to keep rigid-body parts of the static response a
/// modest multiple of the residual part.
pub(super) fn attachment_shift(cutoff_hz: f64) -> f64 {
    hz_to_omega2(0.1 * cutoff_hz)
}

/// The rail's basis: Lanczos modes below the cutoff plus the residual attachment vectors.
pub(super) fn rail_basis(
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
pub(super) fn sleeper_basis(
    k: &Mat<f64>,
    m: &Mat<f64>,
    f: Mat<f64>,
    cutoff_hz: f64,
) -> Result<ComponentBasis, SubstructureError> {
    let n = k.nrows();
    let cholesky_err = |what: &'static str, shift_rad2_s2: f64| {
        move |source| SubstructureError::Eigen {
            what,
            source: EigenError::DenseCholesky {
                what,
                shift_rad2_s2,
                source,
            },
        }
    };
    // Generalised problem via M^{-1/2} (the lumped or consistent M is definite).
    let lm = m
        .llt(Side::Lower)
        .map_err(cholesky_err("sleeper mass", 0.0))?;
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
        .map_err(|error| SubstructureError::Eigen {
            what: "sleeper modes",
            source: EigenError::DenseEigen {
                what: "sleeper modes",
                error,
            },
        })?;
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
        .map_err(cholesky_err("sleeper attachment factorisation", -alpha))?;
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

pub(super) fn concat_cols(a: &Mat<f64>, b: &Mat<f64>) -> Mat<f64> {
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
pub(super) fn identical_sleepers(
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
