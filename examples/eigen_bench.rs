//! Benchmark of the sparse generalised eigensolver on a synthetic rail-like problem.
//!
//! A 3D lattice of nodes (3 DOF each) elongated along x (`nx × ny × nz`, nodes numbered along
//! x), every node coupled to its 26 neighbours (27-point stencil, like trilinear hexahedra)
//! with PSD 3×3 spring blocks, a consistent-mass-like coupling in M, and springs to ground at
//! every node so K is SPD. Not a physics model — a stand-in with the sparsity, numbering and
//! spectral density of the track model.
//!
//! Run: `cargo run --release --example eigen_bench -- [NX] [NY] [NZ] [MODES...]`
//! defaults: NX = 278, NY = 6, NZ = 8 (40 k DOFs), modes 300 1000. For ~150 k DOFs use
//! NX = 1042.

use std::time::Instant;

use corrugation::eigen::factor::ShiftedSystem;
use corrugation::eigen::{hz_to_lambda, lambda_to_hz, solve, EigenOptions, FillOrdering};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, Par};

fn vm_hwm_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM"))
                .and_then(|l| l.split_whitespace().nth(1).map(|v| v.parse::<f64>().ok()))
        })
        .flatten()
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

fn build(nx: usize, ny: usize, nz: usize) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
    let id = |i: usize, j: usize, k: usize| (i * ny + j) * nz + k; // numbered along x
    let h = 0.03; // cell size (m)
    let (e, rho) = (2.1e11, 7850.0);
    let ks = e * h / 8.0; // N/m per neighbour pair
    let mnode = rho * h * h * h; // kg
    let kg = 2.0e7; // ground spring per DOF (N/m)
    let mut kt = Vec::new();
    let mut mt = Vec::new();
    let mut rng = 12345u64;
    let mut rnd = || {
        rng = rng
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    for i in 0..nx {
        for j in 0..ny {
            for k in 0..nz {
                let a = id(i, j, k);
                for d in 0..3 {
                    kt.push(Triplet::new(3 * a + d, 3 * a + d, kg));
                    mt.push(Triplet::new(3 * a + d, 3 * a + d, mnode * 0.5));
                }
                for di in -1i64..=1 {
                    for dj in -1i64..=1 {
                        for dk in -1i64..=1 {
                            let (ii, jj, kk) = (i as i64 + di, j as i64 + dj, k as i64 + dk);
                            if (di, dj, dk) <= (0, 0, 0)
                                || ii >= nx as i64
                                || jj < 0
                                || jj >= ny as i64
                                || kk < 0
                                || kk >= nz as i64
                            {
                                continue;
                            }
                            let b = id(ii as usize, jj as usize, kk as usize);
                            let dv = [di as f64, dj as f64, dk as f64];
                            let d2 = dv.iter().map(|x| x * x).sum::<f64>();
                            let s = ks * (0.9 + 0.2 * rnd()) / d2;
                            // Block B = s (0.3 I + d dᵀ/|d|²): PSD. Pair adds [B −B; −B B].
                            for p in 0..3 {
                                for q in 0..3 {
                                    let bpq =
                                        s * (if p == q { 0.3 } else { 0.0 } + dv[p] * dv[q] / d2);
                                    if bpq == 0.0 {
                                        continue;
                                    }
                                    kt.push(Triplet::new(3 * a + p, 3 * a + q, bpq));
                                    kt.push(Triplet::new(3 * b + p, 3 * b + q, bpq));
                                    kt.push(Triplet::new(3 * a + p, 3 * b + q, -bpq));
                                    kt.push(Triplet::new(3 * b + p, 3 * a + q, -bpq));
                                }
                                // Mass coupling [2c c; c 2c] per DOF (PSD).
                                let c = mnode * 0.5 / 26.0 / d2;
                                mt.push(Triplet::new(3 * a + p, 3 * a + p, 2.0 * c));
                                mt.push(Triplet::new(3 * b + p, 3 * b + p, 2.0 * c));
                                mt.push(Triplet::new(3 * a + p, 3 * b + p, c));
                                mt.push(Triplet::new(3 * b + p, 3 * a + p, c));
                            }
                        }
                    }
                }
            }
        }
    }
    let n = 3 * nx * ny * nz;
    (
        SparseColMat::try_new_from_triplets(n, n, &kt).unwrap(),
        SparseColMat::try_new_from_triplets(n, n, &mt).unwrap(),
    )
}

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let nx = args.first().copied().unwrap_or(278);
    let ny = args.get(1).copied().unwrap_or(6);
    let nz = args.get(2).copied().unwrap_or(8);
    let targets: Vec<usize> = if args.len() > 3 {
        args[3..].to_vec()
    } else {
        vec![300, 1000]
    };
    let t = Instant::now();
    let (k, m) = build(nx, ny, nz);
    let n = k.nrows();
    println!(
        "lattice {nx}×{ny}×{nz}: n = {n} DOFs, nnz(K) = {}, nnz(M) = {}, build {:.2} s, threads {}",
        k.compute_nnz(),
        m.compute_nnz(),
        t.elapsed().as_secs_f64(),
        rayon::current_num_threads()
    );
    let par = Par::rayon(0);
    let mut best = FillOrdering::Amd;
    let mut best_t = f64::INFINITY;
    let mut sys_keep = None;
    for ord in [FillOrdering::Amd, FillOrdering::Identity] {
        let t = Instant::now();
        let sys = ShiftedSystem::new(k.as_ref(), m.as_ref(), ord, par).unwrap();
        let ts = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let f = sys.factorize(hz_to_lambda(1000.0)).unwrap().unwrap();
        let tf = t.elapsed().as_secs_f64();
        println!(
            "ordering {ord:?}: symbolic {ts:.2} s, factor entries {} ({:.1}x nnz(K) lower), numeric LDLT {tf:.2} s, ν(1 kHz) = {}",
            sys.factor_len(),
            sys.factor_len() as f64 / (k.compute_nnz() as f64 / 2.0),
            f.negative_count
        );
        if tf < best_t {
            best_t = tf;
            best = ord;
            sys_keep = Some(sys);
        }
    }
    let sys = sys_keep.unwrap();
    let f = sys.factorize(hz_to_lambda(1000.0)).unwrap().unwrap();
    for bs in [1usize, 8, 16, 32] {
        let mut x = Mat::<f64>::from_fn(n, bs, |i, j| ((i * 7 + j * 13) % 101) as f64 / 101.0);
        let mut buf = sys.solve_buffer(bs);
        let reps = if bs == 1 { 4 } else { 2 };
        let t = Instant::now();
        for _ in 0..reps {
            sys.solve_in_place(&f, x.as_mut(), &mut buf);
        }
        let per = t.elapsed().as_secs_f64() / (reps * bs) as f64;
        println!(
            "solve, block of {bs:2} RHS ({best:?}): {:.4} s per vector",
            per
        );
    }
    // f_max for the target mode counts: bisection on the Sturm count.
    for &target in &targets {
        let (mut lo, mut hi) = (1.0f64, 50_000.0f64);
        let mut fmax = hi;
        for _ in 0..30 {
            let mid = (lo * hi).sqrt();
            let c = sys
                .factorize(hz_to_lambda(mid))
                .unwrap()
                .unwrap()
                .negative_count;
            if c < target {
                lo = mid;
            } else {
                hi = mid;
                fmax = mid;
            }
            if (hi - lo) / hi < 0.01 {
                break;
            }
        }
        let mut o = EigenOptions::new(fmax);
        o.ordering = best;
        let t = Instant::now();
        match solve(k.as_ref(), m.as_ref(), &o, None) {
            Ok(sol) => {
                let tt = t.elapsed().as_secs_f64();
                let rmax = sol.relative_residuals.iter().cloned().fold(0.0, f64::max);
                let tm = &sol.timing;
                println!(
                    "modes < {fmax:.1} Hz: {} (Sturm {}), {} slices, total {tt:.1} s [symbolic {:.1}, {} factorisations {:.1} s, {} solved vectors {:.1} s, checks {:.1} s], max rel residual {rmax:.1e}, M-orth err {:.1e}, f1 {:.1} Hz, f_last {:.1} Hz, VmHWM {:.0} MB",
                    sol.frequencies_hz.len(),
                    sol.sturm_count,
                    sol.slices.len(),
                    tm.symbolic_s,
                    tm.factorizations,
                    tm.factorize_s,
                    tm.solved_vectors,
                    tm.solve_s,
                    tm.check_s,
                    sol.m_orthonormality_error,
                    sol.frequencies_hz[0],
                    lambda_to_hz(*sol.eigenvalues_rad2_s2.last().unwrap()),
                    vm_hwm_mb()
                );
                println!(
                    "   orthogonalisation {:.1} s, Rayleigh-Ritz {:.1} s, restarts/extraction {:.1} s",
                    tm.orthogonalize_s, tm.rayleigh_ritz_s, tm.restart_s
                );
                for s in &sol.slices {
                    println!(
                        "   slice [{:.1}, {:.1}) Hz: {} modes, {} restarts, {} vectors, {:.1} s",
                        lambda_to_hz(s.shift_lo_rad2_s2),
                        lambda_to_hz(s.shift_hi_rad2_s2),
                        s.modes_found,
                        s.restarts,
                        s.solved_vectors,
                        s.lanczos_s
                    );
                }
            }
            Err(e) => println!("modes < {fmax:.1} Hz: FAILED: {e}"),
        }
    }
    println!("peak memory VmHWM {:.0} MB", vm_hwm_mb());
}
