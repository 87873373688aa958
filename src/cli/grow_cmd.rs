//! `corrugation grow`: trial-amplitude growth (docs/theory.md §10.1–§10.4, the reference
//! procedure) and, with `--rounds`, iterative growth (§10.5).
//!
//! Outputs in `--out DIR` (default `corrugation-out/grow`), written atomically:
//! * `consistency.csv` — per amplitude and reference component: the matched W_f, F_L, F_N
//!   wavelengths (mm), frequencies (Hz), deviations, case, class;
//! * `phase.csv` — per amplitude: correlation of the new wear with the corrugation, phase,
//!   growing, consistent growth;
//! * `eigen_comparison.csv` — every component vs the nearest longitudinal-compression,
//!   vertical-bending and wheel eigenfrequency (relative difference);
//! * `trial_shape.csv` — `x_m, wear_band_j_per_m, height_per_um`: the band-passed smooth wear
//!   and the trial corrugation shape for 2A_max = 1 µm (scale by the amplitude);
//! * `iterative.csv` (with `--rounds`): round, passages, amplitude_um, dominant_wavelength_mm;
//! * `grow.json` — the `--json` object.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use serde::Serialize;

use corrugation::dynamics::summary::PassageSummary;
use corrugation::growth::procedure::{
    iterative_growth, trial_growth, GrowthRound, IterativeOptions, TrialGrowth,
};
use corrugation::growth::procedure::{ModeLines, ProcedureError};
use corrugation::growth::verdict::{
    growth_verdict, no_initiation_verdict, sig, InitiationCheck, Verdict,
};
use corrugation::growth::PhaseRelation;
use corrugation::io::{write_atomic, write_csv};
use corrugation::model::Model;
use corrugation::studies::initiation::{evaluate, InitiationCriterion};
use corrugation::units::m_to_mm;

use super::ModelArgs;

/// Trial-amplitude growth: smooth passage, trial corrugations, consistency, limiting amplitude.
#[derive(Debug, Args)]
pub struct GrowCmd {
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
    /// Also run iterative growth for this many rounds (0 = off).
    #[arg(long, default_value_t = 0, value_name = "N")]
    rounds: usize,
    /// Passages per round of the iterative growth.
    #[arg(long, default_value_t = 1000, value_name = "N")]
    passages_per_round: usize,
    /// Output directory.
    #[arg(long, default_value = "corrugation-out/grow", value_name = "DIR")]
    out: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
    /// Modal cache directory.
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
    /// Passage engine: `reduced` (modal, default) or `explicit` (the full explicit FE
    /// path, minutes per passage).
    #[arg(long, value_enum, default_value = "reduced")]
    engine: super::engine::Engine,
}

/// One matched component in the JSON.
#[derive(Serialize)]
pub struct JsonComponent {
    pub reference_wavelength_mm: f64,
    pub wavelength_mm: Option<f64>,
    pub frequency_hz: Option<f64>,
    pub deviation: Option<f64>,
}

/// Components of one amplitude.
#[derive(Serialize)]
pub struct JsonAmplitudeComponents {
    pub amplitude_um: f64,
    #[serde(rename = "W_f")]
    pub wf: Vec<JsonComponent>,
    #[serde(rename = "F_L")]
    pub fl: Vec<JsonComponent>,
    #[serde(rename = "F_N")]
    pub fnn: Vec<JsonComponent>,
}

/// One consistency row in the JSON.
#[derive(Serialize)]
pub struct JsonConsistency {
    pub amplitude_um: f64,
    pub reference_wavelength_mm: f64,
    pub case: String,
    pub class: String,
    pub consistent_signals: String,
}

/// The `--json` object of `grow`.
#[derive(Serialize)]
pub struct GrowJson {
    pub speed_kmh: f64,
    pub amplitudes_um: Vec<f64>,
    pub reference_wavelengths_mm: Vec<f64>,
    pub limiting_amplitude_um: Option<f64>,
    pub phase: Vec<String>,
    pub correlation: Vec<f64>,
    pub grows_consistently: Vec<bool>,
    pub components: Vec<JsonAmplitudeComponents>,
    pub consistency: Vec<JsonConsistency>,
    pub fl_band_rms_n: Vec<f64>,
    pub fn_band_rms_n: Vec<f64>,
    pub iterative: Vec<GrowthRound>,
    /// The plain-language verdict.
    pub verdict: Verdict,
    pub seconds: f64,
}

fn phase_name(p: PhaseRelation) -> &'static str {
    match p {
        PhaseRelation::AntiPhase => "anti-phase",
        PhaseRelation::InPhase => "in-phase",
        PhaseRelation::Indeterminate => "indeterminate",
    }
}

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
    let comp = |r: &corrugation::growth::ConsistencyRow, which: usize| {
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

/// The trial growth of `recorder` (progress on stderr), or `None` when the smooth rail left no
/// wear component to grow (the verdict "no initiation" is then printed by the caller).
pub fn run_trial_growth(
    recorder: &dyn corrugation::dynamics::PassageRecorder,
    m: &Model,
    amplitudes_um: &[f64],
    modes: &ModeLines,
) -> anyhow::Result<Option<TrialGrowth>> {
    let pb = super::progress::bar("trial-amplitude growth (passages: smooth rail + trials)");
    pb.set_length(1 + amplitudes_um.len() as u64);
    let r = trial_growth(recorder, m.run.speed(), amplitudes_um, modes, |k| {
        pb.set_position(k as u64 + 1)
    });
    pb.finish_and_clear();
    match r {
        Ok(g) => Ok(Some(g)),
        Err(ProcedureError::NoReference) => Ok(None),
        Err(e) => Err(e.into()),
    }
}

/// Prints the verdict as the last lines on stdout.
pub fn print_verdict(v: &Verdict) {
    println!();
    for l in &v.lines {
        println!("{l}");
    }
}

/// Writes the CSV files of a trial-growth result into `out`.
pub fn write_growth_files(out: &std::path::Path, g: &TrialGrowth) -> anyhow::Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
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
    )?;
    Ok(())
}

