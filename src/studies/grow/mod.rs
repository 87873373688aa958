//! The outputs of the trial-amplitude growth (docs/theory.md §10.1–§10.4) shared by the
//! `grow` and `predict` products: the run with its progress, the verdict's initiation check,
//! the CSV files and the `grow.json` object.
//!
//! Files written into a growth directory, atomically:
//! * `consistency.csv` — per amplitude and reference component: the matched W_f, F_L, F_N
//!   wavelengths (mm), frequencies (Hz), deviations, case, class;
//! * `phase.csv` — per amplitude: correlation of the new wear with the corrugation, phase,
//!   growing, consistent growth;
//! * `eigen_comparison.csv` — every component vs the nearest longitudinal-compression,
//!   vertical-bending and wheel eigenfrequency (relative difference);
//! * `trial_shape.csv` — `x_m, wear_band_j_per_m, height_per_um`: the band-passed smooth wear
//!   and the trial corrugation shape for 2A_max = 1 µm (scale by the amplitude);
//! * `growth_rate.csv` — the growth-rate spectrum (docs/theory.md §10.6): per wavelength the
//!   frequency, the linear wear per unit roughness (amplitude, phase), the growth rate per
//!   passage, the four parts of the wear response and the same growth rate on a rigid
//!   structure and with the normal receptance only; `growth_rate.svg`/`.png` its plot;
//! * `coupled_modes.csv/.npy/.json` — the coupled wheel–track modes at the speed
//!   ([`super::coupled`]), whose attribution of the dominant wear frequency of every passage
//!   and of the growth-rate spectrum's fastest wavelength is in `grow.json`;
//! * `grow.json` — [`GrowJson`] (with the growth-rate spectrum's summary, [`RateSummary`]),
//!   written last.

mod run;

pub use run::{
    check_amplitudes, run_grow, GrowOptions, GrowOutcome, GrowRun, RatePart,
    DEFAULT_PASSAGES_PER_ROUND,
};

use std::path::Path;

use serde::Serialize;

use super::coupled::attribute_one;
use super::initiation::{evaluate, InitiationCriterion};
use super::StudiesError;
use crate::dynamics::coupled::{CoupledMode, ModeAttribution};
use crate::dynamics::prepared::PreparedModel;
use crate::dynamics::PassageRecorder;
use crate::growth::procedure::{trial_growth, GrowthRound, ModeLines, ProcedureError, TrialGrowth};
use crate::growth::rate::{growth_rate_spectrum, GrowthRateSpectrum, RateOptions};
use crate::growth::verdict::{InitiationCheck, Verdict};
use crate::growth::PhaseRelation;
use crate::io::write_csv;
use crate::model::Model;
use crate::passage::record::WidenedGrid;
use crate::passage::summary::PassageSummary;
use crate::progress::Progress;
use crate::units::m_to_mm;

/// Wheel modes drawn on the maps and compared with the components: contact participation
/// ≥ this share of the largest (−).
pub const WHEEL_LINE_SHARE: f64 = 0.03;

/// The mode families the growth's components are compared with: the track's
/// longitudinal-compression and vertical-bending modes and the wheel modes the contact sees
/// (those drawn on the sweep's maps).
pub fn mode_lines(p: &PreparedModel) -> ModeLines {
    ModeLines {
        longitudinal_hz: p.longitudinal_compression_hz(),
        vertical_hz: p.vertical_bending_hz(),
        wheel_hz: p.wheel_contact_modes_hz(WHEEL_LINE_SHARE),
    }
}

/// The trial amplitudes 2A_max (peak-to-trough, µm) of `grow`, `predict` and a study's growth
/// loop when none are given.
pub const DEFAULT_AMPLITUDES_UM: [f64; 4] = [10.0, 40.0, 80.0, 160.0];

/// One matched component in the JSON.
#[derive(Serialize)]
pub struct JsonComponent {
    /// The reference (smooth-rail) wavelength it was matched to, mm.
    pub reference_wavelength_mm: f64,
    /// The matched wavelength, mm; `None` when nothing matched.
    pub wavelength_mm: Option<f64>,
    /// Its frequency at the passage speed, Hz.
    pub frequency_hz: Option<f64>,
    /// Relative deviation from the reference wavelength (−, 0.03 = 3 %).
    pub deviation: Option<f64>,
}

