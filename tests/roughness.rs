//! Measured roughness: a profile's one-third-octave band levels against a synthetic roughness
//! of known band levels (irregular sampling, gaps, a trend), and the forecast against a known
//! growth applied to that roughness.

use corrugation::growth::rate::{GrowthRateSpectrum, RatePoint};
use corrugation::roughness::{
    forecast, third_octave_bands, Band, BandSpectrum, MeasuredProfile, SpectrumOptions,
};
use corrugation::units::Speed;

/// A deterministic pseudo-random sequence in [0, 1) (a linear congruential generator), so
/// the synthetic roughness is the same on every run.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// One sinusoid of the synthetic roughness: wavenumber (1/m), amplitude (m), phase (rad).
type Tone = (f64, f64, f64);

/// A roughness whose band `b` has the mean square `10^(L_b/10)·r₀²` exactly: sinusoids of
/// equal amplitude, random phases, at wavenumbers three lines apart on the spectral lines of
/// a 4 m segment (so that no two share a Hann lobe and each lobe stays in its band: none within
/// 1.5 lines of an edge).
fn tones(levels: &[(Band, f64)], rng: &mut Lcg) -> Vec<Tone> {
    let dk = 1.0 / 4.0;
    let mut out = Vec::new();
    for (b, level) in levels {
        let ms = 10f64.powf(level / 10.0) * 1e-12;
        let [k0, k1] = b.wavenumbers();
        let first = ((k0 + 1.5 * dk) / dk).ceil() as i64;
        let last = ((k1 - 1.5 * dk) / dk).floor() as i64;
        let ks: Vec<f64> = (first..=last).step_by(3).map(|j| j as f64 * dk).collect();
        assert!(!ks.is_empty(), "band {} m has no line", b.nominal_m());
        let a = (2.0 * ms / ks.len() as f64).sqrt();
        for k in ks {
            out.push((k, a, 2.0 * std::f64::consts::PI * rng.next()));
        }
    }
    out
}

fn height(tones: &[Tone], x: f64) -> f64 {
    tones
        .iter()
        .map(|(k, a, p)| a * (2.0 * std::f64::consts::PI * k * x + p).cos())
        .sum()
}

/// A 40 m record sampled about every millimetre with ±30 % jitter, a 0.2 m gap of missing
/// rows, a 0.3 m stretch of `nan` heights (an edited-out weld), an offset and a trend of
/// 20 µm/m.
fn record(tones: &[Tone], rng: &mut Lcg) -> MeasuredProfile {
    let (mut xs, mut hs) = (Vec::new(), Vec::new());
    let mut x = 0.0;
    while x < 40.0 {
        let missing = (12.0..12.2).contains(&x);
        if !missing {
            let weld = (25.0..25.3).contains(&x);
            let h = if weld {
                f64::NAN
            } else {
                height(tones, x) + 3e-5 + 2e-5 * x
            };
            xs.push(x);
            hs.push(h);
        }
        x += 1e-3 * (0.7 + 0.6 * rng.next());
    }
    MeasuredProfile::new(xs, hs, "synthetic").unwrap()
}

/// The band levels of a synthetic roughness of known spectrum are recovered within 0.5 dB
/// in every band from 160 mm to 12.5 mm (levels from −12 to +8 dB re 1 µm, irregular sampling,
/// two gaps, a trend).
#[test]
fn a_synthetic_profile_s_band_levels_are_recovered_within_half_a_decibel() {
    let mut rng = Lcg(7);
    let bands = third_octave_bands(0.16, 0.0125);
    let levels: Vec<(Band, f64)> = bands
        .iter()
        .map(|b| (*b, -12.0 + 20.0 * rng.next()))
        .collect();
    let t = tones(&levels, &mut rng);
    let p = record(&t, &mut rng);
    let s = p.band_spectrum(&SpectrumOptions::default()).unwrap();
    let mut worst: f64 = 0.0;
    for (b, want) in &levels {
        let got = s
            .level_at(b.centre_m())
            .unwrap_or_else(|| panic!("no band at {} m", b.nominal_m()));
        worst = worst.max((got - want).abs());
        println!(
            "{:>6.1} mm: synthetic {want:6.2} dB, recovered {got:6.2} dB, error {:+.3} dB",
            corrugation::units::m_to_mm(b.nominal_m()),
            got - want
        );
        assert!(
            (got - want).abs() < 0.5,
            "{} mm: {got:.2} dB, expected {want:.2} dB",
            b.nominal_m() * 1e3
        );
    }
    println!("worst band error {worst:.3} dB over {} bands", levels.len());
}

