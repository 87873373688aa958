//! Benchmark of a lone passage beside other work: the default model's passage at 140 km/h
//! (as `corrugation passage`: energy balance, the track's damping product beside the contact
//! step) run alone, beside one and beside two CPU-bound processes, each with the default
//! thread pool and with one thread (as `RAYON_NUM_THREADS=1`). It prints the time loop's
//! median and range per case, the share of steps whose damping product ran on the second
//! thread, and the ratios that the robustness requirement names: beside one process, the
//! default threads' time loop against one thread alone (required ≤ 1.5) and against one
//! thread beside the same process (required ≤ 1.0). Figures in docs/performance.md.
//!
//! Run: `cargo run --release --example passage_interference -- CACHE_DIR [reps]` (default 5
//! repetitions per case, alternating the two thread settings). The cache must hold the
//! default model's modes (`corrugation modes --cache CACHE_DIR`), or they are computed
//! (minutes). The CPU-bound neighbours are this program started again with
//! `CORRUGATION_BURN=1` (a floating-point loop that runs until it is killed); they are
//! killed when their case ends, also when the benchmark fails.

#[path = "common/mod.rs"]
mod common;

use common::{bits_digest, machine_load};
use corrugation::dynamics::{passage::PassageOptions, prepared::PreparedModel};
use corrugation::eigen::cache::ModalCache;
use corrugation::model::{load_model, ModelSource};
use std::process::{Child, Command};
use std::time::Duration;

/// The CPU-bound neighbour: a loop of dependent floating-point operations, forever.
fn burn() -> ! {
    let mut x = 1.000_000_1_f64;
    loop {
        for _ in 0..1_000_000 {
            x = std::hint::black_box(x * 1.000_000_1 + 1e-9);
        }
        if x > 1e300 {
            x = 1.0;
        }
    }
}

/// Neighbours that are killed when dropped.
struct Neighbours(Vec<Child>);

impl Neighbours {
    fn start(n: usize) -> anyhow::Result<Self> {
        let exe = std::env::current_exe()?;
        let mut v = Neighbours(Vec::new());
        for _ in 0..n {
            v.0.push(Command::new(&exe).env("CORRUGATION_BURN", "1").spawn()?);
        }
        // let them reach the scheduler's steady state
        std::thread::sleep(Duration::from_millis(300));
        Ok(v)
    }
}

impl Drop for Neighbours {
    fn drop(&mut self) {
        for c in &mut self.0 {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn main() -> anyhow::Result<()> {
    if std::env::var_os("CORRUGATION_BURN").is_some() {
        burn();
    }
    let args: Vec<String> = std::env::args().collect();
    let Some(cache_dir) = args.get(1) else {
        anyhow::bail!("usage: passage_interference CACHE_DIR [reps]");
    };
    let reps: usize = args.get(2).map(|a| a.parse()).transpose()?.unwrap_or(5);
    let model = load_model(&ModelSource::Builtin, &[])?;
    let cache = ModalCache::new(cache_dir.as_str());
    let opts = PassageOptions {
        overlap: true,
        ..PassageOptions::default()
    };
    let prepared = PreparedModel::new(&model, &cache, &opts)?;
    let engine = &prepared.engine;
    let v = model.run.speed();
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    println!(
        "default passage, 140 km/h, {} pool threads; {reps} repetitions per case; {}",
        rayon::current_num_threads(),
        machine_load()
    );
    let mut digest = None;
    // [neighbours][0 = default threads, 1 = one thread] → loop seconds
    let mut med = [[0.0; 2]; 3];
    for (n, row) in med.iter_mut().enumerate() {
        let _neighbours = Neighbours::start(n)?;
        let mut t = [Vec::new(), Vec::new()];
        let mut split = 0.0;
        for r in 0..2 * reps {
            let single = (r + n) % 2 == 1;
            let rec = if single {
                one.install(|| engine.passage(v, None, &opts, None))?
            } else {
                engine.passage(v, None, &opts, None)?
            };
            if !single {
                split += rec.split_steps as f64 / rec.steps as f64 / reps as f64;
            }
            t[usize::from(single)].push(rec.seconds);
            let h = &rec.histories;
            let mut all = h.normal_n.clone();
            all.extend_from_slice(&h.longitudinal_n);
            all.extend_from_slice(&rec.wear_j_per_m);
            let d = bits_digest(&all);
            if digest.get_or_insert_with(|| d.clone()) != &d {
                anyhow::bail!("the histories differ between runs ({d} vs {digest:?})");
            }
        }
        let range = |v: &[f64]| {
            let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = v.iter().copied().fold(0.0, f64::max);
            format!("{lo:.3}–{hi:.3}")
        };
        let (r0, r1) = (range(&t[0]), range(&t[1]));
        row[0] = median(&mut t[0]);
        row[1] = median(&mut t[1]);
        println!(
            "beside {n} CPU-bound process(es): time loop, default threads {:.3} s ({r0}; {:.0} % of steps split), one thread {:.3} s ({r1}); {}",
            row[0],
            100.0 * split,
            row[1],
            machine_load()
        );
    }
    println!("histories digest {}", digest.unwrap_or_default());
    println!("ratios of the time loop's medians (default threads / one thread):");
    for (n, row) in med.iter().enumerate() {
        println!(
            "  beside {n}: / one thread alone {:.2}, / one thread beside {n} {:.2}",
            row[0] / med[0][1],
            row[0] / row[1]
        );
    }
    let (a, b) = (med[1][0] / med[0][1], med[1][0] / med[1][1]);
    println!(
        "requirement beside one process: ≤ 1.5 × one thread alone: {a:.2} ({}); ≤ one thread beside it: {b:.2} ({})",
        if a <= 1.5 { "met" } else { "missed" },
        if b <= 1.0 { "met" } else { "missed" }
    );
    Ok(())
}
