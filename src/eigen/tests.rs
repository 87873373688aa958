//! Tests of the eigensolver against closed forms and an independent dense solver.
//!
//! Oracles:
//! * dense generalised eigensolver: `M = L Lᵀ` (faer dense Cholesky), `C = L⁻¹ K L⁻ᵀ`,
//!   eigenvalues of `C` by faer's dense `self_adjoint_eigen`;
//! * free-free bar of N linear 2-node elements with consistent mass: the exact discrete
//!   eigenvalues `λ_k = 6c²/h² · (1 − cos(kπ/N)) / (2 + cos(kπ/N))`, k = 0..N
//!   (insert `u_j = cos(kπj/N)` into the assembled equations), and the continuum limit
//!   `f_k = k c / (2L)`;
//! * square free-free scalar spring lattice (equal springs k, equal masses m):
//!   `λ_{ij} = (μ_i + μ_j)/m`, `μ_i = 4k sin²(iπ/(2N))`, with exact double eigenvalues
//!   `λ_{ij} = λ_{ji}`.

use super::{
    factor, hz_to_lambda, lambda_to_hz, solve, EigenError, EigenOptions, EigenSolution,
    FillOrdering,
};
use faer::sparse::{SparseColMat, Triplet};
use faer::Mat;

type Sp = SparseColMat<usize, f64>;

fn sparse(n: usize, t: &[(usize, usize, f64)]) -> Sp {
    let trip: Vec<Triplet<usize, usize, f64>> =
        t.iter().map(|&(i, j, v)| Triplet::new(i, j, v)).collect();
    SparseColMat::try_new_from_triplets(n, n, &trip).unwrap()
}

/// Adds a symmetric 2-DOF element block `[a b; b a]` on DOFs (p, q) in full storage.
fn add2(t: &mut Vec<(usize, usize, f64)>, p: usize, q: usize, diag: f64, off: f64) {
    t.push((p, p, diag));
    t.push((q, q, diag));
    t.push((p, q, off));
    t.push((q, p, off));
}

/// Free-free bar: N linear elements, length L (m), E (Pa), ρ (kg/m³), area 1 m².
fn bar(n_el: usize, l: f64, e: f64, rho: f64) -> (Sp, Sp) {
    let h = l / n_el as f64;
    let (mut kt, mut mt) = (Vec::new(), Vec::new());
    for el in 0..n_el {
        add2(&mut kt, el, el + 1, e / h, -e / h);
        add2(&mut mt, el, el + 1, rho * h / 3.0, rho * h / 6.0);
    }
    (sparse(n_el + 1, &kt), sparse(n_el + 1, &mt))
}

fn bar_exact(n_el: usize, l: f64, e: f64, rho: f64) -> Vec<f64> {
    let h = l / n_el as f64;
    let c2 = e / rho;
    (0..=n_el)
        .map(|k| {
            let ct = (k as f64 * std::f64::consts::PI / n_el as f64).cos();
            6.0 * c2 / (h * h) * (1.0 - ct) / (2.0 + ct)
        })
        .collect()
}

