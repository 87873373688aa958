//! Benchmark of one reduced-order passage of the default model at the model's speed (140
//! km/h) over the 1 m solution zone, modes cached (figures in docs/performance.md): prepares
//! the model once from the modal cache, then runs the passage `reps` times with the energy
//! balance and the damping product beside the contact step (as `corrugation passage`),
//! without either (as the sweeps and studies), and with the damping product beside the contact
//! but no energy balance (a lone passage's loop), and prints per passage the wall and CPU
//! seconds, the split into set-up (integrators, contact grid, static start) and time loop, the
//! machine's load, and a digest of the results (mean forces, band RMS, dominant wavelength,
//! and a bitwise digest of the force and wear histories), so that a speed-up is seen not to
//! change the answer.
//!
//! Run: `cargo run --release --example passage_bench -- CACHE_DIR [fmax_hz [reps [forces.csv]]]`
//! (default 5,000 Hz, 3 repetitions; the CSV gets `t_s, fn_n, fl_n` of the last passage with
//! the energy balance, to compare force histories between builds). The cache must hold the
//! default model's modes (`corrugation modes --cache CACHE_DIR`), or they are computed (minutes).
//! A fourth case runs the studies' passage with the contact on the fe-patch
//! (`contact.influence = "fe-patch"`; the first run builds the patch into the cache, about 70 s
//! and 8.4 GB). The environment variable `PASSAGE_BENCH_CASES` (a comma list of `energy`,
//! `studies`, `alone`, `fe-patch`) runs only those cases, e.g. to profile one of them.

#[path = "common/mod.rs"]
mod common;

use common::{bits_digest, cpu_seconds, machine_load, summary_line};
use corrugation::dynamics::integrator::ModalVerlet;
use corrugation::dynamics::passage::{PassageEngine, PassageOptions};
use corrugation::dynamics::prepared::PreparedModel;
use corrugation::eigen::cache::ModalCache;
use corrugation::model::{load_model, ModelSource};
use corrugation::passage::analysis::summarise;
use std::time::Instant;

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
    let cases = std::env::var("PASSAGE_BENCH_CASES").ok();
    let model = load_model(&ModelSource::Builtin, &[format!("run.fmax={fmax}")])?;
    let cache = ModalCache::new(cache_dir.as_str());
    println!("{}", machine_load());
    let t = Instant::now();
    // as `corrugation passage`: the energy balance, the damping product beside the contact
    let with_energy = PassageOptions {
        overlap: true,
        ..PassageOptions::default()
    };
    let prepared = PreparedModel::new(&model, &cache, &with_energy)?;
    let engine = &prepared.engine;
    let (mt, mw) = engine.mode_counts();
    println!(
        "prepared in {:.1} s: {mt} track + {mw} wheel modes, f_max {fmax} Hz",
        t.elapsed().as_secs_f64()
    );
    let without = PassageOptions {
        energy: false,
        rail_point_offset_m: None,
        overlap: false,
    };
    let alone = PassageOptions {
        overlap: true,
        ..without
    };
    let v = model.run.speed();
    let dt = engine.contact_config(v)?.grid.dx() / v;
    let t = Instant::now();
    let _ = ModalVerlet::new(engine.track_system(), dt)?;
    let integrator_s = t.elapsed().as_secs_f64();
    println!("track integrator set-up alone: {integrator_s:.3} s");
    for (name, opts) in [
        ("energy (CLI)", with_energy),
        ("no energy (studies)", without),
        (
            "no energy, damping product beside the contact (a passage alone)",
            alone,
        ),
    ]
    .into_iter()
    .zip(["energy", "studies", "alone"])
    .filter(|(_, key)| {
        cases
            .as_ref()
            .is_none_or(|c| c.split(',').any(|k| k == *key))
    })
    .map(|(case, _)| case)
    {
        for _ in 0..reps {
            run_case(engine, name, &opts, csv)?;
        }
    }
    // The same passage with the contact solved on the fe-patch (the rail head's and the
    // tread's refined kernels less the global meshes' share) instead of the half-space, as the
    // sweeps and studies run it. The first run builds the patch into the cache (about 70 s and
    // 8.4 GB on the default grid); its preparation time is printed apart from the passages'.
    if cases
        .as_ref()
        .is_none_or(|c| c.split(',').any(|k| k == "fe-patch"))
    {
        let patched = load_model(
            &ModelSource::Builtin,
            &[
                format!("run.fmax={fmax}"),
                "contact.influence=\"fe-patch\"".to_string(),
            ],
        )?;
        let t = Instant::now();
        let prepared = PreparedModel::new(&patched, &cache, &without)?;
        println!(
            "fe-patch model prepared in {:.1} s (the patch read from the cache or built)",
            t.elapsed().as_secs_f64()
        );
        for _ in 0..reps {
            run_case(
                &prepared.engine,
                "fe-patch, no energy (studies)",
                &without,
                None,
            )?;
        }
    }
    Ok(())
}

/// One passage of `engine` at the model's speed with `opts`, timed and digested.
fn run_case(
    engine: &PassageEngine,
    name: &str,
    opts: &PassageOptions,
    csv: Option<&String>,
) -> anyhow::Result<()> {
    let v = engine.model().run.speed();
    let (w0, c0, t0) = (Instant::now(), cpu_seconds(), thread_cpu_seconds());
    let rec = engine.passage(v, None, opts, None)?;
    let (w, c) = (w0.elapsed().as_secs_f64(), cpu_seconds() - c0);
    let ct = thread_cpu_seconds() - t0;
    println!(
        "{name}: {} steps, passage {:.3} s wall, CPU {:.2} s ({:.4} s on the calling thread): set-up {:.3} s, loop {:.3} s ({:.3} ms/step); {}",
        rec.steps,
        w,
        c,
        ct,
        w - rec.seconds,
        rec.seconds,
        1e3 * rec.seconds / rec.steps as f64,
        machine_load()
    );
    let h = &rec.histories;
    let mut hist = h.normal_n.clone();
    hist.extend_from_slice(&h.longitudinal_n);
    hist.extend_from_slice(&rec.wear_j_per_m);
    println!(
        "  static creepage {:.9e}, approach {:.9e} m; histories digest {}",
        rec.static_creepage,
        rec.static_approach_m,
        bits_digest(&hist)
    );
    println!("  {}", summary_line(&summarise(&rec)?));
    if let (Some(path), true) = (csv, opts.energy) {
        let mut s = String::from("t_s,fn_n,fl_n\n");
        for i in 0..h.t_s.len() {
            s += &format!(
                "{:e},{:e},{:e}\n",
                h.t_s[i], h.normal_n[i], h.longitudinal_n[i]
            );
        }
        std::fs::write(path, s)?;
    }
    Ok(())
}

/// CPU time of the calling thread (s) from `/proc/thread-self/schedstat` (nanoseconds on the
/// CPU, finer than the process's 10 ms clock ticks); NaN where it is not available.
fn thread_cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(f64::NAN, |ns| ns * 1e-9)
}
