//! A measured band spectrum carried forward by the growth-rate spectrum: which wavelengths
//! grow on this rail at a speed, how fast, and the band levels after `N` wheel passages.
//!
//! The growth-rate spectrum gives, per wavelength `λ`, the relative change of a roughness
//! amplitude in one wheel passage, `σ(λ)` (docs/theory.md §10.6): an amplitude `A` becomes
//! `A(1 + σ)` and after `N` passages `A(1 + σ)^N`. A band holds many wavelengths; with the
//! roughness's mean square spread evenly over the band's wavenumbers (within a band a
//! measured spectrum says no more), the band's mean square is multiplied by the mean of
//! `(1 + σ)^{2N}` over the growth-rate spectrum's wavelengths in the band:
//!
//! `L_N = L_0 + 10 lg ⟨(1 + σ(λ))^{2N}⟩_band`, and per passage `ΔL = 10 lg ⟨(1 + σ)^2⟩`.
//!
//! Only bands whose centres the growth-rate spectrum covers get a forecast (20–80 mm by
//! default); the others are reported as measured. The forecast is linear: it holds while the
//! roughness stays small against the contact's approach (the trial-amplitude procedure of
//! `grow` tests where growth stops).

use serde::Serialize;

use super::bands::{iso3095_limit_db, BandSpectrum};
use crate::growth::rate::GrowthRateSpectrum;

/// The forecast of one band.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BandForecast {
    /// Nominal centre wavelength (m).
    pub centre_m: f64,
    /// Measured level (dB re 1 µm).
    pub level_db: f64,
    /// ISO 3095:2013 limit of the band (dB re 1 µm), when it has one.
    pub limit_db: Option<f64>,
    /// Change of the band level per wheel passage (dB); `None` when the growth-rate spectrum
    /// does not cover the band.
    pub db_per_passage: Option<f64>,
    /// Level after the forecast's passages (dB re 1 µm); `None` as `db_per_passage`.
    pub level_after_db: Option<f64>,
    /// The growth-rate spectrum's wavelengths in the band.
    pub rate_points: usize,
}

/// A band spectrum carried forward at one speed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Forecast {
    /// Speed (km/h).
    pub speed_kmh: f64,
    /// Wheel passages forecast (−).
    pub passages: f64,
    /// One row per band of the measured spectrum, longest wavelength first.
    pub bands: Vec<BandForecast>,
}

impl Forecast {
    /// The bands that grow (`db_per_passage > 0`), as nominal centres (m).
    pub fn growing_m(&self) -> Vec<f64> {
        self.bands
            .iter()
            .filter(|b| b.db_per_passage.is_some_and(|d| d > 0.0))
            .map(|b| b.centre_m)
            .collect()
    }

    /// The fastest-growing band, if any grows.
    pub fn fastest(&self) -> Option<&BandForecast> {
        self.bands
            .iter()
            .filter(|b| b.db_per_passage.is_some_and(|d| d > 0.0))
            .max_by(|a, b| {
                let (x, y) = (
                    a.db_per_passage.unwrap_or(0.0),
                    b.db_per_passage.unwrap_or(0.0),
                );
                x.total_cmp(&y)
            })
    }

    /// Passages until the fastest-growing band reaches its ISO 3095 limit, when it has one, is
    /// below it and grows; 0 when it is already above.
    pub(crate) fn passages_to_limit(&self) -> Option<f64> {
        let b = self.fastest()?;
        let (limit, rate) = (b.limit_db?, b.db_per_passage?);
        Some(((limit - b.level_db) / rate).max(0.0))
    }

    /// One plain sentence: which bands grow at this speed, how fast, and the fastest one's
    /// level after the forecast's passages.
    pub fn sentence(&self) -> String {
        let mm = |m: f64| {
            format!("{:.3}", crate::units::m_to_mm(m))
                .trim_end_matches('0')
                .trim_end_matches('.')
                .to_string()
        };
        let grow = self.growing_m();
        let Some(f) = self.fastest() else {
            let covered = self
                .bands
                .iter()
                .filter(|b| b.db_per_passage.is_some())
                .count();
            return format!(
                "At {} km/h none of the {covered} band(s) the growth-rate spectrum covers grows: the measured roughness decays there.",
                self.speed_kmh
            );
        };
        let (rate, after) = (
            f.db_per_passage.unwrap_or(0.0),
            f.level_after_db.unwrap_or(f.level_db),
        );
        let mut s = format!(
            "At {} km/h {} band(s) grow ({} mm); the fastest, {} mm, by {:.2e} dB per passage: from {:.1} to {:.1} dB re 1 µm after {:.3e} passages",
            self.speed_kmh,
            grow.len(),
            grow.iter().map(|&m| mm(m)).collect::<Vec<_>>().join(", "),
            mm(f.centre_m),
            rate,
            f.level_db,
            after,
            self.passages
        );
        if let (Some(l), Some(n)) = (f.limit_db, self.passages_to_limit()) {
            s.push_str(&format!(
                "; it reaches the ISO 3095 limit ({l:.1} dB) after {n:.3e} passages"
            ));
        }
        s.push('.');
        s
    }
}