/// Components of one amplitude.
#[derive(Serialize)]
pub struct JsonAmplitudeComponents {
    /// Trial amplitude 2A_max, µm.
    pub amplitude_um: f64,
    /// Matched differential-wear components.
    #[serde(rename = "W_f")]
    pub wf: Vec<JsonComponent>,
    /// Matched longitudinal-force components.
    #[serde(rename = "F_L")]
    pub fl: Vec<JsonComponent>,
    /// Matched normal-force components.
    #[serde(rename = "F_N")]
    pub fnn: Vec<JsonComponent>,
}

/// One consistency row in the JSON.
#[derive(Serialize)]
pub struct JsonConsistency {
    /// Trial amplitude 2A_max, µm.
    pub amplitude_um: f64,
    /// Reference wavelength, mm.
    pub reference_wavelength_mm: f64,
    /// Consistency case (docs/theory.md §10.3).
    pub case: String,
    /// Consistency class.
    pub class: String,
    /// Which signals match the reference (e.g. "W_f F_L").
    pub consistent_signals: String,
}

/// The `grow.json` object (the `--json` output of `grow`; `predict` writes it too).
#[derive(Serialize)]
pub struct GrowJson {
    /// Passage speed, km/h.
    pub speed_kmh: f64,
    /// Trial amplitudes 2A_max, µm.
    pub amplitudes_um: Vec<f64>,
    /// Reference wavelengths (smooth-rail wear components), mm.
    pub reference_wavelengths_mm: Vec<f64>,
    /// Limiting amplitude (2A_max)_l, µm; `None` when the smallest trial does not grow.
    pub limiting_amplitude_um: Option<f64>,
    /// Growth phase per amplitude ("anti-phase", "in-phase", "indeterminate").
    pub phase: Vec<String>,
    /// Correlation of the new wear with the corrugation per amplitude (−1 … 1).
    pub correlation: Vec<f64>,
    /// Whether each amplitude grows consistently.
    pub grows_consistently: Vec<bool>,
    /// Matched components per amplitude.
    pub components: Vec<JsonAmplitudeComponents>,
    /// Consistency rows of every amplitude.
    pub consistency: Vec<JsonConsistency>,
    /// F_L band RMS (20–80 mm) per amplitude, N.
    pub fl_band_rms_n: Vec<f64>,
    /// F_N band RMS (20–80 mm) per amplitude, N.
    pub fn_band_rms_n: Vec<f64>,
    /// Rounds of the iterative growth (empty when not run).
    pub iterative: Vec<GrowthRound>,
    /// The plain-language verdict.
    pub verdict: Verdict,
    /// The dominant wear frequency of the smooth rail and of each trial amplitude attributed
    /// to a coupled wheel–track mode (docs/theory.md §7.10); empty when the coupled modes
    /// were not computed.
    pub coupled: Vec<AmplitudeAttribution>,
    /// The growth-rate spectrum in brief; `None` when it was not computed.
    pub growth_rate: Option<RateSummary>,
    /// The trial amplitude 2A_max (µm) whose passage failed, where the procedure stopped
    /// (the amplitudes above are the ones that ran); `None` when every amplitude ran.
    pub stopped_at_um: Option<f64>,
    /// Why that passage failed, with what to change; `None` when every amplitude ran.
    pub stopped_reason: Option<String>,
    /// The passages whose contact patch reached the boundary of the model's contact grid and
    /// that were rerun on a wider grid, with the grid each ran on; absent when every passage
    /// ran on the model's grid.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub widened_contact_grids: Vec<WidenedPassageGrid>,
    /// Wall-clock time of the run, s (0 when not measured).
    pub seconds: f64,
}

/// A passage of the growth that ran on a widened contact grid
/// ([`crate::passage::setup::run_widening_grid`]).
#[derive(Clone, Debug, Serialize)]
pub struct WidenedPassageGrid {
    /// Trial amplitude 2A_max (µm); 0 for the smooth rail.
    pub amplitude_um: f64,
    /// The grid it ran on.
    pub grid: WidenedGrid,
}

/// The passages of `g` (smooth rail first, then the trial amplitudes) that ran on a widened
/// contact grid.
pub fn widened_contact_grids(g: &TrialGrowth) -> Vec<WidenedPassageGrid> {
    std::iter::once((0.0, &g.smooth))
        .chain(g.amplitudes.iter().map(|a| (a.amplitude_um, &a.summary)))
        .filter_map(|(amplitude_um, s)| {
            s.contact_grid_widened
                .map(|grid| WidenedPassageGrid { amplitude_um, grid })
        })
        .collect()
}

