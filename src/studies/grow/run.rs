//! One run of the `grow` product as a library call ([`run_grow`]): the coupled modes at the
//! speed, the growth-rate spectrum and its check against passages, the trial-amplitude growth
//! with its verdict, iterative rounds, and `grow.json` written last; with the checks of its
//! options ([`GrowOptions::check`], [`check_amplitudes`]). The caller prints.

use std::path::Path;
use std::time::Instant;

use super::{
    grow_json, growth_attribution, growth_rate, initiation_check, mode_lines, rate_check,
    rate_summary, trial_growth_if_any, write_grow_json, write_growth_files, write_growth_rate,
    GrowJson, RateCheck, RateSummary, DEFAULT_AMPLITUDES_UM,
};
use crate::dynamics::prepared::PreparedModel;
use crate::dynamics::PassageRecorder;
use crate::growth::procedure::{iterative_growth, GrowthRound, IterativeOptions, StoppedTrial};
use crate::growth::verdict::{growth_verdict, no_initiation_verdict, Verdict};
use crate::io::write_csv;
use crate::model::Model;
use crate::progress::Progress;
use crate::studies::coupled::{attribute_one, write_coupled_modes};
use crate::studies::StudiesError;
use crate::units::{mm_to_m, um_to_m};

/// Largest trial amplitude 2A_max accepted (µm): 5 mm peak-to-trough, far beyond any
/// corrugation (they are tens of µm).
pub(crate) const MAX_TRIAL_AMPLITUDE_UM: f64 = 5000.0;

/// Most rounds of iterative growth: each round runs one passage (about half a second on the
/// default model, so 1000 rounds take about 10 minutes).
pub(crate) const MAX_ROUNDS: usize = 1000;

/// Default passages per round of the iterative growth: a round's wear is one passage's
/// times this count.
pub const DEFAULT_PASSAGES_PER_ROUND: usize = 1000;

/// The wavelength range of the rate check (mm): the analysis band.
pub(crate) const RATE_CHECK_BAND_MM: [f64; 2] = [20.0, 80.0];

/// Checks trial amplitudes 2A_max (µm) given as `list` (the flag or key, for the message):
/// at least one, each finite and in (0, `MAX_TRIAL_AMPLITUDE_UM`], none twice.
pub fn check_amplitudes(list: &'static str, amplitudes_um: &[f64]) -> Result<(), StudiesError> {
    let bad = amplitudes_um
        .iter()
        .find(|a| !(a.is_finite() && **a > 0.0 && **a <= MAX_TRIAL_AMPLITUDE_UM));
    if amplitudes_um.is_empty() || bad.is_some() {
        return Err(StudiesError::Argument {
            flag: list,
            given: bad.map_or("an empty list".into(), |a| format!("{a} µm")),
            reason: format!(
                "outside (0, {MAX_TRIAL_AMPLITUDE_UM}] µm; give peak-to-trough amplitudes \
                 2A_max in µm, comma separated"
            ),
        });
    }
    crate::lists::check_no_repeats(list, "µm", amplitudes_um)?;
    Ok(())
}

/// What a grow run does besides the trial-amplitude growth.
#[derive(Debug, Clone, PartialEq)]
pub struct GrowOptions {
    /// Trial amplitudes 2A_max (µm); default [`DEFAULT_AMPLITUDES_UM`].
    pub amplitudes_um: Vec<f64>,
    /// Rounds of iterative growth, 0 (default: off) to `MAX_ROUNDS`.
    pub rounds: usize,
    /// Passages per round, at least 1; default [`DEFAULT_PASSAGES_PER_ROUND`].
    pub passages_per_round: usize,
    /// The growth-rate spectrum (default on).
    pub rate: bool,
    /// Wavelengths (mm, within `RATE_CHECK_BAND_MM`) at which the spectrum's linear theory
    /// is checked against passages over 1 µm sinusoidal corrugations; default none.
    pub rate_check_mm: Vec<f64>,
    /// The coupled wheel–track modes and the attribution of the selected frequencies
    /// (default on).
    pub coupled: bool,
}

