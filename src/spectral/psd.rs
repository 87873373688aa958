//! Power spectral density along the rail (wavenumber / wavelength domain and frequency
//! domain) and peak finding with sub-bin accuracy.
//!
//! ## Estimator
//! The record `x_n` (`n = 0..N`, spacing `dx`) is detrended (mean and linear trend removed,
//! [`super::detrend`]), multiplied by the symmetric Hann window
//! `w_n = ½ (1 − cos(2π n/(N−1)))`, zero-padded to `N_fft = next_pow2(pad_factor · N)` and
//! transformed: `X_k = Σ_n w_n u_n e^{−2πi k n / N_fft}`. The one-sided PSD against wavenumber
//! `κ_k = k / (N_fft dx)` (cycles per metre, `λ = 1/κ`) is
//!
//! `P(κ_k) = c_k · dx · |X_k|² / Σ_n w_n²`,  `c_k = 2` except `c = 1` at `k = 0` and `k = N_fft/2`,
//!
//! in (signal unit)²·m. By Parseval, `Σ_k P(κ_k) Δκ = Σ w_n² u_n² / Σ w_n²` exactly (`Δκ = 1/(N_fft dx)`):
//! the PSD integrates to the window-weighted mean square, which equals the variance of a
//! stationary signal. This is the "window power" normalisation (Welch 1967, single segment;
//! Harris, Proc. IEEE 66 (1978) 51, for the Hann window's properties).
//!
//! The frequency-domain PSD at speed `v` is `P_f(f) = P(κ)/v` at `f = v κ` (unit²/Hz), which
//! keeps the integral (variance) unchanged.
//!
//! ## Resolution
//! The bin spacing `1/(N_fft dx)` is `pad_factor` times finer than the intrinsic resolution
//! `1/L` (`L = N dx`); zero padding interpolates, it does not resolve. The Hann main lobe is
//! `±2/L` wide; its first side lobe is −31.5 dB. See the module doc of [`super`] for what a
//! 1 m record means at 40 mm, and [`wavelength_resolution_m`].
//!
//! ## Peaks
//! Local maxima of `P` inside a wavelength band, kept if (a) their topographic prominence in
//! dB (peak over the higher of the lowest points on either side before a higher point) is at
//! least `min_prominence_db`, and (b) they are within `max_below_largest_db` of the largest
//! in-band peak (with the default 20 dB this rejects the Hann side lobes of any in-band peak,
//! which are ≥ 31.5 dB down). The location is refined by fitting a parabola to `ln P` at the
//! three bins around the maximum (for the Hann main lobe, which is close to a Gaussian near its
//! top, this is accurate to a small fraction of a padded bin).

use super::filter::detrend;
use super::signal::check_positive;
use super::{Signal, SpectralError};
use rustfft::{num_complex::Complex, FftPlanner};
use serde::{Deserialize, Serialize};

/// PSD estimator settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PsdOptions {
    /// Zero-padding factor: `N_fft = next_pow2(pad_factor · N)` (≥ 1, default 8).
    pub pad_factor: usize,
}

impl Default for PsdOptions {
    fn default() -> Self {
        Self { pad_factor: 8 }
    }
}

/// One-sided PSD against wavenumber `κ = 1/λ`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Psd {
    /// Wavenumber of each bin, cycles per metre (m⁻¹); `λ = 1/κ`.
    pub wavenumber_per_m: Vec<f64>,
    /// Spectral density, (signal unit)²·m (per unit wavenumber).
    pub psd: Vec<f64>,
    /// Bin spacing `Δκ = 1/(N_fft dx)`, m⁻¹.
    pub bin_per_m: f64,
    /// Record length `L = N dx`, m (intrinsic resolution `1/L`).
    pub record_length_m: f64,
    /// Sample spacing of the record, m.
    pub dx_m: f64,
    /// `Σ w_n` of the window (for amplitude estimates).
    pub window_sum: f64,
    /// `Σ w_n²` of the window (for the density normalisation).
    pub window_sq_sum: f64,
}

/// One-sided PSD against frequency `f = v κ`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrequencyPsd {
    /// Frequency of each bin, Hz.
    pub frequency_hz: Vec<f64>,
    /// Spectral density, (signal unit)²/Hz.
    pub psd: Vec<f64>,
    /// Speed used for the mapping, m/s.
    pub speed_m_per_s: f64,
}