/// The selected (dominant) wear frequency of one passage of the growth attributed to a
/// coupled mode.
#[derive(Clone, Debug, Serialize)]
pub struct AmplitudeAttribution {
    /// Trial amplitude 2A_max (µm); 0 for the smooth rail.
    pub amplitude_um: f64,
    /// The dominant wear frequency (Hz); `None` without a wear peak in the band.
    pub frequency_hz: Option<f64>,
    /// The coupled mode it is attributed to; `None` without a frequency.
    pub mode: Option<ModeAttribution>,
}

/// The smooth rail's and every trial amplitude's dominant wear frequency attributed to the
/// coupled modes `modes`.
pub(crate) fn growth_attribution(
    g: &TrialGrowth,
    modes: &[CoupledMode],
) -> Vec<AmplitudeAttribution> {
    std::iter::once((0.0, &g.smooth))
        .chain(g.amplitudes.iter().map(|a| (a.amplitude_um, &a.summary)))
        .map(|(amplitude_um, s)| AmplitudeAttribution {
            amplitude_um,
            frequency_hz: s.dominant_frequency_hz,
            mode: attribute_one(modes, s.dominant_frequency_hz),
        })
        .collect()
}

/// The growth-rate spectrum (docs/theory.md §10.6) in brief, for `grow.json` and the report.
#[derive(Clone, Debug, Serialize)]
pub struct RateSummary {
    /// Speed (km/h).
    pub speed_kmh: f64,
    /// Wavelength of the largest growth rate (the fastest-growing, or the least-decaying,
    /// wavelength), mm.
    pub fastest_wavelength_mm: f64,
    /// Its frequency at the speed, Hz.
    pub fastest_frequency_hz: f64,
    /// The largest growth rate, per passage (> 0 grows).
    pub max_rate_per_passage: f64,
    /// Its wear phase against the roughness, degrees (±180 grows fastest).
    pub fastest_phase_deg: f64,
    /// How many of the spectrum's wavelengths grow.
    pub growing_wavelengths: usize,
    /// How many wavelengths the spectrum has.
    pub wavelengths: usize,
    /// The wavelength ranges that grow, `[from, to]` mm.
    pub growing_ranges_mm: Vec<[f64; 2]>,
    /// The fastest wavelength's frequency attributed to a coupled mode; `None` without
    /// coupled modes.
    pub fastest_mode: Option<ModeAttribution>,
}

/// The summary of `s`, its fastest wavelength attributed to `modes`; `None` for an empty
/// spectrum.
pub(crate) fn rate_summary(s: &GrowthRateSpectrum, modes: &[CoupledMode]) -> Option<RateSummary> {
    let p = s.fastest()?;
    Some(RateSummary {
        speed_kmh: s.speed.kmh(),
        fastest_wavelength_mm: m_to_mm(p.wavelength_m),
        fastest_frequency_hz: p.frequency_hz,
        max_rate_per_passage: p.growth_rate_per_passage,
        fastest_phase_deg: p.phase_deg,
        growing_wavelengths: s.points.iter().filter(|p| p.grows()).count(),
        wavelengths: s.points.len(),
        growing_ranges_mm: s
            .growing_ranges_m()
            .iter()
            .map(|r| r.map(m_to_mm))
            .collect(),
        fastest_mode: attribute_one(modes, Some(p.frequency_hz)),
    })
}

/// The JSON name of a growth phase.
fn phase_name(p: PhaseRelation) -> &'static str {
    match p {
        PhaseRelation::AntiPhase => "anti-phase",
        PhaseRelation::InPhase => "in-phase",
        PhaseRelation::Indeterminate => "indeterminate",
    }
}

/// The JSON (serde) name of a unit enum variant.
fn json_name<T: Serialize>(v: &T) -> String {
    serde_json::to_value(v)
        .ok()
        .and_then(|v| v.as_str().map(String::from))
        .unwrap_or_default()
}