/// Deterministic pseudo-random numbers in [0, 1).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// 3D lattice of point masses (3 DOF each) joined by isotropic 3×3 springs `k I` to the 6
/// axial and 12 face-diagonal neighbours (random k), random nodal masses plus a consistent-
/// mass-like coupling between axial neighbours (M non-diagonal, positive definite).
/// `ground`: springs to ground at every node (K SPD); otherwise free (3 rigid translations).
fn lattice3d(nx: usize, ny: usize, nz: usize, ground: f64, seed: u64) -> (Sp, Sp) {
    let mut rng = Lcg(seed);
    let id = |i: usize, j: usize, k: usize| (i * ny + j) * nz + k;
    let n = nx * ny * nz * 3;
    let (mut kt, mut mt) = (Vec::new(), Vec::new());
    let offsets: [(i64, i64, i64); 9] = [
        (1, 0, 0),
        (0, 1, 0),
        (0, 0, 1),
        (1, 1, 0),
        (1, -1, 0),
        (1, 0, 1),
        (1, 0, -1),
        (0, 1, 1),
        (0, 1, -1),
    ];
    for i in 0..nx {
        for j in 0..ny {
            for k in 0..nz {
                let a = id(i, j, k);
                let mass = 1.0 + rng.next();
                for d in 0..3 {
                    mt.push((3 * a + d, 3 * a + d, mass));
                    if ground > 0.0 {
                        kt.push((3 * a + d, 3 * a + d, ground * (0.5 + rng.next())));
                    }
                }
                for (o, &(di, dj, dk)) in offsets.iter().enumerate() {
                    let (ii, jj, kk) = (i as i64 + di, j as i64 + dj, k as i64 + dk);
                    if ii < 0
                        || jj < 0
                        || kk < 0
                        || ii >= nx as i64
                        || jj >= ny as i64
                        || kk >= nz as i64
                    {
                        continue;
                    }
                    let b = id(ii as usize, jj as usize, kk as usize);
                    let s = 1.0e7 * (0.5 + rng.next());
                    let mc = if o < 3 { 0.1 } else { 0.0 };
                    for d in 0..3 {
                        add2(&mut kt, 3 * a + d, 3 * b + d, s, -s);
                        if mc > 0.0 {
                            add2(&mut mt, 3 * a + d, 3 * b + d, mc, mc);
                        }
                    }
                }
            }
        }
    }
    (sparse(n, &kt), sparse(n, &mt))
}

/// Square free-free scalar lattice, N × N nodes, equal springs k (N/m), equal masses m (kg).
fn square_lattice(nn: usize, k: f64, m: f64) -> (Sp, Sp) {
    let id = |i: usize, j: usize| i * nn + j;
    let (mut kt, mut mt) = (Vec::new(), Vec::new());
    for i in 0..nn {
        for j in 0..nn {
            mt.push((id(i, j), id(i, j), m));
            if i + 1 < nn {
                add2(&mut kt, id(i, j), id(i + 1, j), k, -k);
            }
            if j + 1 < nn {
                add2(&mut kt, id(i, j), id(i, j + 1), k, -k);
            }
        }
    }
    // Make sure every diagonal entry exists in K.
    for i in 0..nn * nn {
        kt.push((i, i, 0.0));
    }
    (sparse(nn * nn, &kt), sparse(nn * nn, &mt))
}

/// Dense oracle: all eigenvalues (ascending) of K φ = λ M φ.
fn dense_eigenvalues(k: &Sp, m: &Sp) -> Vec<f64> {
    let kd = k.to_dense();
    let md = m.to_dense();
    let l = md.llt(faer::Side::Lower).unwrap().L().to_owned();
    let n = kd.nrows();
    let mut x = kd.clone();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(
        l.as_ref(),
        x.as_mut(),
        faer::Par::Seq,
    );
    let mut c = x.transpose().to_owned();
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(
        l.as_ref(),
        c.as_mut(),
        faer::Par::Seq,
    );
    let c = Mat::<f64>::from_fn(n, n, |i, j| 0.5 * (c[(i, j)] + c[(j, i)]));
    c.self_adjoint_eigenvalues(faer::Side::Lower).unwrap()
}

/// Checks `sol` against the dense oracle: same count below f_max and relative agreement.
fn check_against_dense(sol: &EigenSolution, dense: &[f64], f_min: f64, f_max: f64) -> f64 {
    let (lo, hi) = (hz_to_lambda(f_min), hz_to_lambda(f_max));
    let expect: Vec<f64> = dense
        .iter()
        .copied()
        .filter(|&l| {
            if f_min == 0.0 {
                l < hi
            } else {
                l >= lo && l < hi
            }
        })
        .collect();
    assert_eq!(
        sol.eigenvalues_rad2_s2.len(),
        expect.len(),
        "mode count vs dense"
    );
    assert_eq!(
        sol.sturm_count - sol.sturm_count_below_min,
        expect.len(),
        "Sturm count"
    );
    let mut worst = 0.0f64;
    for (a, b) in sol.eigenvalues_rad2_s2.iter().zip(&expect) {
        // Relative to λ; rigid-body modes (λ ≈ 0) relative to λ_max.
        let err = (a - b).abs() / b.abs().max(1e-6 * hi);
        worst = worst.max(err);
    }
    worst
}

