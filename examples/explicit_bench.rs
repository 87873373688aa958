//! Benchmark of the explicit FE path: one passage at the model's speed, set-up and passage
//! timed (wall and CPU), with the machine's load and a digest of the results so that a
//! speed-up is seen not to change the answer.
//!
//! ```text
//! cargo run --release --example explicit_bench                 # the small test track (~1 min)
//! cargo run --release --example explicit_bench -- default      # the default model (~7 min)
//! cargo run --release --example explicit_bench -- default contact.grid_nx=64
//! ```
//! Further arguments are model overrides `key=value` (TOML values). Figures: docs/performance.md.

use std::time::Instant;

use corrugation::dynamics::passage::PassageOptions;
use corrugation::explicit::{ExplicitModel, ExplicitOptions};
use corrugation::model::{load_model, ModelSource};
use corrugation::passage::analysis::summarise;
use corrugation::progress::cpu_seconds;

/// The small test track of the test suite (80 mm elements, 4 bays).
const SMALL: &[&str] = &corrugation::model::test_problems::SMALL_MODEL;

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".into())
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let default = args.first().is_some_and(|a| a == "default");
    let mut sets: Vec<String> = if default {
        Vec::new()
    } else {
        SMALL.iter().map(|s| s.to_string()).collect()
    };
    sets.extend(args.iter().filter(|a| a.contains('=')).cloned());
    let model = load_model(&ModelSource::Builtin, &sets)?;
    println!(
        "explicit_bench: {} model, overrides [{}]; {} rayon threads; load average before: {}",
        if default { "default" } else { "small test" },
        sets.join(" "),
        rayon::current_num_threads(),
        load_average()
    );
    let t = Instant::now();
    let cpu0 = cpu_seconds();
    let em = ExplicitModel::new(&model, ExplicitOptions::from_model(&model))?;
    let setup_wall = t.elapsed().as_secs_f64();
    let setup_cpu = cpu_seconds().zip(cpu0).map(|(b, a)| b - a);
    let rec = em.passage(model.run.speed(), None, &PassageOptions::default(), None)?;
    let i = &rec.info;
    let s = summarise(&rec.record)?;
    let dof_steps = (i.dofs[0] * i.steps) as f64;
    println!(
        "set-up: {setup_wall:.2} s wall, {} s CPU; DOFs track {} + wheel {}",
        setup_cpu.map_or("?".into(), |c| format!("{c:.2}")),
        i.dofs[0],
        i.dofs[1]
    );
    println!(
        "passage: {:.2} s wall, {} s CPU; {} contact steps × {} track / {} wheel sub-steps; dt {:.4e} s; {:.1} ns per track DOF-step",
        i.seconds,
        i.cpu_seconds.map_or("?".into(), |c| format!("{c:.2}")),
        i.contact_steps,
        i.track_substeps,
        i.wheel_substeps,
        i.dt_s,
        1e9 * i.seconds / dof_steps
    );
    // Digest: the answer, to compare before and after a speed change.
    let fsum: f64 = rec.record.histories.normal_n.iter().sum::<f64>()
        + rec.record.histories.longitudinal_n.iter().sum::<f64>();
    println!(
        "digest: mean F_N {:.6} N, mean F_L {:.6} N, band RMS F_L {:.6} N, F_N {:.6} N, wear {:.6e}, dominant {:.3} Hz, energy error {:.4} %, force sum {:.9e} N",
        s.mean_fn_n,
        s.mean_fl_n,
        s.fl_band_rms_n,
        s.fn_band_rms_n,
        s.wear_band_rms,
        s.dominant_frequency_hz.unwrap_or(f64::NAN),
        100.0 * i.energy_error,
        fsum
    );
    println!("load average after: {}", load_average());
    Ok(())
}
