//! `corrugation predict`: the main job. On one model (default: the embedded
//! Dutch track, RPM3):
//! 1. the modal bases of track and wheel (cached: a rerun reuses them);
//! 2. one passage on the smooth rail (forces, wear, PSDs, plots) → `DIR/passage/`;
//! 3. the trial-amplitude growth (consistency, phase, limiting amplitude) → `DIR/grow/`;
//! 4. a short speed sweep (frequency-selection maps) → `DIR/sweep/`;
//! 5. a report `DIR/report.md` and `DIR/report.html` with the tables and the plots, and every
//!    number as CSV/JSON in the subdirectories; `DIR/predict.json` the headline numbers.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use serde::Serialize;

use corrugation::dynamics::passage::PassageOptions;
use corrugation::dynamics::prepared::PreparedModel;
use corrugation::dynamics::summary::PassageSummary;
use corrugation::growth::procedure::{ModeLines, TrialGrowth};
use corrugation::growth::verdict::{
    case_label, class_label, growth_verdict, no_initiation_verdict, sig, trim_zeros, Verdict,
    CONSISTENCY_LEGEND,
};
use corrugation::io::write_atomic;
use corrugation::model::Model;
use corrugation::report::doc::Document;
use corrugation::studies::speeds::parse_speeds;
use corrugation::studies::sweep::SweepOutcome;
use corrugation::studies::sweep::{sweep, MapOptions};

use super::grow_cmd::GrowJson;
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
    /// Modal cache directory (default: $XDG_CACHE_HOME/corrugation or ~/.cache/corrugation).
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
}

/// What the report is written from.
struct ReportInput<'a> {
    m: &'a Model,
    prepared: &'a PreparedModel,
    smooth: &'a PassageSummary,
    growth: Option<(&'a TrialGrowth, &'a GrowJson)>,
    lines: &'a ModeLines,
    sweep: &'a SweepOutcome,
    verdict: &'a Verdict,
    seconds: f64,
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
    verdict: Verdict,
    sweep_speeds_kmh: Vec<f64>,
    sweep_dominant_wavelength_mm: Vec<Option<f64>>,
    wavelength_range_ratio: Option<f64>,
    speed_range_ratio: f64,
    seconds: f64,
}

/// `v` to 4 significant digits (trailing decimal zeros dropped).
fn f(v: f64) -> String {
    trim_zeros(&sig(v, 4))
}

/// `v` to 4 significant digits, "–" when absent.
fn fo(v: Option<f64>) -> String {
    v.map(f).unwrap_or_else(|| "–".into())
}

/// A relative difference as a percentage (3 significant digits), "–" when absent.
fn pct(v: Option<f64>) -> String {
    v.map(|x| format!("{} %", sig(100.0 * x, 3)))
        .unwrap_or_else(|| "–".into())
}