/// Builds the JSON object of a trial-growth result.
pub fn grow_json(
    g: &TrialGrowth,
    speed_kmh: f64,
    iterative: Vec<GrowthRound>,
    verdict: Verdict,
    seconds: f64,
) -> GrowJson {
    let refs_mm: Vec<f64> = g
        .reference_wavelengths_m
        .iter()
        .map(|&l| m_to_mm(l))
        .collect();
    let comp = |r: &crate::growth::ConsistencyRow, which: usize| {
        let (w, f, d) = match which {
            0 => (r.wf_wavelength_m, r.wf_frequency_hz, r.wf_deviation),
            1 => (r.fl_wavelength_m, r.fl_frequency_hz, r.fl_deviation),
            _ => (r.fn_wavelength_m, r.fn_frequency_hz, r.fn_deviation),
        };
        JsonComponent {
            reference_wavelength_mm: m_to_mm(r.reference_wavelength_m),
            wavelength_mm: w.map(m_to_mm),
            frequency_hz: f,
            deviation: d,
        }
    };
    GrowJson {
        speed_kmh,
        amplitudes_um: g.amplitudes.iter().map(|a| a.amplitude_um).collect(),
        reference_wavelengths_mm: refs_mm,
        limiting_amplitude_um: g.limiting_amplitude_um,
        phase: g
            .amplitudes
            .iter()
            .map(|a| phase_name(a.phase.relation).to_string())
            .collect(),
        correlation: g.amplitudes.iter().map(|a| a.phase.correlation).collect(),
        grows_consistently: g.amplitudes.iter().map(|a| a.grows_consistently).collect(),
        components: g
            .amplitudes
            .iter()
            .map(|a| JsonAmplitudeComponents {
                amplitude_um: a.amplitude_um,
                wf: a.rows.iter().map(|r| comp(r, 0)).collect(),
                fl: a.rows.iter().map(|r| comp(r, 1)).collect(),
                fnn: a.rows.iter().map(|r| comp(r, 2)).collect(),
            })
            .collect(),
        consistency: g
            .amplitudes
            .iter()
            .flat_map(|a| {
                a.rows.iter().map(move |r| JsonConsistency {
                    amplitude_um: a.amplitude_um,
                    reference_wavelength_mm: m_to_mm(r.reference_wavelength_m),
                    case: json_name(&r.case),
                    class: json_name(&r.class),
                    consistent_signals: r.consistent_signals.clone(),
                })
            })
            .collect(),
        fl_band_rms_n: g
            .amplitudes
            .iter()
            .map(|a| a.summary.fl_band_rms_n)
            .collect(),
        fn_band_rms_n: g
            .amplitudes
            .iter()
            .map(|a| a.summary.fn_band_rms_n)
            .collect(),
        iterative,
        verdict,
        coupled: Vec::new(),
        growth_rate: None,
        stopped_at_um: g.stopped.as_ref().map(|s| s.amplitude_um),
        stopped_reason: g.stopped.as_ref().map(|s| s.reason.clone()),
        widened_contact_grids: widened_contact_grids(g),
        seconds,
    }
}

/// The smooth rail's relative wear against the model's initiation threshold
/// (`wear.initiation_threshold`), for the verdict.
pub fn initiation_check(m: &Model, smooth: &PassageSummary) -> InitiationCheck {
    let c = InitiationCriterion::from_model(m);
    let row = evaluate("model", smooth, &c, 1);
    InitiationCheck {
        relative_wear: row.relative_wear,
        threshold: c.min_relative_wear,
        initiates: row.initiates,
    }
}

/// The trial growth of `recorder` at `speed_m_per_s` (m/s) with the trial amplitudes
/// `amplitudes_um` (2A_max, µm), each passage counted on `progress`; `None` when the smooth
/// rail left no wear component to grow (the verdict is then "no initiation").
pub fn trial_growth_if_any(
    recorder: &dyn PassageRecorder,
    speed_m_per_s: f64,
    amplitudes_um: &[f64],
    modes: &ModeLines,
    progress: &dyn Progress,
) -> Result<Option<TrialGrowth>, ProcedureError> {
    progress.stage(
        "trial-amplitude growth (passages: smooth rail + trials)",
        1 + amplitudes_um.len() as u64,
    );
    let r = trial_growth(recorder, speed_m_per_s, amplitudes_um, modes, |k| {
        progress.done(k as u64 + 1)
    });
    progress.finish();
    match r {
        Ok(g) => {
            for w in widened_contact_grids(&g) {
                progress.warn(&format!(
                    "{}: the contact patch reached the boundary of the model's contact grid; the passage was rerun on {}",
                    widened_passage_name(w.amplitude_um),
                    w.grid
                ));
            }
            Ok(Some(g))
        }
        Err(ProcedureError::NoReference) => Ok(None),
        Err(e) => Err(e),
    }
}