/// A growth-rate spectrum with a constant `σ` in each band.
fn rates(sigma_of: impl Fn(f64) -> f64) -> GrowthRateSpectrum {
    let v = Speed::from_kmh(100.0);
    let points = (0..=600)
        .map(|i| {
            let l = 0.02 + 0.06 * i as f64 / 600.0;
            RatePoint {
                wavelength_m: l,
                frequency_hz: v.m_per_s() / l,
                gain_j_per_m2: 0.0,
                phase_deg: 0.0,
                growth_rate_per_passage: sigma_of(l),
                wear_parts_re: [0.0; 4],
                wear_parts_im: [0.0; 4],
                normal_force_n_per_m: 0.0,
                longitudinal_force_n_per_m: 0.0,
            }
        })
        .collect();
    GrowthRateSpectrum {
        speed: v,
        wear_coefficient_m3_per_j: 0.0,
        width_m: 0.0,
        points,
        rigid: Vec::new(),
        normal_only: Vec::new(),
    }
}

/// A known growth: every sinusoid of the synthetic roughness grown by `(1 + σ)^N` with `σ`
/// constant per band (+2e-5 in the 40 and 50 mm bands, −1e-5 in the others of 20–80 mm), the
/// grown profile's band levels measured again; the forecast from the first profile's levels
/// equals them within 0.5 dB, and equals `L_0 + 20 N lg(1 + σ)` to rounding.
#[test]
fn the_forecast_equals_a_known_growth_applied_to_the_roughness() {
    let mut rng = Lcg(11);
    let bands = third_octave_bands(0.1, 0.0125);
    let levels: Vec<(Band, f64)> = bands
        .iter()
        .map(|b| (*b, -5.0 + 4.0 * rng.next()))
        .collect();
    let sigma_of = |l: f64| -> f64 {
        let b = bands.iter().find(|b| b.holds(l));
        match b.map(|b| (b.nominal_m() * 1e3).round() as i64) {
            Some(40) | Some(50) => 2e-5,
            _ => -1e-5,
        }
    };
    let n: f64 = 40_000.0;
    let t0 = tones(&levels, &mut rng);
    let grown: Vec<Tone> = t0
        .iter()
        .map(|&(k, a, p)| (k, a * (1.0 + sigma_of(1.0 / k)).powf(n), p))
        .collect();
    let mut rng2 = Lcg(99);
    let before = record(&t0, &mut rng2)
        .band_spectrum(&SpectrumOptions::default())
        .unwrap();
    let mut rng3 = Lcg(99);
    let after = record(&grown, &mut rng3)
        .band_spectrum(&SpectrumOptions::default())
        .unwrap();
    let f = forecast(&before, &rates(sigma_of), n);
    let mut covered = 0;
    for (i, b) in f.bands.iter().enumerate() {
        let Some(l_after) = b.level_after_db else {
            continue;
        };
        covered += 1;
        let c = before.bands[i].centre_m();
        let measured_after = after.level_at(c).unwrap();
        assert!(
            (l_after - measured_after).abs() < 0.5,
            "{} mm: forecast {l_after:.2} dB, grown profile {measured_after:.2} dB",
            b.centre_m * 1e3
        );
        let s = sigma_of(c);
        let closed = before.level_db[i] + 20.0 * n * (1.0 + s).log10();
        assert!((l_after - closed).abs() < 1e-9, "{l_after} {closed}");
        assert!((b.db_per_passage.unwrap() - 20.0 * (1.0 + s).log10()).abs() < 1e-12);
    }
    // 25 … 80 mm have their centres inside the 20–80 mm rate spectrum (the 20 mm band's
    // exact centre, 19.95 mm, lies just outside it)
    assert_eq!(covered, 6);
    assert_eq!(
        f.growing_m()
            .iter()
            .map(|m| (m * 1e3).round() as i64)
            .collect::<Vec<_>>(),
        vec![50, 40]
    );
    assert!(
        f.sentence().contains("2 band(s) grow (50, 40 mm)"),
        "{}",
        f.sentence()
    );
}

/// The forecast over a tonnage does not overflow: 1e9 passages of a growing band give a
/// finite level, larger by `20·N·lg(1+σ)`.
#[test]
fn a_forecast_over_many_passages_stays_finite() {
    let s = BandSpectrum::parse_csv("wavelength_mm, level_db\n40, 0\n", "t").unwrap();
    let f = forecast(&s, &rates(|_| 1e-6), 1e9);
    let l = f.bands[0].level_after_db.unwrap();
    assert!(l.is_finite());
    assert!(
        (l - 20.0 * 1e9 * (1.0f64 + 1e-6).log10()).abs() < 1e-3 * l.abs(),
        "{l}"
    );
}