impl PredictCmd {
    pub fn run(self) -> anyhow::Result<()> {
        let t0 = Instant::now();
        let m = self.model.load()?;
        super::check_out_dir(&self.out)?;
        let speeds = parse_speeds(&self.speeds)?;
        std::fs::create_dir_all(&self.out)
            .with_context(|| format!("creating {}", self.out.display()))?;
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
        let lines = engine::mode_lines(&prepared);

        // Smooth passage with all records.
        let opts = PassageOptions::default();
        let pb = super::progress::bar("smooth-rail passage (time steps)");
        let rec = prepared
            .engine
            .passage(m.run.speed(), None, &opts, Some(pb.handle()))?;
        pb.finish_and_clear();
        drop(pb);
        let smooth = corrugation::dynamics::analysis::summarise(&rec)?;
        passage_cmd::write_outputs(
            &self.out.join("passage"),
            &rec,
            &smooth,
            m.mesh.fine_element_length,
        )?;

        // Trial-amplitude growth and the verdict.
        let check = grow_cmd::initiation_check(&m, &smooth);
        let g = grow_cmd::run_trial_growth(&prepared.engine, &m, &self.amplitudes_um, &lines)?;
        let verdict = match &g {
            Some(g) => growth_verdict(g, m.run.speed_kmh, &lines, Some(check)),
            None => no_initiation_verdict(m.run.speed_kmh, Some(check)),
        };
        let gj = match &g {
            Some(g) => Some(write_growth(
                &self.out.join("grow"),
                g,
                &m,
                verdict.clone(),
            )?),
            None => None,
        };

        // Short speed sweep.
        let sw = short_sweep(&m, &prepared, &lines, &speeds, &self.out.join("sweep"))?;

        let input = ReportInput {
            m: &m,
            prepared: &prepared,
            smooth: &smooth,
            growth: g.as_ref().zip(gj.as_ref()),
            lines: &lines,
            sweep: &sw,
            verdict: &verdict,
            seconds: t0.elapsed().as_secs_f64(),
        };
        report(&input).write(&self.out.join("report"))?;

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
            limiting_amplitude_um: g.as_ref().and_then(|g| g.limiting_amplitude_um),
            verdict: verdict.clone(),
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
            grow_cmd::print_verdict(&verdict);
        }
        Ok(())
    }
}

/// Writes the growth files and `grow.json` into `dir`; returns the JSON.
fn write_growth(
    dir: &Path,
    g: &TrialGrowth,
    m: &Model,
    verdict: Verdict,
) -> anyhow::Result<GrowJson> {
    grow_cmd::write_growth_files(dir, g)?;
    let gj = grow_cmd::grow_json(g, m.run.speed_kmh, Vec::new(), verdict, 0.0);
    let text = serde_json::to_string_pretty(&gj)?;
    write_atomic(&dir.join("grow.json"), |w| {
        use std::io::Write;
        w.write_all(text.as_bytes())
    })?;
    Ok(gj)
}

/// The short speed sweep of the prediction into `dir`.
fn short_sweep(
    m: &Model,
    prepared: &PreparedModel,
    lines: &ModeLines,
    speeds: &[f64],
    dir: &Path,
) -> anyhow::Result<SweepOutcome> {
    let run_key = format!(
        "{} {}",
        env!("CARGO_PKG_VERSION"),
        blake3::hash(&serde_json::to_vec(m)?).to_hex()
    );
    let map = MapOptions {
        frequency_lines_hz: lines.longitudinal_hz.clone(),
        wheel_lines_hz: lines.wheel_hz.clone(),
        ..MapOptions::default()
    };
    let pb = super::progress::bar("short speed sweep");
    let sw = sweep(prepared, speeds, dir, &map, &run_key, &pb)?;
    Ok(sw)
}

/// The report document.
fn report(r: &ReportInput<'_>) -> Document {
    let mut d = Document::new("Short-pitch corrugation prediction");
    d.heading(2, "Verdict");
    d.paragraph(r.verdict.text());
    model_section(&mut d, r);
    smooth_section(&mut d, r);
    d.heading(2, "Trial-amplitude growth");
    match r.growth {
        Some((g, gj)) => growth_section(&mut d, g, gj),
        None => {
            d.paragraph("No trial growth: the smooth rail left no wear component in 20–80 mm.");
        }
    }
    sweep_section(&mut d, r.sweep);
    d.paragraph("All numbers: passage/*.csv, grow/*.csv and grow.json, sweep/sweep.json and the .npy maps, predict.json.");
    d
}

