//! The consistency table and the growth phase (docs/theory.md §10.2–§10.3).
//!
//! ## Matching
//! For each reference component `λ_ref,j` (the wavelengths of the trial corrugation = those of
//! the initial wear) and each signal (`W_f`, `F_L`, `F_N` of the new passage) the *nearest*
//! peak is taken, nearest in relative deviation `d = |λ − λ_ref,j| / λ_ref,j`
//! ([`crate::spectral::relative_deviation`]). A peak may be the nearest to several
//! references; a signal without peaks gives no match (`None`), which counts as inconsistent.
//!
//! ## Classification (thresholds `strong` = 1 %, `consistent` = 3 % by default)
//! A signal is *consistent* with the reference if `d ≤ consistent`. Then
//! - **Case 1**: all three signals consistent;
//! - **Case 2**: exactly two consistent (any two; which two is recorded);
//! - otherwise no case: class **grey** (inconsistent).
//!
//! Within Case 1 or Case 2 the strength is set by the **largest deviation among the consistent
//! signals of that case** (the *governing deviation*): `≤ strong` → **light green** (strong),
//! otherwise (`strong < d ≤ consistent`) → **dark green** (weaker). So Case 1 with deviations
//! 0.5 %, 0.8 %, 2 % is dark green; Case 2 with 0.5 %, 0.8 % and an inconsistent 10 % is light
//! green (the inconsistent signal is what makes it Case 2, not Case 1).
//!
//! **Boundaries** are inclusive: exactly 1 % is strong, exactly 3 % is consistent. To make a
//! deviation that is exactly 1 % or 3 % in decimal count as such despite binary rounding
//! (e.g. |0.0412 − 0.04|/0.04 = 0.030000000000000027), comparisons use `d ≤ t + 1e-12`.
//!
//! ## Growth phase
//! The corrugation is `h = −c W_band,initial`. The new differential wear grows the
//! corrugation when it is in phase with the initial wear, i.e. in **anti-phase** with the
//! corrugation (a new wear peak deepens an existing trough). The test is the sign of the
//! Pearson correlation `r` of the band-passed new wear with the corrugation height on the
//! same grid: `r ≤ −r₀` → anti-phase (growing), `r ≥ r₀` → in-phase (decaying), `|r| < r₀` →
//! indeterminate, with `r₀ = 0.2` by default (below that the phase relation is too weak
//! to call: for two band-limited records of ≈ 1 m with tens of effective degrees of freedom,
//! |r| ≈ 0.2 is about the level reached by chance).

use super::GrowthError;
use crate::spectral::{correlation_coefficient, relative_deviation, Peak, Signal};
use serde::{Deserialize, Serialize};

/// Rounding allowance for the inclusive threshold comparisons (dimensionless).
const BOUNDARY_EPS: f64 = 1e-12;

/// Deviation thresholds of the consistency table (dimensionless ratios).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ConsistencyThresholds {
    /// At or below: strong ("light green"). Default 0.01.
    pub strong: f64,
    /// At or below: consistent ("dark green" if above `strong`). Default 0.03.
    pub consistent: f64,
}

impl Default for ConsistencyThresholds {
    fn default() -> Self {
        Self {
            strong: 0.01,
            consistent: 0.03,
        }
    }
}

impl ConsistencyThresholds {
    fn validate(&self) -> Result<(), GrowthError> {
        if !self.strong.is_finite() || self.strong < 0.0 {
            return Err(GrowthError::BadThreshold {
                what: "strong",
                value: self.strong,
                reason: "must be finite and >= 0",
            });
        }
        if !self.consistent.is_finite() || self.consistent < self.strong {
            return Err(GrowthError::BadThreshold {
                what: "consistent",
                value: self.consistent,
                reason: "must be finite and >= strong",
            });
        }
        Ok(())
    }
}

/// Which case of the table a reference component falls in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ConsistencyCase {
    /// All three signals within `consistent`.
    Case1,
    /// Exactly two signals within `consistent`.
    Case2,
    /// Fewer than two: inconsistent.
    None,
}

/// Colour class of a table cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ConsistencyClass {
    /// Governing deviation ≤ `strong` (1 %).
    LightGreen,
    /// Governing deviation in (`strong`, `consistent`] (1–3 %).
    DarkGreen,
    /// Inconsistent.
    Grey,
}