impl Default for GrowOptions {
    fn default() -> Self {
        GrowOptions {
            amplitudes_um: DEFAULT_AMPLITUDES_UM.to_vec(),
            rounds: 0,
            passages_per_round: DEFAULT_PASSAGES_PER_ROUND,
            rate: true,
            rate_check_mm: Vec::new(),
            coupled: true,
        }
    }
}

impl GrowOptions {
    /// Checks every option against its range (named by the `grow` command's flags).
    pub fn check(&self) -> Result<(), StudiesError> {
        check_amplitudes("--amplitudes-um", &self.amplitudes_um)?;
        let [lo, hi] = RATE_CHECK_BAND_MM;
        if let Some(l) = self
            .rate_check_mm
            .iter()
            .find(|l| !(l.is_finite() && (lo..=hi).contains(*l)))
        {
            return Err(StudiesError::Argument {
                flag: "--rate-check",
                given: l.to_string(),
                reason: format!("wavelengths must lie in [{lo}, {hi}] mm"),
            });
        }
        crate::lists::check_no_repeats("--rate-check", "mm", &self.rate_check_mm)?;
        if self.passages_per_round == 0 {
            return Err(StudiesError::Argument {
                flag: "--passages-per-round",
                given: "0".into(),
                reason: "out of range, allowed at least 1 passage (a round's wear is one \
                         passage's times this count)"
                    .into(),
            });
        }
        if self.rounds > MAX_ROUNDS {
            return Err(StudiesError::Argument {
                flag: "--rounds",
                given: self.rounds.to_string(),
                reason: format!(
                    "out of range, at most {MAX_ROUNDS} rounds (0 = off; each round runs one \
                     passage, about half a second on the default model, so {MAX_ROUNDS} rounds \
                     take about 10 minutes)"
                ),
            });
        }
        Ok(())
    }
}

/// The growth-rate spectrum's part of a run.
#[derive(Debug, Clone)]
pub struct RatePart {
    /// The spectrum's sentence (its fastest wavelength and how many grow).
    pub sentence: String,
    /// Its summary with the fastest wavelength attributed to a coupled mode.
    pub summary: Option<RateSummary>,
}

/// What a grow run found, its files already written.
pub struct GrowRun {
    /// The growth-rate spectrum (with [`GrowOptions::rate`]).
    pub rate: Option<RatePart>,
    /// The rate checks (with [`GrowOptions::rate_check_mm`]).
    pub rate_checks: Vec<RateCheck>,
    /// The growth, or why there was none.
    pub outcome: GrowOutcome,
    /// `grow.json` as written.
    pub json_text: String,
}

/// The outcome of the trial-amplitude growth.
pub enum GrowOutcome {
    /// The smooth rail has no wear component in the band: no trial was run.
    NoInitiation {
        /// The verdict.
        verdict: Verdict,
    },
    /// The trials ran (all, or up to the one that failed).
    Grown {
        /// The `grow.json` object.
        json: Box<GrowJson>,
        /// The trial whose passage failed, if one did: the amplitudes below it are written.
        stopped: Option<StoppedTrial>,
    },
}

