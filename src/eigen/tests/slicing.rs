//! Tests of the spectrum slicing and the concurrent bands (theory §5.3): pairs carried across
//! a slice bound, slices tiling the band with their Sturm counts, band bounds on coincident
//! eigenvalues, bitwise reproducibility over bands and threads, and slice bounds on clusters
//! more multiple than the block. Oracles as in the parent module: the dense solver and closed
//! forms (spring–mass chains, a diagonal `K`).

use super::{
    add2, assert_quality, check_against_dense, dense_eigenvalues, f_max_above, gap_after,
    grounded_lattice_band, lambda_to_hz, lattice3d, solve, sparse, square_lattice,
    square_lattice_exact, EigenOptions, EigenSolution, Sp,
};

#[test]
fn converged_pairs_above_a_boundary_carry_into_the_next_slice() {
    // Several slices on a grounded lattice: some slice starts with pairs the previous one
    // converged above its boundary; all modes still match the dense solver and are
    // M-orthonormal across slices.
    let (k, m) = lattice3d(6, 5, 5, 2e6, 13);
    let dense = dense_eigenvalues(&k, &m);
    let f_max = lambda_to_hz(dense[260]) * 0.5 + lambda_to_hz(dense[261]) * 0.5;
    let mut o = EigenOptions::new(f_max);
    o.modes_per_slice = 45;
    o.full_orthogonality_check = true;
    let sol = solve(k.as_ref(), m.as_ref(), &o, None).unwrap();
    assert_quality(&sol);
    assert_eq!(sol.frequencies_hz.len(), 261);
    let carried: usize = sol.slices.iter().map(|s| s.carried).sum();
    eprintln!(
        "{} slices, carried per slice {:?}, M-orth {:e}",
        sol.slices.len(),
        sol.slices.iter().map(|s| s.carried).collect::<Vec<_>>(),
        sol.m_orthonormality_error
    );
    assert!(sol.slices.len() >= 4 && carried > 0);
    assert!(check_against_dense(&sol, &dense, 0.0, f_max) < 1e-8);
    // Every slice deflates the modes of the earlier ones after its basis pass, so the result
    // is orthogonal to round-off (4.7e-13 measured).
    assert!(sol.m_orthonormality_error < 1e-11);
}

/// Slices of a solution tile the band: every slice starts where the previous ended, with the
/// same Sturm count (also across the bounds of concurrent bands).
fn assert_slices_tile(sol: &EigenSolution) {
    for w in sol.slices.windows(2) {
        assert_eq!(w[0].shift_hi_rad2_s2, w[1].shift_lo_rad2_s2, "slice bounds");
        assert_eq!(
            w[0].sturm_hi, w[1].sturm_lo,
            "Sturm counts at a slice bound"
        );
    }
}

/// Solves with `o` (its `concurrent_bands` set), checks residuals, orthonormality,
/// slice tiling, the band count and the eigenvalues against `exact` (closed form or dense
/// solver) to 1e-8 relative.
fn solve_in_bands(k: &Sp, m: &Sp, o: &EigenOptions, exact: &[f64], label: &str) -> EigenSolution {
    let sol = solve(k.as_ref(), m.as_ref(), o, None).unwrap();
    assert_quality(&sol);
    assert_slices_tile(&sol);
    let worst = check_against_dense(&sol, exact, o.f_min_hz, o.f_max_hz);
    eprintln!(
        "{label}, {} bands: {} modes in {} slices, worst rel err {worst:e}, M-orth {:.1e}",
        sol.timing.bands,
        sol.frequencies_hz.len(),
        sol.slices.len(),
        sol.m_orthonormality_error
    );
    assert_eq!(Some(sol.timing.bands), o.concurrent_bands);
    assert!(worst < 1e-8, "worst relative eigenvalue error {worst:e}");
    sol
}

/// Concurrent bands: the same eigenvalues as the dense solver (1e-8), the exact count, a
/// full M-orthonormality check across the band bounds (the model is small enough for the
/// full ΦᵀMΦ), with rigid-body modes in the lowest band (free lattice), with `f_min > 0`
/// (grounded lattice: every band starts with a two-sided slice), run concurrently and one
/// after the other.
#[test]
fn concurrent_bands_match_dense_solver_with_exact_counts() {
    let (k, m) = lattice3d(6, 5, 4, 0.0, 7);
    let dense = dense_eigenvalues(&k, &m);
    let f_max = lambda_to_hz(dense[dense.len() / 2]) * 1.0001;
    for (bands, parallel) in [(2usize, true), (3, false)] {
        let mut o = EigenOptions::new(f_max);
        o.block_size = 6;
        o.modes_per_slice = 40;
        o.concurrent_bands = Some(bands);
        o.parallel = parallel;
        let sol = solve_in_bands(&k, &m, &o, &dense, "free lattice");
        assert!(sol.frequencies_hz[2] < 1e-3 && sol.frequencies_hz[3] > 1.0);
    }
    let (k, m, dense, mut o) = grounded_lattice_band();
    o.concurrent_bands = Some(2);
    let sol = solve_in_bands(&k, &m, &o, &dense, "grounded lattice from f_min");
    assert_eq!(sol.frequencies_hz.len(), 261);
}

