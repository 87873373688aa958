//! From a passage record to its [`PassageSummary`] (docs/theory.md §9): the signals along the rail
//! in the solution zone (`x = x₀ + V t` maps time to position), zero-phase band-pass
//! 20–80 mm, one-sided PSD in the wavelength domain (Hann window, ×8 zero padding, see
//! [`crate::spectral::psd`]), peaks with sub-bin accuracy, `f = V/λ`.
//!
//! Record length L = the solution zone (default 1 m): wavenumber resolution 1/L, i.e. at
//! 40 mm a wavelength resolution λ²/L = 1.6 mm; peaks are interpolated within a bin.

use super::record::PassageRecord;
use super::summary::{PassageSummary, WavelengthComponent, WavelengthSpectrum};
use super::PassageError;
use crate::spectral::{band_pass, find_peaks, BandPass, PeakOptions, Psd, PsdOptions, Signal};
use crate::units::{m_to_mm, Speed};

/// A signal of the record restricted to the solution zone.
pub fn zone_signal(rec: &PassageRecord, values: &[f64]) -> Result<Signal, PassageError> {
    let [z0, z1] = rec.zone_m;
    let h = &rec.histories;
    let i0 = h.x_m.partition_point(|&x| x < z0);
    let i1 = h.x_m.partition_point(|&x| x <= z1);
    if i1 <= i0 + 8 {
        return Err(PassageError::SolutionZoneTooShort {
            steps: i1.saturating_sub(i0),
        });
    }
    let dx = rec.speed_m_per_s * rec.dt_s;
    Ok(Signal::new(h.x_m[i0], dx, values[i0..i1].to_vec())?)
}

/// The wear `W_f(x)` of the record as a signal (J/m).
pub fn wear_signal(rec: &PassageRecord) -> Result<Signal, PassageError> {
    let dx = if rec.wear_x_m.len() > 1 {
        rec.wear_x_m[1] - rec.wear_x_m[0]
    } else {
        rec.speed_m_per_s * rec.dt_s
    };
    Ok(Signal::new(rec.wear_x_m[0], dx, rec.wear_j_per_m.clone())?)
}

/// Band-passed signal, its PSD, and its peaks.
pub struct Analysed {
    /// Mean of the raw signal.
    pub mean: f64,
    /// The band-passed signal.
    pub band: Signal,
    /// RMS of the band-passed signal.
    pub band_rms: f64,
    /// RMS of the signal filtered with the band's roll-offs inside it
    /// ([`BandPass::inside`]): the content strictly inside 20–80 mm.
    pub inside_rms: f64,
    /// PSD of the band-passed signal.
    pub psd: Psd,
    /// Peaks in 20–80 mm, strongest first.
    pub peaks: Vec<WavelengthComponent>,
    /// The same peaks as the spectral toolkit returns them (m, Hz).
    pub raw_peaks: Vec<crate::spectral::Peak>,
}

impl Analysed {
    /// The PSD of the band-passed signal at the positive wavenumbers `k` (1/m) as the
    /// columns of the passage's `psd_*.csv`: wavelength `1/k` (m), frequency `v k` (Hz) at
    /// speed `v` (m/s), and the one-sided PSD per unit wavenumber (signal² · m).
    pub fn psd_columns(&self, v: f64) -> [Vec<f64>; 3] {
        let mut c: [Vec<f64>; 3] = Default::default();
        for (k, p) in self.psd.wavenumber_per_m.iter().zip(&self.psd.psd) {
            if *k > 0.0 {
                c[0].push(1.0 / k);
                c[1].push(v * k);
                c[2].push(*p);
            }
        }
        c
    }
}

/// The band analyses of a passage's wear along the rail (`W_f`, J/m) and of its `F_L` and
/// `F_N` in the solution zone (N), in that order, at the passage's speed: what `passage`
/// writes to `wear.csv` (band-passed wear) and `psd_wear.csv`, `psd_fl.csv`, `psd_fn.csv`.
pub fn band_analyses(rec: &PassageRecord) -> Result<[Analysed; 3], PassageError> {
    let v = rec.speed_m_per_s;
    let h = &rec.histories;
    Ok([
        analyse(&wear_signal(rec)?, v)?,
        analyse(&zone_signal(rec, &h.longitudinal_n)?, v)?,
        analyse(&zone_signal(rec, &h.normal_n)?, v)?,
    ])
}

/// Analyses one signal along the rail at speed `v` (m/s).
pub fn analyse(sig: &Signal, v: f64) -> Result<Analysed, PassageError> {
    let mean = sig.values.iter().sum::<f64>() / sig.len() as f64;
    let band = band_pass(sig, &BandPass::default())?;
    let rms = |s: &Signal| (s.values.iter().map(|x| x * x).sum::<f64>() / s.len() as f64).sqrt();
    let band_rms = rms(&band);
    let inside_rms = rms(&band_pass(sig, &BandPass::default().inside()?)?);
    let psd = Psd::estimate(&band, &PsdOptions::default())?;
    let raw_peaks = if band_rms > 0.0 {
        find_peaks(&psd, &PeakOptions::default(), v)?
    } else {
        Vec::new()
    };
    let peaks = raw_peaks
        .iter()
        .map(|p| WavelengthComponent {
            wavelength_mm: m_to_mm(p.wavelength_m),
            frequency_hz: p.frequency_hz,
            psd: p.psd,
        })
        .collect();
    Ok(Analysed {
        mean,
        band,
        band_rms,
        inside_rms,
        psd,
        peaks,
        raw_peaks,
    })
}