/// Runs the `grow` product on the prepared model `prepared` of `m` (the trial passages on
/// `recorder`: the reduced engine of `prepared` or another engine), writing its files into
/// `out` (created if missing; `grow.json` last). `started` is the run's start, for the time
/// `grow.json` reports (the whole run, the modal bases included).
pub fn run_grow(
    m: &Model,
    prepared: &PreparedModel,
    recorder: &dyn PassageRecorder,
    opts: &GrowOptions,
    out: &Path,
    started: Instant,
    progress: &dyn Progress,
) -> Result<GrowRun, StudiesError> {
    opts.check()?;
    std::fs::create_dir_all(out).map_err(StudiesError::io(out))?;
    let speed = m.run.speed();
    let coupled = if opts.coupled {
        let cm = prepared.coupled_modes(speed, &[])?;
        write_coupled_modes(out, &cm)?;
        cm.modes
    } else {
        Vec::new()
    };
    let rate = if opts.rate {
        let s = growth_rate(m, prepared, m.run.requested_speed(), progress)
            .map_err(StudiesError::RateSpectrum)?;
        progress.finish();
        write_growth_rate(out, &s)?;
        Some(RatePart {
            sentence: s.sentence(),
            summary: rate_summary(&s, &coupled),
        })
    } else {
        None
    };
    let rate_checks = if opts.rate_check_mm.is_empty() {
        Vec::new()
    } else {
        let l: Vec<f64> = opts.rate_check_mm.iter().map(|&v| mm_to_m(v)).collect();
        rate_check(prepared, speed, &l, um_to_m(1.0), out)?
    };
    let summary = rate.as_ref().and_then(|r| r.summary.clone());
    let modes = mode_lines(prepared);
    let g = trial_growth_if_any(recorder, speed, &opts.amplitudes_um, &modes, progress)?;
    progress.finish();
    let Some(g) = g else {
        let verdict = no_initiation_verdict(m.run.speed_kmh, None);
        let json_text = json_text(&serde_json::json!({
            "speed_kmh": m.run.speed_kmh,
            "verdict": verdict,
            "growth_rate": summary,
        }))?;
        write_grow_json(out, &json_text)?;
        return Ok(GrowRun {
            rate,
            rate_checks,
            outcome: GrowOutcome::NoInitiation { verdict },
            json_text,
        });
    };
    let strongest = attribute_one(&coupled, g.smooth.dominant_frequency_hz);
    let verdict = growth_verdict(
        &g,
        m.run.speed_kmh,
        &modes,
        Some(initiation_check(m, &g.smooth)),
        strongest.as_ref(),
    );
    write_growth_files(out, &g)?;
    let rounds = if opts.rounds > 0 {
        iterative(recorder, m, opts, out, progress)?
    } else {
        Vec::new()
    };
    let mut j = grow_json(
        &g,
        m.run.speed_kmh,
        rounds,
        verdict,
        started.elapsed().as_secs_f64(),
    );
    j.coupled = growth_attribution(&g, &coupled);
    j.growth_rate = summary;
    let json_text = json_text(&j)?;
    write_grow_json(out, &json_text)?;
    Ok(GrowRun {
        rate,
        rate_checks,
        outcome: GrowOutcome::Grown {
            json: Box::new(j),
            stopped: g.stopped.clone(),
        },
        json_text,
    })
}

fn json_text<T: serde::Serialize>(v: &T) -> Result<String, StudiesError> {
    serde_json::to_string_pretty(v).map_err(|source| StudiesError::Json {
        what: "grow.json",
        source,
    })
}

/// `opts.rounds` rounds of iterative growth, written to `iterative.csv`: round, passages,
/// amplitude (µm), dominant wavelength (mm).
fn iterative(
    recorder: &dyn PassageRecorder,
    m: &Model,
    opts: &GrowOptions,
    out: &Path,
    progress: &dyn Progress,
) -> Result<Vec<GrowthRound>, StudiesError> {
    progress.stage("iterative growth (rounds)", opts.rounds as u64);
    let (r, _) = iterative_growth(
        recorder,
        m.run.speed(),
        &IterativeOptions {
            passages_per_round: opts.passages_per_round,
            max_rounds: opts.rounds,
            saturation: 0.01,
            wear_coefficient_m3_per_j: m.wear.coefficient,
        },
        |r| progress.done(r.round as u64),
    )?;
    progress.finish();
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
    let path = out.join("iterative.csv");
    write_csv(
        &path,
        &[
            "round",
            "passages",
            "amplitude_um",
            "dominant_wavelength_mm",
        ],
        rows,
    )
    .map_err(StudiesError::io(&path))?;
    Ok(r)
}