/// Concurrent bands are reproducible: solved concurrently (the last band running switches to
/// all threads when the other finishes, at a moment that depends on timing) or one after the
/// other on one thread, the eigenvalues and mode shapes are bitwise the same. The lattice
/// has more than 2 × 8192 DOFs, so the dense products are split over row ranges.
#[test]
fn concurrent_bands_are_bitwise_reproducible() {
    let (k, m) = lattice3d(40, 12, 12, 2e6, 17);
    assert!(k.nrows() > 2 * 8192);
    let mut o = EigenOptions::new(1.0);
    o.f_max_hz = f_max_above(&k, &m, 120);
    o.modes_per_slice = 30;
    o.concurrent_bands = Some(2);
    let mut runs = Vec::new();
    for parallel in [true, false] {
        o.parallel = parallel;
        let sol = solve(k.as_ref(), m.as_ref(), &o, None).unwrap();
        assert_quality(&sol);
        assert_eq!(sol.timing.bands, 2);
        runs.push(sol);
    }
    assert_eq!(runs[0].eigenvalues_rad2_s2, runs[1].eigenvalues_rad2_s2);
    assert!(runs[0].modes == runs[1].modes, "mode shapes differ bitwise");
}

/// Concurrent bands on a spectrum full of exactly coincident pairs (square lattice, closed
/// form): a band bound between or near the two members of a pair must neither lose nor
/// duplicate one (the Sturm counts at the shared bound decide), and the pairs' vectors stay
/// M-orthonormal across the bound.
#[test]
fn concurrent_bands_keep_double_eigenvalues_at_their_bounds() {
    let (nn, kk, mm) = (20usize, 1.0e6, 2.0);
    let (k, m) = square_lattice(nn, kk, mm);
    let exact = square_lattice_exact(nn, kk, mm);
    let (idx, f_max) = gap_after(&exact, 250);
    for bands in [2usize, 4] {
        let mut o = EigenOptions::new(f_max);
        o.block_size = 4;
        o.modes_per_slice = 30;
        o.concurrent_bands = Some(bands);
        let sol = solve_in_bands(&k, &m, &o, &exact, "square lattice");
        assert_eq!(sol.sturm_count, idx + 1);
    }
}

/// Solves `k`, `m` to the f_max just above the `count`-th eigenvalue with the default
/// options inside a rayon pool of `threads` threads.
fn solve_in_pool(k: &Sp, m: &Sp, count: usize, threads: usize) -> EigenSolution {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut o = EigenOptions::new(f_max_above(k, m, count));
        o.modes_per_slice = 30;
        solve(k.as_ref(), m.as_ref(), &o, None).unwrap()
    })
}

/// The modes should not depend on the number of threads: solved with the default options in
/// a pool of one thread and in a pool of two, the eigenvalues and mode shapes should be
/// bitwise the same. Known to fail: with the band count, the solve column groups and the
/// row ranges fixed, the eigenvalues of this one-band lattice still differ in the last bits
/// (a thread-dependent step remains, not yet found); ignored until it is fixed.
#[test]
#[ignore = "known defect: the modes still differ in the last bits between 1 and 2 threads"]
fn modes_are_bitwise_independent_of_the_thread_count() {
    {
        let (nx, bands) = (40, 1);
        let (k, m) = lattice3d(nx, 12, 12, 2e6, 17);
        assert!(k.nrows() > 2 * 8192);
        let one = solve_in_pool(&k, &m, 90, 1);
        let two = solve_in_pool(&k, &m, 90, 2);
        assert_quality(&one);
        assert_eq!(one.timing.bands, bands, "{nx}");
        assert_eq!(two.timing.bands, bands, "{nx}");
        assert_eq!(one.eigenvalues_rad2_s2, two.eigenvalues_rad2_s2, "{nx}");
        assert!(one.modes == two.modes, "{nx}: mode shapes differ bitwise");
    }
}

/// `copies` decoupled fixed–free spring–mass chains of `masses` masses m (kg), copy p with
/// springs `k (1 + spread · p)` (N/m): eigenvalues `λ = 4 k_p/m · sin²((2j − 1)π/(2(2n + 1)))`,
/// j = 1..n (insert `u_i = sin(iθ)`, `u_0 = 0`, the free end's equation closing the set), so
/// every chain eigenvalue is a cluster of `copies` eigenvalues of relative width
/// `spread · (copies − 1)` (`copies` equal ones at `spread = 0`): the shape of a long
/// track's sleeper modes on identical supports.
fn clustered_chains(copies: usize, masses: usize, spread: f64) -> (Sp, Sp, Vec<f64>) {
    let (k, m) = (1e6, 1.0);
    let (mut kt, mut mt) = (Vec::new(), Vec::new());
    let mut exact = Vec::new();
    for p in 0..copies {
        let kp = k * (1.0 + spread * p as f64);
        let d = |i: usize| p * masses + i;
        for i in 0..masses {
            mt.push((d(i), d(i), m));
            // the spring below mass i (to the ground for i = 0)
            kt.push((d(i), d(i), kp));
            if i > 0 {
                add2(&mut kt, d(i - 1), d(i), 0.0, -kp);
                kt.push((d(i - 1), d(i - 1), kp));
            }
        }
        for j in 1..=masses {
            let th = (2 * j - 1) as f64 * std::f64::consts::PI / (2 * (2 * masses + 1)) as f64;
            exact.push(4.0 * kp / m * th.sin().powi(2));
        }
    }
    exact.sort_by(f64::total_cmp);
    let n = copies * masses;
    (sparse(n, &kt), sparse(n, &mt), exact)
}