fn assert_quality(sol: &EigenSolution) {
    // Relative residual for elastic modes (f > 1 Hz); backward error for all, incl. rigid.
    let rmax = sol
        .relative_residuals
        .iter()
        .zip(&sol.frequencies_hz)
        .filter(|(_, &f)| f > 1.0)
        .map(|(r, _)| *r)
        .fold(0.0, f64::max);
    let bmax = sol.backward_errors.iter().cloned().fold(0.0, f64::max);
    eprintln!(
        "  max rel residual (elastic) {rmax:.2e}, max backward error {bmax:.2e}, M-orth err {:.2e}",
        sol.m_orthonormality_error
    );
    // Default tolerance 1e-8 on the transformed residual → relative residuals ≲ 1e-7.
    assert!(rmax < 1e-7, "max relative residual {rmax:e}");
    assert!(bmax < 1e-8, "max backward error {bmax:e}");
    assert!(
        sol.m_orthonormality_error < 1e-8,
        "M-orthonormality error {:e}",
        sol.m_orthonormality_error
    );
    let found: usize = sol.slices.iter().map(|s| s.modes_found).sum();
    for s in &sol.slices {
        assert_eq!(
            s.modes_found,
            s.sturm_hi - s.sturm_lo,
            "per-slice Sturm count"
        );
    }
    assert_eq!(found, sol.sturm_count - sol.sturm_count_below_min);
}

#[test]
fn bar_matches_exact_discrete_eigenvalues_with_rigid_mode() {
    let (e, rho, l, n_el) = (210e9, 7850.0, 10.0, 200);
    let (k, m) = bar(n_el, l, e, rho);
    let mut o = EigenOptions::new(5000.0);
    o.block_size = 4;
    o.modes_per_slice = 6; // force several slices
    let sol = solve(k.as_ref(), m.as_ref(), &o, None).unwrap();
    assert_quality(&sol);
    let exact = bar_exact(n_el, l, e, rho);
    let worst = check_against_dense(&sol, &exact, 0.0, 5000.0);
    eprintln!(
        "bar: {} modes, {} slices, worst rel err vs exact discrete {worst:e}, f1 = {} Hz",
        sol.frequencies_hz.len(),
        sol.slices.len(),
        sol.frequencies_hz[1]
    );
    assert!(worst < 1e-8, "worst relative eigenvalue error {worst:e}");
    assert!(
        sol.frequencies_hz[0] < 1e-3,
        "rigid-body mode at {} Hz",
        sol.frequencies_hz[0]
    );
    assert!(sol.slices.len() >= 3);
}

#[test]
fn bar_converges_to_c_over_2l_harmonics() {
    // Continuum free-free bar: f_k = k c / (2L). Linear elements with consistent mass
    // over-estimate by (kπh/L)²/24 relative at leading order, i.e. the error falls as h².
    let (e, rho, l): (f64, f64, f64) = (210e9, 7850.0, 10.0);
    let c = (e / rho).sqrt();
    let mut prev_err = f64::INFINITY;
    for n_el in [25usize, 50, 100, 200] {
        let (k, m) = bar(n_el, l, e, rho);
        let mut o = EigenOptions::new(1500.0);
        o.block_size = 4;
        let sol = solve(k.as_ref(), m.as_ref(), &o, None).unwrap();
        assert_quality(&sol);
        let f5 = sol.frequencies_hz[5];
        let exact = 5.0 * c / (2.0 * l);
        let err = (f5 - exact) / exact;
        let h = l / n_el as f64;
        let predicted = (5.0 * std::f64::consts::PI * h / l).powi(2) / 24.0;
        eprintln!("bar N={n_el}: f5 = {f5:.4} Hz, c/2L·5 = {exact:.4} Hz, rel err {err:.3e}, predicted {predicted:.3e}");
        assert!(err > 0.0, "consistent mass over-estimates");
        assert!((err - predicted).abs() < 0.05 * predicted, "h² error law");
        assert!(err < prev_err / 3.9);
        prev_err = err;
    }
}