/// The forecast of `measured` after `passages` wheel passages with the growth-rate spectrum
/// `rates` (its speed is the forecast's).
pub fn forecast(measured: &BandSpectrum, rates: &GrowthRateSpectrum, passages: f64) -> Forecast {
    let bands = measured
        .bands
        .iter()
        .zip(&measured.level_db)
        .map(|(b, &level_db)| {
            let sigma: Vec<f64> = rates
                .points
                .iter()
                .filter(|p| b.holds(p.wavelength_m))
                .map(|p| p.growth_rate_per_passage)
                .collect();
            let covered = !sigma.is_empty()
                && rates
                    .points
                    .first()
                    .is_some_and(|p| p.wavelength_m <= b.centre_m())
                && rates
                    .points
                    .last()
                    .is_some_and(|p| p.wavelength_m >= b.centre_m());
            // 10 lg ⟨(1 + σ)^k⟩ in the log domain (log-sum-exp): (1 + σ)^{2N} overflows for
            // the passages of a tonnage
            let db_of_mean_gain = |k: f64| {
                let v: Vec<f64> = sigma
                    .iter()
                    .map(|s| k * (1.0 + s).max(1e-300).ln())
                    .collect();
                let top = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                let mean = v.iter().map(|x| (x - top).exp()).sum::<f64>() / v.len() as f64;
                10.0 * (top + mean.ln()) / std::f64::consts::LN_10
            };
            let (db_per_passage, level_after_db) = if covered {
                (
                    Some(db_of_mean_gain(2.0)),
                    Some(level_db + db_of_mean_gain(2.0 * passages)),
                )
            } else {
                (None, None)
            };
            BandForecast {
                centre_m: b.nominal_m(),
                level_db,
                limit_db: iso3095_limit_db(b.centre_m()),
                db_per_passage,
                level_after_db,
                rate_points: sigma.len(),
            }
        })
        .collect();
    Forecast {
        speed_kmh: rates.speed.kmh(),
        passages,
        bands,
    }
}

/// Wheel passages over one rail in `mgt` million gross tonnes of traffic with the wheel load
/// `wheel_load_n` (N): every axle (two wheels, one on each rail) carries `2W/g`.
pub(crate) fn passages_of_mgt(mgt: f64, wheel_load_n: f64) -> f64 {
    const G: f64 = 9.81;
    mgt * 1e9 / (2.0 * wheel_load_n / G)
}

/// Most wheel passages a forecast takes (−).
pub(crate) const MAX_PASSAGES: f64 = 1e12;

/// Most traffic a forecast takes (million gross tonnes).
pub(crate) const MAX_MGT: f64 = 1000.0;

/// Default traffic of a forecast when neither is given (million gross tonnes).
pub(crate) const DEFAULT_MGT: f64 = 1.0;

/// The wheel passages of a forecast from the traffic given as `passages` (1 to
/// `MAX_PASSAGES`) or `mgt` (million gross tonnes, above 0 to `MAX_MGT`; default
/// `DEFAULT_MGT`) at the wheel load `wheel_load_n` (N); not both.
pub fn traffic_passages(
    passages: Option<f64>,
    mgt: Option<f64>,
    wheel_load_n: f64,
) -> Result<f64, super::RoughnessError> {
    use super::RoughnessError::OutOfRange;
    match (passages, mgt) {
        (Some(_), Some(_)) => Err(OutOfRange {
            what: "traffic",
            value: f64::NAN,
            expected: "give the passages or the MGT, not both".into(),
        }),
        (Some(n), None) if n.is_finite() && (1.0..=MAX_PASSAGES).contains(&n) => Ok(n),
        (Some(n), None) => Err(OutOfRange {
            what: "passages",
            value: n,
            expected: format!("out of range, allowed 1 to {MAX_PASSAGES:e} wheel passages"),
        }),
        (None, g) => {
            let g = g.unwrap_or(DEFAULT_MGT);
            if g.is_finite() && g > 0.0 && g <= MAX_MGT {
                Ok(passages_of_mgt(g, wheel_load_n))
            } else {
                Err(OutOfRange {
                    what: "mgt",
                    value: g,
                    expected: format!(
                        "out of range, allowed above 0 to {MAX_MGT} million gross tonnes"
                    ),
                })
            }
        }
    }
}