/// Eigenvalues more multiple than the block (24 equal ones, block 4): a slice's Lanczos run
/// converges such a cluster only in part, so the gap its converged values leave can hide
/// many more eigenvalues than the slice wanted. The slice bound is then moved down by its
/// Sturm count (`recut`): every slice holds at most 1.5 targets (here two clusters, 48;
/// without the recut the first and last slices held 72), and the eigenvalues match the
/// closed form. The band above 0 Hz is the case where a bound placed by the count alone,
/// off the converged values, landed on an exactly multiple eigenvalue and split its count
/// (1 of 24 below it: the next slice failed); bounds now sit in gaps of converged values.
#[test]
fn clusters_larger_than_the_block_keep_slices_near_the_target() {
    let (copies, masses) = (24, 30);
    let (k, m, exact) = clustered_chains(copies, masses, 0.0);
    let between = |i: usize| lambda_to_hz(0.5 * (exact[i * copies - 1] + exact[i * copies]));
    // From 0 Hz (open-ended slices), and from the 10th cluster to the top of the chains'
    // spectrum, where the clusters crowd (sin² flattens): slices of a band above 0 Hz are
    // capped by the previous slice's density, which the crowding defeats.
    let top = lambda_to_hz(exact[exact.len() - 1] * 1.001);
    for (f_min, f_max, bands) in [
        (0.0, between(12), 1),
        (0.0, between(12), 2),
        (between(10), top, 1),
    ] {
        let mut o = EigenOptions::new(f_max);
        o.f_min_hz = f_min;
        o.block_size = 4;
        o.modes_per_slice = 40;
        o.concurrent_bands = Some(bands);
        let sol = solve(k.as_ref(), m.as_ref(), &o, None).unwrap();
        assert_quality(&sol);
        assert_slices_tile(&sol);
        let worst = check_against_dense(&sol, &exact, f_min, f_max);
        let sizes: Vec<usize> = sol.slices.iter().map(|s| s.modes_found).collect();
        eprintln!(
            "{f_min:.0}-{f_max:.0} Hz, {bands} bands: slices {sizes:?}, worst rel err {worst:e}"
        );
        assert!(worst < 1e-8, "worst relative eigenvalue error {worst:e}");
        let allowed = (1.5 * o.modes_per_slice as f64) as usize;
        assert!(
            sizes.iter().all(|&s| s <= allowed),
            "slice sizes {sizes:?} above {allowed}"
        );
    }
}

/// A cap placed by a sparse slice's density over a dense cluster (`K = diag(λ)`, `M = I`: the
/// eigenvalues are the diagonal): 40 sparse eigenvalues, 200 within 0.5 % of each other, 40
/// sparse again, solved in a band above 0 Hz whose second slice is capped by the first one's
/// density. The cap encloses about 210 modes (target 40); it must not end the slice (which
/// would build a subspace for all of them): the slice runs open-ended below it and is cut in a
/// gap of its converged values, so every slice holds at most 1.5 targets.
#[test]
fn a_cap_over_a_dense_cluster_does_not_end_the_slice() {
    let mut exact: Vec<f64> = (0..40).map(|i| 1e6 * (1.0 + i as f64)).collect();
    exact.extend((0..200).map(|j| 41e6 + 1e3 * j as f64));
    exact.extend((0..40).map(|i| 45e6 + 1e6 * i as f64));
    let n = exact.len();
    let k = sparse(
        n,
        &exact
            .iter()
            .enumerate()
            .map(|(i, &l)| (i, i, l))
            .collect::<Vec<_>>(),
    );
    let m = sparse(n, &(0..n).map(|i| (i, i, 1.0)).collect::<Vec<_>>());
    let (f_min, f_max) = (lambda_to_hz(10.5e6), lambda_to_hz(60.5e6));
    let mut o = EigenOptions::new(f_max);
    o.f_min_hz = f_min;
    o.block_size = 4;
    o.modes_per_slice = 40;
    o.concurrent_bands = Some(1);
    let sol = solve(k.as_ref(), m.as_ref(), &o, None).unwrap();
    assert_quality(&sol);
    assert_slices_tile(&sol);
    let worst = check_against_dense(&sol, &exact, f_min, f_max);
    let sizes: Vec<usize> = sol.slices.iter().map(|s| s.modes_found).collect();
    eprintln!("slices {sizes:?}, worst rel err {worst:e}");
    assert!(worst < 1e-10, "worst relative eigenvalue error {worst:e}");
    assert!(
        sizes.iter().all(|&s| s <= 60),
        "slice sizes {sizes:?} above 60"
    );
}