/// How the growth's outputs name a passage: the smooth rail (`amplitude_um` 0) or a trial
/// amplitude.
pub fn widened_passage_name(amplitude_um: f64) -> String {
    if amplitude_um == 0.0 {
        "smooth rail".into()
    } else {
        format!("trial amplitude {amplitude_um} µm")
    }
}

/// Writes the CSV files of a trial-growth result into `out`: `consistency.csv`,
/// `phase.csv`, `eigen_comparison.csv` and `trial_shape.csv`.
pub(crate) fn write_growth_files(out: &Path, g: &TrialGrowth) -> Result<(), StudiesError> {
    std::fs::create_dir_all(out).map_err(StudiesError::io(out))?;
    write_consistency_csv(out, g)?;
    write_phase_csv(out, g)?;
    write_eigen_comparison_csv(out, g)?;
    write_trial_shape_csv(out, g)
}

/// `consistency.csv`: per amplitude and reference component, the matched W_f, F_L and F_N
/// wavelengths (mm), frequencies (Hz) and deviations, the case and the class.
fn write_consistency_csv(out: &Path, g: &TrialGrowth) -> Result<(), StudiesError> {
    let opt = |v: Option<f64>| v.map(|x| format!("{x:e}")).unwrap_or_default();
    let mut rows: Vec<Vec<String>> = Vec::new();
    for a in &g.amplitudes {
        for r in &a.rows {
            rows.push(vec![
                format!("{}", a.amplitude_um),
                format!("{:e}", m_to_mm(r.reference_wavelength_m)),
                opt(r.wf_wavelength_m.map(m_to_mm)),
                opt(r.wf_frequency_hz),
                opt(r.wf_deviation),
                opt(r.fl_wavelength_m.map(m_to_mm)),
                opt(r.fl_frequency_hz),
                opt(r.fl_deviation),
                opt(r.fn_wavelength_m.map(m_to_mm)),
                opt(r.fn_frequency_hz),
                opt(r.fn_deviation),
                json_name(&r.case),
                json_name(&r.class),
                r.consistent_signals.clone(),
            ]);
        }
    }
    write_text_csv(
        &out.join("consistency.csv"),
        &[
            "amplitude_um",
            "reference_wavelength_mm",
            "wf_wavelength_mm",
            "wf_frequency_hz",
            "wf_deviation",
            "fl_wavelength_mm",
            "fl_frequency_hz",
            "fl_deviation",
            "fn_wavelength_mm",
            "fn_frequency_hz",
            "fn_deviation",
            "case",
            "class",
            "consistent_signals",
        ],
        &rows,
    )?;
    Ok(())
}

/// `phase.csv`: per amplitude, the correlation of the new wear with the corrugation, the
/// phase, growth, and the band RMS of F_L, F_N (N) and the wear (J/m).
fn write_phase_csv(out: &Path, g: &TrialGrowth) -> Result<(), StudiesError> {
    let rows: Vec<Vec<String>> = g
        .amplitudes
        .iter()
        .map(|a| {
            vec![
                format!("{}", a.amplitude_um),
                format!("{:e}", a.phase.correlation),
                phase_name(a.phase.relation).to_string(),
                format!("{}", a.phase.growing == Some(true)),
                format!("{}", a.grows_consistently),
                format!("{:e}", a.summary.fl_band_rms_n),
                format!("{:e}", a.summary.fn_band_rms_n),
                format!("{:e}", a.summary.wear_band_rms),
            ]
        })
        .collect();
    write_text_csv(
        &out.join("phase.csv"),
        &[
            "amplitude_um",
            "correlation",
            "phase",
            "growing",
            "grows_consistently",
            "fl_band_rms_n",
            "fn_band_rms_n",
            "wear_band_rms_j_per_m",
        ],
        &rows,
    )?;
    Ok(())
}