/// The in-band part (20–80 mm) of a PSD as a wavelength spectrum.
pub fn band_spectrum(psd: &Psd) -> WavelengthSpectrum {
    let bp = BandPass::default();
    let mut out = WavelengthSpectrum::default();
    for (k, &p) in psd.wavenumber_per_m.iter().zip(&psd.psd) {
        if *k > 0.0 {
            let l = 1.0 / k;
            if l >= bp.lambda_min_m && l <= bp.lambda_max_m {
                out.wavelength_m.push(l);
                out.psd.push(p);
            }
        }
    }
    out
}

/// [`PassageError::ContactLost`] when the normal force is zero (or not positive) at any step:
/// a wheel off the rail transmits no force and wears nothing, which is no rolling result.
pub(crate) fn check_contact(h: &crate::passage::record::Histories) -> Result<(), PassageError> {
    let lost: Vec<usize> = (0..h.normal_n.len())
        .filter(|&i| h.normal_n[i].is_nan() || h.normal_n[i] <= 0.0)
        .collect();
    match lost.first() {
        None => Ok(()),
        Some(&i) => Err(PassageError::ContactLost {
            t_s: h.t_s[i],
            x_m: h.x_m[i],
            lost: lost.len(),
            steps: h.normal_n.len(),
        }),
    }
}

/// The summary of a passage record, at the record's speed (m/s) converted to km/h.
pub fn summarise(rec: &PassageRecord) -> Result<PassageSummary, PassageError> {
    summarise_at(rec, Speed::from_m_per_s(rec.speed_m_per_s))
}

/// The summary of a passage record run at `speed` (`speed.m_per_s()` is the record's
/// `speed_m_per_s`): its `speed_kmh` is `speed.kmh()` exactly, the speed as the caller gave it.
pub fn summarise_at(rec: &PassageRecord, speed: Speed) -> Result<PassageSummary, PassageError> {
    check_contact(&rec.histories)?;
    let v = speed.m_per_s();
    let h = &rec.histories;
    let fl = analyse(&zone_signal(rec, &h.longitudinal_n)?, v)?;
    let fnn = analyse(&zone_signal(rec, &h.normal_n)?, v)?;
    let w = analyse(&wear_signal(rec)?, v)?;
    let dom = w.peaks.first().cloned();
    Ok(PassageSummary {
        speed_kmh: speed.kmh(),
        mean_fn_n: fnn.mean,
        mean_fl_n: fl.mean,
        fl_band_rms_n: fl.band_rms,
        fn_band_rms_n: fnn.band_rms,
        wear_band_rms: w.band_rms,
        fl_inside_band_rms_n: fl.inside_rms,
        fn_inside_band_rms_n: fnn.inside_rms,
        wear_inside_band_rms: w.inside_rms,
        wear_mean: w.mean,
        dominant_wavelength_mm: dom.as_ref().map(|c| c.wavelength_mm),
        dominant_frequency_hz: dom.as_ref().map(|c| c.frequency_hz),
        wear_psd: band_spectrum(&w.psd),
        fl_psd: band_spectrum(&fl.psd),
        fn_psd: band_spectrum(&fnn.psd),
        wear_components: w.peaks,
        fl_components: fl.peaks,
        fn_components: fnn.peaks,
        steps: rec.steps,
        seconds: rec.seconds,
        contact_grid_widened: rec.contact_grid_widened,
    })
}

#[cfg(test)]
mod contact_tests {
    use super::{check_contact, PassageError};
    use crate::passage::record::Histories;

    fn histories(normal_n: &[f64]) -> Histories {
        let n = normal_n.len();
        Histories {
            t_s: (0..n).map(|i| i as f64 * 1e-4).collect(),
            x_m: (0..n).map(|i| 1.0 + i as f64 * 1e-3).collect(),
            normal_n: normal_n.to_vec(),
            ..Histories::default()
        }
    }

    #[test]
    fn a_step_without_normal_force_is_a_lost_contact_not_a_result() {
        assert!(check_contact(&histories(&[1e5, 9e4, 1.1e5])).is_ok());
        // Steps 2 and 3 of 4 at zero force: the first is at t = 2e-4 s, x = 1.002 m.
        match check_contact(&histories(&[1e5, 2e4, 0.0, 0.0])) {
            Err(PassageError::ContactLost {
                lost: 2, steps: 4, ..
            }) => {}
            other => panic!("{other:?}"),
        }
        let e = check_contact(&histories(&[1e5, 0.0, 0.0, f64::NAN])).unwrap_err();
        let text = e.to_string();
        assert!(
            text.contains("t = 0.000100 s") && text.contains("x = 1.0010 m"),
            "{text}"
        );
        assert!(
            text.contains("3 of 4") && text.contains("vehicle.primary_stiffness"),
            "{text}"
        );
    }
}
