//! `corrugation roughness`: a measured rail roughness (a profile or a one-third-octave band
//! spectrum) forecast by the growth-rate spectrum, and a passage over the measured profile
//! ([`corrugation::studies::roughness`]).
//!
//! Outputs in `--out DIR` (default `corrugation-out/roughness`): `roughness.csv`,
//! `roughness.json`, `roughness.svg/.png`, `report.md/.html` and, for a profile, the files of
//! `passage` for the passage over it in `DIR/passage`.

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use corrugation::dynamics::passage::PassageOptions;
use corrugation::roughness::{traffic_passages, BandSpectrum, MeasuredProfile, SpectrumOptions};
use corrugation::studies::roughness::{roughness_forecasts, write_roughness};
use corrugation::studies::speeds::parse_speeds;

use super::ModelArgs;

/// Which wavelengths of a measured rail roughness grow at which speeds, and how fast.
#[derive(Debug, Args)]
pub(crate) struct RoughnessCmd {
    #[command(flatten)]
    model: ModelArgs,
    /// A measured profile: CSV `x_m, height_um` (any sampling; `nan` or an empty height for
    /// a gap).
    #[arg(
        long,
        value_name = "FILE",
        conflicts_with = "spectrum",
        required_unless_present = "spectrum"
    )]
    profile: Option<PathBuf>,
    /// A one-third-octave band spectrum: CSV `wavelength_mm, level_db` (dB re 1 µm).
    #[arg(long, value_name = "FILE")]
    spectrum: Option<PathBuf>,
    /// Speeds (km/h): a list `80,120,160` or `START:STOP:STEP`; default the model's speed.
    #[arg(long, value_name = "KMH")]
    speeds: Option<String>,
    /// Traffic to forecast, in wheel passages over the rail (default: that of --mgt).
    #[arg(long, value_name = "N", conflicts_with = "mgt")]
    passages: Option<f64>,
    /// Traffic to forecast, in million gross tonnes (default 1 MGT; wheel passages = MGT ×
    /// 1e9 kg / (2 × wheel load / g)).
    #[arg(long, value_name = "MGT")]
    mgt: Option<f64>,
    /// Segment length of the profile's band analysis (m), 0.1 to 20.
    #[arg(long, default_value_t = corrugation::roughness::profile::DEFAULT_SEGMENT_LENGTH_M, value_name = "M")]
    segment_m: f64,
    /// Skip the passage over the measured profile.
    #[arg(long)]
    no_passage: bool,
    /// Output directory.
    #[arg(long, default_value = "corrugation-out/roughness", value_name = "DIR")]
    out: PathBuf,
    /// Print the outcome as JSON.
    #[arg(long)]
    json: bool,
    /// Modal cache directory.
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
}

impl RoughnessCmd {
    /// Runs the command.
    pub fn run(self) -> anyhow::Result<()> {
        let m = self.model.load()?;
        let passages = traffic_passages(self.passages, self.mgt, m.vehicle.wheel_load)
            .context("--passages / --mgt")?;
        let speeds = match &self.speeds {
            Some(s) => parse_speeds(s)?,
            None => vec![m.run.speed_kmh],
        };
        let opts = SpectrumOptions {
            segment_length_m: self.segment_m,
            ..SpectrumOptions::default()
        };
        let (source, measured, profile) = match (&self.profile, &self.spectrum) {
            (Some(p), _) => {
                let prof = MeasuredProfile::read_csv(p)?;
                if let Some(w) = prof.unit_slip() {
                    eprintln!("warning: {w}");
                }
                let bands = prof
                    .band_spectrum(&opts)
                    .with_context(|| format!("--profile {}", p.display()))?;
                (format!("the profile {}", p.display()), bands, Some(prof))
            }
            (None, Some(s)) => (
                format!("the band spectrum {}", s.display()),
                BandSpectrum::read_csv(s)?,
                None,
            ),
            (None, None) => anyhow::bail!("give --profile FILE or --spectrum FILE"),
        };
        super::check_out_outside_cache(&self.out, self.cache.as_deref())?;
        super::check_out_dir(&self.out)?;
        let prepared = super::engine::prepared(&m, self.cache.as_deref())?;
        let pb = super::progress::bar("growth-rate spectra");
        let o = roughness_forecasts(&m, &prepared, &source, &measured, &speeds, passages, &pb)?;
        pb.finish_and_clear();
        write_roughness(&self.out, &o)?;
        if let (Some(prof), false) = (&profile, self.no_passage) {
            // the longest continuous part of the record laid on the rail where the wheel's
            // contact passes (its first metres)
            let [a, b] = prepared.engine.rail_under_contact_m(m.run.speed())?;
            let rail = prof
                .longest_part_on_track(a, b - a, &opts)
                .context("the profile has no continuous part to run a passage over")?;
            if let Some(w) =
                corrugation::passage::setup::check_profile_grid(&m, rail.peak_to_trough_m())?
            {
                eprintln!("warning: --profile: {w}");
            }
            let pb = super::progress::bar("passage over the measured profile (time steps)");
            let rec = prepared
                .engine
                .passage(
                    m.run.speed(),
                    Some(&rail),
                    &PassageOptions::default(),
                    Some(&pb),
                )
                .context("running the passage over the measured profile")?;
            pb.finish_and_clear();
            let summary = corrugation::passage::analysis::summarise(&rec)?;
            let dir = self.out.join("passage");
            corrugation::studies::passage::write_passage(
                &dir,
                &rec,
                &summary,
                m.mesh.fine_element_length,
            )?;
            if !self.json {
                println!(
                    "passage over the first {:.2} m of the measured profile's longest continuous part at {} km/h: F_L band RMS {:.1} N, dominant wear wavelength {} → {}",
                    b - a,
                    m.run.speed_kmh,
                    summary.fl_band_rms_n,
                    summary
                        .dominant_wavelength_mm
                        .map_or("none in 20–80 mm".into(), |l| format!("{l:.1} mm")),
                    dir.display()
                );
            }
        }
        if self.json {
            println!("{}", serde_json::to_string_pretty(&o)?);
        } else {
            for l in o.summary_lines() {
                println!("{l}");
            }
            println!("outputs in {}", self.out.display());
        }
        Ok(())
    }
}
