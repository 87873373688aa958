//! Benchmark: build + assemble the default track model and extract all modes below f_max.
//!
//! `cargo run --release --example track_modes_bench -- [FMAX_HZ] [--set key=value ...]`
//! Prints DOFs, assembly time, eigen timing, mode count, Sturm count, residuals and peak memory.

use corrugation::eigen::factor::ShiftedSystem;
use corrugation::eigen::{hz_to_lambda, solve, EigenOptions, FillOrdering};
use faer::sparse::SparseColMat;
use faer::{Mat, Par};
use std::time::Instant;

use corrugation::eigen::classify::{TrackClassifier, TrackFamily};
use corrugation::eigen::EigenSolution;

/// Classifies every mode and prints the key ones: family counts, the pinned-pinned modes,
/// the lowest longitudinal-compression (LC) modes, and `sleeper` modes whose rail motion is
/// LC (hidden by the sleeper override). One line per mode starts with `KEY`, for scripts.
fn report_classes(track: &TrackStructure, sol: &EigenSolution) -> anyhow::Result<()> {
    let t = Instant::now();
    let c = TrackClassifier::new(track)?;
    let n = sol.modes.nrows();
    let mut counts = std::collections::BTreeMap::new();
    let mut col = vec![0.0; n];
    let mut lines = Vec::new();
    for (i, &f) in sol.frequencies_hz.iter().enumerate() {
        for (r, v) in col.iter_mut().enumerate() {
            *v = sol.modes[(r, i)];
        }
        let k = c.classify(track, &col)?;
        *counts.entry(k.family.name()).or_insert(0usize) += 1;
        let rail = k.rail_family.unwrap_or(k.family);
        if k.family == TrackFamily::VerticalBending && (600.0..1800.0).contains(&f) {
            // Pinned-pinned candidates: RMS of the section deflection w at the sleeper
            // centres over its RMS along the rail (0 = nodes exactly at the sleepers).
            let sm = c.section_motion(&track.dofmap.expand(&col)?)?;
            let xs: Vec<f64> = sm.iter().map(|s| s.x_m).collect();
            let w: Vec<f64> = sm.iter().map(|s| s.w).collect();
            let at = |x: f64| {
                let i = xs.partition_point(|&v| v < x).clamp(1, xs.len() - 1);
                let t = (x - xs[i - 1]) / (xs[i] - xs[i - 1]);
                w[i - 1] + t * (w[i] - w[i - 1])
            };
            let sl = &track.layout.sleepers;
            let r_s = (sl.iter().map(|&x| at(x).powi(2)).sum::<f64>() / sl.len() as f64).sqrt();
            let r_all = (w.iter().map(|v| v * v).sum::<f64>() / w.len() as f64).sqrt();
            lines.push(format!(
                "KEY VB f_hz {f:.1} wavelength_m {} node_ratio {:.2} pinned_pinned {}",
                k.wavelength_m.map_or("-".into(), |l| format!("{l:.3}")),
                r_s / r_all,
                k.pinned_pinned
            ));
        }
        let tag = if k.pinned_pinned {
            Some("pinned_pinned")
        } else if k.family == TrackFamily::LongitudinalCompression {
            Some("LC")
        } else if rail == TrackFamily::LongitudinalCompression {
            Some("LC_rail_of_sleeper_mode")
        } else if k.family == TrackFamily::VerticalBending && k.amplitudes[0] >= 0.5 {
            // Coupled: vertical bending wins narrowly over a large section-mean u_x.
            Some("VB_with_LC")
        } else if k.family == TrackFamily::LongitudinalShear {
            Some("LS")
        } else {
            None
        };
        if let Some(tag) = tag {
            lines.push(format!(
                "KEY {tag} f_hz {f:.1} family {} rail_family {} wavelength_m {} amp[LC,LS,V,L,T] [{:.2},{:.2},{:.2},{:.2},{:.2}] x_head/web/foot {:.2}/{:.2}/{:.2} sleeper_ke {:.2} fit {:.2} energy rail/sl/pad/bal {:.2}/{:.2}/{:.2}/{:.2}",
                k.family.name(),
                rail.name(),
                k.wavelength_m.map_or("-".into(), |l| format!("{l:.3}")),
                k.amplitudes[0], k.amplitudes[1], k.amplitudes[2], k.amplitudes[3], k.amplitudes[4],
                k.rail_x_head, k.rail_x_web, k.rail_x_foot,
                k.sleeper_kinetic_share, k.section_fit,
                k.energy.rail, k.energy.sleepers, k.energy.fastening, k.energy.ballast
            ));
        }
    }
    println!(
        "families: {counts:?} (classification {:.1} s)",
        t.elapsed().as_secs_f64()
    );
    for l in lines {
        println!("{l}");
    }
    Ok(())
}