/// Bad input is refused with the file and what to change: a header without units, positions
/// that do not ascend, a record with no segment without a gap.
#[test]
fn bad_profiles_are_refused_with_what_to_change() {
    let e = MeasuredProfile::parse_csv("x, h\n0, 1\n", "p.csv").unwrap_err();
    assert!(e.to_string().contains("p.csv") && e.to_string().contains("x_m, height_um"));
    let e = MeasuredProfile::parse_csv(
        "x_m, height_um\n0,1\n0.1,1\n0.05,1\n0.2,1\n0.3,1\n0.4,1\n0.5,1\n0.6,1\n0.7,1\n",
        "p.csv",
    )
    .unwrap_err();
    assert!(e.to_string().contains("ascend"), "{e}");
    let text: String = std::iter::once("x_m, height_um\n".to_string())
        .chain((0..500).map(|i| format!("{},{}\n", i as f64 * 1e-3, (i % 7) as f64)))
        .collect();
    let p = MeasuredProfile::parse_csv(&text, "short.csv").unwrap();
    let e = p.band_spectrum(&SpectrumOptions::default()).unwrap_err();
    assert!(e.to_string().contains("without a gap"), "{e}");
    // heights in nm read as µm: a warning names the unit
    let text: String = std::iter::once("x_m, height_um\n".to_string())
        .chain((0..500).map(|i| format!("{},{}\n", i as f64 * 1e-3, 5000.0 * (i as f64).sin())))
        .collect();
    let p = MeasuredProfile::parse_csv(&text, "nm.csv").unwrap();
    assert!(p.unit_slip().unwrap().contains("µm"));
}

/// Traffic in MGT becomes wheel passages over one rail as `MGT·1e9 kg / (2W/g)`: 1 MGT at
/// W = 100 kN is 49 050 passages; out-of-range and doubly given traffic is refused; a band
/// spectrum from arrays equals the one from its CSV.
#[test]
fn traffic_and_band_arrays() {
    use corrugation::roughness::traffic_passages;
    let n = traffic_passages(None, Some(1.0), 1e5).unwrap();
    assert!((n - 1e9 * 9.81 / 2e5).abs() < 1e-6, "{n}");
    assert_eq!(traffic_passages(Some(1e4), None, 1e5).unwrap(), 1e4);
    assert_eq!(traffic_passages(None, None, 1e5).unwrap(), n);
    for (p, g) in [(Some(0.5), None), (None, Some(0.0)), (Some(1e4), Some(1.0))] {
        assert!(traffic_passages(p, g, 1e5).is_err(), "{p:?} {g:?}");
    }
    let a = BandSpectrum::from_levels(&[0.04, 0.0315], &[-3.0, -6.0], "a").unwrap();
    let c = BandSpectrum::parse_csv("wavelength_m, level_db\n0.04, -3\n0.0315, -6\n", "c").unwrap();
    assert_eq!(a, c);
    assert!(BandSpectrum::from_levels(&[0.04], &[f64::NAN], "a").is_err());
}

/// A standard normal deviate (Box–Muller) from the test's generator.
fn normal(rng: &mut Lcg) -> f64 {
    let u = 1.0 - rng.next();
    (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * rng.next()).cos()
}

/// The random-process roughness of validation/roughness.md: one-sided spectrum
/// `S(k) = A·k⁻³` (m²·m) from 2 to 120 1/m, the 40 mm band at 0 dB re 1 µm.
struct PowerLaw {
    /// Level constant `A` (m²/m²).
    a: f64,
}

impl PowerLaw {
    const K_MIN: f64 = 2.0;
    const K_MAX: f64 = 120.0;

    fn new() -> Self {
        let [k0, k1] = Band { index: 14 }.wavenumbers(); // 39.8 mm, the 40 mm band
        Self {
            a: 2.0e-12 / (k0.powi(-2) - k1.powi(-2)),
        }
    }

    fn density(&self, k: f64) -> f64 {
        if (Self::K_MIN..=Self::K_MAX).contains(&k) {
            self.a * k.powi(-3)
        } else {
            0.0
        }
    }

    /// The band's true level (dB re 1 µm): `10 lg(A/2·(k₀⁻² − k₁⁻²) / r₀²)`.
    fn level_db(&self, b: &Band) -> f64 {
        let [k0, k1] = b.wavenumbers();
        10.0 * (self.a / 2.0 * (k0.powi(-2) - k1.powi(-2)) / 1e-12).log10()
    }