/// The nearest peak of one signal to a reference component.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub(crate) struct ComponentMatch {
    /// Wavelength of the matched peak, m (`None`: the signal has no peaks).
    pub wavelength_m: Option<f64>,
    /// Frequency `v/λ` of the matched peak, Hz.
    pub frequency_hz: Option<f64>,
    /// Relative deviation from the reference wavelength (dimensionless).
    pub deviation: Option<f64>,
}

/// One row of the consistency table (flat, so it serialises to one CSV line; `None` fields
/// are empty cells).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConsistencyRow {
    /// Peak-to-trough `2A_max` of the trial corrugation of this passage, m.
    pub two_a_max_m: f64,
    /// Index `j` of the reference component.
    pub reference_index: usize,
    /// Reference wavelength `λ_ref,j`, m.
    pub reference_wavelength_m: f64,
    /// Matched wavelength of the differential wear `W_f`, m.
    pub wf_wavelength_m: Option<f64>,
    /// Frequency of the matched `W_f` component, Hz.
    pub wf_frequency_hz: Option<f64>,
    /// Deviation of the `W_f` component.
    pub wf_deviation: Option<f64>,
    /// Matched wavelength of the longitudinal force `F_L`, m.
    pub fl_wavelength_m: Option<f64>,
    /// Frequency of the matched `F_L` component, Hz.
    pub fl_frequency_hz: Option<f64>,
    /// Deviation of the `F_L` component.
    pub fl_deviation: Option<f64>,
    /// Matched wavelength of the normal force `F_N`, m.
    pub fn_wavelength_m: Option<f64>,
    /// Frequency of the matched `F_N` component, Hz.
    pub fn_frequency_hz: Option<f64>,
    /// Deviation of the `F_N` component.
    pub fn_deviation: Option<f64>,
    /// Case 1 / Case 2 / none.
    pub case: ConsistencyCase,
    /// Colour class.
    pub class: ConsistencyClass,
    /// The consistent signals, e.g. `"W_f+F_L"` (empty if none).
    pub consistent_signals: String,
    /// Largest deviation among the consistent signals of the case (sets the class).
    pub governing_deviation: Option<f64>,
}

/// Phase relation of the new wear to the corrugation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PhaseRelation {
    /// New wear in anti-phase with the corrugation (in phase with the initial wear): growing.
    AntiPhase,
    /// New wear in phase with the corrugation: decaying.
    InPhase,
    /// `|r|` below the threshold: no call.
    Indeterminate,
}

/// Growth-phase result.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GrowthPhase {
    /// Pearson correlation of the new wear with the corrugation height.
    pub correlation: f64,
    /// Threshold `r₀` used.
    pub threshold: f64,
    /// The phase relation.
    pub relation: PhaseRelation,
    /// `Some(true)` growing (anti-phase), `Some(false)` decaying (in-phase), `None`
    /// indeterminate.
    pub growing: Option<bool>,
}

/// The peak of `peaks` nearest (in relative deviation) to `reference_wavelength_m` (m).
pub(crate) fn match_nearest(
    reference_wavelength_m: f64,
    peaks: &[Peak],
) -> Result<ComponentMatch, GrowthError> {
    let mut best: Option<(f64, &Peak)> = None;
    for p in peaks {
        let d = relative_deviation(p.wavelength_m, reference_wavelength_m)?;
        if best.is_none_or(|(bd, _)| d < bd) {
            best = Some((d, p));
        }
    }
    Ok(match best {
        Some((d, p)) => ComponentMatch {
            wavelength_m: Some(p.wavelength_m),
            frequency_hz: Some(p.frequency_hz),
            deviation: Some(d),
        },
        None => ComponentMatch {
            wavelength_m: None,
            frequency_hz: None,
            deviation: None,
        },
    })
}

