//! Diagnostic: how the modal point compliance of the rail's contact line varies *within* an
//! element along the rail — the source of element-passing excitation in a passage (a moving
//! contact sees the rail's stiffness change with the element period `h`, i.e. a parametric
//! excitation at `v / h`).
//!
//! For the kept track modes, `c_d(x) = Σ_k r_{d,k}(x)² / ω_k²` (m/N) with `r(x)` the
//! contact line's interpolated modal rows (the passage's `RailContactLine::rows_at`), sampled
//! at node planes and mid-elements over the solution zone. Prints, per direction, the mean
//! compliance, the mean relative dip at mid-element `1 − c(mid) / ½(c_p + c_{p+1})`, and the
//! residual (constant) series compliance the passage adds.
//!
//! `cargo run --release --example contact_line_compliance -- [--cache DIR] [--set k=v]...`
//! (modes from the cache, computed when absent).

use corrugation::dynamics::{passage::PassageOptions, prepared::PreparedModel};
use corrugation::eigen::cache::{default_cache_dir, ModalCache};
use corrugation::model::{load_model, ModelSource};

fn main() -> anyhow::Result<()> {
    let mut sets = Vec::new();
    let mut cache = None;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--set" => sets.push(
                args.next()
                    .ok_or_else(|| anyhow::anyhow!("--set needs k=v"))?,
            ),
            "--cache" => {
                cache = Some(
                    args.next()
                        .ok_or_else(|| anyhow::anyhow!("--cache needs DIR"))?,
                )
            }
            other => anyhow::bail!("unknown argument {other}"),
        }
    }
    let model = load_model(&ModelSource::Builtin, &sets)?;
    let cache = ModalCache::new(cache.map(Into::into).unwrap_or_else(default_cache_dir));
    let prep = PreparedModel::new(&model, &cache, &PassageOptions::default())?;
    let eng = &prep.engine;
    let line = eng.rail_line();
    let w2 = &eng.track_system().omega2;
    let m = line.modes;
    let [x0, x1] = eng.travel_m();
    let mut rows = vec![0.0; 3 * m];
    let mut comp = |x: f64| -> anyhow::Result<[f64; 3]> {
        line.rows_at(x, &mut rows)?;
        Ok([0, 1, 2].map(|d| {
            (0..m)
                .filter(|&k| w2[k] > 0.0)
                .map(|k| rows[d * m + k].powi(2) / w2[k])
                .sum()
        }))
    };
    let px = &line.planes_x_m;
    let mut mean = [0.0; 3];
    let mut dip = [0.0; 3];
    let mut dip_max = [0.0f64; 3];
    let mut n = 0usize;
    let mut h_sum = 0.0;
    for p in 0..px.len() - 1 {
        if px[p] < x0 || px[p + 1] > x1 {
            continue;
        }
        let (a, b) = (comp(px[p])?, comp(px[p + 1])?);
        let c = comp(0.5 * (px[p] + px[p + 1]))?;
        for d in 0..3 {
            let avg = 0.5 * (a[d] + b[d]);
            mean[d] += avg;
            let r = 1.0 - c[d] / avg;
            dip[d] += r;
            dip_max[d] = dip_max[d].max(r);
        }
        h_sum += px[p + 1] - px[p];
        n += 1;
    }
    let series = eng.series_compliance();
    println!(
        "{} track modes (f_max {} Hz), {} elements over the travel [{x0:.3}, {x1:.3}] m, mean length {:.1} mm",
        m,
        model.run.fmax,
        n,
        1e3 * h_sum / n as f64
    );
    for (d, name) in ["x", "t", "n"].iter().enumerate() {
        println!(
            "{name}: modal compliance mean {:.3e} m/N; mid-element dip mean {:.2} %, max {:.2} %; residual series compliance {:.3e} m/N",
            mean[d] / n as f64,
            100.0 * dip[d] / n as f64,
            100.0 * dip_max[d],
            series[d]
        );
    }
    Ok(())
}