/// `eigen_comparison.csv`: every component against the nearest longitudinal-compression,
/// vertical-bending and wheel eigenfrequency (Hz, relative difference).
fn write_eigen_comparison_csv(out: &Path, g: &TrialGrowth) -> Result<(), StudiesError> {
    let opt = |v: Option<f64>| v.map(|x| format!("{x:e}")).unwrap_or_default();
    let rows: Vec<Vec<String>> = g
        .eigen
        .iter()
        .map(|e| {
            vec![
                e.signal.clone(),
                format!("{}", e.amplitude_um),
                format!("{:e}", e.wavelength_mm),
                format!("{:e}", e.frequency_hz),
                opt(e.nearest_longitudinal_hz),
                opt(e.longitudinal_difference),
                opt(e.nearest_vertical_hz),
                opt(e.vertical_difference),
                opt(e.nearest_wheel_hz),
                opt(e.wheel_difference),
            ]
        })
        .collect();
    write_text_csv(
        &out.join("eigen_comparison.csv"),
        &[
            "signal",
            "amplitude_um",
            "wavelength_mm",
            "frequency_hz",
            "nearest_longitudinal_hz",
            "longitudinal_difference",
            "nearest_vertical_hz",
            "vertical_difference",
            "nearest_wheel_hz",
            "wheel_difference",
        ],
        &rows,
    )?;
    Ok(())
}

/// `trial_shape.csv`: the band-passed smooth wear (J/m) and the trial corrugation shape for
/// 2A_max = 1 µm along the rail (m).
fn write_trial_shape_csv(out: &Path, g: &TrialGrowth) -> Result<(), StudiesError> {
    let wb = &g.smooth_wear_band;
    let (lo, hi) = wb
        .values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, u), &v| {
            (l.min(v), u.max(v))
        });
    let ptp = (hi - lo).max(f64::MIN_POSITIVE);
    write_csv(
        &out.join("trial_shape.csv"),
        &["x_m", "wear_band_j_per_m", "height_per_um"],
        (0..wb.len()).map(|i| vec![wb.x_m(i), wb.values[i], -wb.values[i] / ptp]),
    )
    .map_err(StudiesError::io(&out.join("trial_shape.csv")))?;
    Ok(())
}

/// The growth-rate spectrum of `p` at `speed`, with the model's wear coefficient and the
/// default settings ([`RateOptions`]), counted as one stage on `progress`.
pub fn growth_rate(
    m: &Model,
    p: &PreparedModel,
    speed: crate::units::Speed,
    progress: &dyn Progress,
) -> Result<GrowthRateSpectrum, crate::dynamics::DynamicsError> {
    progress.stage("growth-rate spectrum (linear wear response)", 1);
    let s = growth_rate_spectrum(
        &p.engine,
        speed,
        m.wear.coefficient,
        &RateOptions::default(),
    );
    progress.done(1);
    progress.finish();
    s
}

/// Writes `growth_rate.csv` and its plot (`growth_rate.svg`, `.png`: growth rate per passage
/// against wavelength, with the rigid-structure and normal-only variants) into `out`.
pub(crate) fn write_growth_rate(out: &Path, s: &GrowthRateSpectrum) -> Result<(), StudiesError> {
    std::fs::create_dir_all(out).map_err(StudiesError::io(out))?;
    let path = out.join("growth_rate.csv");
    let mut header = vec![
        "wavelength_mm",
        "frequency_hz",
        "gain_j_per_m2",
        "phase_deg",
        "growth_rate_per_passage",
    ];
    let parts = [
        "wear_roughness_re_j_per_m2",
        "wear_approach_re_j_per_m2",
        "wear_creepage_x_re_j_per_m2",
        "wear_creepage_t_re_j_per_m2",
    ];
    header.extend(parts);
    header.extend([
        "normal_force_n_per_m",
        "longitudinal_force_n_per_m",
        "rigid_phase_deg",
        "rigid_growth_rate_per_passage",
        "normal_only_phase_deg",
        "normal_only_growth_rate_per_passage",
    ]);
    let rows = s
        .points
        .iter()
        .zip(s.rigid.iter().zip(&s.normal_only))
        .map(|(p, (r, n))| {
            let mut row = vec![
                m_to_mm(p.wavelength_m),
                p.frequency_hz,
                p.gain_j_per_m2,
                p.phase_deg,
                p.growth_rate_per_passage,
            ];
            row.extend(p.wear_parts_re);
            row.extend([
                p.normal_force_n_per_m,
                p.longitudinal_force_n_per_m,
                r.phase_deg,
                r.growth_rate_per_passage,
                n.phase_deg,
                n.growth_rate_per_passage,
            ]);
            row
        });
    write_csv(&path, &header, rows).map_err(StudiesError::io(&path))?;
    let series = |name: &str, pts: &[crate::growth::rate::RatePoint]| {
        crate::report::plot::Series::new(
            name,
            pts.iter().map(|p| m_to_mm(p.wavelength_m)).collect(),
            pts.iter().map(|p| p.growth_rate_per_passage).collect(),
        )
    };
    let stem = out.join("growth_rate");
    let zero_x: Vec<f64> = [s.points.first(), s.points.last()]
        .into_iter()
        .flatten()
        .map(|p| m_to_mm(p.wavelength_m))
        .collect();
    crate::report::plot::line_plot(
        &stem,
        &format!(
            "Growth-rate spectrum at {:.0} km/h (> 0 grows)",
            s.speed.kmh()
        ),
        "wavelength (mm)",
        "growth rate per passage (-)",
        &[
            series("coupled wheel-track", &s.points),
            series("rigid structure", &s.rigid),
            series("normal receptance only", &s.normal_only),
            // the line between growth and decay
            crate::report::plot::Series::new(
                "0: no growth",
                zero_x.clone(),
                vec![0.0; zero_x.len()],
            ),
        ],
    )?;
    Ok(())
}