/// Cost of the building blocks on this model: symbolic analysis and numeric LDLᵀ per
/// ordering, block solves per vector, and a dense n × 200 by 200 × 16 product.
fn probe(k: &SparseColMat<usize, f64>, m: &SparseColMat<usize, f64>, f_max: f64) {
    let n = k.nrows();
    for par in [Par::Seq, Par::rayon(0)] {
        for ord in [
            FillOrdering::Amd,
            FillOrdering::Identity,
            FillOrdering::Metis,
        ] {
            let t = Instant::now();
            let sys = ShiftedSystem::new(k.as_ref(), m.as_ref(), ord, par).unwrap();
            let ts = t.elapsed().as_secs_f64();
            let t = Instant::now();
            let f = sys.factorize(hz_to_lambda(f_max)).unwrap().unwrap();
            let tf = t.elapsed().as_secs_f64();
            println!(
                "{par:?} {ord:?}: symbolic {ts:.2} s, factor entries {}, LDLT {tf:.2} s, nu {}",
                sys.factor_len(),
                f.negative_count
            );
            for bs in [1usize, 16, 32, 64] {
                let mut x = Mat::<f64>::from_fn(n, bs, |i, j| ((i * 7 + j * 13) % 101) as f64);
                let mut buf = sys.solve_buffer(bs);
                let t = Instant::now();
                sys.solve_in_place(&f, x.as_mut(), &mut buf);
                println!(
                    "   solve block {bs}: {:.4} s per vector",
                    t.elapsed().as_secs_f64() / bs as f64
                );
            }
        }
    }
    for (jj, bb) in [(200usize, 16usize), (200, 64), (1000, 200)] {
        let a = Mat::<f64>::from_fn(n, jj, |i, j| ((i + j) % 17) as f64);
        let b = Mat::<f64>::from_fn(n, bb, |i, j| ((i * 3 + j) % 13) as f64);
        for par in [Par::Seq, Par::rayon(0)] {
            let t = Instant::now();
            let c = a.transpose() * &b;
            let _ = c;
            let t1 = t.elapsed().as_secs_f64();
            let mut c = Mat::<f64>::zeros(jj, bb);
            let t = Instant::now();
            faer::linalg::matmul::matmul(
                c.as_mut(),
                faer::Accum::Replace,
                a.transpose(),
                b.as_ref(),
                1.0,
                par,
            );
            let t2 = t.elapsed().as_secs_f64();
            println!(
                "gemm Vt·Z n×{jj} by n×{bb}: {t2:.3} s {par:?} ({:.1} GFlop/s; operator default {t1:.3} s)",
                2.0 * n as f64 * jj as f64 * bb as f64 / t2 / 1e9
            );
        }
    }
}
use corrugation::model::{load_model, ModelSource};
use corrugation::structure::TrackStructure;

