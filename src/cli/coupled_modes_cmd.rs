//! `corrugation coupled-modes`: the eigenmodes of the reduced wheel + track system coupled
//! by the contact linearised at the static rolling state (normal Hertz stiffness, creep
//! force with its lag), at the mid-span and the sleeper nearest the solution-zone centre
//! (or `--at`), with frequency, damping ratio, the energy shares in wheel, rail (by the
//! family of the rail's motion) and support, and the motion at the contact
//! (docs/theory.md §7.10).
//!
//! Outputs in `--out DIR` (default `corrugation-out/coupled-modes`), written atomically:
//! `coupled_modes.csv`, `coupled_modes.npy` (same columns) and `coupled_modes.json` (the
//! `--json` object); see [`corrugation::studies::coupled`].

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use corrugation::studies::coupled::write_coupled_modes;

use super::ModelArgs;

/// Coupled wheel–track modes at the contact (linearised contact at the static state).
#[derive(Debug, Args)]
pub(crate) struct CoupledModesCmd {
    #[command(flatten)]
    model: ModelArgs,
    /// Contact positions (m along the rail); default: the mid-span and the sleeper nearest
    /// the centre of the solution zone.
    #[arg(allow_hyphen_values = true, long = "at", value_name = "M")]
    at_m: Vec<f64>,
    /// Highest frequency listed on the terminal (Hz; the files hold every mode).
    #[arg(
        allow_hyphen_values = true,
        long,
        default_value_t = corrugation::studies::coupled::DEFAULT_LIST_TO_HZ,
        value_name = "HZ"
    )]
    list_to_hz: f64,
    /// Output directory.
    #[arg(
        long,
        default_value = "corrugation-out/coupled-modes",
        value_name = "DIR"
    )]
    out: PathBuf,
    /// Print the result as JSON.
    #[arg(long)]
    json: bool,
    /// Modal cache directory (default: $XDG_CACHE_HOME/corrugation or ~/.cache/corrugation).
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
}

impl CoupledModesCmd {
    pub fn run(self) -> anyhow::Result<()> {
        if !(self.list_to_hz.is_finite() && self.list_to_hz > 0.0) {
            anyhow::bail!(
                "--list-to-hz {}: out of range, allowed a frequency greater than 0 Hz",
                self.list_to_hz
            );
        }
        corrugation::lists::check_no_repeats("--at", "m", &self.at_m)?;
        let m = self.model.load()?;
        m.check_on_track("--at", &self.at_m)?;
        super::check_out_outside_cache(&self.out, self.cache.as_deref())?;
        super::check_out_dir(&self.out)?;
        let t0 = std::time::Instant::now();
        let prepared = super::engine::prepared(&m, self.cache.as_deref())?;
        let cm = prepared
            .coupled_modes(m.run.speed(), &self.at_m)
            .context("coupled wheel–track modes")?;
        write_coupled_modes(&self.out, &cm)?;
        if self.json {
            println!("{}", serde_json::to_string_pretty(&cm)?);
            return Ok(());
        }
        let l = &cm.linearisation;
        println!(
            "contact at the static state ({:.1} m/s): k_n {:.3e} N/m, creep coefficient x {:.3e} N, t {:.3e} N, relaxation length x {:.2} mm, t {:.2} mm",
            cm.speed_m_per_s,
            l.normal_stiffness_n_per_m,
            l.creep_coefficient_n[0],
            l.creep_coefficient_n[1],
            corrugation::units::m_to_mm(l.relaxation_length_m[0]),
            corrugation::units::m_to_mm(l.relaxation_length_m[1])
        );
        println!("position_m  frequency_hz  damping_%  rail_x/n  dominant (share)");
        for md in cm.below(self.list_to_hz) {
            let (d, v) = md.shares.dominant();
            println!(
                "{:>9.3}  {:>12.1}  {:>9.3}  {:>8.3}  {d} ({:.0} %)",
                md.position_m,
                md.frequency_hz,
                100.0 * md.damping_ratio,
                md.rail_x_to_n,
                100.0 * v
            );
        }
        println!(
            "{} modes at {} position(s) in {:.1} s; wrote {}",
            cm.modes.len(),
            cm.positions_m.len(),
            t0.elapsed().as_secs_f64(),
            self.out.join("coupled_modes.csv").display()
        );
        Ok(())
    }
}
