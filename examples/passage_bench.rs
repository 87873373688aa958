//! Benchmark of one reduced-order passage of the default model (target: under 1 s at
//! 140 km/h over the 1 m solution zone, modes cached; figures in docs/performance.md): prepares the model once from the modal cache, then
//! runs the passage `reps` times with the energy balance (as `corrugation passage`) and without
//! (as the studies), and prints wall and CPU seconds per passage and ms per step.
//!
//! Run: `cargo run --release --example passage_bench -- CACHE_DIR [fmax_hz [reps [forces.csv]]]`
//! (default 5,000 Hz, 3 repetitions; the CSV gets `t_s, fn_n, fl_n` of the last passage with
//! the energy balance, to compare force histories between builds). The cache must hold the
//! default model's modes (`corrugation modes --cache CACHE_DIR`), or they are computed (minutes).

use corrugation::dynamics::passage::{PassageOptions, PreparedModel};
use corrugation::eigen::cache::ModalCache;
use corrugation::model::{load_model, ModelSource};
use std::time::Instant;

/// CPU time of this process (user + system, s) from `/proc/self/stat` (Linux, 100 Hz clock
/// ticks; `NaN` elsewhere): the machine is shared, so wall time alone says little.
fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return f64::NAN;
    };
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<f64> = rest
        .split_whitespace()
        .skip(11)
        .take(2)
        .filter_map(|v| v.parse().ok())
        .collect();
    if f.len() == 2 {
        (f[0] + f[1]) / 100.0
    } else {
        f64::NAN
    }
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let Some(cache_dir) = args.get(1) else {
        anyhow::bail!("usage: passage_bench CACHE_DIR [fmax_hz [reps [forces.csv]]]");
    };
    let fmax: f64 = args
        .get(2)
        .map(|a| a.parse())
        .transpose()?
        .unwrap_or(5000.0);
    let reps: usize = args.get(3).map(|a| a.parse()).transpose()?.unwrap_or(3);
    let csv = args.get(4);
    let model = load_model(&ModelSource::Builtin, &[format!("run.fmax={fmax}")])?;
    let cache = ModalCache::new(cache_dir.as_str());
    let t = Instant::now();
    let with_energy = PassageOptions::default();
    let prepared = PreparedModel::new(&model, &cache, &with_energy)?;
    let (mt, mw) = prepared.engine.mode_counts();
    println!(
        "prepared in {:.1} s: {mt} track + {mw} wheel modes, f_max {fmax} Hz",
        t.elapsed().as_secs_f64()
    );
    let without = PassageOptions {
        energy: false,
        rail_point_offset_m: None,
    };
    let v = model.run.speed();
    for (name, opts) in [
        ("energy (CLI)", with_energy),
        ("no energy (studies)", without),
    ] {
        for _ in 0..reps {
            let (w0, c0) = (Instant::now(), cpu_seconds());
            let rec = prepared.engine.passage(v, None, &opts, None)?;
            let (w, c) = (w0.elapsed().as_secs_f64(), cpu_seconds() - c0);
            println!(
                "{name}: {} steps, passage {:.3} s (loop {:.3} s, {:.3} ms/step), CPU {:.2} s; \
                 static creepage {:.9e}, approach {:.9e} m",
                rec.steps,
                w,
                rec.seconds,
                1e3 * rec.seconds / rec.steps as f64,
                c,
                rec.static_creepage,
                rec.static_approach_m
            );
            if let (Some(path), true) = (csv, opts.energy) {
                let h = &rec.histories;
                let mut s = String::from("t_s,fn_n,fl_n\n");
                for i in 0..h.t_s.len() {
                    s += &format!(
                        "{:e},{:e},{:e}\n",
                        h.t_s[i], h.normal_n[i], h.longitudinal_n[i]
                    );
                }
                std::fs::write(path, s)?;
            }
        }
    }
    Ok(())
}
