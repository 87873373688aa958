//! Correlation and phase between two signals along the rail.
//!
//! - [`correlation_coefficient`]: Pearson's normalised correlation at zero lag,
//!   `r = Σ (a−ā)(b−b̄) / √(Σ (a−ā)² Σ (b−b̄)²)` ∈ [−1, 1]. For the growth phase this is the
//!   sign that matters (docs/theory.md §10.3).
//! - [`cross_phase_rad`]: the cross-spectral phase at one wavelength. Each signal is written
//!   near wavenumber `κ = 1/λ` as `A cos(2π κ x + φ)`; the phase of the Hann-windowed Fourier
//!   sum `Z = Σ w_n (s_n − s̄) e^{−2πi κ x_n}` (at the exact `κ`, no bin rounding) is `φ`, and the
//!   function returns `φ_a − φ_b = arg(Z_a Z_b*)` ∈ (−π, π]. If `a(x) = b(x − s)` then
//!   `φ_a − φ_b = −2π s/λ (mod 2π)`.
//! - [`lag_of_max_correlation`]: the shift `s` (m) that maximises the Pearson correlation of
//!   `a(x + s)` with `b(x)` over their overlap, `|s| ≤ max_lag_m`, refined by a parabola
//!   through the three correlation values around the best integer lag. If `a(x) = b(x − s0)`
//!   (a is b moved forward by `s0`), the result is `s0`.

use super::signal::check_positive;
use super::{Signal, SpectralError};
use serde::{Deserialize, Serialize};

/// Result of a lag search.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LagResult {
    /// Lag `s` of maximum correlation of `a(x + s)` with `b(x)`, m (sub-sample interpolated).
    pub lag_m: f64,
    /// Pearson correlation at the best integer lag.
    pub correlation: f64,
}

/// Pearson correlation coefficient at zero lag of two signals on the same grid.
pub fn correlation_coefficient(a: &Signal, b: &Signal) -> Result<f64, SpectralError> {
    a.check_same_grid(b)?;
    if a.len() < 2 {
        return Err(SpectralError::TooShort {
            len: a.len(),
            min: 2,
        });
    }
    pearson(&a.values, &b.values)
}

fn pearson(a: &[f64], b: &[f64]) -> Result<f64, SpectralError> {
    let n = a.len() as f64;
    let ma = a.iter().sum::<f64>() / n;
    let mb = b.iter().sum::<f64>() / n;
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (&x, &y) in a.iter().zip(b) {
        let (da, db) = (x - ma, y - mb);
        sab += da * db;
        saa += da * da;
        sbb += db * db;
    }
    if saa.is_nan() || saa <= 0.0 {
        return Err(SpectralError::ZeroVariance {
            what: "first signal",
        });
    }
    if sbb.is_nan() || sbb <= 0.0 {
        return Err(SpectralError::ZeroVariance {
            what: "second signal",
        });
    }
    Ok((sab / (saa * sbb).sqrt()).clamp(-1.0, 1.0))
}

/// Cross-spectral phase `φ_a − φ_b` (rad, in (−π, π]) at `wavelength_m` (m) of two signals
/// on the same grid (see the module doc for the convention).
pub fn cross_phase_rad(a: &Signal, b: &Signal, wavelength_m: f64) -> Result<f64, SpectralError> {
    a.check_same_grid(b)?;
    check_positive("wavelength_m", wavelength_m)?;
    let n = a.len();
    if n < 8 {
        return Err(SpectralError::TooShort { len: n, min: 8 });
    }
    let za = windowed_fourier(a, wavelength_m);
    let zb = windowed_fourier(b, wavelength_m);
    if za.0.hypot(za.1) == 0.0 {
        return Err(SpectralError::ZeroVariance {
            what: "first signal at this wavelength",
        });
    }
    if zb.0.hypot(zb.1) == 0.0 {
        return Err(SpectralError::ZeroVariance {
            what: "second signal at this wavelength",
        });
    }
    // Z_a Z_b* = (ar + i ai)(br − i bi)
    let re = za.0 * zb.0 + za.1 * zb.1;
    let im = za.1 * zb.0 - za.0 * zb.1;
    Ok(im.atan2(re))
}

/// Hann-windowed Fourier sum at wavenumber 1/λ, as (re, im).
fn windowed_fourier(s: &Signal, wavelength_m: f64) -> (f64, f64) {
    let n = s.len();
    let mean = s.values.iter().sum::<f64>() / n as f64;
    let two_pi = 2.0 * std::f64::consts::PI;
    let (mut re, mut im) = (0.0, 0.0);
    for (i, &v) in s.values.iter().enumerate() {
        let w = 0.5 * (1.0 - (two_pi * i as f64 / (n - 1) as f64).cos());
        let ph = two_pi * s.x_m(i) / wavelength_m;
        re += w * (v - mean) * ph.cos();
        im -= w * (v - mean) * ph.sin();
    }
    (re, im)
}

/// Lag (m) of maximum Pearson correlation of `a(x + s)` with `b(x)`, `|s| ≤ max_lag_m`
/// (at most half the record, so the overlap keeps at least half the samples).
pub fn lag_of_max_correlation(
    a: &Signal,
    b: &Signal,
    max_lag_m: f64,
) -> Result<LagResult, SpectralError> {
    a.check_same_grid(b)?;
    let n = a.len();
    if n < 8 {
        return Err(SpectralError::TooShort { len: n, min: 8 });
    }
    if !max_lag_m.is_finite() || max_lag_m < 0.0 {
        return Err(SpectralError::NotPositive {
            what: "max_lag_m",
            value: max_lag_m,
        });
    }
    let lmax = (max_lag_m / a.dx_m).floor() as usize;
    if lmax > n / 2 {
        return Err(SpectralError::TooShort {
            len: n,
            min: 2 * lmax,
        });
    }
    pearson(&a.values, &a.values)?;
    pearson(&b.values, &b.values)?;
    let r_at = |l: isize| -> f64 {
        // pairs (a[i + l], b[i])
        let (sa, sb) = if l >= 0 {
            let l = l as usize;
            (&a.values[l..], &b.values[..n - l])
        } else {
            let l = (-l) as usize;
            (&a.values[..n - l], &b.values[l..])
        };
        pearson(sa, sb).unwrap_or(0.0)
    };
    let lm = lmax as isize;
    let (mut best_l, mut best_r) = (0isize, f64::NEG_INFINITY);
    for l in -lm..=lm {
        let r = r_at(l);
        if r > best_r {
            best_r = r;
            best_l = l;
        }
    }
    let mut delta = 0.0;
    if best_l > -lm && best_l < lm {
        let (r0, r2) = (r_at(best_l - 1), r_at(best_l + 1));
        let den = r0 - 2.0 * best_r + r2;
        if den < 0.0 {
            delta = (0.5 * (r0 - r2) / den).clamp(-0.5, 0.5);
        }
    }
    Ok(LagResult {
        lag_m: (best_l as f64 + delta) * a.dx_m,
        correlation: best_r,
    })
}