#[test]
fn free_3d_lattice_matches_dense_solver() {
    let (k, m) = lattice3d(6, 5, 4, 0.0, 7);
    let dense = dense_eigenvalues(&k, &m);
    // Band covering about half the spectrum, several slices.
    let f_max = lambda_to_hz(dense[dense.len() / 2]) * 1.0001;
    let mut o = EigenOptions::new(f_max);
    o.block_size = 6;
    o.modes_per_slice = 40;
    let sol = solve(k.as_ref(), m.as_ref(), &o, None).unwrap();
    assert_quality(&sol);
    let worst = check_against_dense(&sol, &dense, 0.0, f_max);
    eprintln!(
        "free lattice n={}: {} modes in {} slices, worst rel err {worst:e}, rigid λ = {:e}, {:e}, {:e}",
        k.nrows(),
        sol.frequencies_hz.len(),
        sol.slices.len(),
        sol.eigenvalues_rad2_s2[0],
        sol.eigenvalues_rad2_s2[1],
        sol.eigenvalues_rad2_s2[2]
    );
    assert!(worst < 1e-8, "worst relative eigenvalue error {worst:e}");
    // Three rigid translations.
    assert!(sol.frequencies_hz[2] < 1e-3 && sol.frequencies_hz[3] > 1.0);
    // Eigenvalues below GROUNDED_TEST·|σ₀| (the rigid ones): no grounded-structure probe,
    // every solved vector belongs to a slice.
    let in_slices: usize = sol.slices.iter().map(|s| s.solved_vectors).sum();
    assert_eq!(sol.timing.solved_vectors, in_slices);
}

/// Grounded 5 × 5 × 5 lattice, its dense eigenvalues, and options for the band from just
/// below its 41st eigenvalue to midway between its 301st and 302nd (261 modes).
fn grounded_lattice_band() -> (Sp, Sp, Vec<f64>, EigenOptions) {
    let (k, m) = lattice3d(5, 5, 5, 2e6, 11);
    let dense = dense_eigenvalues(&k, &m);
    let f_min = lambda_to_hz(dense[40]) * 0.9999 + lambda_to_hz(dense[39]) * 0.0001;
    let f_max = lambda_to_hz(dense[300]) * 0.5 + lambda_to_hz(dense[301]) * 0.5;
    let mut o = EigenOptions::new(f_max);
    o.f_min_hz = f_min;
    o.block_size = 8;
    o.modes_per_slice = 60;
    (k, m, dense, o)
}

#[test]
fn grounded_3d_lattice_band_with_f_min_matches_dense_solver() {
    let (k, m, dense, mut o) = grounded_lattice_band();
    let (f_min, f_max) = (o.f_min_hz, o.f_max_hz);
    o.ordering = FillOrdering::Identity;
    let sol = solve(k.as_ref(), m.as_ref(), &o, None).unwrap();
    assert_quality(&sol);
    let worst = check_against_dense(&sol, &dense, f_min, f_max);
    eprintln!(
        "grounded lattice n={}: {} modes in [{f_min:.1}, {f_max:.1}) Hz, {} slices, worst rel err {worst:e}",
        k.nrows(),
        sol.frequencies_hz.len(),
        sol.slices.len()
    );
    assert_eq!(sol.frequencies_hz.len(), 261);
    assert!(worst < 1e-8);
}

/// Closed-form eigenvalues (ascending) of [`square_lattice`]: `(μ_a + μ_b)/m` with the
/// free-free chain values `μ_i = 4k sin²(iπ/2n)`; every `a ≠ b` pair is a double eigenvalue.
fn square_lattice_exact(nn: usize, kk: f64, mm: f64) -> Vec<f64> {
    let mu: Vec<f64> = (0..nn)
        .map(|i| {
            4.0 * kk
                * (i as f64 * std::f64::consts::PI / (2.0 * nn as f64))
                    .sin()
                    .powi(2)
        })
        .collect();
    let mut exact: Vec<f64> = mu
        .iter()
        .flat_map(|a| mu.iter().map(move |b| (a + b) / mm))
        .collect();
    exact.sort_by(f64::total_cmp);
    exact
}

