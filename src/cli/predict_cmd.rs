//! `corrugation predict`: the main job. On one model (default: the embedded
//! Dutch track, RPM3):
//! 1. the modal bases of track and wheel (cached: a rerun reuses them);
//! 2. one passage on the smooth rail (forces, wear, PSDs, plots) → `DIR/passage/`;
//! 3. the trial-amplitude growth (consistency, phase, limiting amplitude) → `DIR/grow/`;
//! 4. a short speed sweep (frequency-selection maps) → `DIR/sweep/`;
//! 5. a report `DIR/report.md` and `DIR/report.html` with the tables and the plots, and every
//!    number as CSV/JSON in the subdirectories; `DIR/predict.json` the headline numbers.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use serde::Serialize;

use corrugation::dynamics::passage::PassageOptions;
use corrugation::eigen::basis::progress_bar;
use corrugation::eigen::classify::TrackFamily;
use corrugation::growth::procedure::{trial_growth, ModeLines};
use corrugation::io::write_atomic;
use corrugation::report::doc::Document;
use corrugation::studies::speeds::parse_speeds;
use corrugation::studies::sweep::{sweep, MapOptions};

use super::{engine, grow_cmd, passage_cmd, ModelArgs};

/// The full prediction: modes, smooth passage, trial growth, short speed sweep, report.
#[derive(Debug, Args)]
pub struct PredictCmd {
    #[command(flatten)]
    model: ModelArgs,
    /// Trial amplitudes 2A_max (peak-to-trough, µm), comma separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "10,40,80,160",
        value_name = "UM,..."
    )]
    amplitudes_um: Vec<f64>,
    /// Speeds of the short sweep (km/h): start:stop:step or a list.
    #[arg(long, default_value = "60:220:40", value_name = "SPEEDS")]
    speeds: String,
    /// Output directory.
    #[arg(long, default_value = "corrugation-out/predict", value_name = "DIR")]
    out: PathBuf,
    /// Print the headline numbers as JSON.
    #[arg(long)]
    json: bool,
    /// Modal cache directory.
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
}

/// Headline numbers of a prediction.
#[derive(Serialize)]
struct PredictJson {
    speed_kmh: f64,
    track_modes: usize,
    wheel_modes: usize,
    modes_cached: bool,
    modal_seconds: f64,
    longitudinal_compression_hz: Vec<f64>,
    dominant_wavelength_mm: Option<f64>,
    dominant_frequency_hz: Option<f64>,
    wear_components: Vec<corrugation::dynamics::WavelengthComponent>,
    fl_components: Vec<corrugation::dynamics::WavelengthComponent>,
    limiting_amplitude_um: Option<f64>,
    sweep_speeds_kmh: Vec<f64>,
    sweep_dominant_wavelength_mm: Vec<Option<f64>>,
    wavelength_range_ratio: Option<f64>,
    speed_range_ratio: f64,
    seconds: f64,
}

fn f(v: f64) -> String {
    format!("{v:.4}")
}

fn fo(v: Option<f64>) -> String {
    v.map(|x| format!("{x:.4}")).unwrap_or_else(|| "–".into())
}

