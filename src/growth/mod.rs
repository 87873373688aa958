//! Growth analysis: trial corrugations, the consistency table and the growth phase
//! (docs/theory.md §2.2 b–d and §10).
//!
//! - [`trial`]: the trial corrugation `h(x) = −c · W_band(x)` with `c` such that the
//!   peak-to-trough of `h` is `2A_max` (docs/theory.md §10.1).
//! - [`consistency`]: matching the wavelength components of `W_f`, `F_L`, `F_N` of a new
//!   passage to the reference components, the Case 1 / Case 2 / grey classification, and the
//!   growth phase (sign of the correlation of the new wear with the corrugation).
//! - [`verdict`]: the plain-language verdict of a trial-amplitude growth.
//! - [`rate`]: the growth-rate spectrum, the linear wear response to a small sinusoidal
//!   roughness per wavelength (docs/theory.md §10.6).
//!
//! Lengths are metres, frequencies Hz; deviations are dimensionless ratios (0.03 = 3 %).

pub mod consistency;
pub mod procedure;
pub mod rate;
pub mod trial;
pub mod verdict;

pub use consistency::{
    classify, ConsistencyCase, ConsistencyClass, ConsistencyRow, ConsistencyThresholds,
    GrowthPhase, PhaseRelation,
};
pub(crate) use consistency::{consistency_table, growth_phase};
pub(crate) use trial::trial_corrugation;

use crate::spectral::SpectralError;

/// Errors of the growth analysis. Each variant says what to change.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GrowthError {
    /// An error from the spectral toolkit (grid mismatch, zero variance, …).
    #[error(transparent)]
    Spectral(#[from] SpectralError),
    /// No reference wavelength components were given.
    #[error("no reference wavelength components: give at least one λ_ref")]
    EmptyReference,
    /// A reference wavelength is not finite and positive.
    #[error("reference wavelength {index} is {value} m: must be finite and > 0")]
    BadReference {
        /// Index of the reference component.
        index: usize,
        /// The value given, m.
        value: f64,
    },
    /// Thresholds must satisfy 0 ≤ strong ≤ consistent (or 0 ≤ indeterminate band < 1).
    #[error("bad threshold {what} = {value}: {reason}")]
    BadThreshold {
        /// Which threshold.
        what: &'static str,
        /// Its value.
        value: f64,
        /// The rule it breaks.
        reason: &'static str,
    },
    /// The wear signal is flat (zero peak-to-trough): no corrugation can be scaled from it.
    #[error(
        "band-passed wear has zero peak-to-trough: no trial corrugation can be scaled from it"
    )]
    FlatWear,
    /// The requested trial amplitude is not finite and ≥ 0.
    #[error("trial peak-to-trough 2A_max = {value} m: must be finite and >= 0")]
    BadAmplitude {
        /// The value given, m.
        value: f64,
    },
}
