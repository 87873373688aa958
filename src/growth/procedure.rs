//! The growth procedures on top of the passage engine (docs/theory.md §2.2 and §10).
//!
//! **Trial-amplitude growth (the reference procedure).** One passage on the smooth rail gives
//! the initial differential wear `W_band` (20–80 mm) and its wavelength components, the
//! references λ_ref. For each trial amplitude `2A_max` the rail gets the trial corrugation
//! `h = −c·W_band` (peak-to-trough 2A_max, `super::trial_corrugation`) and one passage is
//! run over it. For each amplitude:
//! - the components of `W_f`, `F_L`, `F_N` matched to λ_ref, their deviations and the
//!   consistency table (Case 1 / Case 2, ≤ 1 % light green, 1–3 % dark green, else grey;
//!   `super::consistency_table`);
//! - the growth phase: the correlation of the new band-passed wear with the corrugation
//!   height; anti-phase (r ≤ −0.2) = the wear digs the troughs deeper = growing
//!   (`super::growth_phase`);
//! - *consistent growth* = growing phase **and** at least one reference component in
//!   Case 1 or Case 2.
//!
//! The limiting amplitude `(2A_max)_l` is the largest amplitude of the ascending list up to
//! which every amplitude grows consistently (`None` if the smallest already does not).
//! Every component's frequency is also compared with the nearest longitudinal-compression
//! and vertical-bending eigenfrequencies of the track and the nearest wheel mode the contact
//! sees (the relative "difference", docs/theory.md §9.5).
//!
//! **Iterative growth (beyond the reference).** Round after round, the wear of `N`
//! passages is removed from the rail: depth `Δh(x) = −N·k·W_f(x)/(2b)` (m), with `k`
//! (m³/J) the volume worn per joule of frictional work (`wear.coefficient`), `W_f(x)` the
//! frictional work per metre of rail (J/m) of the last passage and `2b` the static contact
//! width (m). Only the band-passed part shapes corrugation; the mean wear is a uniform
//! lowering and is removed. `k` ≈ 1e-13 m³/J corresponds to an Archard coefficient
//! K ≈ 1e-4 (mild wear) on rail steel of hardness H ≈ 3 GPa at µ = 0.4 (k = K/(µH)). The amplitude (peak-to-trough) and the dominant wavelengths are
//! recorded each round, until the amplitude saturates (relative change below a tolerance)
//! or the round limit.

use serde::Serialize;

use super::{
    consistency_table, growth_phase, trial_corrugation, ConsistencyRow, ConsistencyThresholds,
    GrowthError, GrowthPhase,
};
use crate::dynamics::PassageRecorder;
use crate::passage::analysis::{analyse, wear_signal, zone_signal, Analysed};
use crate::passage::record::PassageRecord;
use crate::passage::summary::{PassageSummary, WavelengthComponent};
use crate::passage::{PassageError, RailProfile};
use crate::spectral::{band_pass, relative_difference, BandPass, Signal};
use crate::units::Speed;

