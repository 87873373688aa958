//! Soak benchmark: many passages in one process, with the memory watched. The small test
//! model's reduced passage is run `N` times (default 1000) in one `PreparedModel`, cycling
//! over speeds and a smooth and a corrugated rail (so the contact grids and the profile paths
//! are exercised, not one cached state), as a sweep or a long study does in one process. It
//! prints the resident set size (`VmRSS` of `/proc/self/status`) every 50 passages and checks
//! that memory is flat: the resident size after the last passage at most 5 % (and 16 MiB)
//! above its size after the first 100 passages (the allocator's working set is reached by
//! then), and every passage's histories finite and bitwise equal to the first passage at the
//! same speed and rail (a leak of state between passages would change them).
//!
//! Run: `cargo run --release --example passage_soak -- CACHE_DIR [N]`. The small model's
//! modes are solved into CACHE_DIR on the first run (under a minute). Figures in
//! docs/performance.md.

#[path = "common/mod.rs"]
mod common;

use common::{bits_digest, machine_load};
use corrugation::dynamics::RailProfile;
use corrugation::dynamics::{passage::PassageOptions, prepared::PreparedModel};
use corrugation::eigen::cache::ModalCache;
use corrugation::model::{load_model, test_problems::SMALL_MODEL, ModelSource};
use std::collections::HashMap;

/// The resident set size of this process (bytes), from `/proc/self/status` (Linux).
fn rss_bytes() -> anyhow::Result<u64> {
    let status = std::fs::read_to_string("/proc/self/status")?;
    let line = status
        .lines()
        .find(|l| l.starts_with("VmRSS:"))
        .ok_or_else(|| anyhow::anyhow!("no VmRSS in /proc/self/status"))?;
    let kib: u64 = line
        .split_whitespace()
        .nth(1)
        .ok_or_else(|| anyhow::anyhow!("bad VmRSS line {line}"))?
        .parse()?;
    Ok(kib * 1024)
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let Some(cache_dir) = args.get(1) else {
        anyhow::bail!("usage: passage_soak CACHE_DIR [passages]");
    };
    let n: usize = args.get(2).map(|a| a.parse()).transpose()?.unwrap_or(1000);
    let sets: Vec<String> = SMALL_MODEL.iter().map(|s| s.to_string()).collect();
    let model = load_model(&ModelSource::Builtin, &sets)?;
    let cache = ModalCache::new(cache_dir.as_str());
    let opts = PassageOptions::default();
    let prepared = PreparedModel::new(&model, &cache, &opts)?;
    let engine = &prepared.engine;
    let speeds_kmh = [60.0, 100.0, 140.0, 180.0];
    // a 40 µm, 40 mm corrugation over the solution zone
    let [z0, z1] = engine.zone_m();
    let x_m: Vec<f64> = (0..=400)
        .map(|i| z0 + (z1 - z0) * i as f64 / 400.0)
        .collect();
    let height_m = x_m
        .iter()
        .map(|x| 20e-6 * (std::f64::consts::TAU * (x - z0) / 0.040).sin())
        .collect();
    let profile = RailProfile::new(x_m, height_m)?;
    println!(
        "passage soak: small model, {n} passages cycling over {speeds_kmh:?} km/h, smooth and corrugated; {}",
        machine_load()
    );
    let mut digests: HashMap<(usize, bool), String> = HashMap::new();
    let mut rss_at_100 = None;
    let t0 = std::time::Instant::now();
    let rss0 = rss_bytes()?;
    for i in 0..n {
        let k = i % speeds_kmh.len();
        let corrugated = (i / speeds_kmh.len()) % 2 == 1;
        let v = speeds_kmh[k] / 3.6;
        let rec = engine.passage(v, corrugated.then_some(&profile), &opts, None)?;
        let h = &rec.histories;
        let mut all = h.normal_n.clone();
        all.extend_from_slice(&h.longitudinal_n);
        all.extend_from_slice(&rec.wear_j_per_m);
        if let Some(bad) = all.iter().find(|x| !x.is_finite()) {
            anyhow::bail!("passage {i}: a non-finite history value {bad}");
        }
        let d = bits_digest(&all);
        let first = digests.entry((k, corrugated)).or_insert_with(|| d.clone());
        if *first != d {
            anyhow::bail!("passage {i}: histories {d} differ from the first passage at the same speed and rail {first}");
        }
        if i + 1 == 100.min(n) {
            rss_at_100 = Some(rss_bytes()?);
        }
        if (i + 1) % 50 == 0 || i + 1 == n {
            println!(
                "{:5} passages  {:7.1} s  RSS {:7.1} MiB",
                i + 1,
                t0.elapsed().as_secs_f64(),
                rss_bytes()? as f64 / 1048576.0
            );
        }
    }
    let last = rss_bytes()?;
    let at_100 = rss_at_100.unwrap_or(rss0);
    let growth = last as f64 - at_100 as f64;
    let limit = (0.05 * at_100 as f64).max(16.0 * 1048576.0);
    println!(
        "RSS before the first passage {:.1} MiB, after 100 {:.1} MiB, after {n} {:.1} MiB: growth {:.2} MiB (limit {:.1} MiB): {}; histories bitwise equal per speed and rail over all passages; {}",
        rss0 as f64 / 1048576.0,
        at_100 as f64 / 1048576.0,
        last as f64 / 1048576.0,
        growth / 1048576.0,
        limit / 1048576.0,
        if growth <= limit { "flat" } else { "GROWING" },
        machine_load()
    );
    if growth > limit {
        anyhow::bail!("memory grew by {:.1} MiB over the soak", growth / 1048576.0);
    }
    Ok(())
}