/// A spectral peak (a wavelength component).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Peak {
    /// Wavelength of the component, m (sub-bin interpolated).
    pub wavelength_m: f64,
    /// Wavenumber `1/λ`, m⁻¹.
    pub wavenumber_per_m: f64,
    /// Frequency `v/λ` at the passing speed, Hz.
    pub frequency_hz: f64,
    /// Interpolated PSD at the peak, (signal unit)²·m.
    pub psd: f64,
    /// Amplitude of a pure sine that gives this peak height (signal unit); exact for an
    /// isolated sine, an estimate otherwise.
    pub amplitude: f64,
}

/// Peak-finding settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PeakOptions {
    /// Shortest wavelength searched, m (default 0.020).
    pub lambda_min_m: f64,
    /// Longest wavelength searched, m (default 0.080).
    pub lambda_max_m: f64,
    /// Minimum topographic prominence, dB (default 6).
    pub min_prominence_db: f64,
    /// Peaks more than this many dB below the largest in-band peak are dropped (default 20).
    pub max_below_largest_db: f64,
    /// At most this many peaks are returned, largest first (default 5).
    pub max_count: usize,
}

impl Default for PeakOptions {
    fn default() -> Self {
        Self {
            lambda_min_m: 0.020,
            lambda_max_m: 0.080,
            min_prominence_db: 6.0,
            max_below_largest_db: 20.0,
            max_count: 5,
        }
    }
}

/// Wavelength resolution `Δλ ≈ λ²/L` (m) of a record of length `record_length_m` at
/// wavelength `wavelength_m`: the wavelength step that corresponds to the intrinsic
/// wavenumber resolution `1/L`. E.g. 1 m at 40 mm → 1.6 mm (4 %).
pub fn wavelength_resolution_m(wavelength_m: f64, record_length_m: f64) -> f64 {
    wavelength_m * wavelength_m / record_length_m
}

impl Psd {
    /// Estimate the PSD of `signal` (see the module doc).
    pub fn estimate(signal: &Signal, opts: &PsdOptions) -> Result<Self, SpectralError> {
        let n = signal.values.len();
        if n < 8 {
            return Err(SpectralError::TooShort { len: n, min: 8 });
        }
        if opts.pad_factor == 0 {
            return Err(SpectralError::NotPositive {
                what: "pad_factor",
                value: 0.0,
            });
        }
        let u = detrend(signal)?;
        let nfft = (opts.pad_factor * n).next_power_of_two();
        let mut buf = vec![Complex::new(0.0, 0.0); nfft];
        let (mut s1, mut s2) = (0.0, 0.0);
        let two_pi = 2.0 * std::f64::consts::PI;
        for (i, (&v, b)) in u.values.iter().zip(buf.iter_mut()).enumerate() {
            let w = 0.5 * (1.0 - (two_pi * i as f64 / (n - 1) as f64).cos());
            s1 += w;
            s2 += w * w;
            *b = Complex::new(w * v, 0.0);
        }
        FftPlanner::<f64>::new()
            .plan_fft_forward(nfft)
            .process(&mut buf);
        let half = nfft / 2;
        let dk = 1.0 / (nfft as f64 * signal.dx_m);
        let mut kappa = Vec::with_capacity(half + 1);
        let mut psd = Vec::with_capacity(half + 1);
        for (k, x) in buf.iter().take(half + 1).enumerate() {
            let c = if k == 0 || k == half { 1.0 } else { 2.0 };
            kappa.push(k as f64 * dk);
            psd.push(c * signal.dx_m * x.norm_sqr() / s2);
        }
        Ok(Self {
            wavenumber_per_m: kappa,
            psd,
            bin_per_m: dk,
            record_length_m: signal.length_m(),
            dx_m: signal.dx_m,
            window_sum: s1,
            window_sq_sum: s2,
        })
    }

    /// `Σ P Δκ`: the window-weighted mean square of the detrended signal (Parseval).
    pub fn integral(&self) -> f64 {
        self.psd.iter().sum::<f64>() * self.bin_per_m
    }

    /// Wavelength of bin `i`, m (infinite for the DC bin).
    pub fn wavelength_m(&self, i: usize) -> f64 {
        1.0 / self.wavenumber_per_m[i]
    }