    /// One record of `length_m` sampled every millimetre: `Σ_j a_j cos(2πk_j x) + b_j
    /// sin(2πk_j x)` over the record's lines `k_j = j/length`, `a_j, b_j ~ N(0, S(k_j)/length)`,
    /// by one inverse FFT.
    fn record(&self, length_m: f64, rng: &mut Lcg) -> MeasuredProfile {
        use rustfft::{num_complex::Complex64, FftPlanner};
        let n = (length_m / 1e-3).round() as usize;
        let dk = 1.0 / length_m;
        let mut c = vec![Complex64::new(0.0, 0.0); n];
        for (j, cj) in c.iter_mut().enumerate().take(n / 2).skip(1) {
            let s = (self.density(j as f64 * dk) * dk).sqrt();
            *cj = Complex64::new(s * normal(rng), -s * normal(rng));
        }
        FftPlanner::<f64>::new().plan_fft_inverse(n).process(&mut c);
        let xs = (0..n).map(|i| i as f64 * 1e-3).collect();
        let hs = c.iter().map(|z| z.re).collect();
        MeasuredProfile::new(xs, hs, "random process").unwrap()
    }
}

/// The estimator's predicted standard deviation of a band level (dB) for `segments`
/// half-overlapping Hann segments of 4 m: `4.34·√(2.6/(n·K))`, `n` the lines in the band.
fn predicted_sigma_db(b: &Band, segments: usize) -> f64 {
    let [k0, k1] = b.wavenumbers();
    let lines = (k1 - k0) * SpectrumOptions::default().segment_length_m;
    10.0 / std::f64::consts::LN_10 * (2.6 / (lines * segments as f64)).sqrt()
}

/// R1 and R2 of validation/roughness.md: over 20 independent 40 m records of a random-process
/// roughness, the band analysis is unbiased (mean error within 0.3 dB in every band from
/// 160 mm to 12.5 mm) and its spread is what the record length predicts (0.5–1.6 × σ).
#[test]
fn a_random_process_s_band_levels_are_estimated_without_bias_and_with_the_predicted_spread() {
    let process = PowerLaw::new();
    let bands = third_octave_bands(0.16, 0.0125);
    let mut rng = Lcg(20_261_130);
    let records = 20;
    let errors: Vec<Vec<f64>> = (0..records)
        .map(|_| {
            let s = process
                .record(40.0, &mut rng)
                .band_spectrum(&SpectrumOptions::default())
                .unwrap();
            bands
                .iter()
                .map(|b| s.level_at(b.centre_m()).unwrap() - process.level_db(b))
                .collect()
        })
        .collect();
    println!("band (mm)  true (dB)  mean error  std  predicted σ  ratio");
    let mut misses = Vec::new();
    for (i, b) in bands.iter().enumerate() {
        let e: Vec<f64> = errors.iter().map(|r| r[i]).collect();
        let mean = e.iter().sum::<f64>() / records as f64;
        let std = (e.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (records - 1) as f64).sqrt();
        let sigma = predicted_sigma_db(b, 19);
        println!(
            "{:>8.1}  {:>9.2}  {mean:>+10.3}  {std:.3}  {sigma:>11.3}  {:.2}",
            corrugation::units::m_to_mm(b.nominal_m()),
            process.level_db(b),
            std / sigma
        );
        if mean.abs() > 0.3 {
            misses.push(format!(
                "{} mm: mean error {mean:+.3} dB",
                b.nominal_m() * 1e3
            ));
        }
        if !(0.5..=1.6).contains(&(std / sigma)) {
            misses.push(format!(
                "{} mm: spread {std:.3} dB against σ {sigma:.3} dB",
                b.nominal_m() * 1e3
            ));
        }
    }
    assert!(misses.is_empty(), "{misses:?}");
}

/// R3 of validation/roughness.md: one 400 m record of the random-process roughness gives
/// every band whose predicted σ is at most 0.17 dB within 0.5 dB of its true level.
#[test]
fn a_long_random_record_s_band_levels_are_within_half_a_decibel() {
    let process = PowerLaw::new();
    let mut rng = Lcg(400);
    let s = process
        .record(400.0, &mut rng)
        .band_spectrum(&SpectrumOptions::default())
        .unwrap();
    let mut tested = 0;
    for b in third_octave_bands(0.16, 0.0125) {
        let error = s.level_at(b.centre_m()).unwrap() - process.level_db(&b);
        let sigma = predicted_sigma_db(&b, 199);
        println!(
            "{:>6.1} mm: error {error:+.3} dB, predicted σ {sigma:.3} dB",
            corrugation::units::m_to_mm(b.nominal_m())
        );
        if sigma <= 0.17 {
            tested += 1;
            assert!(
                error.abs() <= 0.5,
                "{} mm: {error:+.3} dB",
                b.nominal_m() * 1e3
            );
        }
    }
    assert!(tested >= 10, "only {tested} bands have σ ≤ 0.17 dB");
}