/// The model and its track modes by family.
fn model_section(d: &mut Document, r: &ReportInput<'_>) {
    let (m, p) = (r.m, r.prepared);
    let (mt, mw) = p.engine.mode_counts();
    d.heading(2, "Model");
    d.paragraph(format!(
        "Fastening model {}, {} bays of {} m, speed {} km/h, modes below {} Hz ({} track, {} wheel). Generated by corrugation {} in {:.0} s.",
        m.fastening.model(),
        m.track.bays,
        f(m.track.sleeper_spacing),
        f(m.run.speed_kmh),
        f(m.run.fmax),
        mt,
        mw,
        env!("CARGO_PKG_VERSION"),
        r.seconds
    ));
    d.heading(3, "Track modes by family");
    let mut fam: std::collections::BTreeMap<String, (usize, f64)> = Default::default();
    for (fq, c) in p.track_frequencies_hz.iter().zip(&p.track_classes) {
        let e = fam
            .entry(c.family.name().replace('_', " "))
            .or_insert((0, *fq));
        e.0 += 1;
    }
    d.table(
        &["family", "modes", "lowest (Hz)"],
        fam.iter()
            .map(|(k, (n, lo))| vec![k.clone(), n.to_string(), f(*lo)])
            .collect(),
    );
    let list = |v: &[f64]| {
        if v.is_empty() {
            "none below f_max".to_string()
        } else {
            v.iter().map(|&x| f(x)).collect::<Vec<_>>().join(", ")
        }
    };
    d.paragraph(format!(
        "Longitudinal-compression eigenfrequencies (Hz): {}. Wheel modes the contact sees (Hz): {}.",
        list(&r.lines.longitudinal_hz),
        list(&r.lines.wheel_hz)
    ));
}

/// The smooth-rail passage: indicators, components, plots.
fn smooth_section(d: &mut Document, r: &ReportInput<'_>) {
    let s = r.smooth;
    let check = grow_cmd::initiation_check(r.m, s);
    d.heading(2, "Smooth-rail passage");
    d.table(
        &["quantity", "value"],
        vec![
            vec!["mean F_N (N)".into(), f(s.mean_fn_n)],
            vec!["mean F_L (N)".into(), f(s.mean_fl_n)],
            vec!["F_L band RMS 20–80 mm (N)".into(), f(s.fl_band_rms_n)],
            vec!["F_N band RMS 20–80 mm (N)".into(), f(s.fn_band_rms_n)],
            vec!["W_f band RMS (J/m)".into(), f(s.wear_band_rms)],
            vec!["W_f mean (J/m)".into(), f(s.wear_mean)],
            vec![
                format!(
                    "W_f band RMS / mean (initiation threshold {} %, wear.initiation_threshold)",
                    trim_zeros(&sig(100.0 * check.threshold, 3))
                ),
                pct(check.relative_wear),
            ],
            vec![
                "initiates (criterion of docs/theory.md §11.4)".into(),
                (if check.initiates { "yes" } else { "no" }).into(),
            ],
            vec![
                "dominant wavelength (mm)".into(),
                fo(s.dominant_wavelength_mm),
            ],
            vec![
                "dominant frequency (Hz)".into(),
                fo(s.dominant_frequency_hz),
            ],
        ],
    );
    let comp_rows = |name: &str, c: &[corrugation::dynamics::WavelengthComponent]| {
        c.iter()
            .map(|c| {
                vec![
                    name.to_string(),
                    sig(c.wavelength_mm, 3),
                    sig(c.frequency_hz, 4),
                    format!("{:.3e}", c.psd),
                ]
            })
            .collect::<Vec<_>>()
    };
    let mut rows = comp_rows("W_f", &s.wear_components);
    rows.extend(comp_rows("F_L", &s.fl_components));
    rows.extend(comp_rows("F_N", &s.fn_components));
    d.table(
        &[
            "signal",
            "wavelength (mm)",
            "frequency (Hz)",
            "PSD (signal unit² · m)",
        ],
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
}

/// The trial-amplitude growth: phase, consistency (with its legend), eigenfrequencies.
fn growth_section(d: &mut Document, g: &TrialGrowth, gj: &GrowJson) {
    d.paragraph(format!(
        "Reference wavelengths (smooth-rail wear components, mm): {}. Limiting amplitude (2A_max)_l: {}.",
        gj.reference_wavelengths_mm
            .iter()
            .map(|&v| sig(v, 3))
            .collect::<Vec<_>>()
            .join(", "),
        gj.limiting_amplitude_um
            .map(|a| format!("{} µm", f(a)))
            .unwrap_or_else(|| "none: the smallest trial amplitude does not grow consistently".into())
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
                    f(gj.amplitudes_um[i]),
                    gj.phase[i].clone(),
                    format!("{:+.2}", gj.correlation[i]),
                    (if gj.grows_consistently[i] {
                        "yes"
                    } else {
                        "no"
                    })
                    .into(),
                    sig(gj.fl_band_rms_n[i], 3),
                    sig(gj.fn_band_rms_n[i], 3),
                ]
            })
            .collect(),
    );
    d.heading(3, "Components by amplitude and consistency");
    d.paragraph(CONSISTENCY_LEGEND);
    let mut rows = Vec::new();
    for a in &g.amplitudes {
        for r in &a.rows {
            let c = |w: Option<f64>, dev: Option<f64>| {
                format!(
                    "{} ({})",
                    w.map(|x| sig(1000.0 * x, 3)).unwrap_or_else(|| "–".into()),
                    pct(dev)
                )
            };
            rows.push(vec![
                f(a.amplitude_um),
                sig(1000.0 * r.reference_wavelength_m, 3),
                c(r.wf_wavelength_m, r.wf_deviation),
                c(r.fl_wavelength_m, r.fl_deviation),
                c(r.fn_wavelength_m, r.fn_deviation),
                case_label(r.case).into(),
                class_label(r.class).into(),
            ]);
        }
    }
    d.table(
        &[
            "2A_max (µm)",
            "λ_ref (mm)",
            "W_f λ (mm) (rel. deviation)",
            "F_L λ (mm) (rel. deviation)",
            "F_N λ (mm) (rel. deviation)",
            "case",
            "class",
        ],
        rows,
    );
    eigen_section(d, g);
}