impl PredictCmd {
    pub fn run(self) -> anyhow::Result<()> {
        let t0 = Instant::now();
        let m = self.model.load()?;
        super::check_out_dir(&self.out)?;
        let speeds = parse_speeds(&self.speeds)?;
        std::fs::create_dir_all(&self.out)
            .with_context(|| format!("creating {}", self.out.display()))?;
        eprintln!(
            "predict: modal bases below {} Hz (cached in {})",
            m.run.fmax,
            self.cache
                .clone()
                .unwrap_or_else(corrugation::eigen::cache::default_cache_dir)
                .display()
        );
        let prepared = engine::prepared(&m, self.cache.as_deref())?;
        let (mt, mw) = prepared.engine.mode_counts();
        eprintln!(
            "predict: {mt} track and {mw} wheel modes ({}; {:.1} s)",
            if prepared.cached {
                "from the cache"
            } else {
                "computed and cached"
            },
            prepared.modal_seconds
        );
        let lines = ModeLines {
            longitudinal_hz: prepared.longitudinal_compression_hz(),
            vertical_hz: prepared.vertical_bending_hz(),
        };

        // Smooth passage with all records.
        let opts = PassageOptions::default();
        let pb = progress_bar("smooth-rail passage");
        let rec = prepared
            .engine
            .passage(m.run.speed(), None, &opts, Some(&pb))?;
        pb.finish_and_clear();
        let smooth = corrugation::dynamics::analysis::summarise(&rec)?;
        let pdir = self.out.join("passage");
        passage_cmd::write_outputs(&pdir, &rec, &smooth)?;

        // Trial-amplitude growth.
        let pb = progress_bar("trial-amplitude growth (passages)");
        pb.set_length(1 + self.amplitudes_um.len() as u64);
        let g = trial_growth(
            &prepared.engine,
            m.run.speed(),
            &self.amplitudes_um,
            &lines,
            |k| pb.set_position(k as u64 + 1),
        )?;
        pb.finish_and_clear();
        let gdir = self.out.join("grow");
        grow_cmd::write_growth_files(&gdir, &g)?;
        let gj = grow_cmd::grow_json(&g, m.run.speed_kmh, Vec::new(), 0.0);
        let text = serde_json::to_string_pretty(&gj)?;
        write_atomic(&gdir.join("grow.json"), |w| {
            use std::io::Write;
            w.write_all(text.as_bytes())
        })?;

        // Short speed sweep.
        let sdir = self.out.join("sweep");
        let run_key = format!(
            "{} {}",
            env!("CARGO_PKG_VERSION"),
            blake3::hash(&serde_json::to_vec(&m)?).to_hex()
        );
        let map = MapOptions {
            frequency_lines_hz: lines.longitudinal_hz.clone(),
            wheel_lines_hz: prepared.wheel_contact_modes_hz(super::sweep_cmd::WHEEL_LINE_SHARE),
            ..MapOptions::default()
        };
        let sw = sweep(&prepared, &speeds, &sdir, &map, &run_key, true)?;

        // Report.
        let mut d = Document::new("Short-pitch corrugation prediction");
        d.paragraph(format!(
            "Model: fastening `{:?}`, {} bays of {} m, speed {} km/h, modes below {} Hz ({} track, {} wheel). Generated by corrugation {} in {:.0} s.",
            m.fastening.model,
            m.track.bays,
            m.track.sleeper_spacing,
            m.run.speed_kmh,
            m.run.fmax,
            mt,
            mw,
            env!("CARGO_PKG_VERSION"),
            t0.elapsed().as_secs_f64()
        ));
        d.heading(2, "Track modes by family");
        let mut fam: std::collections::BTreeMap<String, (usize, f64)> = Default::default();
        for (fq, c) in prepared
            .track_frequencies_hz
            .iter()
            .zip(&prepared.track_classes)
        {
            let e = fam.entry(c.family.name().to_string()).or_insert((0, *fq));
            e.0 += 1;
        }
        d.table(
            &["family", "modes", "lowest (Hz)"],
            fam.iter()
                .map(|(k, (n, lo))| vec![k.clone(), n.to_string(), format!("{lo:.1}")])
                .collect(),
        );
        let lc: Vec<String> = prepared
            .track_frequencies_hz
            .iter()
            .zip(&prepared.track_classes)
            .filter(|(_, c)| c.family == TrackFamily::LongitudinalCompression)
            .map(|(f, _)| format!("{f:.0}"))
            .collect();
        d.paragraph(format!(
            "Longitudinal-compression eigenfrequencies (Hz): {}.",
            if lc.is_empty() {
                "none below f_max".to_string()
            } else {
                lc.join(", ")
            }
        ));
        d.heading(2, "Smooth-rail passage");
        d.table(
            &["quantity", "value"],
            vec![
                vec!["mean F_N (N)".into(), f(smooth.mean_fn_n)],
                vec!["mean F_L (N)".into(), f(smooth.mean_fl_n)],
                vec!["F_L band RMS 20–80 mm (N)".into(), f(smooth.fl_band_rms_n)],
                vec!["F_N band RMS 20–80 mm (N)".into(), f(smooth.fn_band_rms_n)],
                vec![
                    "W_f band RMS (J/m)".into(),
                    format!("{:.4e}", smooth.wear_band_rms),
                ],
                vec!["W_f mean (J/m)".into(), format!("{:.4e}", smooth.wear_mean)],
                vec![
                    "dominant wavelength (mm)".into(),
                    fo(smooth.dominant_wavelength_mm),
                ],
                vec![
                    "dominant frequency (Hz)".into(),
                    fo(smooth.dominant_frequency_hz),
                ],
            ],
        );
        let comp_rows = |name: &str, c: &[corrugation::dynamics::WavelengthComponent]| {
            c.iter()
                .map(|c| {
                    vec![
                        name.to_string(),
                        format!("{:.2}", c.wavelength_mm),
                        format!("{:.0}", c.frequency_hz),
                        format!("{:.3e}", c.psd),
                    ]
                })
                .collect::<Vec<_>>()
        };
        let mut rows = comp_rows("W_f", &smooth.wear_components);
        rows.extend(comp_rows("F_L", &smooth.fl_components));
        rows.extend(comp_rows("F_N", &smooth.fn_components));
        d.table(
            &["signal", "wavelength (mm)", "frequency (Hz)", "PSD"],
            rows,
        );
        for (alt, p) in [
            ("band-passed signals", "passage/band_x.png"),
            ("wear PSD", "passage/psd_wear.png"),
            ("F_L PSD", "passage/psd_fl.png"),
            ("F_N PSD", "passage/psd_fn.png"),
        ] {
            d.image(alt, p);
        }
        d.heading(2, "Trial-amplitude growth");
        d.paragraph(format!(
            "Reference wavelengths (smooth-rail wear components, mm): {}. Limiting amplitude (2A_max)_l: {}.",
            gj.reference_wavelengths_mm
                .iter()
                .map(|v| format!("{v:.2}"))
                .collect::<Vec<_>>()
                .join(", "),
            gj.limiting_amplitude_um
                .map(|a| format!("{a} µm"))
                .unwrap_or_else(|| "no trial amplitude grows consistently".into())
        ));
        d.table(
            &[
                "2A_max (µm)",
                "phase",
                "r",
                "consistent growth",
                "F_L band RMS (N)",
                "F_N band RMS (N)",
            ],
            (0..gj.amplitudes_um.len())
                .map(|i| {
                    vec![
                        format!("{}", gj.amplitudes_um[i]),
                        gj.phase[i].clone(),
                        format!("{:+.2}", gj.correlation[i]),
                        gj.grows_consistently[i].to_string(),
                        format!("{:.1}", gj.fl_band_rms_n[i]),
                        format!("{:.1}", gj.fn_band_rms_n[i]),
                    ]
                })
                .collect(),
        );
        d.heading(3, "Components by amplitude and consistency");
        let mut rows = Vec::new();
        for a in &g.amplitudes {
            for r in &a.rows {
                let mm = |v: Option<f64>| {
                    v.map(|x| format!("{:.2}", 1000.0 * x))
                        .unwrap_or_else(|| "–".into())
                };
                let pc = |v: Option<f64>| {
                    v.map(|x| format!("{:.1} %", 100.0 * x))
                        .unwrap_or_else(|| "–".into())
                };
                rows.push(vec![
                    format!("{}", a.amplitude_um),
                    format!("{:.2}", 1000.0 * r.reference_wavelength_m),
                    format!("{} ({})", mm(r.wf_wavelength_m), pc(r.wf_deviation)),
                    format!("{} ({})", mm(r.fl_wavelength_m), pc(r.fl_deviation)),
                    format!("{} ({})", mm(r.fn_wavelength_m), pc(r.fn_deviation)),
                    format!("{:?}", r.case),
                    format!("{:?}", r.class),
                ]);
            }
        }
        d.table(
            &[
                "2A_max (µm)",
                "λ_ref (mm)",
                "W_f (mm, dev.)",
                "F_L (mm, dev.)",
                "F_N (mm, dev.)",
                "case",
                "class",
            ],
            rows,
        );
        d.heading(3, "Components vs eigenfrequencies");
        d.table(
            &[
                "signal",
                "2A_max (µm)",
                "λ (mm)",
                "f (Hz)",
                "nearest long. compression (Hz)",
                "difference",
                "nearest vertical bending (Hz)",
                "difference",
            ],
            g.eigen
                .iter()
                .map(|e| {
                    vec![
                        e.signal.clone(),
                        format!("{}", e.amplitude_um),
                        format!("{:.2}", e.wavelength_mm),
                        format!("{:.0}", e.frequency_hz),
                        fo(e.nearest_longitudinal_hz),
                        fo(e.longitudinal_difference),
                        fo(e.nearest_vertical_hz),
                        fo(e.vertical_difference),
                    ]
                })
                .collect(),
        );
        d.heading(2, "Speed sweep (frequency selection)");
        d.table(
            &[
                "speed (km/h)",
                "dominant wavelength (mm)",
                "dominant frequency (Hz)",
            ],
            (0..sw.record.speeds_kmh.len())
                .map(|i| {
                    vec![
                        format!("{:.1}", sw.record.speeds_kmh[i]),
                        fo(sw.record.dominant_wavelength_mm[i]),
                        fo(sw.record.dominant_frequency_hz[i]),
                    ]
                })
                .collect(),
        );
        d.paragraph(format!(
            "Speed range ratio {:.3}; wavelength range ratio {}.",
            sw.record.speed_range_ratio,
            fo(sw.record.wavelength_range_ratio)
        ));
        for (alt, p) in [
            (
                "wear map (speed × wavelength)",
                "sweep/map_wear_wavelength.png",
            ),
            (
                "wear map (speed × frequency)",
                "sweep/map_wear_frequency.png",
            ),
            ("dominant wavelength", "sweep/dominant_wavelength.png"),
        ] {
            d.image(alt, p);
        }
        d.paragraph("All numbers: passage/*.csv, grow/*.csv and grow.json, sweep/sweep.json and the .npy maps, predict.json.");
        d.write(&self.out.join("report"))?;

        let j = PredictJson {
            speed_kmh: m.run.speed_kmh,
            track_modes: mt,
            wheel_modes: mw,
            modes_cached: prepared.cached,
            modal_seconds: prepared.modal_seconds,
            longitudinal_compression_hz: lines.longitudinal_hz.clone(),
            dominant_wavelength_mm: smooth.dominant_wavelength_mm,
            dominant_frequency_hz: smooth.dominant_frequency_hz,
            wear_components: smooth.wear_components.clone(),
            fl_components: smooth.fl_components.clone(),
            limiting_amplitude_um: g.limiting_amplitude_um,
            sweep_speeds_kmh: sw.record.speeds_kmh.clone(),
            sweep_dominant_wavelength_mm: sw.record.dominant_wavelength_mm.clone(),
            wavelength_range_ratio: sw.record.wavelength_range_ratio,
            speed_range_ratio: sw.record.speed_range_ratio,
            seconds: t0.elapsed().as_secs_f64(),
        };
        let text = serde_json::to_string_pretty(&j)?;
        write_atomic(&self.out.join("predict.json"), |w| {
            use std::io::Write;
            w.write_all(text.as_bytes())
        })?;
        if self.json {
            println!("{text}");
        } else {
            println!(
                "predict: dominant wavelength {} mm ({} Hz) at {} km/h; limiting amplitude {}; sweep wavelength range ratio {} over speed range ratio {:.2}",
                fo(j.dominant_wavelength_mm),
                fo(j.dominant_frequency_hz),
                j.speed_kmh,
                j.limiting_amplitude_um.map(|a| format!("{a} µm")).unwrap_or_else(|| "none".into()),
                fo(j.wavelength_range_ratio),
                j.speed_range_ratio
            );
            println!("report: {}", self.out.join("report.html").display());
        }
        Ok(())
    }
}
