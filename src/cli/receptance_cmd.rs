//! `corrugation receptance`: the reduced model's receptances at the contact (rail at the
//! mid-span and over the sleeper nearest the solution-zone centre, the wheel at its contact
//! point) and the normal contact force per unit roughness, with their peaks: which
//! resonances a sweep's frequency selection can lock on (docs/theory.md §7.6).
//!
//! Outputs in `--out DIR` (default `corrugation-out/receptance`), written atomically: the
//! files of [`corrugation::studies::receptance`] (`receptance.csv`, `receptance.json` — the
//! `--json` object — and the plots).

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use corrugation::studies::receptance::{receptances, Peak, ReceptanceOptions};

use super::ModelArgs;

/// Receptances of the track and the wheel at the contact, and their peaks.
#[derive(Debug, Args)]
pub(crate) struct ReceptanceCmd {
    #[command(flatten)]
    model: ModelArgs,
    /// Lowest frequency (Hz).
    #[arg(
        allow_hyphen_values = true,
        long,
        default_value_t = corrugation::studies::receptance::ReceptanceOptions::default().from_hz,
        value_name = "HZ"
    )]
    from_hz: f64,
    /// Highest frequency (Hz); default: the smaller of run.fmax and 3000 Hz (the top of a
    /// 54.8–219 km/h sweep map: 219 km/h / 20 mm ≈ 3.04 kHz).
    #[arg(allow_hyphen_values = true, long, value_name = "HZ")]
    to_hz: Option<f64>,
    /// Frequency step (Hz).
    /// (One complex LU of the m × m modal dynamic stiffness per frequency: ≈ 0.05 s at the
    /// default model's 746 track modes, 2 cores.)
    #[arg(
        allow_hyphen_values = true,
        long,
        default_value_t = corrugation::studies::receptance::ReceptanceOptions::default().step_hz,
        value_name = "HZ"
    )]
    step_hz: f64,
    /// Rail positions (m along the rail); default: the mid-span and the sleeper nearest the
    /// centre of the solution zone.
    #[arg(allow_hyphen_values = true, long = "at", value_name = "M")]
    at_m: Vec<f64>,
    /// Output directory.
    #[arg(long, default_value = "corrugation-out/receptance", value_name = "DIR")]
    out: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
    /// Modal cache directory (default: $XDG_CACHE_HOME/corrugation or ~/.cache/corrugation).
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
}

impl ReceptanceCmd {
    pub fn run(self) -> anyhow::Result<()> {
        let t0 = std::time::Instant::now();
        corrugation::lists::check_no_repeats("--at", "m", &self.at_m)?;
        super::check_out_outside_cache(&self.out, self.cache.as_deref())?;
        super::check_out_dir(&self.out)?;
        let m = self.model.load()?;
        m.check_on_track("--at", &self.at_m)?;
        let opts = ReceptanceOptions {
            from_hz: self.from_hz,
            to_hz: self.to_hz,
            step_hz: self.step_hz,
            at_m: self.at_m.clone(),
        };
        let grid = opts.grid(m.run.fmax)?;
        let n = grid.frequencies_hz.len();
        let prepared = super::engine::prepared(&m, self.cache.as_deref())?;
        let pb = super::progress::bar(&format!(
            "receptance ({n} frequencies, {} modes)",
            prepared.track_frequencies_hz.len()
        ));
        let rec = receptances(&prepared, &opts, &grid, t0)?;
        pb.finish_and_clear();
        let json = rec
            .write(&self.out)
            .with_context(|| format!("writing {}", self.out.display()))?;
        if self.json {
            println!("{json}");
            return Ok(());
        }
        let fmt = |v: &[Peak]| {
            v.iter()
                .take(5)
                .map(|p| format!("{:.0} Hz ({:.2e})", p.frequency_hz, p.value))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let summary = &rec.summary;
        for rp in &summary.rail {
            println!("rail {} (x = {:.3} m):", rp.label, rp.x_m);
            println!("  |H_xx| peaks (m/N): {}", fmt(&rp.longitudinal));
            println!("  |H_nn| peaks (m/N): {}", fmt(&rp.normal));
            println!(
                "  force per roughness peaks (N/m): {}",
                fmt(&rp.force_per_roughness)
            );
        }
        println!("wheel |H_xx| peaks: {}", fmt(&summary.wheel_longitudinal));
        println!("wheel |H_nn| peaks: {}", fmt(&summary.wheel_normal));
        println!(
            "{} frequencies in {:.1} s; outputs in {}",
            n,
            summary.seconds,
            self.out.display()
        );
        Ok(())
    }
}
