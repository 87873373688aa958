//! Benchmark: build + assemble the default track model and extract all modes below f_max.
//!
//! `cargo run --release --example track_modes_bench -- [FMAX_HZ] [--set key=value ...]`
//! Prints DOFs, assembly time, eigen timing, mode count, Sturm count, residuals and peak memory.

use corrugation::eigen::{solve, EigenOptions};
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
        model.fastening.model.name(),
        track.dofmap.n_free(),
        t.elapsed().as_secs_f64() - asm,
        asm
    );
    let opts = EigenOptions::new(f_max);
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
        "eigen total {:.1} s: symbolic {:.1} s, {} factorisations {:.1} s, {} solved vectors {:.1} s, checks {:.1} s, factor entries {}",
        tm.total_s, tm.symbolic_s, tm.factorizations, tm.factorize_s, tm.solved_vectors, tm.solve_s, tm.check_s, tm.factor_entries
    );
    println!("peak memory {:.0} MB", peak_rss_mb());
    let shown: Vec<String> = sol
        .frequencies_hz
        .iter()
        .take(12)
        .map(|f| format!("{f:.1}"))
        .collect();
    println!("lowest frequencies (Hz): {}", shown.join(", "));
    Ok(())
}