/// One wavelength of the check of the growth-rate spectrum against passages.
#[derive(Clone, Debug, Serialize)]
pub struct RateCheck {
    /// Wavelength (mm).
    pub wavelength_mm: f64,
    /// Linear theory: `|G|` (J/m per m) and `arg G` (degrees).
    pub linear_gain_j_per_m2: f64,
    /// Linear theory's phase (degrees).
    pub linear_phase_deg: f64,
    /// Passages: `|G|` (J/m per m).
    pub passage_gain_j_per_m2: f64,
    /// Passages: phase (degrees).
    pub passage_phase_deg: f64,
    /// `|G_linear| / |G_passage|` (−).
    pub amplitude_ratio: f64,
    /// `arg(G_linear / G_passage)` (degrees).
    pub phase_difference_deg: f64,
}

/// The growth-rate spectrum's linear theory against passages over sinusoidal corrugations of
/// amplitude `amplitude_m` (m) at `wavelengths_m` (m, within 20–80 mm) at `speed_m_per_s`
/// (docs/theory.md §10.6, validation/growth_rate.md): one smooth passage and one per
/// wavelength; `rate_check.csv` in `out`.
pub fn rate_check(
    p: &PreparedModel,
    speed_m_per_s: f64,
    wavelengths_m: &[f64],
    amplitude_m: f64,
    out: &Path,
) -> Result<Vec<RateCheck>, StudiesError> {
    use crate::dynamics::passage::PassageOptions;
    use crate::growth::rate::{linear_responses, passage_gain};
    let opts = PassageOptions {
        energy: false,
        rail_point_offset_m: None,
        overlap: false,
    };
    let dynamics = |e: crate::dynamics::DynamicsError| StudiesError::StudyCase {
        file: "growth-rate check".into(),
        case: format!("{:?} m", wavelengths_m),
        message: e.to_string(),
    };
    let smooth = p
        .engine
        .passage(speed_m_per_s, None, &opts, None)
        .map_err(dynamics)?;
    let lin = linear_responses(
        &p.engine,
        speed_m_per_s,
        wavelengths_m,
        &RateOptions::default(),
    )
    .map_err(dynamics)?;
    let mut rows = Vec::new();
    for (&l, r) in wavelengths_m.iter().zip(&lin) {
        let gp = passage_gain(&p.engine, &smooth, l, amplitude_m).map_err(dynamics)?;
        let gl = r[0].wear;
        rows.push(RateCheck {
            wavelength_mm: m_to_mm(l),
            linear_gain_j_per_m2: gl.norm(),
            linear_phase_deg: gl.arg().to_degrees(),
            passage_gain_j_per_m2: gp.norm(),
            passage_phase_deg: gp.arg().to_degrees(),
            amplitude_ratio: gl.norm() / gp.norm(),
            phase_difference_deg: (gl / gp).arg().to_degrees(),
        });
    }
    std::fs::create_dir_all(out).map_err(StudiesError::io(out))?;
    let path = out.join("rate_check.csv");
    write_csv(
        &path,
        &[
            "wavelength_mm",
            "linear_gain_j_per_m2",
            "linear_phase_deg",
            "passage_gain_j_per_m2",
            "passage_phase_deg",
            "amplitude_ratio",
            "phase_difference_deg",
        ],
        rows.iter().map(|r| {
            vec![
                r.wavelength_mm,
                r.linear_gain_j_per_m2,
                r.linear_phase_deg,
                r.passage_gain_j_per_m2,
                r.passage_phase_deg,
                r.amplitude_ratio,
                r.phase_difference_deg,
            ]
        }),
    )
    .map_err(StudiesError::io(&path))?;
    Ok(rows)
}