/// The first index `i ≥ start` with `λ_{i+1}` distinct from `λ_i` (relative 1e-6), and the
/// frequency (Hz) midway between them: an `f_max` that splits no coincident pair.
fn gap_after(exact: &[f64], start: usize) -> (usize, f64) {
    let mut idx = start;
    while (exact[idx + 1] - exact[idx]) < 1e-6 * exact[idx] {
        idx += 1;
    }
    (idx, lambda_to_hz(0.5 * (exact[idx] + exact[idx + 1])))
}

#[test]
fn square_lattice_double_eigenvalues_closed_form_and_sturm() {
    let (nn, kk, mm) = (20usize, 1.0e6, 2.0);
    let (k, m) = square_lattice(nn, kk, mm);
    let exact = square_lattice_exact(nn, kk, mm);
    let (idx, f_max) = gap_after(&exact, 150);
    let mut o = EigenOptions::new(f_max);
    o.block_size = 4;
    o.modes_per_slice = 30;
    let sol = solve(k.as_ref(), m.as_ref(), &o, None).unwrap();
    assert_quality(&sol);
    let worst = check_against_dense(&sol, &exact, 0.0, f_max);
    let doubles = exact[..=idx]
        .windows(2)
        .filter(|w| (w[1] - w[0]).abs() < 1e-9 * w[1])
        .count();
    eprintln!(
        "square lattice: {} modes ({} coincident pairs), {} slices, Sturm {}, worst rel err {worst:e}",
        sol.frequencies_hz.len(),
        doubles,
        sol.slices.len(),
        sol.sturm_count
    );
    assert!(doubles > 50);
    assert_eq!(sol.sturm_count, idx + 1);
    assert!(worst < 1e-8);
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let (k, m) = bar(10, 1.0, 1.0, 1.0);
    let (k2, _) = bar(11, 1.0, 1.0, 1.0);
    assert!(matches!(
        solve(k2.as_ref(), m.as_ref(), &EigenOptions::new(1.0), None),
        Err(EigenError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        solve(k.as_ref(), m.as_ref(), &EigenOptions::new(-1.0), None),
        Err(EigenError::InvalidOption { .. })
    ));
    // Negative mass: K − σ₀M is indefinite at σ₀ < 0.
    let (k, _) = bar(10, 1.0, 1.0, 1.0);
    let (_, mneg) = bar(10, 1.0, 1.0, -1.0);
    assert!(matches!(
        solve(k.as_ref(), mneg.as_ref(), &EigenOptions::new(1.0), None),
        Err(EigenError::NotSemiDefinite { .. })
    ));
}

#[test]
fn grounded_lattice_from_zero_moves_first_shift_up_and_matches_dense() {
    // Grounded: no eigenvalue near 0, so the first slice starts at 0.9 λ₁ (Sturm count 0
    // there is proven by the factorisation) instead of the negative shift.
    let (k, m) = lattice3d(5, 4, 4, 5e7, 3);
    let dense = dense_eigenvalues(&k, &m);
    let f_max = lambda_to_hz(0.5 * (dense[119] + dense[120]));
    let mut o = EigenOptions::new(f_max);
    o.block_size = 8;
    o.modes_per_slice = 50;
    let sol = solve(k.as_ref(), m.as_ref(), &o, None).unwrap();
    assert_quality(&sol);
    let worst = check_against_dense(&sol, &dense, 0.0, f_max);
    eprintln!(
        "grounded lattice from 0: {} modes, first slice starts at {:.1} Hz (f1 = {:.1} Hz), worst rel err {worst:e}",
        sol.frequencies_hz.len(),
        lambda_to_hz(sol.slices[0].shift_lo_rad2_s2),
        sol.frequencies_hz[0]
    );
    assert_eq!(sol.frequencies_hz.len(), 120);
    assert!(sol.slices[0].shift_lo_rad2_s2 > 0.5 * sol.eigenvalues_rad2_s2[0]);
    // The probe that found λ₁ ran (its solves belong to no slice).
    let in_slices: usize = sol.slices.iter().map(|s| s.solved_vectors).sum();
    assert!(sol.timing.solved_vectors > in_slices);
    assert!(worst < 1e-8);
}

/// `sym_spmm` (8 columns per sweep, parallel row chunks) against the dense product, for a
/// column count that is not a multiple of 8 and for a non-contiguous (strided) input.
#[test]
fn sym_spmm_matches_dense_product() {
    // 3 × 20 × 6 × 6 = 2160 DOFs: two row chunks of the parallel product.
    let (k, _) = lattice3d(20, 6, 6, 1.0, 7);
    let n = k.nrows();
    let kd = k.to_dense();
    let x = Mat::<f64>::from_fn(n, 11, |i, j| ((i * 31 + j * 17) % 97) as f64 / 97.0 - 0.5);
    let mut y = Mat::<f64>::zeros(n, 11);
    super::spmm::sym_spmm(k.as_ref(), x.as_ref(), y.as_mut());
    let yd = &kd * &x;
    let scale = yd.norm_max();
    assert!((&y - &yd).norm_max() <= 1e-13 * scale, "contiguous input");
    // Strided input: the rows of a transposed matrix.
    let xt = x.transpose().to_owned();
    let mut y2 = Mat::<f64>::zeros(n, 11);
    super::spmm::sym_spmm(k.as_ref(), xt.as_ref().transpose(), y2.as_mut());
    assert!((&y2 - &yd).norm_max() <= 1e-13 * scale, "strided input");
}

/// The row-split tall products (2 threads) against the sequential gemm.
#[test]
fn row_split_tall_products_match_sequential_gemm() {
    let n = 40_000; // above 2 × MIN_ROWS_PER_THREAD, so the split is used
    let v = Mat::<f64>::from_fn(n, 37, |i, j| (((i * 13 + j * 7) % 101) as f64).sin());
    let z = Mat::<f64>::from_fn(n, 5, |i, j| (((i * 3 + j * 11) % 89) as f64).cos());
    let par = faer::Par::rayon(2);
    let c = super::spmm::tall_t_mul(v.as_ref(), z.as_ref(), par);
    let cd = v.transpose() * &z;
    assert!((&c - &cd).norm_max() <= 1e-12 * cd.norm_max());
    let mut z2 = z.clone();
    super::spmm::tall_mul_add(z2.as_mut(), v.as_ref(), c.as_ref(), -0.5, par);
    let zd = &z - faer::Scale(0.5) * (&v * &c);
    assert!((&z2 - &zd).norm_max() <= 1e-12 * zd.norm_max());
    // In-place V[:, 0..k] = V[:, 0..j] S (thick restart), k < j, against the plain product.
    let s = Mat::<f64>::from_fn(37, 20, |i, j| (((i * 5 + j * 3) % 23) as f64).sin());
    let vs = &v * &s;
    let mut v2 = v.clone();
    super::spmm::tall_right_mul_in_place(v2.as_mut(), s.as_ref(), par);
    assert!((v2.as_ref().subcols(0, 20) - &vs).norm_max() <= 1e-12 * vs.norm_max());
    assert!(
        v2.as_ref().subcols(20, 17) == v.as_ref().subcols(20, 17),
        "tail untouched"
    );
    // Fused Gram–Schmidt sweep for a diagonal M: z − V c and Vᵀ diag(d) (z − V c), against
    // the plain products, on split rows (par) and in one piece (Seq); n is not a multiple of
    // the row block.
    let d: Vec<f64> = (0..n).map(|i| 1.0 + (i % 7) as f64).collect();
    let zu = &z - &v * &c;
    let dzu = Mat::<f64>::from_fn(n, 5, |i, j| d[i] * zu[(i, j)]);
    let expect = v.transpose() * &dzu;
    let mut fused = Vec::new();
    for p in [par, faer::Par::Seq] {
        let mut z3 = z.clone();
        let got = super::spmm::tall_update_then_t_mul(z3.as_mut(), v.as_ref(), c.as_ref(), &d, p);
        assert!((&z3 - &zu).norm_max() <= 1e-12 * zu.norm_max());
        assert!((&got - &expect).norm_max() <= 1e-12 * expect.norm_max());
        fused.push((z3, got));
    }
    // Bitwise the same for every parallelism (the row ranges do not depend on it): a band
    // that goes parallel when the other bands finish gets the same numbers.
    assert!(fused[0] == fused[1], "fused sweep: Seq vs parallel");
    let c_seq = super::spmm::tall_t_mul(v.as_ref(), z.as_ref(), faer::Par::Seq);
    assert!(c_seq == c, "Vᵀ Z: Seq vs parallel");
    let mut z_seq = z.clone();
    super::spmm::tall_mul_add(z_seq.as_mut(), v.as_ref(), c.as_ref(), -0.5, faer::Par::Seq);
    assert!(z_seq == z2, "Z − V C: Seq vs parallel");
}

#[test]
fn nested_dissection_ordering_gives_less_fill_and_the_same_modes() {
    // A cube lattice: numbered along one axis, the factor is a band of width ~ny·nz·3; nested
    // dissection cuts it with planes of the same size but recursively, so it fills less.
    let (k, m) = lattice3d(12, 12, 12, 2e6, 5);
    let len = |o: FillOrdering| {
        factor::ShiftedSystem::new(k.as_ref(), m.as_ref(), o, faer::Par::Seq)
            .unwrap()
            .factor_len()
    };
    let (id, nd, auto) = (
        len(FillOrdering::Identity),
        len(FillOrdering::Metis),
        len(FillOrdering::Auto),
    );
    eprintln!("cube lattice factor entries: identity {id}, METIS {nd}, auto {auto}");
    assert!((nd as f64) < 0.8 * id as f64, "METIS {nd} vs identity {id}");
    assert!(auto <= nd);
    // The ordering changes the factor, not the eigenpairs: all below f_max agree with the
    // dense solver, and the Sturm count holds.
    let (k, m) = lattice3d(5, 5, 5, 2e6, 11);
    let dense = dense_eigenvalues(&k, &m);
    let f_max = lambda_to_hz(dense[120]) * 0.5 + lambda_to_hz(dense[121]) * 0.5;
    let mut o = EigenOptions::new(f_max);
    o.ordering = FillOrdering::Metis;
    o.modes_per_slice = 50;
    let sol = solve(k.as_ref(), m.as_ref(), &o, None).unwrap();
    assert_quality(&sol);
    assert_eq!(sol.frequencies_hz.len(), 121);
    assert!(check_against_dense(&sol, &dense, 0.0, f_max) < 1e-8);
}

#[test]
fn parallel_column_group_solve_equals_sequential_solve() {
    // The column groups are solved concurrently with the same factor: the result must be the
    // sequential solve's, and (K − σM) x must give back the right-hand side.
    let (k, m) = lattice3d(6, 5, 4, 2e6, 3);
    let n = k.nrows();
    let sigma = hz_to_lambda(150.0);
    let rhs = Mat::<f64>::from_fn(n, 7, |i, j| ((i * 31 + j * 17) % 23) as f64 - 11.0);
    let mut out = Vec::new();
    for par in [faer::Par::Seq, faer::Par::rayon(2)] {
        let sys =
            factor::ShiftedSystem::new(k.as_ref(), m.as_ref(), FillOrdering::Metis, par).unwrap();
        let f = sys.factorize(sigma).unwrap().unwrap();
        let mut x = rhs.clone();
        // A workspace sized for fewer columns is replaced, not overrun.
        let mut ws = sys.solve_buffer(3);
        sys.solve_in_place(&f, x.as_mut(), &mut ws);
        out.push(x);
    }
    let (xs, xp) = (&out[0], &out[1]);
    let scale = xs.norm_max();
    assert!((xs - xp).norm_max() <= 1e-12 * scale);
    // The numeric factorisation and the one-group solve give bitwise the same result for
    // every parallelism (what lets a band switch its parallelism with the load).
    let sys = factor::ShiftedSystem::new(
        k.as_ref(),
        m.as_ref(),
        FillOrdering::Metis,
        faer::Par::rayon(2),
    )
    .unwrap();
    let fs = sys.factorize_with(sigma, faer::Par::Seq).unwrap().unwrap();
    let fp = sys
        .factorize_with(sigma, faer::Par::rayon(2))
        .unwrap()
        .unwrap();
    let mut ws = sys.solve_buffer(7);
    let mut one = Vec::new();
    for (f, par) in [
        (&fs, faer::Par::Seq),
        (&fp, faer::Par::Seq),
        (&fs, faer::Par::rayon(2)),
    ] {
        let mut x = rhs.clone();
        sys.solve_in_place_one_group(f, x.as_mut(), &mut ws, par);
        one.push(x);
    }
    assert!(one[0] == one[1], "factorisation: Seq vs parallel");
    assert!(one[0] == one[2], "one-group solve: Seq vs parallel");
    assert!((&one[0] - xs).norm_max() <= 1e-12 * scale);
    // Residual of the parallel solution with the assembled matrices.
    let kd = k.to_dense();
    let md = m.to_dense();
    let a = &kd - faer::Scale(sigma) * &md;
    let r = &a * xp - &rhs;
    assert!(r.norm_max() <= 1e-8 * rhs.norm_max(), "{}", r.norm_max());
}

/// A frequency (Hz) just above the `count`-th eigenvalue of `k`, `m`, by bisection on the
/// Sturm count of a factorisation (no dense solve).
fn f_max_above(k: &Sp, m: &Sp, count: usize) -> f64 {
    let sys =
        factor::ShiftedSystem::new(k.as_ref(), m.as_ref(), FillOrdering::Auto, faer::Par::Seq)
            .unwrap();
    let (mut lo, mut hi) = (1.0f64, 1e6f64);
    for _ in 0..40 {
        let mid = (lo * hi).sqrt();
        let nu = sys
            .factorize(hz_to_lambda(mid))
            .unwrap()
            .map_or(0, |f| f.negative_count);
        if nu < count {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// The modal basis hands the solver the mass without the stored zeros of the pattern it
/// shares with K (`eigen::basis`, to save memory): the modes must be the same to the bit as with
/// the zeros stored, since the factorisations' pattern is K's either way and a stored zero
/// adds nothing to any sum.
#[test]
fn a_mass_without_its_stored_zeros_gives_the_same_modes_to_the_bit() {
    let (k, m) = lattice3d(6, 5, 5, 2e6, 3);
    let diag: Vec<f64> = (0..m.nrows())
        .map(|j| {
            let (rows, vals) = (m.row_idx_of_col_raw(j), m.val_of_col(j));
            rows.iter().zip(vals).map(|(_, v)| v).sum()
        })
        .collect();
    let mut on_k = Vec::new();
    for (j, &d) in diag.iter().enumerate() {
        for &i in k.row_idx_of_col_raw(j) {
            on_k.push((i, j, if i == j { d } else { 0.0 }));
        }
    }
    let m_stored = sparse(k.nrows(), &on_k);
    let m_compact = sparse(
        k.nrows(),
        &diag
            .iter()
            .enumerate()
            .map(|(j, &v)| (j, j, v))
            .collect::<Vec<_>>(),
    );
    assert!(m_stored.compute_nnz() > 10 * m_compact.compute_nnz());
    let o = EigenOptions::new(f_max_above(&k, &m_compact, 60));
    let a = solve(k.as_ref(), m_stored.as_ref(), &o, None).unwrap();
    let b = solve(k.as_ref(), m_compact.as_ref(), &o, None).unwrap();
    assert_eq!(a.frequencies_hz.len(), 60);
    assert_eq!(a.eigenvalues_rad2_s2, b.eigenvalues_rad2_s2);
    assert_eq!(a.modes, b.modes);
}

mod slicing;
