//! Mean/trend removal and the zero-phase band-pass in the wavelength domain.
//!
//! ## Method
//! 1. **Detrend**: the least-squares line `a + b x` is subtracted (removes the mean and a
//!    linear drift, e.g. a slowly growing wear depth), [`detrend`].
//! 2. **Edge treatment: whole-record even mirror extension.** The detrended record
//!    `u_0 … u_{N−1}` is extended to `u_0 … u_{N−1}, u_{N−2} … u_1` (period `M = 2N − 2`, the
//!    DCT-I symmetric extension). The periodic extension is continuous, so there is no jump at
//!    the record ends (a jump would leak into every wavelength); only the slope is
//!    discontinuous there, and its leakage decays as `1/κ²` and stays near the record ends.
//!    Unlike a cosine taper, mirror extension does not change amplitudes anywhere: every
//!    sample keeps its weight, so phases and amplitudes of two passages filtered the same way
//!    are comparable sample by sample.
//! 3. **Zero-phase mask in the FFT domain.** The FFT of the extension is multiplied by a real,
//!    even mask `H(|κ|)` of wavenumber `κ = 1/λ` (cycles/m) and transformed back; a real even
//!    mask has zero phase, so no component is shifted. `H = 1` on the whole nominal band
//!    `1/λ_max ≤ κ ≤ 1/λ_min` (so nothing inside 20–80 mm is attenuated), with raised-cosine
//!    roll-offs of width `transition_per_m` *outside* it: with the defaults (20–80 mm, 5 m⁻¹)
//!    `H` falls from 1 at 80 mm (κ = 12.5 m⁻¹) to 0 at 133 mm (7.5 m⁻¹), and from 1 at 20 mm
//!    (50 m⁻¹) to 0 at 18.2 mm (55 m⁻¹). The smooth roll-off keeps the filter's impulse
//!    response short (main ringing ≈ `1/transition` = 0.2 m, decaying ∝ 1/x³ beyond) instead
//!    of the slowly decaying sinc of a brick wall. The result is the first `N` samples of the
//!    filtered extension.
//!
//! ## Edge zone (measured, 1 m record at 0.5 mm, see the tests)
//! The slope kink of the mirror extension leaks into the band near the record ends, over
//! about the impulse-response length. Away from the ends (0.15 m margin) in-band sines keep
//! their amplitude within 0.6 % (22–75 mm) and out-of-band sines are reduced by 42 dB
//! (150 mm) to 62 dB (5 mm); over the *whole* record the rejection is only 23–34 dB and
//! the in-band amplitude 1–3 % low. So evaluate phases and amplitudes on a record that
//! extends ≈ 0.15 m beyond the zone of interest, or discard that margin after filtering.
//!
//! Reference: the FFT-domain zero-phase filtering of short records as recommended in
//! docs/theory.md §9.2 ("Short records"); symmetric extension as in the DCT-I (Strang, "The
//! discrete cosine transform", SIAM Review 41 (1999) 135–147).

use super::signal::{check_finite, check_positive};
use super::{Signal, SpectralError};
use rustfft::{num_complex::Complex, FftPlanner};
use serde::{Deserialize, Serialize};

/// Zero-phase band-pass settings (wavelength domain).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BandPass {
    /// Shortest wavelength passed with gain 1, m (default 0.020).
    pub lambda_min_m: f64,
    /// Longest wavelength passed with gain 1, m (default 0.080).
    pub lambda_max_m: f64,
    /// Width of each raised-cosine roll-off outside the band, in wavenumber (cycles per m,
    /// m⁻¹; default 5.0). Smaller = sharper band edge but longer ringing (≈ 1/width m).
    pub transition_per_m: f64,
}

impl Default for BandPass {
    fn default() -> Self {
        Self {
            lambda_min_m: 0.020,
            lambda_max_m: 0.080,
            transition_per_m: 5.0,
        }
    }
}

impl BandPass {
    /// Gain of the mask at wavenumber `kappa_per_m` (m⁻¹, sign ignored): 1 in the band,
    /// raised-cosine roll-off of width `transition_per_m` outside it, 0 beyond.
    pub fn gain(&self, kappa_per_m: f64) -> f64 {
        let k = kappa_per_m.abs();
        let lo = 1.0 / self.lambda_max_m;
        let hi = 1.0 / self.lambda_min_m;
        let b = self.transition_per_m;
        if (lo..=hi).contains(&k) {
            1.0
        } else if k < lo && k > lo - b {
            0.5 * (1.0 - (std::f64::consts::PI * (k - (lo - b)) / b).cos())
        } else if k > hi && k < hi + b {
            0.5 * (1.0 + (std::f64::consts::PI * (k - hi) / b).cos())
        } else {
            0.0
        }
    }

