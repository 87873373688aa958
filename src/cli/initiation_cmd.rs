//! `corrugation initiation`: RPM1–RPM5 (or any list of models) on the smooth rail — band RMS
//! and PSD peaks of F_L, F_N and the differential wear, and whether each initiates
//! corrugation ([`corrugation::studies::initiation`] states the criterion).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;

use corrugation::model::{load_model, ModelSource};
use corrugation::studies::initiation::{
    check_peaks, check_speed_kmh, run_initiation, write_initiation, InitiationCriterion,
};

use super::{engine, ModelArgs};

/// Initiation table of several fastening models (or model files) on the smooth rail.
#[derive(Debug, Args)]
pub(crate) struct InitiationCmd {
    #[command(flatten)]
    model: ModelArgs,
    /// Fastening models compared, each applied to the model as --set fastening.model=NAME.
    #[arg(
        long,
        value_delimiter = ',',
        default_values = corrugation::model::PRESET_NAMES,
        value_name = "NAMES"
    )]
    variants: Vec<String>,
    /// Compare these model files instead of --variants (named by file stem; --set applies to
    /// each).
    #[arg(long = "models", num_args = 1.., value_name = "FILE")]
    models: Vec<PathBuf>,
    /// Speed (km/h); default: the model's run.speed_kmh.
    #[arg(allow_hyphen_values = true, long, value_name = "KMH")]
    speed: Option<f64>,
    /// Initiation threshold on the wear's band RMS relative to its mean (−, 0 to 1); default:
    /// each model's `wear.initiation_threshold` (0.01 in the shipped models).
    #[arg(allow_hyphen_values = true, long, value_name = "RATIO")]
    min_relative_wear: Option<f64>,
    /// Largest relative deviation of F_L's dominant wavelength from the wear's (−).
    #[arg(allow_hyphen_values = true, long, default_value_t = InitiationCriterion::DEFAULT_MAX_WAVELENGTH_DEVIATION, value_name = "RATIO")]
    max_wavelength_deviation: f64,
    /// PSD peaks per signal in the table.
    #[arg(
        allow_hyphen_values = true,
        long,
        default_value_t = corrugation::studies::initiation::DEFAULT_PEAKS,
        value_name = "N"
    )]
    peaks: usize,
    /// Output directory.
    #[arg(long, default_value = "corrugation-out/initiation", value_name = "DIR")]
    out: PathBuf,
    /// Print the table as JSON on stdout.
    #[arg(long)]
    json: bool,
    /// Modal cache directory (default: $XDG_CACHE_HOME/corrugation or ~/.cache/corrugation).
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
    /// Passage engine: `reduced` (modal, default) or `explicit` (the full explicit FE
    /// path, minutes per passage).
    #[arg(long, value_enum, default_value = "reduced")]
    engine: super::engine::Engine,
}

/// One model's line: its relative wear against its threshold and the outcome.
fn initiation_line(r: &corrugation::studies::initiation::InitiationRow) -> String {
    use corrugation::growth::verdict::sig;
    let pc = |v: Option<f64>| v.map_or("–".into(), |v| format!("{} %", sig(100.0 * v, 3)));
    format!(
        "{:>8}: F_L band RMS {} N, wear band RMS / mean {} (threshold {}), initiates: {} ({})",
        r.name,
        sig(r.fl_band_rms_n, 3),
        pc(r.relative_wear),
        pc(r.threshold),
        if r.initiates { "yes" } else { "no" },
        r.reason
    )
}

impl InitiationCmd {
    /// Runs the command.
    pub fn run(self) -> anyhow::Result<()> {
        let t0 = Instant::now();
        super::check_out_outside_cache(&self.out, self.cache.as_deref())?;
        super::check_out_dir(&self.out)?;
        // The criterion as the flags set it (each model's own threshold is checked with it).
        InitiationCriterion {
            min_relative_wear: self
                .min_relative_wear
                .unwrap_or(InitiationCriterion::DEFAULT_MIN_RELATIVE_WEAR),
            max_wavelength_deviation: self.max_wavelength_deviation,
        }
        .check()?;
        check_peaks(self.peaks)?;
        let variants: Vec<&str> = self.variants.iter().map(|v| v.trim()).collect();
        corrugation::lists::check_no_repeats("--variants", "", &variants)?;
        let models: Vec<String> = self
            .models
            .iter()
            .map(|f| f.display().to_string())
            .collect();
        corrugation::lists::check_no_repeats("--models", "", &models)?;
        // Each model's own threshold unless the flag overrides it.
        let criterion_of = |m: &corrugation::model::Model| InitiationCriterion {
            min_relative_wear: self
                .min_relative_wear
                .unwrap_or(m.wear.initiation_threshold),
            max_wavelength_deviation: self.max_wavelength_deviation,
        };
        if !self.models.is_empty() && self.model.model.is_some() {
            anyhow::bail!(
                "--model and --models: give either one model file (its fastening variants are compared) or the files to compare"
            );
        }
        // All models first, so a bad name or key stops before any passage.
        let mut cases = Vec::new();
        if self.models.is_empty() {
            for v in &self.variants {
                let mut set = self.model.set.clone();
                set.push(format!("fastening.model=\"{}\"", v.trim()));
                let m = load_model(&self.model.source(), &set)
                    .with_context(|| format!("the model of --variants {}", v.trim()))?;
                super::warn_unit_slips(&format!("--variants {}", v.trim()), &m);
                cases.push((v.trim().to_string(), m));
            }
        } else {
            for f in &self.models {
                let name = f
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_else(|| f.display().to_string());
                let m = load_model(&ModelSource::File(f.clone()), &self.model.set)?;
                super::warn_unit_slips(&f.display().to_string(), &m);
                cases.push((name, m));
            }
        }
        let mut rows = Vec::new();
        for (name, model) in &cases {
            let speed = self.speed.unwrap_or(model.run.speed_kmh);
            check_speed_kmh(speed)?;
            // One engine at a time: each holds its modal basis.
            let runner = engine::runner_for_engine(model, self.cache.as_deref(), self.engine)?;
            rows.extend(run_initiation(
                &[(name.clone(), runner.as_ref())],
                speed,
                &criterion_of(model),
                self.peaks,
                &super::progress::bar(&format!("initiation: {name}")),
            )?);
        }
        let Some((_, first)) = cases.first() else {
            anyhow::bail!("no models to compare: give --variants or --models");
        };
        let criterion = criterion_of(first);
        write_initiation(&self.out, &rows, &criterion, self.peaks)?;
        for r in &rows {
            eprintln!("{}", initiation_line(r));
        }
        if self.json {
            let j = serde_json::json!({
                "criterion": criterion,
                "rows": rows,
                "seconds": t0.elapsed().as_secs_f64(),
            });
            println!("{}", serde_json::to_string_pretty(&j)?);
        }
        Ok(())
    }
}