    /// Amplitude (signal unit) of a pure sine whose Hann-windowed PSD peak is `psd`:
    /// `|X| = A Σw / 2`, so `A = √(2 P Σw² / dx) / Σw`.
    pub(crate) fn sine_amplitude(&self, psd: f64) -> f64 {
        (2.0 * psd.max(0.0) * self.window_sq_sum / self.dx_m).sqrt() / self.window_sum
    }

    /// The same PSD against frequency `f = v κ` (Hz), density `P/v` (unit²/Hz).
    pub fn to_frequency(&self, speed_m_per_s: f64) -> Result<FrequencyPsd, SpectralError> {
        check_positive("speed_m_per_s", speed_m_per_s)?;
        Ok(FrequencyPsd {
            frequency_hz: self
                .wavenumber_per_m
                .iter()
                .map(|k| k * speed_m_per_s)
                .collect(),
            psd: self.psd.iter().map(|p| p / speed_m_per_s).collect(),
            speed_m_per_s,
        })
    }
}

/// Find the peaks of `psd` in a wavelength band (see the module doc), largest first, with
/// frequencies `f = v/λ` at `speed_m_per_s` (m/s).
pub fn find_peaks(
    psd: &Psd,
    opts: &PeakOptions,
    speed_m_per_s: f64,
) -> Result<Vec<Peak>, SpectralError> {
    check_positive("speed_m_per_s", speed_m_per_s)?;
    check_positive("lambda_min_m", opts.lambda_min_m)?;
    check_positive("lambda_max_m", opts.lambda_max_m)?;
    if opts.lambda_min_m >= opts.lambda_max_m {
        return Err(SpectralError::BadBand {
            lambda_min_m: opts.lambda_min_m,
            lambda_max_m: opts.lambda_max_m,
            reason: "lambda_min_m must be < lambda_max_m",
        });
    }
    let p = &psd.psd;
    let n = p.len();
    let pmax = p.iter().cloned().fold(0.0, f64::max);
    if n < 3 || pmax <= 0.0 {
        return Ok(Vec::new());
    }
    let floor = pmax * 1e-30 + f64::MIN_POSITIVE;
    let db = |v: f64| 10.0 * (v + floor).log10();
    let (klo, khi) = (1.0 / opts.lambda_max_m, 1.0 / opts.lambda_min_m);
    let mut cands: Vec<(usize, f64)> = Vec::new(); // (bin, prominence dB)
    for k in 1..n - 1 {
        let kk = psd.wavenumber_per_m[k];
        if kk < klo || kk > khi || !(p[k] > p[k - 1] && p[k] >= p[k + 1]) {
            continue;
        }
        let mut left_min = p[k];
        for &v in p[..k].iter().rev() {
            if v > p[k] {
                break;
            }
            left_min = left_min.min(v);
        }
        let mut right_min = p[k];
        for &v in &p[k + 1..] {
            if v > p[k] {
                break;
            }
            right_min = right_min.min(v);
        }
        let prom = db(p[k]) - db(left_min.max(right_min));
        if prom >= opts.min_prominence_db {
            cands.push((k, prom));
        }
    }
    let largest = cands.iter().map(|&(k, _)| p[k]).fold(0.0, f64::max);
    let mut peaks: Vec<Peak> = cands
        .into_iter()
        .filter(|&(k, _)| db(p[k]) >= db(largest) - opts.max_below_largest_db)
        .map(|(k, _)| {
            let (a, b, c) = (
                (p[k - 1] + floor).ln(),
                (p[k] + floor).ln(),
                (p[k + 1] + floor).ln(),
            );
            let den = a - 2.0 * b + c;
            let delta = if den < 0.0 {
                (0.5 * (a - c) / den).clamp(-0.5, 0.5)
            } else {
                0.0
            };
            let lnp = b - 0.25 * (a - c) * delta;
            let kappa = psd.wavenumber_per_m[k] + delta * psd.bin_per_m;
            let pk = lnp.exp();
            Peak {
                wavelength_m: 1.0 / kappa,
                wavenumber_per_m: kappa,
                frequency_hz: speed_m_per_s * kappa,
                psd: pk,
                amplitude: psd.sine_amplitude(pk),
            }
        })
        .collect();
    peaks.sort_by(|a, b| b.psd.total_cmp(&a.psd));
    peaks.truncate(opts.max_count);
    Ok(peaks)
}
