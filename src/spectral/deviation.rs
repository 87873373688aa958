//! Relative deviation and difference of spectral components (docs/theory.md §9.5).
//!
//! - **Deviation** of a component from its reference component:
//!   `d = |λ_j − λ_ref,j| / λ_ref,j` (dimensionless; 0.03 = 3 %), the references being the
//!   wavelengths of the trial corrugation (= those of the initial wear).
//! - **Difference**: the same ratio against a reference of another kind, e.g. a component's
//!   frequency `f = v/λ` against an eigenfrequency: `|f − f_eig| / f_eig`.
//!
//! Both take the absolute value of the reference, so the ratio is well defined for signed
//! quantities; a zero or non-finite reference is an error.

use super::SpectralError;

/// Relative deviation `|value − reference| / |reference|` (dimensionless). Same unit for both
/// arguments (e.g. wavelengths in m).
pub fn relative_deviation(value: f64, reference: f64) -> Result<f64, SpectralError> {
    if !value.is_finite() {
        return Err(SpectralError::NonFinite {
            what: "value",
            index: 0,
        });
    }
    if !reference.is_finite() {
        return Err(SpectralError::NonFinite {
            what: "reference",
            index: 0,
        });
    }
    if reference == 0.0 {
        return Err(SpectralError::ZeroReference);
    }
    Ok((value - reference).abs() / reference.abs())
}

/// Relative difference against a reference of another kind, e.g. `frequency_hz` of a
/// component vs an eigenfrequency `reference` (Hz): `|value − reference| / |reference|`.
/// Identical formula to [`relative_deviation`]; the name records which comparison is meant.
pub fn relative_difference(value: f64, reference: f64) -> Result<f64, SpectralError> {
    relative_deviation(value, reference)
}

#[cfg(test)]
mod tests {
    use super::{relative_deviation, relative_difference, SpectralError};
    #[test]
    fn deviation_closed_form() {
        // 41.0 mm vs 40.0 mm reference: 2.5 %; 1400 Hz vs 1000 Hz eigenfrequency: 40 %.
        assert!((relative_deviation(0.041, 0.040).unwrap() - 0.025).abs() < 1e-12);
        assert!((relative_deviation(0.039, 0.040).unwrap() - 0.025).abs() < 1e-12);
        assert!((relative_difference(1400.0, 1000.0).unwrap() - 0.4).abs() < 1e-15);
        assert_eq!(
            relative_deviation(1.0, 0.0),
            Err(SpectralError::ZeroReference)
        );
        assert!(relative_deviation(f64::NAN, 1.0).is_err());
    }
}
