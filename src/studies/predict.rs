//! The prediction product (`corrugation predict`): on one prepared model
//! 1. one passage on the smooth rail (forces, wear, PSDs, plots) → `DIR/passage/`
//!    ([`super::passage::write_passage`], the `passage` command's files);
//! 2. the trial-amplitude growth (consistency, phase, limiting amplitude) → `DIR/grow/`;
//! 3. a short speed sweep (frequency-selection maps) → `DIR/sweep/`;
//! 4. a report `DIR/report.md` and `DIR/report.html` with the tables and the plots;
//!    `DIR/predict.json` ([`PredictJson`]) the headline numbers, written last.
//!
//! Progress is reported to a [`Progress`]; nothing is printed.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use super::coupled::{attribute_one, write_passage_attribution, SummaryAttribution};
use super::grow::{
    grow_json, growth_attribution, initiation_check, trial_growth_if_any, write_growth_files,
    GrowJson, RateSummary,
};
use super::sweep::{sweep, MapOptions, SweepOutcome};
use super::StudiesError;
use crate::dynamics::coupled::{attribution_text, CoupledMode, CoupledModes, ModeAttribution};
use crate::dynamics::passage::PassageOptions;
use crate::dynamics::prepared::PreparedModel;
use crate::dynamics::{DynamicsError, WavelengthComponent};
use crate::growth::procedure::{ModeLines, ProcedureError, TrialGrowth};
use crate::growth::verdict::{
    case_label, class_colour, class_label, growth_verdict, no_initiation_verdict, sig, trim_zeros,
    Verdict, CONSISTENCY_LEGEND,
};
use crate::model::Model;
use crate::passage::summary::PassageSummary;
use crate::progress::Progress;
use crate::report::doc::Document;