fn peak_rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines().find(|l| l.starts_with("VmHWM")).and_then(|l| {
                l.split_whitespace()
                    .nth(1)
                    .and_then(|v| v.parse::<f64>().ok())
            })
        })
        .map(|kb| kb / 1024.0)
        .unwrap_or(f64::NAN)
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let f_max: f64 = args.first().and_then(|a| a.parse().ok()).unwrap_or(2000.0);
    let sets: Vec<String> = args
        .windows(2)
        .filter(|w| w[0] == "--set")
        .map(|w| w[1].clone())
        .collect();
    let model = load_model(&ModelSource::Builtin, &sets)?;
    let t = std::time::Instant::now();
    let track = TrackStructure::build(&model)?;
    let (mats, asm) = track.assemble()?;
    println!(
        "model {} | free DOFs {} | build {:.2} s | assembly {:.2} s",
        model.fastening.model().name(),
        track.dofmap.n_free(),
        t.elapsed().as_secs_f64() - asm,
        asm
    );
    if args.iter().any(|a| a == "--probe") {
        probe(&mats.k, &mats.m, f_max);
        return Ok(());
    }
    let mut opts = EigenOptions::new(f_max);
    // Option overrides for tuning runs: EIGEN_BLOCK, EIGEN_MPS (modes per slice),
    // EIGEN_KEEP (restart_keep), EIGEN_RATIO (subspace_ratio), EIGEN_TOL (tolerance),
    // EIGEN_SEQ=1 (no threads), EIGEN_FMIN (Hz), EIGEN_BANDS (concurrent bands).
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f64>().ok());
    if let Some(b) = env("EIGEN_BLOCK") {
        opts.block_size = b as usize;
    }
    if let Some(m) = env("EIGEN_MPS") {
        opts.modes_per_slice = m as usize;
    }
    if let Some(r) = env("EIGEN_RATIO") {
        opts.subspace_ratio = r;
    }
    if let Some(t) = env("EIGEN_TOL") {
        opts.tolerance = t;
    }
    if let Some(k) = env("EIGEN_KEEP") {
        opts.restart_keep = k;
    }
    if let Some(f) = env("EIGEN_FMIN") {
        opts.f_min_hz = f;
    }
    if let Some(b) = env("EIGEN_BANDS") {
        opts.concurrent_bands = Some(b as usize);
    }
    if env("EIGEN_SEQ") == Some(1.0) {
        opts.parallel = false;
    }
    let sol = solve(mats.k.as_ref(), mats.m.as_ref(), &opts, None)?;
    let max_res = sol.relative_residuals.iter().cloned().fold(0.0, f64::max);
    println!(
        "f_max {f_max} Hz | modes {} | Sturm {} | max residual {:.2e} | M-orth {:.2e}",
        sol.frequencies_hz.len(),
        sol.sturm_count,
        max_res,
        sol.m_orthonormality_error
    );
    let tm = &sol.timing;
    println!(
        "eigen total {:.1} s ({} bands; phase times summed over bands): symbolic {:.1} s, {} factorisations {:.1} s, {} solved vectors {:.1} s, checks {:.1} s, factor entries {}",
        tm.total_s, tm.bands, tm.symbolic_s, tm.factorizations, tm.factorize_s, tm.solved_vectors, tm.solve_s, tm.check_s, tm.factor_entries
    );
    println!(
        "   orthogonalisation {:.1} s ({} blocks, {} passes, M products {:.1} s), Rayleigh-Ritz {:.1} s, restarts/extraction {:.1} s",
        tm.orthogonalize_s,
        tm.orthogonalized_blocks,
        tm.orthogonalization_passes,
        tm.orthogonalize_spmm_s,
        tm.rayleigh_ritz_s,
        tm.restart_s
    );
    for s in &sol.slices {
        println!(
            "   slice [{:.1}, {:.1}) Hz: {} modes, {} restarts, {} vectors, {:.1} s",
            corrugation::eigen::lambda_to_hz(s.shift_lo_rad2_s2),
            corrugation::eigen::lambda_to_hz(s.shift_hi_rad2_s2),
            s.modes_found,
            s.restarts,
            s.solved_vectors,
            s.lanczos_s
        );
    }
    println!("peak memory {:.0} MB", peak_rss_mb());
    if args.iter().any(|a| a == "--classify") {
        report_classes(&track, &sol)?;
    }
    let shown: Vec<String> = sol
        .frequencies_hz
        .iter()
        .take(12)
        .map(|f| format!("{f:.1}"))
        .collect();
    println!("lowest frequencies (Hz): {}", shown.join(", "));
    // Bit-level digest of the eigenvalues and mode shapes (FNV-1a): equal digests on two
    // runs mean bit-identical results (the solve must not depend on thread timing).
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |x: f64| {
        for byte in x.to_bits().to_le_bytes() {
            h = (h ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3);
        }
    };
    sol.eigenvalues_rad2_s2.iter().for_each(|&l| eat(l));
    for c in 0..sol.modes.ncols() {
        sol.modes.col(c).iter().step_by(97).for_each(|&x| eat(x));
    }
    println!("digest {h:016x} (eigenvalues and every 97th entry of every mode, bitwise)");
    Ok(())
}