    /// The same nominal band with its roll-offs moved inside it: gain 0 outside
    /// `lambda_min_m..=lambda_max_m`, 1 on `1/(1/λ_max + w) ..= 1/(1/λ_min − w)`
    /// (`w = transition_per_m`); for the default 20–80 mm band, 1 on 22.2–57.1 mm. Nothing
    /// outside the band counts, at the price of attenuating its edges (docs/theory.md §9.2).
    /// [`SpectralError::BadBand`] when the band is not wider than two roll-offs in
    /// wavenumber.
    pub fn inside(&self) -> Result<BandPass, SpectralError> {
        check_positive("lambda_min_m", self.lambda_min_m)?;
        check_positive("lambda_max_m", self.lambda_max_m)?;
        check_positive("transition_per_m", self.transition_per_m)?;
        let (lo, hi, w) = (
            1.0 / self.lambda_max_m,
            1.0 / self.lambda_min_m,
            self.transition_per_m,
        );
        if hi - w <= lo + w {
            return Err(SpectralError::BadBand {
                lambda_min_m: self.lambda_min_m,
                lambda_max_m: self.lambda_max_m,
                reason: "band narrower than two roll-offs: no room for them inside it",
            });
        }
        Ok(BandPass {
            lambda_min_m: 1.0 / (hi - w),
            lambda_max_m: 1.0 / (lo + w),
            transition_per_m: w,
        })
    }

    fn validate(&self, dx_m: f64, length_m: f64) -> Result<(), SpectralError> {
        let bad = |reason| SpectralError::BadBand {
            lambda_min_m: self.lambda_min_m,
            lambda_max_m: self.lambda_max_m,
            reason,
        };
        check_positive("lambda_min_m", self.lambda_min_m)?;
        check_positive("lambda_max_m", self.lambda_max_m)?;
        check_positive("transition_per_m", self.transition_per_m)?;
        if self.lambda_min_m >= self.lambda_max_m {
            return Err(bad("lambda_min_m must be < lambda_max_m"));
        }
        if 1.0 / self.lambda_min_m + self.transition_per_m > 0.5 / dx_m {
            return Err(bad(
                "band plus roll-off reaches the Nyquist wavenumber 1/(2 dx): sample finer",
            ));
        }
        if length_m < self.lambda_max_m {
            return Err(bad("record shorter than lambda_max_m: use a longer record"));
        }
        Ok(())
    }
}

/// Subtract the least-squares line `a + b x` from the samples (mean and linear trend removal).
/// Needs at least 2 samples.
pub fn detrend(signal: &Signal) -> Result<Signal, SpectralError> {
    let n = signal.values.len();
    if n < 2 {
        return Err(SpectralError::TooShort { len: n, min: 2 });
    }
    check_finite("values", &signal.values)?;
    // Regress on the centred index t = i − (n−1)/2 (exactly orthogonal to the constant).
    let c = (n - 1) as f64 / 2.0;
    let mean = signal.values.iter().sum::<f64>() / n as f64;
    let (mut sty, mut stt) = (0.0, 0.0);
    for (i, &y) in signal.values.iter().enumerate() {
        let t = i as f64 - c;
        sty += t * y;
        stt += t * t;
    }
    let slope = sty / stt;
    let values = signal
        .values
        .iter()
        .enumerate()
        .map(|(i, &y)| y - mean - slope * (i as f64 - c))
        .collect();
    Ok(Signal {
        x0_m: signal.x0_m,
        dx_m: signal.dx_m,
        values,
    })
}

/// Zero-phase band-pass (see the module doc): detrend, even mirror extension, real mask in the
/// FFT domain, crop. The output is on the same grid as the input.
pub fn band_pass(signal: &Signal, band: &BandPass) -> Result<Signal, SpectralError> {
    let n = signal.values.len();
    if n < 4 {
        return Err(SpectralError::TooShort { len: n, min: 4 });
    }
    check_positive("dx_m", signal.dx_m)?;
    band.validate(signal.dx_m, signal.length_m())?;
    let u = detrend(signal)?;
    let m = 2 * n - 2;
    let mut buf: Vec<Complex<f64>> = Vec::with_capacity(m);
    buf.extend(u.values.iter().map(|&v| Complex::new(v, 0.0)));
    buf.extend(
        u.values[1..n - 1]
            .iter()
            .rev()
            .map(|&v| Complex::new(v, 0.0)),
    );
    let mut planner = FftPlanner::<f64>::new();
    let fwd = planner.plan_fft_forward(m);
    let inv = planner.plan_fft_inverse(m);
    let mut scratch = vec![
        Complex::new(0.0, 0.0);
        fwd.get_inplace_scratch_len()
            .max(inv.get_inplace_scratch_len())
    ];
    fwd.process_with_scratch(&mut buf, &mut scratch);
    let dk = 1.0 / (m as f64 * signal.dx_m);
    for (k, c) in buf.iter_mut().enumerate() {
        let kk = k.min(m - k) as f64 * dk;
        *c *= band.gain(kk) / m as f64;
    }
    inv.process_with_scratch(&mut buf, &mut scratch);
    Ok(Signal {
        x0_m: signal.x0_m,
        dx_m: signal.dx_m,
        values: buf[..n].iter().map(|c| c.re).collect(),
    })
}