/// `grow.json` in `out` (the `--json` object), atomically: written last, it marks a complete
/// run.
fn write_grow_json(out: &std::path::Path, text: &str) -> anyhow::Result<()> {
    let p = out.join("grow.json");
    corrugation::io::write_text(&p, text).with_context(|| format!("writing {}", p.display()))
}

/// A CSV of text cells, atomically.
pub fn write_text_csv(
    path: &std::path::Path,
    header: &[&str],
    rows: &[Vec<String>],
) -> anyhow::Result<()> {
    write_atomic(path, |w| {
        let mut c = csv::Writer::from_writer(w);
        c.write_record(header).map_err(std::io::Error::other)?;
        for r in rows {
            c.write_record(r).map_err(std::io::Error::other)?;
        }
        c.flush()
    })
    .with_context(|| format!("writing {}", path.display()))
}

/// The growth table on stdout (figures to 3–4 significant digits).
fn print_growth(j: &GrowJson) {
    println!(
        "trial-amplitude growth at {} km/h: reference wavelengths {} mm",
        sig(j.speed_kmh, 4),
        j.reference_wavelengths_mm
            .iter()
            .map(|&v| sig(v, 3))
            .collect::<Vec<_>>()
            .join(", ")
    );
    for (i, a) in j.amplitudes_um.iter().enumerate() {
        println!(
            "  2A_max {:>5} µm: {} (r = {:+.2}), consistent growth: {}, F_L band RMS {} N, F_N band RMS {} N",
            sig(*a, 4),
            j.phase[i],
            j.correlation[i],
            if j.grows_consistently[i] { "yes" } else { "no" },
            sig(j.fl_band_rms_n[i], 3),
            sig(j.fn_band_rms_n[i], 3)
        );
    }
    match j.limiting_amplitude_um {
        Some(a) => println!("  limiting amplitude (2A_max)_l = {} µm", sig(a, 4)),
        None => println!(
            "  limiting amplitude: none (the smallest trial amplitude does not grow consistently)"
        ),
    }
}

impl GrowCmd {
    pub fn run(self) -> anyhow::Result<()> {
        let t0 = Instant::now();
        if self.amplitudes_um.is_empty()
            || self
                .amplitudes_um
                .iter()
                .any(|a| !(a.is_finite() && *a > 0.0 && *a <= 5000.0))
        {
            anyhow::bail!(
                "--amplitudes-um must be a list of peak-to-trough amplitudes in (0, 5000] µm (got {:?})",
                self.amplitudes_um
            );
        }
        let m = self.model.load()?;
        super::check_out_dir(&self.out)?;
        let prepared = super::engine::prepared(&m, self.cache.as_deref())?;
        let modes = super::engine::mode_lines(&prepared);
        let explicit = match self.engine {
            super::engine::Engine::Explicit => Some(super::engine::explicit_model(&m)?),
            super::engine::Engine::Reduced => None,
        };
        let recorder: &dyn corrugation::dynamics::PassageRecorder = match &explicit {
            Some(e) => e,
            None => &prepared.engine,
        };
        let Some(g) = run_trial_growth(recorder, &m, &self.amplitudes_um, &modes)? else {
            let v = no_initiation_verdict(m.run.speed_kmh, None);
            let text = serde_json::to_string_pretty(&serde_json::json!({
                "speed_kmh": m.run.speed_kmh,
                "verdict": v,
            }))?;
            write_grow_json(&self.out, &text)?;
            if self.json {
                println!("{text}");
            } else {
                print_verdict(&v);
            }
            return Ok(());
        };
        let verdict = growth_verdict(
            &g,
            m.run.speed_kmh,
            &modes,
            Some(initiation_check(&m, &g.smooth)),
        );
        write_growth_files(&self.out, &g)?;
        let mut rounds = Vec::new();
        if self.rounds > 0 {
            let pb = super::progress::bar("iterative growth (rounds)");
            pb.set_length(self.rounds as u64);
            let (r, _) = iterative_growth(
                recorder,
                m.run.speed(),
                &IterativeOptions {
                    passages_per_round: self.passages_per_round,
                    max_rounds: self.rounds,
                    saturation: 0.01,
                    wear_coefficient_m3_per_j: m.wear.coefficient,
                },
                |r| pb.set_position(r.round as u64),
            )?;
            pb.finish_and_clear();
            let rows: Vec<Vec<f64>> = r
                .iter()
                .map(|r| {
                    vec![
                        r.round as f64,
                        r.passages as f64,
                        r.amplitude_um,
                        r.dominant_wavelength_mm.unwrap_or(f64::NAN),
                    ]
                })
                .collect();
            write_csv(
                &self.out.join("iterative.csv"),
                &[
                    "round",
                    "passages",
                    "amplitude_um",
                    "dominant_wavelength_mm",
                ],
                rows,
            )?;
            rounds = r;
        }
        let j = grow_json(
            &g,
            m.run.speed_kmh,
            rounds,
            verdict,
            t0.elapsed().as_secs_f64(),
        );
        let text = serde_json::to_string_pretty(&j)?;
        write_grow_json(&self.out, &text)?;
        if self.json {
            println!("{text}");
        } else {
            print_growth(&j);
            println!("  outputs in {}", self.out.display());
            print_verdict(&j.verdict);
        }
        Ok(())
    }
}