/// Components vs the nearest eigenfrequencies of the three mode families.
fn eigen_section(d: &mut Document, g: &TrialGrowth) {
    d.heading(3, "Components vs eigenfrequencies");
    d.paragraph(
        "Each component's frequency against the nearest eigenfrequency of three families: the \
         track's longitudinal-compression (LC) and vertical-bending (VB) modes and the wheel modes \
         the contact sees. The relative difference is |f − f_mode| / f_mode.",
    );
    d.table(
        &[
            "signal",
            "2A_max (µm)",
            "λ (mm)",
            "f (Hz)",
            "nearest LC (Hz)",
            "rel. difference LC",
            "nearest VB (Hz)",
            "rel. difference VB",
            "nearest wheel (Hz)",
            "rel. difference wheel",
        ],
        g.eigen
            .iter()
            .map(|e| {
                vec![
                    e.signal.clone(),
                    f(e.amplitude_um),
                    sig(e.wavelength_mm, 3),
                    sig(e.frequency_hz, 4),
                    fo(e.nearest_longitudinal_hz),
                    pct(e.longitudinal_difference),
                    fo(e.nearest_vertical_hz),
                    pct(e.vertical_difference),
                    fo(e.nearest_wheel_hz),
                    pct(e.wheel_difference),
                ]
            })
            .collect(),
    );
}

/// The short sweep: dominant wavelength per speed and the maps.
fn sweep_section(d: &mut Document, sw: &SweepOutcome) {
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
                    f(sw.record.speeds_kmh[i]),
                    sw.record.dominant_wavelength_mm[i]
                        .map(|v| sig(v, 3))
                        .unwrap_or_else(|| "–".into()),
                    fo(sw.record.dominant_frequency_hz[i]),
                ]
            })
            .collect(),
    );
    d.paragraph(format!(
        "Speed range ratio {}; wavelength range ratio {} (frequency selection shows as a wavelength range ratio much smaller than the speed range ratio).",
        sig(sw.record.speed_range_ratio, 3),
        sw.record
            .wavelength_range_ratio
            .map(|v| sig(v, 3))
            .unwrap_or_else(|| "–".into())
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
}
