//! Measured rail roughness, and what the wear loop makes of it.
//!
//! A rail's roughness comes from a trolley or an acoustic-roughness campaign in one of two
//! forms: a **profile** (height along the rail, any sampling, with gaps and a trend) or a
//! **one-third-octave spectrum** (band levels `L = 10 lg(r²_rms / r₀²)` in dB re
//! `r₀ = 1 µm` per wavelength band, the form of EN 15610 and ISO 3095). This module
//!
//! - reads both ([`MeasuredProfile::read_csv`], [`BandSpectrum::read_csv`]);
//! - turns a profile into its band spectrum the way EN 15610 describes for its Fourier method
//!   ([`MeasuredProfile::band_spectrum`]): the record split at gaps, each continuous part
//!   resampled to its median spacing, cut into segments (4 m by default, half overlapping), mean and
//!   linear trend removed per segment, a Hann window, the averaged one-sided spectrum summed
//!   into base-ten one-third-octave bands with the lines at a band edge shared by the part
//!   of their width inside ([`bands`]);
//! - carries the ISO 3095:2013 limit spectrum of a reference track ([`bands::iso3095_limit_db`]);
//! - applies the model's growth-rate spectrum to a band spectrum ([`mod@forecast`]): each band's
//!   level after `N` wheel passages, `L_N = L_0 + 10 lg⟨(1 + σ(λ))^{2N}⟩_band` with `σ` the
//!   relative amplitude change per passage of the linear wear loop (docs/theory.md §10.6,
//!   §10.7 for this module).
//!
//! Assumptions: the roughness is a stationary random process within a band (the band level
//! is its mean square); the growth-rate spectrum is linear in the amplitude, so the forecast
//! holds while the roughness stays small against the contact's approach (tens of µm); the
//! spike removal and the curvature processing of EN 15610 (a probe tip narrower than a
//! wheel) are not applied: the passage over the profile models the wheel's contact itself.
//!
//! References: EN 15610:2019, *Railway applications — Acoustics — Rail and wheel roughness
//! measurement related to noise generation* (the processing); ISO 3095:2013, *Acoustics —
//! Railway applications — Measurement of noise emitted by railbound vehicles*, Figure 2 (the
//! limit spectrum).

pub mod bands;
pub mod forecast;
pub mod profile;

pub use bands::{iso3095_limit_db, third_octave_bands, Band, BandSpectrum};
pub use forecast::{forecast, traffic_passages, BandForecast, Forecast};
pub use profile::{MeasuredProfile, SpectrumOptions};

use std::path::PathBuf;

/// Errors of reading and processing a measured roughness. Each names the file (when there
/// is one) and what to change.
#[derive(Debug, thiserror::Error)]
pub enum RoughnessError {
    /// The file could not be read.
    #[error("{path}: cannot read the roughness file: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The file's content is not a roughness of the expected form.
    #[error("{path}: {reason}")]
    Format {
        /// The file (or "profile" for arrays).
        path: String,
        /// What is wrong and what the file should hold.
        reason: String,
    },
    /// A processing setting or the data is out of its range.
    #[error("{what} = {value}: {expected}")]
    OutOfRange {
        /// The setting or quantity.
        what: &'static str,
        /// The value given or found.
        value: f64,
        /// The allowed range and why.
        expected: String,
    },
}

/// The text of the roughness file `path`.
fn read_text(path: &std::path::Path) -> Result<String, RoughnessError> {
    std::fs::read_to_string(path).map_err(|source| RoughnessError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// The lowercased header cells and the data lines (trimmed; blank lines and `#` comments
/// dropped) of a roughness CSV named `name`; `expected` is the header it should have, for
/// the message of an empty file.
fn csv_lines<'a>(
    text: &'a str,
    name: &str,
    expected: &str,
) -> Result<(Vec<String>, Vec<&'a str>), RoughnessError> {
    let mut lines = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'));
    let header = lines
        .next()
        .ok_or_else(|| RoughnessError::Format {
            path: name.to_string(),
            reason: format!("empty: expected a header `{expected}`"),
        })?
        .split(',')
        .map(|s| s.trim().to_ascii_lowercase())
        .collect();
    Ok((header, lines.collect()))
}
