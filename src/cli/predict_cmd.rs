//! `corrugation predict`: the main job. On one model (default: the embedded
//! Dutch track, RPM3):
//! 1. the modal bases of track and wheel (cached: a rerun reuses them);
//! 2. one passage on the smooth rail (forces, wear, PSDs, plots) → `DIR/passage/`;
//! 3. the trial-amplitude growth (consistency, phase, limiting amplitude) → `DIR/grow/`;
//! 4. a short speed sweep (frequency-selection maps) → `DIR/sweep/`;
//! 5. a report `DIR/report.md` and `DIR/report.html` with the tables and the plots, and every
//!    number as CSV/JSON in the subdirectories; `DIR/predict.json` the headline numbers.

use std::path::PathBuf;

use clap::Args;

use corrugation::growth::verdict::{sig, trim_zeros};
use corrugation::studies::predict::{predict, PredictOptions};
use corrugation::studies::speeds::parse_speeds;

use super::{engine, grow_cmd, ModelArgs};

/// The full prediction: modes, smooth passage, trial growth, short speed sweep, report.
#[derive(Debug, Args)]
pub(crate) struct PredictCmd {
    #[command(flatten)]
    model: ModelArgs,
    /// Trial amplitudes 2A_max (peak-to-trough, µm), comma separated.
    #[arg(
        allow_hyphen_values = true,
        long,
        value_delimiter = ',',
        default_values_t = corrugation::studies::grow::DEFAULT_AMPLITUDES_UM,
        value_name = "UM,..."
    )]
    amplitudes_um: Vec<f64>,
    /// Speeds of the short sweep (km/h): start:stop:step or a list.
    #[arg(
        allow_hyphen_values = true,
        long,
        default_value = corrugation::studies::predict::DEFAULT_PREDICT_SPEEDS,
        value_name = "SPEEDS"
    )]
    speeds: String,
    /// Not an option of `predict` (hidden): caught so that the error says how to set the
    /// prediction's speed, where clap would suggest `--speeds` (the short sweep's).
    #[arg(long, hide = true, allow_hyphen_values = true, value_name = "KMH")]
    speed: Option<String>,
    /// Output directory.
    #[arg(long, default_value = "corrugation-out/predict", value_name = "DIR")]
    out: PathBuf,
    /// Print the headline numbers as JSON.
    #[arg(long)]
    json: bool,
    /// Modal cache directory (default: $XDG_CACHE_HOME/corrugation or ~/.cache/corrugation).
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
}

/// `v` to 4 significant digits (trailing decimal zeros dropped).
fn f(v: f64) -> String {
    trim_zeros(&sig(v, 4))
}

/// `v` to 4 significant digits, "–" when absent.
fn fo(v: Option<f64>) -> String {
    v.map(f).unwrap_or_else(|| "–".into())
}

impl PredictCmd {
    pub fn run(self) -> anyhow::Result<()> {
        if let Some(v) = &self.speed {
            anyhow::bail!(
                "--speed: predict runs at the model's speed (run.speed_kmh, km/h): give \
                 --set run.speed_kmh={v}; --speeds only sets the speeds of the short sweep"
            );
        }
        corrugation::studies::grow::check_amplitudes("--amplitudes-um", &self.amplitudes_um)?;
        let m = self.model.load()?;
        super::check_trial_profile_grid(&self.amplitudes_um, &m)?;
        super::check_out_outside_cache(&self.out, self.cache.as_deref())?;
        super::check_out_dir(&self.out)?;
        let speeds = parse_speeds(&self.speeds)?;
        let prepared = engine::prepared(&m, self.cache.as_deref())?;
        let (mt, mw) = prepared.engine.mode_counts();
        eprintln!(
            "predict: {mt} track and {mw} wheel modes below {} Hz ({}; {:.1} s)",
            m.run.fmax,
            if prepared.cached {
                "from the cache"
            } else {
                "computed and cached"
            },
            prepared.modal_seconds
        );
        let opts = PredictOptions {
            amplitudes_um: self.amplitudes_um,
            sweep_speeds_kmh: speeds,
        };
        let pb = super::progress::bar("prediction");
        let p = predict(&m, &prepared, &opts, &self.out, &pb)?;
        pb.finish_and_clear();
        drop(pb);
        let j = &p.json;
        if self.json {
            println!("{}", serde_json::to_string_pretty(j)?);
        } else {
            println!(
                "predict: dominant wear wavelength {} mm ({} Hz) at {} km/h; sweep: wavelength range ratio {} over speed range ratio {}",
                j.dominant_wavelength_mm
                    .map(|v| sig(v, 3))
                    .unwrap_or_else(|| "–".into()),
                fo(j.dominant_frequency_hz),
                f(j.speed_kmh),
                fo(j.wavelength_range_ratio),
                f(j.speed_range_ratio)
            );
            println!("report: {}", self.out.join("report.html").display());
            grow_cmd::print_verdict(&p.verdict);
        }
        Ok(())
    }
}
