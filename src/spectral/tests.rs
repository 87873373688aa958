//! Tests of the spectral toolkit on synthetic signals with known answers.

use super::{
    band_pass, correlation_coefficient, cross_phase_rad, detrend, find_peaks,
    lag_of_max_correlation, relative_deviation, wavelength_resolution_m, BandPass, PeakOptions,
    Psd, PsdOptions, Signal, SpectralError,
};
use std::f64::consts::PI;

/// Deterministic uniform noise in [−1, 1) (xorshift64), variance 1/3.
pub(crate) struct Noise(u64);
impl Noise {
    pub(crate) fn new(seed: u64) -> Self {
        Self(seed.max(1))
    }
    pub(crate) fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// Sum of sines `Σ A sin(2π x/λ + φ)` on `n` samples at `dx` from `x0`.
fn sines(x0: f64, dx: f64, n: usize, comps: &[(f64, f64, f64)]) -> Signal {
    let v = (0..n)
        .map(|i| {
            let x = x0 + i as f64 * dx;
            comps
                .iter()
                .map(|&(lam, a, ph)| a * (2.0 * PI * x / lam + ph).sin())
                .sum()
        })
        .collect();
    Signal::new(x0, dx, v).unwrap()
}

/// Least-squares amplitude of the component at wavelength `lam` over samples `[i0, i1)`.
fn fitted_amplitude(s: &Signal, lam: f64, i0: usize, i1: usize) -> f64 {
    let (mut scc, mut sss, mut scs, mut syc, mut sys) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for i in i0..i1 {
        let ph = 2.0 * PI * s.x_m(i) / lam;
        let (c, sn, y) = (ph.cos(), ph.sin(), s.values[i]);
        scc += c * c;
        sss += sn * sn;
        scs += c * sn;
        syc += y * c;
        sys += y * sn;
    }
    let det = scc * sss - scs * scs;
    let a = (syc * sss - sys * scs) / det;
    let b = (sys * scc - syc * scs) / det;
    a.hypot(b)
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

const V: f64 = 140.0 / 3.6; // reference speed, m/s

fn test_record() -> Signal {
    // 1 m at 0.5 mm: in-band 27.3 / 41.0 / 63.5 mm, out-of-band 5 mm and 300 mm, plus noise
    // (uniform, rms 0.1 · 0.577).
    let mut s = sines(
        0.3,
        0.0005,
        2000,
        &[
            (0.0273, 1.0, 0.3),
            (0.0410, 0.7, 1.9),
            (0.0635, 0.5, -0.8),
            (0.005, 0.8, 0.0),
            (0.300, 3.0, 0.5),
        ],
    );
    let mut nz = Noise::new(7);
    for v in &mut s.values {
        *v += 0.1 * nz.next();
    }
    s
}

#[test]
fn peaks_recovered_within_half_percent() {
    let s = test_record();
    let psd = Psd::estimate(&s, &PsdOptions::default()).unwrap();
    let peaks = find_peaks(&psd, &PeakOptions::default(), V).unwrap();
    let truth = [0.0273, 0.0410, 0.0635];
    assert_eq!(peaks.len(), 3, "peaks: {peaks:?}");
    // Largest first: amplitudes 1.0, 0.7, 0.5.
    for (p, (&lam, &amp)) in peaks.iter().zip(truth.iter().zip(&[1.0, 0.7, 0.5])) {
        let dev = relative_deviation(p.wavelength_m, lam).unwrap();
        eprintln!(
            "true {:.4} mm  found {:.5} mm  dev {:.4} %  f {:.2} Hz  amplitude {:.4} (true {amp})",
            lam * 1e3,
            p.wavelength_m * 1e3,
            dev * 100.0,
            p.frequency_hz,
            p.amplitude
        );
        assert!(dev < 0.005, "deviation {dev}");
        // f = v/λ exactly, given v.
        assert!((p.frequency_hz - V / p.wavelength_m).abs() < 1e-9 * p.frequency_hz);
        assert!((p.amplitude / amp - 1.0).abs() < 0.05);
    }
}

#[test]
fn frequency_psd_maps_by_speed_and_keeps_variance() {
    let s = test_record();
    let psd = Psd::estimate(&s, &PsdOptions::default()).unwrap();
    let fp = psd.to_frequency(V).unwrap();
    for i in [1usize, 100, 1000] {
        assert!((fp.frequency_hz[i] - V * psd.wavenumber_per_m[i]).abs() < 1e-9);
    }
    let df = fp.frequency_hz[1] - fp.frequency_hz[0];
    let int_f: f64 = fp.psd.iter().sum::<f64>() * df;
    assert!((int_f / psd.integral() - 1.0).abs() < 1e-12);
}

#[test]
fn psd_parseval() {
    // Exact identity: Σ P Δκ = Σ w²u² / Σ w² (u detrended), to rounding.
    let s = test_record();
    let psd = Psd::estimate(&s, &PsdOptions { pad_factor: 4 }).unwrap();
    let u = detrend(&s).unwrap();
    let n = u.len();
    let (mut num, mut den) = (0.0, 0.0);
    for (i, &x) in u.values.iter().enumerate() {
        let w = 0.5 * (1.0 - (2.0 * PI * i as f64 / (n - 1) as f64).cos());
        num += w * w * x * x;
        den += w * w;
    }
    let rel = (psd.integral() / (num / den) - 1.0).abs();
    eprintln!("Parseval identity rel. error {rel:.2e}");
    assert!(rel < 1e-10);
    // Stationary multi-sine: window-weighted mean square ≈ variance Σ A²/2.
    let s = sines(
        0.0,
        0.0005,
        2000,
        &[(0.0273, 1.0, 0.3), (0.041, 0.7, 1.9), (0.0635, 0.5, -0.8)],
    );
    let var = (1.0 + 0.49 + 0.25) / 2.0;
    let psd = Psd::estimate(&s, &PsdOptions::default()).unwrap();
    let rel = (psd.integral() / var - 1.0).abs();
    eprintln!("PSD integral vs variance Σ A²/2: rel. error {rel:.2e}");
    assert!(rel < 0.01);
}

#[test]
fn resolution_at_40_mm_for_1_m_record() {
    // Δκ = 1/L = 1 m⁻¹ → Δλ = λ² /L = 1.6 mm at 40 mm.
    assert!((wavelength_resolution_m(0.040, 1.0) - 0.0016).abs() < 1e-15);
    let psd = Psd::estimate(&test_record(), &PsdOptions::default()).unwrap();
    assert!((psd.record_length_m - 1.0).abs() < 1e-12);
    // 2000 samples × 8 → 16384 bins: Δκ_bin = 1/(16384 · 0.5 mm) = 0.122 m⁻¹.
    assert!((psd.bin_per_m - 1.0 / (16384.0 * 0.0005)).abs() < 1e-12);
}

#[test]
fn band_pass_keeps_band_amplitudes() {
    // In-band sines alone; amplitude fitted over the interior (0.15 m from each end).
    let bp = BandPass::default();
    for &lam in &[0.022, 0.0273, 0.041, 0.0635, 0.075] {
        let s = sines(0.0, 0.0005, 2000, &[(lam, 1.0, 0.7)]);
        let f = band_pass(&s, &bp).unwrap();
        let a = fitted_amplitude(&f, lam, 300, 1700);
        let a_all = fitted_amplitude(&f, lam, 0, 2000);
        eprintln!(
            "λ {:.1} mm: interior amplitude {a:.5}, whole record {a_all:.5}",
            lam * 1e3
        );
        assert!((a - 1.0).abs() < 0.01, "λ {lam}: amplitude {a}");
    }
}

#[test]
fn band_pass_rejects_out_of_band() {
    let bp = BandPass::default();
    for &lam in &[0.005, 0.010, 0.150, 0.300] {
        let s = sines(0.0, 0.0005, 2000, &[(lam, 1.0, 0.4)]);
        let f = band_pass(&s, &bp).unwrap();
        let att_int = 20.0 * (rms(&f.values[300..1700]) / rms(&s.values[300..1700])).log10();
        let att_all = 20.0 * (rms(&f.values) / rms(&s.values)).log10();
        eprintln!(
            "λ {:.0} mm: interior {att_int:.1} dB, whole record {att_all:.1} dB",
            lam * 1e3
        );
        assert!(att_int < -40.0, "λ {lam}: {att_int} dB");
    }
}

/// The band with its roll-offs inside it, against the raised cosine's closed form: for
/// 20–80 mm (12.5–50 m⁻¹, roll-off 5 m⁻¹) gain 1 on 17.5–45 m⁻¹, 0 outside 12.5–50 m⁻¹, ½
/// half-way (15 and 47.5 m⁻¹). A 107 mm line (κ = 9.35 m⁻¹), which the product's band
/// passes at its roll-off gain `½(1 − cos(π(κ − 7.5)/5))` = 0.30, is removed, and a 40 mm
/// line is kept whole (amplitudes fitted over the interior).
#[test]
fn band_with_inside_rolloffs_passes_nothing_outside_the_band() {
    let bp = BandPass::default();
    let inside = bp.inside().unwrap();
    assert!((inside.lambda_min_m - 1.0 / 45.0).abs() < 1e-15);
    assert!((inside.lambda_max_m - 1.0 / 17.5).abs() < 1e-15);
    for (k, g) in [
        (12.4, 0.0),
        (12.5, 0.0),
        (15.0, 0.5),
        (17.5, 1.0),
        (30.0, 1.0),
        (45.0, 1.0),
        (47.5, 0.5),
        (50.0, 0.0),
        (50.1, 0.0),
    ] {
        assert!(
            (inside.gain(k) - g).abs() < 1e-12,
            "κ {k}: {} vs {g}",
            inside.gain(k)
        );
    }
    let k107 = 1.0 / 0.107;
    let g107 = 0.5 * (1.0 - (PI * (k107 - 7.5) / 5.0).cos());
    assert!((bp.gain(k107) - g107).abs() < 1e-12 && (g107 - 0.30).abs() < 0.01);
    let s = sines(0.0, 0.0005, 4000, &[(0.040, 1.0, 0.3), (0.107, 2.0, 1.1)]);
    let f = band_pass(&s, &bp).unwrap();
    let fi = band_pass(&s, &inside).unwrap();
    for (sig, a40, a107) in [(&f, 1.0, 2.0 * g107), (&fi, 1.0, 0.0)] {
        let b40 = fitted_amplitude(sig, 0.040, 600, 3400);
        let b107 = fitted_amplitude(sig, 0.107, 600, 3400);
        assert!((b40 - a40).abs() < 0.01, "40 mm: {b40} vs {a40}");
        assert!((b107 - a107).abs() < 0.01, "107 mm: {b107} vs {a107}");
    }
    // A band too narrow for two roll-offs inside it.
    let narrow = BandPass {
        lambda_min_m: 0.05,
        lambda_max_m: 0.06,
        transition_per_m: 5.0,
    };
    assert!(matches!(
        narrow.inside(),
        Err(SpectralError::BadBand { .. })
    ));
}

#[test]
fn band_pass_is_zero_phase() {
    let bp = BandPass::default();
    let s = sines(
        0.1,
        0.0005,
        2000,
        &[
            (0.041, 1.0, 0.3),
            (0.0273, 0.5, 1.1),
            (0.300, 2.0, 0.0),
            (0.005, 0.5, 0.0),
        ],
    );
    let f = band_pass(&s, &bp).unwrap();
    let clean = sines(0.1, 0.0005, 2000, &[(0.041, 1.0, 0.3), (0.0273, 0.5, 1.1)]);
    let lag = lag_of_max_correlation(&f, &clean, 0.010).unwrap();
    let ph = cross_phase_rad(&f, &clean, 0.041).unwrap();
    eprintln!(
        "zero phase: lag {:.3e} m, r {:.5}, phase at 41 mm {ph:.2e} rad",
        lag.lag_m, lag.correlation
    );
    assert!(lag.lag_m.abs() < 1e-5);
    assert!(ph.abs() < 1e-3);
    // Over the interior (0.15 m margins) the filtered signal equals the in-band part.
    let r_int = correlation_coefficient(
        &f.window_x(0.25, 0.85).unwrap(),
        &clean.window_x(0.25, 0.85).unwrap(),
    )
    .unwrap();
    eprintln!("interior correlation with the in-band part: {r_int:.6}");
    assert!(lag.correlation > 0.99);
    assert!(r_int > 0.9999);
}

#[test]
fn band_pass_rejects_bad_bands() {
    let s = sines(0.0, 0.0005, 2000, &[(0.041, 1.0, 0.0)]);
    let bad = BandPass {
        lambda_min_m: 0.08,
        lambda_max_m: 0.02,
        ..Default::default()
    };
    assert!(matches!(
        band_pass(&s, &bad),
        Err(SpectralError::BadBand { .. })
    ));
    let coarse = sines(0.0, 0.012, 100, &[(0.041, 1.0, 0.0)]);
    assert!(matches!(
        band_pass(&coarse, &BandPass::default()),
        Err(SpectralError::BadBand { .. })
    ));
    let short = sines(0.0, 0.0005, 100, &[(0.041, 1.0, 0.0)]);
    assert!(matches!(
        band_pass(&short, &BandPass::default()),
        Err(SpectralError::BadBand { .. })
    ));
}

#[test]
fn detrend_removes_line_exactly() {
    let s = Signal::new(
        0.0,
        0.001,
        (0..500).map(|i| 2.0 + 0.01 * i as f64).collect(),
    )
    .unwrap();
    let d = detrend(&s).unwrap();
    assert!(d.values.iter().all(|v| v.abs() < 1e-12));
}

#[test]
fn correlation_sign_and_quarter_wave() {
    // 1 m holding an integer number of 40 mm waves: closed forms r = 1, −1, 0.
    let lam = 0.040;
    let a = sines(0.0, 0.0005, 2000, &[(lam, 1.0, 0.2)]);
    let neg = Signal::new(a.x0_m, a.dx_m, a.values.iter().map(|v| -v).collect()).unwrap();
    let quarter = sines(0.0, 0.0005, 2000, &[(lam, 1.0, 0.2 - PI / 2.0)]); // shifted by λ/4
    let r1 = correlation_coefficient(&a, &a).unwrap();
    let rm = correlation_coefficient(&a, &neg).unwrap();
    let rq = correlation_coefficient(&a, &quarter).unwrap();
    eprintln!("r(self) {r1}, r(neg) {rm}, r(λ/4) {rq:.2e}");
    assert!((r1 - 1.0).abs() < 1e-12);
    assert!((rm + 1.0).abs() < 1e-12);
    assert!(rq.abs() < 1e-10);
    // Cross-spectral phase: −π for the negative, +π/2 for the λ/4 shift (φ_a − φ_b).
    let pm = cross_phase_rad(&a, &neg, lam).unwrap();
    let pq = cross_phase_rad(&a, &quarter, lam).unwrap();
    assert!((pm.abs() - PI).abs() < 1e-9);
    assert!((pq - PI / 2.0).abs() < 1e-6, "{pq}");
    // Zero variance is an error, not NaN.
    let flat = Signal::new(0.0, 0.0005, vec![1.0; 2000]).unwrap();
    assert!(matches!(
        correlation_coefficient(&a, &flat),
        Err(SpectralError::ZeroVariance { .. })
    ));
}

#[test]
fn cross_phase_of_shift_not_on_period() {
    // a(x) = b(x − s): φ_a − φ_b = −2π s/λ. 0.7 m record (non-integer number of waves).
    let (lam, s0) = (0.0273, 0.004);
    let b = sines(0.3, 0.0005, 1400, &[(lam, 1.0, 0.0)]);
    let a = sines(0.3, 0.0005, 1400, &[(lam, 1.0, -2.0 * PI * s0 / lam)]);
    let ph = cross_phase_rad(&a, &b, lam).unwrap();
    let want = -2.0 * PI * s0 / lam;
    eprintln!("cross phase {ph:.6} rad, closed form {want:.6}");
    assert!((ph - want).abs() < 1e-3);
}

#[test]
fn lag_of_shifted_signal_recovered() {
    // Broadband band-passed noise b; a(x) = b(x − s0) built by shifting the samples by an
    // integer plus a fractional part (linear interpolation of a 4× finer record).
    let mut nz = Noise::new(11);
    let fine: Vec<f64> = (0..8000).map(|_| nz.next()).collect();
    let fine = band_pass(
        &Signal::new(0.0, 0.000125, fine).unwrap(),
        &BandPass::default(),
    )
    .unwrap();
    // b = fine[4k + 400], a = fine[4k + 400 − m]: a(x) = b(x − m · 0.125 mm).
    for &m in &[0isize, 37, -50, 121] {
        let b: Vec<f64> = (0..1500).map(|k| fine.values[4 * k + 400]).collect();
        let a: Vec<f64> = (0..1500)
            .map(|k| fine.values[(4 * k as isize + 400 - m) as usize])
            .collect();
        let b = Signal::new(0.0, 0.0005, b).unwrap();
        let a = Signal::new(0.0, 0.0005, a).unwrap();
        let lag = lag_of_max_correlation(&a, &b, 0.03).unwrap();
        let want = m as f64 * 0.000125;
        eprintln!(
            "shift {:.4} mm → lag {:.4} mm (r {:.4})",
            want * 1e3,
            lag.lag_m * 1e3,
            lag.correlation
        );
        assert!(
            (lag.lag_m - want).abs() < 0.1 * 0.0005,
            "m {m}: {} vs {want}",
            lag.lag_m
        );
    }
}

#[test]
fn bad_inputs_are_errors() {
    let a = sines(0.0, 0.0005, 2000, &[(0.04, 1.0, 0.0)]);
    let b = sines(0.0, 0.0005, 1999, &[(0.04, 1.0, 0.0)]);
    assert!(matches!(
        correlation_coefficient(&a, &b),
        Err(SpectralError::GridMismatch { .. })
    ));
    assert!(Psd::estimate(&a, &PsdOptions { pad_factor: 0 }).is_err());
    let psd = Psd::estimate(&a, &PsdOptions::default()).unwrap();
    assert!(find_peaks(&psd, &PeakOptions::default(), 0.0).is_err());
    assert!(lag_of_max_correlation(&a, &a, 0.6).is_err());
}