/// Errors of the growth procedures.
#[derive(Debug, thiserror::Error)]
pub enum ProcedureError {
    /// A passage failed.
    #[error(transparent)]
    Passage(#[from] PassageError),
    /// The growth analysis failed.
    #[error(transparent)]
    Growth(#[from] GrowthError),
    /// The smooth rail left no differential wear to build a trial corrugation from.
    #[error("the smooth-rail passage left no wear component in 20–80 mm: nothing to grow (try RPM3/RPM4, a longer solution zone or a finer contact grid)")]
    NoReference,
}

/// A component compared with the nearest eigenfrequencies of two families.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EigenComparison {
    /// Signal: "W_f", "F_L" or "F_N".
    pub signal: String,
    /// Trial amplitude 2A_max (µm; 0 for the smooth rail).
    pub amplitude_um: f64,
    /// Component wavelength (mm).
    pub wavelength_mm: f64,
    /// Component frequency (Hz).
    pub frequency_hz: f64,
    /// Nearest longitudinal-compression eigenfrequency (Hz).
    pub nearest_longitudinal_hz: Option<f64>,
    /// Relative difference to it (−).
    pub longitudinal_difference: Option<f64>,
    /// Nearest vertical-bending eigenfrequency (Hz).
    pub nearest_vertical_hz: Option<f64>,
    /// Relative difference to it (−).
    pub vertical_difference: Option<f64>,
    /// Nearest wheel mode the contact sees (Hz).
    pub nearest_wheel_hz: Option<f64>,
    /// Relative difference to it (−).
    pub wheel_difference: Option<f64>,
}

/// One trial amplitude.
#[derive(Clone, Debug, Serialize)]
pub struct AmplitudeResult {
    /// 2A_max (µm).
    pub amplitude_um: f64,
    /// The passage summary over the trial corrugation.
    pub summary: PassageSummary,
    /// Growth phase of the new wear relative to the corrugation.
    pub phase: GrowthPhase,
    /// Consistency table rows (one per reference component).
    pub rows: Vec<ConsistencyRow>,
    /// Growing phase and at least one reference in Case 1 or Case 2.
    pub grows_consistently: bool,
}

/// The result of the trial-amplitude procedure.
#[derive(Clone, Debug, Serialize)]
pub struct TrialGrowth {
    /// Smooth-rail passage.
    pub smooth: PassageSummary,
    /// Reference wavelengths (m): the smooth-rail wear components.
    pub reference_wavelengths_m: Vec<f64>,
    /// Per amplitude, ascending.
    pub amplitudes: Vec<AmplitudeResult>,
    /// Limiting amplitude (µm), see the module doc.
    pub limiting_amplitude_um: Option<f64>,
    /// Components vs eigenfrequencies.
    pub eigen: Vec<EigenComparison>,
    /// The band-passed smooth-rail wear (x in m, J/m), the shape of every trial corrugation.
    pub smooth_wear_band: Signal,
    /// The trial amplitude whose passage failed, if one did: the procedure stops there (the
    /// larger amplitudes are not run) and keeps the amplitudes below it. `None` when every
    /// amplitude ran.
    pub stopped: Option<StoppedTrial>,
}

/// A trial amplitude whose passage failed (e.g. the contact patch outgrew the contact grid
/// under the dynamic load of a deep corrugation).
#[derive(Clone, Debug, Serialize)]
pub struct StoppedTrial {
    /// 2A_max of the failed trial (µm).
    pub amplitude_um: f64,
    /// The passage's error, with what to change.
    pub reason: String,
}

/// Eigenfrequencies of the mode families the components are compared with (Hz).
#[derive(Clone, Debug, Default)]
pub struct ModeLines {
    /// Longitudinal-compression modes of the track (Hz).
    pub longitudinal_hz: Vec<f64>,
    /// Vertical-bending modes of the track (Hz).
    pub vertical_hz: Vec<f64>,
    /// Wheel modes the contact sees (Hz; e.g.
    /// [`crate::dynamics::prepared::PreparedModel::wheel_contact_modes_hz`]).
    pub wheel_hz: Vec<f64>,
}

fn nearest(f: f64, list: &[f64]) -> (Option<f64>, Option<f64>) {
    let best = list
        .iter()
        .copied()
        .min_by(|a, b| (a - f).abs().total_cmp(&(b - f).abs()));
    match best {
        Some(b) => (Some(b), relative_difference(f, b).ok()),
        None => (None, None),
    }
}

fn compare(
    signal: &str,
    amplitude_um: f64,
    comps: &[WavelengthComponent],
    modes: &ModeLines,
    out: &mut Vec<EigenComparison>,
) {
    for c in comps {
        let (lh, ld) = nearest(c.frequency_hz, &modes.longitudinal_hz);
        let (vh, vd) = nearest(c.frequency_hz, &modes.vertical_hz);
        let (wh, wd) = nearest(c.frequency_hz, &modes.wheel_hz);
        out.push(EigenComparison {
            signal: signal.into(),
            amplitude_um,
            wavelength_mm: c.wavelength_mm,
            frequency_hz: c.frequency_hz,
            nearest_longitudinal_hz: lh,
            longitudinal_difference: ld,
            nearest_vertical_hz: vh,
            vertical_difference: vd,
            nearest_wheel_hz: wh,
            wheel_difference: wd,
        });
    }
}

/// The three analysed signals of a record: (wear, F_L, F_N).
pub(crate) fn analyse_record(
    rec: &PassageRecord,
) -> Result<(Analysed, Analysed, Analysed), PassageError> {
    let v = rec.speed_m_per_s;
    Ok((
        analyse(&wear_signal(rec)?, v)?,
        analyse(&zone_signal(rec, &rec.histories.longitudinal_n)?, v)?,
        analyse(&zone_signal(rec, &rec.histories.normal_n)?, v)?,
    ))
}

/// Runs the trial-amplitude procedure at `speed_m_per_s` for the amplitudes `2A_max` (µm,
/// any order; run ascending). `on_passage` is called after each passage (for progress).
/// A failed smooth-rail passage is an error; a failed trial passage stops the procedure at
/// that amplitude ([`TrialGrowth::stopped`]) and keeps the amplitudes that ran.
pub fn trial_growth(
    engine: &dyn PassageRecorder,
    speed_m_per_s: f64,
    amplitudes_um: &[f64],
    modes: &ModeLines,
    mut on_passage: impl FnMut(usize),
) -> Result<TrialGrowth, ProcedureError> {
    let thresholds = ConsistencyThresholds::default();
    let rec0 = engine.record(Speed::from_m_per_s(speed_m_per_s), None)?;
    on_passage(0);
    let smooth = crate::passage::analysis::summarise(&rec0)?;
    let (w0, _, _) = analyse_record(&rec0)?;
    let reference: Vec<f64> = w0.raw_peaks.iter().map(|p| p.wavelength_m).collect();
    if reference.is_empty() {
        return Err(ProcedureError::NoReference);
    }
    let mut eigen = Vec::new();
    compare("W_f", 0.0, &smooth.wear_components, modes, &mut eigen);
    compare("F_L", 0.0, &smooth.fl_components, modes, &mut eigen);
    compare("F_N", 0.0, &smooth.fn_components, modes, &mut eigen);
    let mut amps: Vec<f64> = amplitudes_um.to_vec();
    amps.sort_by(f64::total_cmp);
    let mut results = Vec::with_capacity(amps.len());
    let mut stopped = None;
    for (k, &a_um) in amps.iter().enumerate() {
        let trial = trial_corrugation(&w0.band, crate::units::um_to_m(a_um))?;
        let x: Vec<f64> = (0..trial.height.len())
            .map(|i| trial.height.x_m(i))
            .collect();
        let profile = RailProfile::new(x, trial.height.values.clone())?;
        let rec = match engine.record(Speed::from_m_per_s(speed_m_per_s), Some(&profile)) {
            Ok(rec) => rec,
            Err(e) => {
                stopped = Some(StoppedTrial {
                    amplitude_um: a_um,
                    reason: e.to_string(),
                });
                break;
            }
        };
        on_passage(k + 1);
        let summary = crate::passage::analysis::summarise(&rec)?;
        let (w, fl, fnn) = analyse_record(&rec)?;
        let rows = consistency_table(
            trial.two_a_max_m,
            &reference,
            &w.raw_peaks,
            &fl.raw_peaks,
            &fnn.raw_peaks,
            &thresholds,
        )?;
        let phase = growth_phase(&w.band, &trial.height, 0.2)?;
        let grows_consistently = phase.growing == Some(true)
            && rows.iter().any(|r| r.case != super::ConsistencyCase::None);
        compare("W_f", a_um, &summary.wear_components, modes, &mut eigen);
        compare("F_L", a_um, &summary.fl_components, modes, &mut eigen);
        compare("F_N", a_um, &summary.fn_components, modes, &mut eigen);
        results.push(AmplitudeResult {
            amplitude_um: a_um,
            summary,
            phase,
            rows,
            grows_consistently,
        });
    }
    let limiting_amplitude_um = results
        .iter()
        .take_while(|r| r.grows_consistently)
        .last()
        .map(|r| r.amplitude_um);
    Ok(TrialGrowth {
        smooth,
        reference_wavelengths_m: reference,
        amplitudes: results,
        limiting_amplitude_um,
        eigen,
        smooth_wear_band: w0.band,
        stopped,
    })
}

/// One round of the iterative growth.
#[derive(Clone, Debug, Serialize)]
pub struct GrowthRound {
    /// Round number (1 = after the first N passages).
    pub round: usize,
    /// Passages so far.
    pub passages: usize,
    /// Peak-to-trough of the band-passed rail profile in the solution zone (µm).
    pub amplitude_um: f64,
    /// Dominant wavelength of the wear of the last passage (mm).
    pub dominant_wavelength_mm: Option<f64>,
    /// Wear components of the last passage.
    pub wear_components: Vec<WavelengthComponent>,
}

/// Iterative growth settings.
#[derive(Clone, Copy, Debug)]
pub struct IterativeOptions {
    /// Passages per round N (−).
    pub passages_per_round: usize,
    /// Maximum number of rounds.
    pub max_rounds: usize,
    /// Stop when the amplitude changes by less than this fraction in a round (−).
    pub saturation: f64,
    /// Wear coefficient k (m³/J).
    pub wear_coefficient_m3_per_j: f64,
}

/// Iterative growth from the smooth rail (see the module doc). Returns the rounds and the
/// final rail profile.
pub fn iterative_growth(
    engine: &dyn PassageRecorder,
    speed_m_per_s: f64,
    opts: &IterativeOptions,
    mut on_round: impl FnMut(&GrowthRound),
) -> Result<(Vec<GrowthRound>, RailProfile), ProcedureError> {
    let width = 2.0 * engine.hertz_b_m();
    let mut profile: Option<RailProfile> = None;
    let mut rounds = Vec::new();
    let mut last_amp = 0.0;
    for round in 1..=opts.max_rounds {
        let rec = engine.record(Speed::from_m_per_s(speed_m_per_s), profile.as_ref())?;
        let w = wear_signal(&rec)?;
        let wb = band_pass(&w, &BandPass::default()).map_err(GrowthError::from)?;
        let scale = opts.passages_per_round as f64 * opts.wear_coefficient_m3_per_j / width;
        let x: Vec<f64> = (0..wb.len()).map(|i| wb.x_m(i)).collect();
        let mut h: Vec<f64> = match &profile {
            Some(p) => x.iter().map(|&xi| p.height_at(xi)).collect(),
            None => vec![0.0; x.len()],
        };
        for (hi, wi) in h.iter_mut().zip(&wb.values) {
            *hi -= scale * wi;
        }
        let hs = Signal::new(x[0], wb.dx_m, h.clone()).map_err(GrowthError::from)?;
        let hb = band_pass(&hs, &BandPass::default()).map_err(GrowthError::from)?;
        let (lo, hi) = hb
            .values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, u), &v| {
                (l.min(v), u.max(v))
            });
        let amp = hi - lo;
        let an = analyse(&w, speed_m_per_s)?;
        let r = GrowthRound {
            round,
            passages: round * opts.passages_per_round,
            amplitude_um: crate::units::m_to_um(amp),
            dominant_wavelength_mm: an.peaks.first().map(|c| c.wavelength_mm),
            wear_components: an.peaks,
        };
        on_round(&r);
        rounds.push(r);
        profile = Some(RailProfile::new(x, hb.values)?);
        if round > 1 && (amp - last_amp).abs() <= opts.saturation * amp.abs().max(f64::MIN_POSITIVE)
        {
            break;
        }
        last_amp = amp;
    }
    let profile = profile.ok_or(ProcedureError::NoReference)?;
    Ok((rounds, profile))
}
