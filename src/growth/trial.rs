//! Trial corrugation from the band-passed initial differential wear.
//!
//! The corrugation is in antiphase with the differential wear (a wear peak digs a trough):
//! the rail-top height is `h(x) = −c · W_band(x)` (m), with `c = 2A_max / (max W_band −
//! min W_band)` so that `max h − min h = 2A_max` (docs/theory.md §2.2 b and
//! §10.1). `W_band` must already be band-passed (20–80 mm,
//! [`crate::spectral::band_pass`]); its unit is whatever the wear is measured in (J/m² of
//! frictional work, or m of depth), `c` converts it to metres.

use super::GrowthError;
use crate::spectral::Signal;
use serde::{Deserialize, Serialize};

/// A trial corrugation: the rail-top height profile and the scale used.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct TrialCorrugation {
    /// Rail-top height `h(x) = −c W_band(x)`, m, on the grid of the wear signal.
    pub height: Signal,
    /// Scale `c` (m per wear unit), ≥ 0.
    pub scale: f64,
    /// Peak-to-trough `2A_max` of the height, m.
    pub two_a_max_m: f64,
}

/// Build the trial corrugation `h = −c · W_band` with peak-to-trough `two_a_max_m` (m).
pub(crate) fn trial_corrugation(
    wear_band: &Signal,
    two_a_max_m: f64,
) -> Result<TrialCorrugation, GrowthError> {
    if !two_a_max_m.is_finite() || two_a_max_m < 0.0 {
        return Err(GrowthError::BadAmplitude { value: two_a_max_m });
    }
    if let Some(index) = wear_band.values.iter().position(|v| !v.is_finite()) {
        return Err(crate::spectral::SpectralError::NonFinite {
            what: "wear_band",
            index,
        }
        .into());
    }
    let (lo, hi) = wear_band
        .values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    let ptp = hi - lo;
    if !(ptp.is_finite() && ptp > 0.0) {
        return Err(GrowthError::FlatWear);
    }
    let scale = two_a_max_m / ptp;
    let height = Signal {
        x0_m: wear_band.x0_m,
        dx_m: wear_band.dx_m,
        values: wear_band.values.iter().map(|&w| -scale * w).collect(),
    };
    Ok(TrialCorrugation {
        height,
        scale,
        two_a_max_m,
    })
}

#[cfg(test)]
mod tests {
    use super::{trial_corrugation, GrowthError, Signal};
    use crate::spectral::{band_pass, correlation_coefficient, BandPass};
    use std::f64::consts::PI;

    fn wear() -> Signal {
        let v: Vec<f64> = (0..2000)
            .map(|i| {
                let x = 0.3 + i as f64 * 0.0005;
                3.0 * (2.0 * PI * x / 0.041).sin() + 1.2 * (2.0 * PI * x / 0.0273 + 0.4).sin() + 0.5
            })
            .collect();
        band_pass(&Signal::new(0.3, 0.0005, v).unwrap(), &BandPass::default()).unwrap()
    }

    #[test]
    fn peak_to_trough_is_two_a_max_and_sign_is_antiphase() {
        let w = wear();
        for &two_a in &[10e-6, 40e-6, 80e-6, 160e-6] {
            let t = trial_corrugation(&w, two_a).unwrap();
            let (lo, hi) = t
                .height
                .values
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
                    (l.min(v), h.max(v))
                });
            let rel = ((hi - lo) / two_a - 1.0).abs();
            assert!(rel < 4.0 * f64::EPSILON, "2A {two_a}: rel err {rel:e}");
            // Antiphase: h = −c W exactly, so the correlation is −1 (closed form).
            let r = correlation_coefficient(&t.height, &w).unwrap();
            assert!((r + 1.0).abs() < 1e-12);
            // Wear maximum ↔ height minimum at the same sample.
            let imax = (0..w.len())
                .max_by(|&a, &b| w.values[a].total_cmp(&w.values[b]))
                .unwrap();
            assert_eq!(t.height.values[imax], lo);
        }
    }

    #[test]
    fn bad_inputs() {
        let flat = Signal::new(0.0, 0.001, vec![2.0; 100]).unwrap();
        assert_eq!(trial_corrugation(&flat, 1e-5), Err(GrowthError::FlatWear));
        assert!(matches!(
            trial_corrugation(&wear(), -1e-5),
            Err(GrowthError::BadAmplitude { .. })
        ));
        assert!(matches!(
            trial_corrugation(&wear(), f64::NAN),
            Err(GrowthError::BadAmplitude { .. })
        ));
    }
}
