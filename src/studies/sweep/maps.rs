//! The frequency-selection maps assembled from the speed files.

use std::path::Path;

use crate::units::mm_to_m;

use super::report::write_outputs;
use super::run::same_speed;
use super::{linspace, read_summary, speed_file, MapOptions, StudiesError, SweepMaps, SweepRecord};
use crate::dynamics::{PassageSummary, WavelengthSpectrum};

/// PSD per wavenumber of `s` at wavenumber `k` (1/m): linear interpolation in `k` between
/// the spectrum's samples; 0 outside them.
pub(crate) fn psd_at_wavenumber(s: &WavelengthSpectrum, k: f64) -> f64 {
    let n = s.wavelength_m.len().min(s.psd.len());
    // Samples sorted by wavenumber ascending = wavelength descending (as stored).
    let kk = |i: usize| 1.0 / s.wavelength_m[i];
    if n == 0 || !k.is_finite() {
        return 0.0;
    }
    if n == 1 {
        return if (kk(0) - k).abs() <= 1e-12 * k.abs() {
            s.psd[0]
        } else {
            0.0
        };
    }
    let (lo, hi) = (kk(0).min(kk(n - 1)), kk(0).max(kk(n - 1)));
    if k < lo || k > hi {
        return 0.0;
    }
    let ascending = kk(0) <= kk(n - 1);
    let idx = |j: usize| if ascending { j } else { n - 1 - j };
    let j = (1..n).find(|&j| kk(idx(j)) >= k).unwrap_or(n - 1);
    let (a, b) = (idx(j - 1), idx(j));
    let (ka, kb) = (kk(a), kk(b));
    if kb == ka {
        return s.psd[b];
    }
    let t = (k - ka) / (kb - ka);
    s.psd[a] * (1.0 - t) + s.psd[b] * t
}

/// Reads the speed files of `speeds_kmh` from `dir/speeds` and writes every assembled output
/// of the module doc into `dir`.
pub fn assemble(
    dir: &Path,
    speeds_kmh: &[f64],
    opts: &MapOptions,
) -> Result<(SweepRecord, SweepMaps), StudiesError> {
    opts.check()?;
    let mut speeds = speeds_kmh.to_vec();
    speeds.sort_by(f64::total_cmp);
    if speeds.is_empty() {
        return Err(StudiesError::NoSpeeds);
    }
    let summaries = speeds
        .iter()
        .map(|&v| {
            let p = speed_file(dir, v);
            let s = read_summary(&p)?;
            if !same_speed(s.speed_kmh, v) {
                return Err(StudiesError::BadFile {
                    path: p,
                    reason: format!("holds {} km/h, expected {v} km/h", s.speed_kmh),
                });
            }
            Ok(s)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let maps = build_maps(&speeds, &summaries, opts);
    let dominant_wavelength_mm: Vec<Option<f64>> =
        summaries.iter().map(|s| s.dominant_wavelength_mm).collect();
    let dominant_frequency_hz: Vec<Option<f64>> =
        summaries.iter().map(|s| s.dominant_frequency_hz).collect();
    let lam: Vec<f64> = dominant_wavelength_mm.iter().flatten().copied().collect();
    let wavelength_range_ratio = (!lam.is_empty()).then(|| {
        lam.iter().copied().fold(f64::MIN, f64::max) / lam.iter().copied().fold(f64::MAX, f64::min)
    });
    let fl_dominant_frequency_hz: Vec<Option<f64>> = summaries
        .iter()
        .map(|s| s.fl_components.first().map(|c| c.frequency_hz))
        .collect();
    let attribute = |f: &[Option<f64>]| -> Vec<_> {
        f.iter()
            .map(|&f| crate::studies::coupled::attribute_one(&opts.coupled_modes, f))
            .collect()
    };
    let record = SweepRecord {
        speed_range_ratio: speeds[speeds.len() - 1] / speeds[0],
        speeds_kmh: speeds,
        wear_coupled: attribute(&dominant_frequency_hz),
        fl_coupled: attribute(&fl_dominant_frequency_hz),
        dominant_wavelength_mm,
        dominant_frequency_hz,
        fl_dominant_frequency_hz,
        wavelength_range_ratio,
        seconds: summaries.iter().map(|s| s.seconds).sum(),
        map: opts.clone(),
    };
    write_outputs(dir, &record, &maps)?;
    Ok((record, maps))
}

fn build_maps(speeds: &[f64], summaries: &[PassageSummary], opts: &MapOptions) -> SweepMaps {
    let lam = opts.wavelength_grid_mm();
    let vms: Vec<f64> = speeds.iter().map(|&v| crate::units::kmh_to_ms(v)).collect();
    let (lmin, lmax) = (
        mm_to_m(opts.wavelength_min_mm),
        mm_to_m(opts.wavelength_max_mm),
    );
    let f_lo = vms.iter().copied().fold(f64::MAX, f64::min) / lmax;
    let f_hi = vms.iter().copied().fold(f64::MIN, f64::max) / lmin;
    let freq = linspace(f_lo, f_hi, opts.frequency_points);
    let mut m = SweepMaps {
        speeds_kmh: speeds.to_vec(),
        wavelength_mm: lam.clone(),
        frequency_hz: freq.clone(),
        wear_wavelength: Vec::with_capacity(speeds.len() * lam.len()),
        fl_wavelength: Vec::with_capacity(speeds.len() * lam.len()),
        wear_frequency: Vec::with_capacity(speeds.len() * freq.len()),
        fl_frequency: Vec::with_capacity(speeds.len() * freq.len()),
    };
    for (s, &v) in summaries.iter().zip(&vms) {
        for &l in &lam {
            let k = 1.0 / mm_to_m(l);
            m.wear_wavelength.push(psd_at_wavenumber(&s.wear_psd, k));
            m.fl_wavelength.push(psd_at_wavenumber(&s.fl_psd, k));
        }
        for &f in &freq {
            let lambda = v / f;
            let inside = (lmin * (1.0 - 1e-12)..=lmax * (1.0 + 1e-12)).contains(&lambda);
            let k = f / v;
            let val = |sp: &WavelengthSpectrum| {
                if inside {
                    psd_at_wavenumber(sp, k) / v
                } else {
                    0.0
                }
            };
            m.wear_frequency.push(val(&s.wear_psd));
            m.fl_frequency.push(val(&s.fl_psd));
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::{psd_at_wavenumber, WavelengthSpectrum};
    #[test]
    fn wavenumber_interpolation_is_linear_in_k_and_zero_outside() {
        // Samples at λ = 0.08, 0.04, 0.02 m → k = 12.5, 25, 50 1/m.
        let s = WavelengthSpectrum {
            wavelength_m: vec![0.08, 0.04, 0.02],
            psd: vec![1.0, 3.0, 7.0],
        };
        assert_eq!(psd_at_wavenumber(&s, 12.5), 1.0);
        assert_eq!(psd_at_wavenumber(&s, 25.0), 3.0);
        assert!((psd_at_wavenumber(&s, 18.75) - 2.0).abs() < 1e-12);
        assert!((psd_at_wavenumber(&s, 37.5) - 5.0).abs() < 1e-12);
        assert_eq!(psd_at_wavenumber(&s, 12.0), 0.0);
        assert_eq!(psd_at_wavenumber(&s, 51.0), 0.0);
        assert_eq!(psd_at_wavenumber(&WavelengthSpectrum::default(), 20.0), 0.0);
    }
}
