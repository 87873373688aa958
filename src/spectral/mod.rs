//! Spectral analysis of signals along the rail.
//!
//! This module turns signals along the rail (differential wear `W_f`, longitudinal contact force
//! `F_L`, normal force `F_N`, rail-top height) into the quantities the corrugation analysis is
//! judged on (docs/theory.md §6.6 and §9):
//!
//! - [`signal`]: a signal sampled uniformly along the rail (`x0_m`, `dx_m`, values); time maps to
//!   position by `x = v t`; linear resampling of irregular samples (contact forces at time
//!   steps) onto a uniform grid.
//! - [`filter`]: mean and linear-trend removal and the zero-phase band-pass in the wavelength
//!   domain (default 20–80 mm), done in the FFT domain on a mirror-extended record.
//! - [`psd`]: one-sided PSD against wavenumber `κ = 1/λ` (cycles per metre), with a Hann window
//!   and zero padding, and its frequency-domain form `f = v κ`; peak finding with sub-bin
//!   (quadratic-in-log) interpolation.
//! - [`correlation`]: normalised correlation at zero lag, cross-spectral phase at a wavelength,
//!   lag of maximum correlation.
//! - [`deviation`]: the relative deviation `|λ − λ_ref| / λ_ref` (and the same ratio, called a
//!   *difference*, against another reference such as an eigenfrequency).
//!
//! ## Short records (docs/theory.md §9.2)
//! A solution zone of length `L` (0.5–1 m) has an intrinsic wavenumber resolution
//! `Δκ = 1/L`. For `L = 1 m`, `Δκ = 1 m⁻¹`; at `λ = 40 mm` (`κ = 25 m⁻¹`) the neighbouring
//! resolvable wavenumbers are 24 and 26 m⁻¹, i.e. `λ = 41.7` and `38.5 mm`: a wavelength
//! resolution `Δλ ≈ λ² Δκ = 1.6 mm` (4 %). With the Hann window two components must be about
//! `2/L` apart to be separated (3.2 mm at 40 mm). Zero padding only interpolates the spectrum;
//! it does not add resolution, but together with the quadratic interpolation it locates an
//! *isolated* peak to far better than one bin (tests: < 0.5 % of λ, measured ≲ 0.05 %).
//! See [`psd::wavelength_resolution_m`].
//!
//! All lengths are metres, wavenumbers cycles per metre (m⁻¹), frequencies Hz, speeds m/s.

pub mod correlation;
pub mod deviation;
pub mod filter;
pub mod nodal;
pub mod psd;
pub mod signal;

pub use correlation::{
    correlation_coefficient, cross_phase_rad, lag_of_max_correlation, LagResult,
};
pub use deviation::{relative_deviation, relative_difference};
pub use filter::{band_pass, detrend, BandPass};
pub use psd::{
    find_peaks, wavelength_resolution_m, FrequencyPsd, Peak, PeakOptions, Psd, PsdOptions,
};
pub use signal::{resample_linear, Signal};

/// Errors of the spectral toolkit. Each variant says what to change.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SpectralError {
    /// The record has too few samples for the operation.
    #[error("signal has {len} samples, need at least {min}: use a longer record")]
    TooShort {
        /// Number of samples given.
        len: usize,
        /// Minimum required.
        min: usize,
    },
    /// A value (sample, coordinate or parameter) is NaN or infinite.
    #[error("non-finite value in {what} at index {index}: clean the input")]
    NonFinite {
        /// Which input.
        what: &'static str,
        /// Index of the first offending value.
        index: usize,
    },
    /// A sample spacing, speed, length or other strictly positive parameter is not positive.
    #[error("{what} must be finite and > 0, got {value}")]
    NotPositive {
        /// Which parameter.
        what: &'static str,
        /// The value given.
        value: f64,
    },
    /// The wavelength band is empty or not resolvable on this grid.
    #[error("bad wavelength band [{lambda_min_m} m, {lambda_max_m} m]: {reason}")]
    BadBand {
        /// Shortest wavelength of the band, m.
        lambda_min_m: f64,
        /// Longest wavelength of the band, m.
        lambda_max_m: f64,
        /// What is wrong.
        reason: &'static str,
    },
    /// Two signals that must share a grid do not.
    #[error("signals are on different grids ({reason}): resample one onto the other first")]
    GridMismatch {
        /// What differs.
        reason: &'static str,
    },
    /// Irregular sample positions are not strictly increasing.
    #[error("sample positions must be strictly increasing; x[{index}] <= x[{index} - 1]")]
    NotIncreasing {
        /// Index of the first offending position.
        index: usize,
    },
    /// A requested grid extends beyond the data range (no extrapolation is done).
    #[error("requested x range [{from_m}, {to_m}] m exceeds the data range [{data_from_m}, {data_to_m}] m")]
    OutOfRange {
        /// Start of the requested range, m.
        from_m: f64,
        /// End of the requested range, m.
        to_m: f64,
        /// Start of the data, m.
        data_from_m: f64,
        /// End of the data, m.
        data_to_m: f64,
    },
    /// A signal has zero variance where a normalisation needs it.
    #[error("{what} has zero variance: a constant signal has no correlation or phase")]
    ZeroVariance {
        /// Which signal.
        what: &'static str,
    },
    /// A reference value for a relative deviation is zero.
    #[error("reference value is zero: a relative deviation needs a non-zero reference")]
    ZeroReference,
}

#[cfg(test)]
pub(crate) mod tests;