/// Classify the deviations of (`W_f`, `F_L`, `F_N`) (see the module doc). Returns the case,
/// the class, the indices of the consistent signals and the governing deviation.
pub fn classify(
    deviations: [Option<f64>; 3],
    thresholds: &ConsistencyThresholds,
) -> Result<(ConsistencyCase, ConsistencyClass, Vec<usize>, Option<f64>), GrowthError> {
    thresholds.validate()?;
    let ok: Vec<usize> = (0..3)
        .filter(|&i| deviations[i].is_some_and(|d| d <= thresholds.consistent + BOUNDARY_EPS))
        .collect();
    let case = match ok.len() {
        3 => ConsistencyCase::Case1,
        2 => ConsistencyCase::Case2,
        _ => ConsistencyCase::None,
    };
    if case == ConsistencyCase::None {
        return Ok((case, ConsistencyClass::Grey, ok, None));
    }
    let gov = ok.iter().filter_map(|&i| deviations[i]).fold(0.0, f64::max);
    let class = if gov <= thresholds.strong + BOUNDARY_EPS {
        ConsistencyClass::LightGreen
    } else {
        ConsistencyClass::DarkGreen
    };
    Ok((case, class, ok, Some(gov)))
}

/// Build the consistency table of one passage (trial amplitude `two_a_max_m`, m): one row per
/// reference wavelength (m), matching the peaks of `W_f`, `F_L` and `F_N`.
pub(crate) fn consistency_table(
    two_a_max_m: f64,
    reference_wavelengths_m: &[f64],
    wear_peaks: &[Peak],
    longitudinal_force_peaks: &[Peak],
    normal_force_peaks: &[Peak],
    thresholds: &ConsistencyThresholds,
) -> Result<Vec<ConsistencyRow>, GrowthError> {
    thresholds.validate()?;
    if reference_wavelengths_m.is_empty() {
        return Err(GrowthError::EmptyReference);
    }
    const NAMES: [&str; 3] = ["W_f", "F_L", "F_N"];
    let mut rows = Vec::with_capacity(reference_wavelengths_m.len());
    for (j, &lam) in reference_wavelengths_m.iter().enumerate() {
        if !(lam.is_finite() && lam > 0.0) {
            return Err(GrowthError::BadReference {
                index: j,
                value: lam,
            });
        }
        let m = [
            match_nearest(lam, wear_peaks)?,
            match_nearest(lam, longitudinal_force_peaks)?,
            match_nearest(lam, normal_force_peaks)?,
        ];
        let (case, class, ok, gov) =
            classify([m[0].deviation, m[1].deviation, m[2].deviation], thresholds)?;
        let consistent_signals = ok.iter().map(|&i| NAMES[i]).collect::<Vec<_>>().join("+");
        rows.push(ConsistencyRow {
            two_a_max_m,
            reference_index: j,
            reference_wavelength_m: lam,
            wf_wavelength_m: m[0].wavelength_m,
            wf_frequency_hz: m[0].frequency_hz,
            wf_deviation: m[0].deviation,
            fl_wavelength_m: m[1].wavelength_m,
            fl_frequency_hz: m[1].frequency_hz,
            fl_deviation: m[1].deviation,
            fn_wavelength_m: m[2].wavelength_m,
            fn_frequency_hz: m[2].frequency_hz,
            fn_deviation: m[2].deviation,
            case,
            class,
            consistent_signals,
            governing_deviation: gov,
        });
    }
    Ok(rows)
}

/// Growth phase of the band-passed new wear against the corrugation height (same grid), with
/// indeterminate band `|r| < threshold` (`threshold` in [0, 1), default choice 0.2).
pub(crate) fn growth_phase(
    new_wear_band: &Signal,
    corrugation_height: &Signal,
    threshold: f64,
) -> Result<GrowthPhase, GrowthError> {
    if !(0.0..1.0).contains(&threshold) {
        return Err(GrowthError::BadThreshold {
            what: "threshold",
            value: threshold,
            reason: "must be in [0, 1)",
        });
    }
    let r = correlation_coefficient(new_wear_band, corrugation_height)?;
    let (relation, growing) = if r <= -threshold && r < 0.0 {
        (PhaseRelation::AntiPhase, Some(true))
    } else if r >= threshold && r > 0.0 {
        (PhaseRelation::InPhase, Some(false))
    } else {
        (PhaseRelation::Indeterminate, None)
    };
    Ok(GrowthPhase {
        correlation: r,
        threshold,
        relation,
        growing,
    })
}

#[cfg(test)]
mod tests;
