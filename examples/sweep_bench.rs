//! Benchmark of a speed sweep of the default model, modes cached (figures in
//! docs/performance.md): prepares the model once from the modal cache, runs the sweep into a
//! fresh scratch directory (removed afterwards) with the `sweep` command's options, and prints
//! the wall and CPU seconds, the thread count, the machine's load, and digests of the results
//! (the dominant wavelengths, the maps, the per-speed summaries) so that a speed-up — or a
//! change of the thread count — is seen not to change the answer.
//!
//! Run: `cargo run --release --example sweep_bench -- CACHE_DIR [SPEEDS [KEY=VALUE ...]]`
//! (SPEEDS as `corrugation sweep --speeds`, default `54.8:219:1`, the 165-speed map; the
//! `KEY=VALUE` pairs are model overrides as `--set`, e.g. a small model to compare thread
//! counts: `RAYON_NUM_THREADS=1 … sweep_bench CACHE 60:200:20 track.bays=4 run.fmax=1000`).

#[path = "common/mod.rs"]
mod common;

use common::{bits_digest, cpu_seconds, machine_load, summary_values};
use corrugation::dynamics::{passage::PassageOptions, prepared::PreparedModel};
use corrugation::eigen::cache::ModalCache;
use corrugation::model::{load_model, ModelSource};
use corrugation::studies::speeds::parse_speeds;
use corrugation::studies::sweep::{read_summary, speed_file, sweep, MapOptions};
use std::time::Instant;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let Some(cache_dir) = args.get(1) else {
        anyhow::bail!("usage: sweep_bench CACHE_DIR [SPEEDS [KEY=VALUE ...]]");
    };
    let spec = args.get(2).map_or("54.8:219:1", |s| s.as_str());
    let overrides: Vec<String> = args.iter().skip(3).cloned().collect();
    let speeds = parse_speeds(spec)?;
    let model = load_model(&ModelSource::Builtin, &overrides)?;
    let cache = ModalCache::new(cache_dir.as_str());
    println!(
        "{}; {} rayon threads",
        machine_load(),
        rayon::current_num_threads()
    );
    let t = Instant::now();
    let opts = PassageOptions {
        energy: false,
        rail_point_offset_m: None,
        overlap: false,
    };
    let prepared = PreparedModel::new(&model, &cache, &opts)?;
    let (mt, mw) = prepared.engine.mode_counts();
    println!(
        "prepared in {:.1} s: {mt} track + {mw} wheel modes, f_max {} Hz",
        t.elapsed().as_secs_f64(),
        model.run.fmax
    );
    let p = &prepared.times;
    println!(
        "preparation (wall s; the track's side beside the wheel's): track mesh {:.2}, basis {:.2}, \
         damping {:.2} | wheel mesh {:.2}, basis {:.2}, assembly {:.2}, Rayleigh {:.2} | \
         engine {:.2} | residual flexibility: track {:.2}, wheel {:.2} | total {:.2}",
        p.track_mesh,
        p.track_basis,
        p.track_damping,
        p.wheel_mesh,
        p.wheel_basis,
        p.wheel_assembly,
        p.wheel_rayleigh,
        p.engine,
        p.track_residual,
        p.wheel_residual,
        p.total
    );
    let map = MapOptions {
        frequency_lines_hz: prepared.longitudinal_compression_hz(),
        ..MapOptions::default()
    };
    let dir = std::env::temp_dir().join(format!("sweep_bench.{}", std::process::id()));
    if dir.exists() {
        std::fs::remove_dir_all(&dir)?;
    }
    let (w0, c0) = (Instant::now(), cpu_seconds());
    let out = sweep(
        &prepared,
        &speeds,
        &dir,
        &map,
        "sweep_bench",
        &corrugation::progress::Silent,
    );
    let (w, c) = (w0.elapsed().as_secs_f64(), cpu_seconds() - c0);
    let out = match out {
        Ok(o) => o,
        Err(e) => {
            let _ = std::fs::remove_dir_all(&dir);
            return Err(e.into());
        }
    };
    let mut per_speed = Vec::new();
    for &v in &speeds {
        per_speed.extend(summary_values(&read_summary(&speed_file(&dir, v))?));
    }
    std::fs::remove_dir_all(&dir)?;
    println!(
        "sweep of {} speeds ({spec}): {w:.1} s wall, CPU {c:.1} s ({:.3} s wall per speed); {}",
        speeds.len(),
        w / speeds.len() as f64,
        machine_load()
    );
    let dominant: Vec<f64> = out
        .record
        .dominant_wavelength_mm
        .iter()
        .map(|d| d.unwrap_or(f64::NAN))
        .collect();
    let m = &out.maps;
    let mut maps = m.wear_wavelength.clone();
    for v in [&m.fl_wavelength, &m.wear_frequency, &m.fl_frequency] {
        maps.extend_from_slice(v);
    }
    println!(
        "wavelength range ratio {}; digests: dominant wavelengths {}, maps {}, summaries {}",
        out.record
            .wavelength_range_ratio
            .map_or("none".into(), |r| format!("{r:.9}")),
        bits_digest(&dominant),
        bits_digest(&maps),
        bits_digest(&per_speed)
    );
    Ok(())
}