/// Errors of a prediction; each names the stage that failed.
#[derive(Debug, thiserror::Error)]
pub enum PredictError {
    /// The smooth-rail passage or its analysis failed.
    #[error("smooth-rail passage: {0}")]
    Passage(#[from] DynamicsError),
    /// The smooth-rail record's analysis failed.
    #[error("smooth-rail passage: {0}")]
    Analysis(#[from] crate::passage::PassageError),
    /// The trial-amplitude growth failed.
    #[error("trial-amplitude growth: {0}")]
    Growth(#[from] ProcedureError),
    /// The sweep, or writing a growth file, failed.
    #[error(transparent)]
    Studies(#[from] StudiesError),
    /// The report could not be written.
    #[error("report: {0}")]
    Report(#[from] crate::report::ReportError),
    /// An output directory could not be created.
    #[error("{}: {source}", path.display())]
    Io {
        /// The directory or file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
}

/// The speeds of the prediction's short sweep when none are given (km/h): 60 to 220 km/h in
/// steps of 40 km/h (five speeds, the range of a full sweep at a tenth of its cost).
pub const DEFAULT_PREDICT_SPEEDS: &str = "60:220:40";

/// What a prediction runs.
#[derive(Clone, Debug, PartialEq)]
pub struct PredictOptions {
    /// Trial amplitudes 2A_max (peak-to-trough, µm); default
    /// [`DEFAULT_AMPLITUDES_UM`](super::grow::DEFAULT_AMPLITUDES_UM).
    pub amplitudes_um: Vec<f64>,
    /// Speeds of the short sweep, km/h (as the user gave them; labels and file names).
    pub sweep_speeds_kmh: Vec<f64>,
}

/// Everything a prediction produced (also written into its directory).
pub struct Prediction {
    /// The smooth-rail passage summary.
    pub smooth: PassageSummary,
    /// The trial-amplitude growth; `None` when the smooth rail left nothing to grow.
    pub growth: Option<TrialGrowth>,
    /// The mode lines the components were compared with.
    pub lines: ModeLines,
    /// The short sweep.
    pub sweep: SweepOutcome,
    /// The verdict.
    pub verdict: Verdict,
    /// The headline numbers (`predict.json`).
    pub json: PredictJson,
}

/// What the report is written from.
struct ReportInput<'a> {
    m: &'a Model,
    prepared: &'a PreparedModel,
    smooth: &'a PassageSummary,
    growth: Option<(&'a TrialGrowth, &'a GrowJson)>,
    lines: &'a ModeLines,
    rate: &'a crate::growth::rate::GrowthRateSpectrum,
    rate_brief: Option<&'a RateSummary>,
    attribution: &'a SummaryAttribution,
    sweep: &'a SweepOutcome,
    verdict: &'a Verdict,
    seconds: f64,
}

/// Headline numbers of a prediction (`predict.json`).
#[derive(Clone, Debug, Serialize)]
pub struct PredictJson {
    /// Passage speed, km/h.
    pub speed_kmh: f64,
    /// Track modes in the basis.
    pub track_modes: usize,
    /// Wheel modes in the basis.
    pub wheel_modes: usize,
    /// Whether the modal bases came from the cache.
    pub modes_cached: bool,
    /// Time to load or compute the modal bases, s.
    pub modal_seconds: f64,
    /// Longitudinal-compression eigenfrequencies of the track, Hz.
    pub longitudinal_compression_hz: Vec<f64>,
    /// Dominant wear wavelength of the smooth passage, mm.
    pub dominant_wavelength_mm: Option<f64>,
    /// Dominant wear frequency of the smooth passage, Hz.
    pub dominant_frequency_hz: Option<f64>,
    /// Wear components of the smooth passage.
    pub wear_components: Vec<WavelengthComponent>,
    /// F_L components of the smooth passage.
    pub fl_components: Vec<WavelengthComponent>,
    /// Limiting amplitude (2A_max)_l, µm.
    pub limiting_amplitude_um: Option<f64>,
    /// The verdict.
    pub verdict: Verdict,
    /// Which wavelengths a small roughness grows at (the growth-rate spectrum, one sentence;
    /// numbers in `grow/growth_rate.csv`).
    pub growth_rate: String,
    /// The growth-rate spectrum in brief (fastest wavelength and its coupled mode).
    pub growth_rate_summary: Option<RateSummary>,
    /// The smooth passage's wear components attributed to coupled wheel–track modes
    /// (all signals in `passage/coupled_attribution.json`).
    pub wear_coupled: Vec<ModeAttribution>,
    /// Speeds of the short sweep, km/h.
    pub sweep_speeds_kmh: Vec<f64>,
    /// Dominant wavelength per sweep speed, mm.
    pub sweep_dominant_wavelength_mm: Vec<Option<f64>>,
    /// Wavelength range ratio of the sweep.
    pub wavelength_range_ratio: Option<f64>,
    /// Speed range ratio of the sweep.
    pub speed_range_ratio: f64,
    /// Wall-clock time of the prediction, s.
    pub seconds: f64,
}

/// Runs the prediction on `prepared` (the modal model of `m`) into `out` (created): the smooth
/// passage (its files into `out/passage`), the growth into
/// `out/grow`, the short sweep into `out/sweep`, the report and `out/predict.json` (last).
pub fn predict(
    m: &Model,
    prepared: &PreparedModel,
    opts: &PredictOptions,
    out: &Path,
    progress: &dyn Progress,
) -> Result<Prediction, PredictError> {
    let t0 = Instant::now();
    std::fs::create_dir_all(out).map_err(|source| PredictError::Io {
        path: out.to_path_buf(),
        source,
    })?;
    let dirs = StageDirs::in_dir(out);
    let lines = super::grow::mode_lines(prepared);
    let smooth = smooth_passage(m, prepared, &dirs.passage, progress)?;
    progress.stage("coupled wheel–track modes", 1);
    let coupled = prepared.coupled_modes(m.run.speed(), &[]);
    progress.finish();
    let coupled = coupled.map_err(StudiesError::from)?;
    let attribution = write_passage_attribution(&dirs.passage, &coupled, &smooth)?;
    let check = initiation_check(m, &smooth);
    let growth = trial_growth_if_any(
        &prepared.engine,
        m.run.speed(),
        &opts.amplitudes_um,
        &lines,
        progress,
    )?;
    let verdict = match &growth {
        Some(g) => growth_verdict(
            g,
            m.run.speed_kmh,
            &lines,
            Some(check),
            attribute_one(&coupled.modes, g.smooth.dominant_frequency_hz).as_ref(),
        ),
        None => no_initiation_verdict(m.run.speed_kmh, Some(check)),
    };
    let rate = super::grow::growth_rate(m, prepared, m.run.requested_speed(), progress)?;
    super::grow::write_growth_rate(&dirs.grow, &rate)?;
    let rate_brief = super::grow::rate_summary(&rate, &coupled.modes);
    let gj = match &growth {
        Some(g) => Some(write_growth(
            &dirs.grow,
            g,
            m,
            verdict.clone(),
            &coupled.modes,
            rate_brief.clone(),
        )?),
        None => None,
    };
    let sw = short_sweep(
        m,
        prepared,
        &lines,
        &coupled,
        &opts.sweep_speeds_kmh,
        &dirs.sweep,
        progress,
    )?;
    let input = ReportInput {
        m,
        prepared,
        smooth: &smooth,
        growth: growth.as_ref().zip(gj.as_ref()),
        lines: &lines,
        rate: &rate,
        rate_brief: rate_brief.as_ref(),
        attribution: &attribution,
        sweep: &sw,
        verdict: &verdict,
        seconds: t0.elapsed().as_secs_f64(),
    };
    report(&input).write(&dirs.report)?;
    let json = predict_json(&input, t0.elapsed().as_secs_f64());
    let text = pretty_json("predict.json", &json)?;
    let p = out.join("predict.json");
    crate::io::write_text(&p, &text).map_err(StudiesError::io(&p))?;
    Ok(Prediction {
        smooth,
        growth,
        lines,
        sweep: sw,
        verdict,
        json,
    })
}

/// The directories of a prediction's stages inside its output directory.
struct StageDirs {
    /// The smooth-rail passage and its attribution to coupled modes: `passage`.
    passage: PathBuf,
    /// The growth-rate spectrum and the trial-amplitude growth: `grow`.
    grow: PathBuf,
    /// The short speed sweep: `sweep`.
    sweep: PathBuf,
    /// The report: `report`.
    report: PathBuf,
}

impl StageDirs {
    /// The stage directories in `out`.
    fn in_dir(out: &Path) -> Self {
        StageDirs {
            passage: out.join("passage"),
            grow: out.join("grow"),
            sweep: out.join("sweep"),
            report: out.join("report"),
        }
    }
}

/// `value` as pretty-printed JSON; `what` names it in an error.
fn pretty_json<T: Serialize>(what: &'static str, value: &T) -> Result<String, StudiesError> {
    serde_json::to_string_pretty(value).map_err(|source| StudiesError::Json { what, source })
}

/// The smooth-rail passage with all records; its files go into `dir`.
fn smooth_passage(
    m: &Model,
    prepared: &PreparedModel,
    dir: &Path,
    progress: &dyn Progress,
) -> Result<PassageSummary, PredictError> {
    progress.stage("smooth-rail passage (time steps)", 0);
    let rec = prepared.engine.passage(
        m.run.speed(),
        None,
        &PassageOptions::default(),
        Some(progress),
    );
    progress.finish();
    let rec = rec?;
    let smooth = crate::passage::analysis::summarise(&rec)?;
    super::passage::write_passage(dir, &rec, &smooth, m.mesh.fine_element_length)?;
    Ok(smooth)
}

/// The headline numbers of a finished prediction.
fn predict_json(r: &ReportInput<'_>, seconds: f64) -> PredictJson {
    let (mt, mw) = r.prepared.engine.mode_counts();
    let (s, sw) = (r.smooth, &r.sweep.record);
    PredictJson {
        speed_kmh: r.m.run.speed_kmh,
        track_modes: mt,
        wheel_modes: mw,
        modes_cached: r.prepared.cached,
        modal_seconds: r.prepared.modal_seconds,
        longitudinal_compression_hz: r.lines.longitudinal_hz.clone(),
        dominant_wavelength_mm: s.dominant_wavelength_mm,
        dominant_frequency_hz: s.dominant_frequency_hz,
        wear_components: s.wear_components.clone(),
        fl_components: s.fl_components.clone(),
        limiting_amplitude_um: r.growth.and_then(|(g, _)| g.limiting_amplitude_um),
        verdict: r.verdict.clone(),
        growth_rate: r.rate.sentence(),
        growth_rate_summary: r.rate_brief.cloned(),
        wear_coupled: r.attribution.wear.clone(),
        sweep_speeds_kmh: sw.speeds_kmh.clone(),
        sweep_dominant_wavelength_mm: sw.dominant_wavelength_mm.clone(),
        wavelength_range_ratio: sw.wavelength_range_ratio,
        speed_range_ratio: sw.speed_range_ratio,
        seconds,
    }
}

/// Writes the growth files and `grow.json` into `dir`; returns the JSON.
fn write_growth(
    dir: &Path,
    g: &TrialGrowth,
    m: &Model,
    verdict: Verdict,
    coupled: &[CoupledMode],
    rate: Option<RateSummary>,
) -> Result<GrowJson, StudiesError> {
    write_growth_files(dir, g)?;
    let mut gj = grow_json(g, m.run.speed_kmh, Vec::new(), verdict, 0.0);
    gj.coupled = growth_attribution(g, coupled);
    gj.growth_rate = rate;
    let text = pretty_json("grow.json", &gj)?;
    super::grow::write_grow_json(dir, &text)?;
    Ok(gj)
}

/// The short speed sweep of the prediction into `dir`.
fn short_sweep(
    m: &Model,
    prepared: &PreparedModel,
    lines: &ModeLines,
    coupled: &CoupledModes,
    speeds_kmh: &[f64],
    dir: &Path,
    progress: &dyn Progress,
) -> Result<SweepOutcome, StudiesError> {
    // The modes at the prediction's speed serve the sweep when it lies in the swept range.
    let v_c = super::coupled::sweep_reference_speed_kmh(m.run.speed_kmh, speeds_kmh);
    let other;
    let coupled = if v_c == m.run.speed_kmh {
        coupled
    } else {
        other = prepared.coupled_modes(crate::units::kmh_to_ms(v_c), &[])?;
        &other
    };
    let run_key = crate::model::identity::run_key(m).map_err(|source| StudiesError::Json {
        what: "model",
        source,
    })?;
    let map = MapOptions {
        frequency_lines_hz: lines.longitudinal_hz.clone(),
        wheel_lines_hz: lines.wheel_hz.clone(),
        coupled_speed_kmh: Some(v_c),
        coupled_modes: coupled.visible(),
        ..MapOptions::default()
    };
    sweep(prepared, speeds_kmh, dir, &map, &run_key, progress)
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
    rate_section(&mut d, r);
    coupled_section(&mut d, r);
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
        "Fastening model {}, {} bays of {} m, speed {} km/h, modes below {} Hz ({} track, {} wheel). Generated by corrugation {}: modal bases and residual flexibilities {:.0} s ({}), then passages, growth and sweep {:.0} s.",
        m.fastening.model(),
        m.track.bays,
        f(m.track.sleeper_spacing),
        f(m.run.speed_kmh),
        f(m.run.fmax),
        mt,
        mw,
        env!("CARGO_PKG_VERSION"),
        p.modal_seconds + p.residual_seconds,
        if p.cached {
            "bases loaded from the modal cache"
        } else {
            "bases computed"
        },
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
    let check = initiation_check(r.m, s);
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
    let comp_rows = |name: &str, c: &[crate::dynamics::WavelengthComponent]| {
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
                    w.map(|x| sig(crate::units::m_to_mm(x), 3))
                        .unwrap_or_else(|| "–".into()),
                    pct(dev)
                )
            };
            rows.push(vec![
                f(a.amplitude_um),
                sig(crate::units::m_to_mm(r.reference_wavelength_m), 3),
                c(r.wf_wavelength_m, r.wf_deviation),
                c(r.fl_wavelength_m, r.fl_deviation),
                c(r.fn_wavelength_m, r.fn_deviation),
                case_label(r.case).into(),
                class_label(r.class).into(),
            ]);
        }
    }
    // The class column (6) in its colour in the HTML.
    d.table_shaded(
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
        |_, j, c| if j == 6 { class_colour(c) } else { None },
    );
    eigen_section(d, g);
}

/// The growth-rate spectrum beside the trial amplitudes: which wavelengths grow.
fn rate_section(d: &mut Document, r: &ReportInput<'_>) {
    d.heading(2, "Growth-rate spectrum (linear, small roughness)");
    d.paragraph(r.rate.sentence());
    d.paragraph(
        "The new wear of one passage over a small sinusoidal roughness, per unit roughness, \
         from the coupled receptances and the contact linearised by its own solver \
         (docs/theory.md §10.6): growth rate σ = −k_w Re(G)/(2b) per passage, > 0 grows. \
         The trial amplitudes above are large (10–160 µm, nonlinear) and shaped like the \
         smooth-rail wear; this spectrum is the small-amplitude limit, wavelength by wavelength. \
         Numbers: grow/growth_rate.csv.",
    );
    d.image("growth-rate spectrum", "grow/growth_rate.png");
}

/// Components vs the nearest eigenfrequencies of the three mode families.
fn eigen_section(d: &mut Document, g: &TrialGrowth) {
    d.heading(3, "Components vs eigenfrequencies");
    d.paragraph(
        "Each component's frequency against the nearest eigenfrequency of three families: the \
         track's longitudinal-compression (LC) and vertical-bending (VB) modes and the wheel modes \
         the contact sees. The relative difference is |f − f_mode| / f_mode. The strongest \
         component of each signal per passage; every component is in grow/eigen_comparison.csv.",
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
        strongest_per_passage(&g.eigen)
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

/// The first (strongest) component of each signal of each passage: the components of a
/// passage's signal come strongest first.
fn strongest_per_passage(
    eigen: &[crate::growth::procedure::EigenComparison],
) -> impl Iterator<Item = &crate::growth::procedure::EigenComparison> {
    eigen.iter().enumerate().filter_map(move |(i, e)| {
        let first = eigen[..i]
            .iter()
            .all(|p| p.signal != e.signal || p.amplitude_um != e.amplitude_um);
        first.then_some(e)
    })
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
        "Speed range ratio {}; wavelength range ratio {} (frequency selection shows as a wavelength range ratio much smaller than the speed range ratio). The coupled wheel–track mode each speed's dominant frequency is attributed to, and the speed ranges each selects over: sweep/report.md, sweep/dominant.csv; red dotted lines on the maps: the coupled modes the contact sees.",
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

/// The selected frequencies of the prediction attributed to coupled wheel–track modes: the
/// smooth passage's wear components, each trial amplitude's dominant wear frequency, the
/// growth-rate spectrum's fastest wavelength.
fn coupled_section(d: &mut Document, r: &ReportInput<'_>) {
    d.heading(2, "Coupled wheel–track modes of the selected frequencies");
    d.paragraph(
        "Each selected frequency attributed to a coupled wheel–track mode (docs/theory.md \
         §7.10: the eigenmodes of wheel and track joined by the contact linearised at the \
         static state; among the modes within 3 % the one that moves the contact most), with \
         the mode's energy shares in wheel, rail (by family) and support. Numbers: \
         passage/coupled_modes.csv, passage/coupled_attribution.json, grow/grow.json, \
         sweep/dominant.csv.",
    );
    let mut rows: Vec<Vec<String>> = r
        .attribution
        .wear
        .iter()
        .map(|a| vec!["smooth-rail wear component".into(), attribution_text(a)])
        .collect();
    if let Some((_, gj)) = r.growth {
        rows.extend(gj.coupled.iter().filter(|a| a.amplitude_um > 0.0).map(|a| {
            vec![
                format!("dominant wear, 2A_max {} µm", f(a.amplitude_um)),
                a.mode
                    .as_ref()
                    .map(attribution_text)
                    .unwrap_or_else(|| "no wear peak in the band".into()),
            ]
        }));
    }
    if let Some(b) = r.rate_brief {
        rows.push(vec![
            format!(
                "growth-rate spectrum: fastest {} mm (σ {} per passage; {} of {} wavelengths grow)",
                sig(b.fastest_wavelength_mm, 3),
                sig(b.max_rate_per_passage, 3),
                b.growing_wavelengths,
                b.wavelengths
            ),
            b.fastest_mode
                .as_ref()
                .map(attribution_text)
                .unwrap_or_else(|| "–".into()),
        ]);
    }
    d.table(&["selected frequency of", "coupled mode"], rows);
}