/// `grow.json` in `out` (the `--json` object of `grow`), atomically: written last, it marks a
/// complete run.
pub(crate) fn write_grow_json(out: &Path, text: &str) -> Result<(), StudiesError> {
    let p = out.join("grow.json");
    crate::io::write_text(&p, text).map_err(StudiesError::io(&p))
}

/// A CSV of text cells, atomically ([`crate::io::write_text_csv`]).
pub fn write_text_csv(
    path: &Path,
    header: &[&str],
    rows: &[Vec<String>],
) -> Result<(), StudiesError> {
    crate::io::write_text_csv(path, header, rows).map_err(StudiesError::io(path))
}

/// The growth loop of one study case (`growth = true` in a study file) on the prepared
/// reduced model `p` of `model`: the trial-amplitude procedure at the model's speed with
/// [`DEFAULT_AMPLITUDES_UM`]; columns `limiting_amplitude_um` (µm, 0 when no amplitude grows
/// consistently), `consistent_amplitudes` (how many of the four grow consistently) and, when
/// any of its passages ran on a widened contact grid, `widened_contact_grids` (how many).
pub fn study_growth(
    model: &Model,
    p: &PreparedModel,
) -> Result<std::collections::BTreeMap<String, f64>, crate::studies::BoxError> {
    let modes = mode_lines(p);
    let g = trial_growth(
        &p.engine,
        model.run.speed(),
        &DEFAULT_AMPLITUDES_UM,
        &modes,
        |_| {},
    )?;
    if let Some(s) = &g.stopped {
        return Err(format!(
            "growth: the trial amplitude {} µm failed: {}",
            s.amplitude_um, s.reason
        )
        .into());
    }
    let mut out = std::collections::BTreeMap::new();
    out.insert(
        "limiting_amplitude_um".to_string(),
        g.limiting_amplitude_um.unwrap_or(0.0),
    );
    out.insert(
        "consistent_amplitudes".to_string(),
        g.amplitudes.iter().filter(|a| a.grows_consistently).count() as f64,
    );
    // passages rerun on a widened contact grid (docs/theory.md §6.8): a column only when some
    // case has one
    let widened = widened_contact_grids(&g).len();
    if widened > 0 {
        out.insert("widened_contact_grids".to_string(), widened as f64);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::{rate_summary, GrowthRateSpectrum};
    use crate::growth::rate::RatePoint;
    use crate::units::Speed;

    /// The growth-rate summary carries the model's speed exactly: 60 km/h reads 60, not the
    /// 60.00000000000001 of a round trip through m/s (`60 / 3.6 * 3.6`).
    #[test]
    fn rate_summary_carries_the_requested_speed() {
        assert_ne!(60.0_f64 / 3.6 * 3.6, 60.0);
        let point = |l: f64, sigma: f64| RatePoint {
            wavelength_m: l,
            frequency_hz: 60.0 / 3.6 / l,
            gain_j_per_m2: 1.0,
            phase_deg: 180.0,
            growth_rate_per_passage: sigma,
            wear_parts_re: [0.0; 4],
            wear_parts_im: [0.0; 4],
            normal_force_n_per_m: 0.0,
            longitudinal_force_n_per_m: 0.0,
        };
        let s = GrowthRateSpectrum {
            speed: Speed::from_kmh(60.0),
            wear_coefficient_m3_per_j: 1e-13,
            width_m: 0.01,
            points: vec![point(0.03, -1.0), point(0.04, 2.0)],
            rigid: vec![],
            normal_only: vec![],
        };
        let brief = rate_summary(&s, &[]).unwrap();
        assert_eq!(brief.speed_kmh, 60.0);
        assert_eq!(brief.fastest_wavelength_mm, 40.0);
        assert_eq!(brief.growing_wavelengths, 1);
    }
}
