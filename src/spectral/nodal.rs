//! The nodal spectrum: the frequencies a rail-top point's longitudinal displacement holds
//! while the wheel rolls over it (docs/theory.md §9.7).
//!
//! This is how the reference study obtained its "longitudinal-compression frequencies" of a
//! rail held at one strip per sleeper: not by an eigenanalysis, but from the spectrum of one
//! rail-top node's longitudinal displacement over a short stretch of the wheel's travel near
//! the node (from 0.1 m before to 0.2 m after it). Such a spectrum holds whatever drives the
//! rail at the contact — wheel modes and coupled modes included — so its peaks are reported
//! as "f_L by the nodal spectrum" beside the eigenfrequencies, never as eigenfrequencies.
//!
//! The record is the time history `u_x(t)` over the steps whose contact position lies in a
//! window of the travel. It is analysed with the PSD estimator of [`super::psd`] with time
//! in place of position (so its "wavenumber" is the frequency in Hz and its PSD is in
//! m²/Hz); peaks are found in a frequency band with the same rules. The intrinsic frequency
//! resolution of a record of duration `T` is `1/T` (Hz): 0.3 m at 140 km/h lasts 7.7 ms, a
//! resolution of 130 Hz; zero padding only interpolates.

use serde::{Deserialize, Serialize};

use super::{find_peaks, PeakOptions, Psd, PsdOptions, Signal, SpectralError};

/// One peak of a nodal spectrum.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct NodalPeak {
    /// Frequency (Hz).
    pub frequency_hz: f64,
    /// PSD of the longitudinal displacement at the peak (m²/Hz).
    pub psd_m2_per_hz: f64,
}

/// The spectrum of one record of a rail-top point's longitudinal displacement.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NodalSpectrum {
    /// What the record is (e.g. `short` or `zone`).
    pub record: String,
    /// Position of the point along the rail (m).
    pub point_x_m: f64,
    /// Contact positions the record spans, `[from, to]` (m).
    pub contact_from_to_m: [f64; 2],
    /// Duration of the record (s).
    pub duration_s: f64,
    /// Intrinsic frequency resolution `1/T` (Hz).
    pub resolution_hz: f64,
    /// Peaks, strongest first.
    pub peaks: Vec<NodalPeak>,
}

/// The history of one rail-top point during a passage.
#[derive(Clone, Copy, Debug)]
pub struct NodalHistory<'a> {
    /// Position of the point along the rail (m).
    pub point_x_m: f64,
    /// Times of the steps (s), uniform step.
    pub t_s: &'a [f64],
    /// Contact position at each step (m).
    pub x_contact_m: &'a [f64],
    /// Longitudinal displacement of the point at each step (m).
    pub ux_m: &'a [f64],
}

/// Spectrum of the history's `u_x` over the steps whose contact position lies in
/// `window_m = [from, to]` (m), with peaks in `band_hz = [lo, hi]` (Hz), at most `max_peaks`.
///
/// Errors: histories of different lengths, fewer than 16 steps in the window, a bad band.
pub fn nodal_spectrum(
    h: &NodalHistory<'_>,
    record: &str,
    window_m: [f64; 2],
    band_hz: [f64; 2],
    max_peaks: usize,
) -> Result<NodalSpectrum, SpectralError> {
    let (point_x_m, t_s, x_contact_m, ux_m) = (h.point_x_m, h.t_s, h.x_contact_m, h.ux_m);
    if t_s.len() != ux_m.len() || x_contact_m.len() != ux_m.len() {
        return Err(SpectralError::TooShort {
            len: ux_m.len().min(t_s.len()).min(x_contact_m.len()),
            min: ux_m.len().max(t_s.len()).max(x_contact_m.len()),
        });
    }
    let idx: Vec<usize> = (0..ux_m.len())
        .filter(|&i| x_contact_m[i] >= window_m[0] && x_contact_m[i] <= window_m[1])
        .collect();
    if idx.len() < 16 {
        return Err(SpectralError::TooShort {
            len: idx.len(),
            min: 16,
        });
    }
    let (i0, i1) = (idx[0], idx[idx.len() - 1]);
    let dt = (t_s[i1] - t_s[i0]) / (i1 - i0) as f64;
    let sig = Signal::new(t_s[i0], dt, ux_m[i0..=i1].to_vec())?;
    let psd = Psd::estimate(&sig, &PsdOptions::default())?;
    let opts = PeakOptions {
        lambda_min_m: 1.0 / band_hz[1],
        lambda_max_m: 1.0 / band_hz[0],
        max_count: max_peaks,
        ..PeakOptions::default()
    };
    // Unit "speed": time in place of position, so wavenumber = frequency.
    let peaks = find_peaks(&psd, &opts, 1.0)?
        .iter()
        .map(|p| NodalPeak {
            frequency_hz: p.frequency_hz,
            psd_m2_per_hz: p.psd,
        })
        .collect();
    let duration = sig.length_m();
    Ok(NodalSpectrum {
        record: record.to_string(),
        point_x_m,
        contact_from_to_m: [x_contact_m[i0], x_contact_m[i1]],
        duration_s: duration,
        resolution_hz: 1.0 / duration,
        peaks,
    })
}

/// The reference study's short record around a point at `x_m`: the contact from 0.1 m
/// before to 0.2 m after it (m).
pub fn short_window_m(x_m: f64) -> [f64; 2] {
    [x_m - 0.1, x_m + 0.2]
}

#[cfg(test)]
mod tests {
    use super::{nodal_spectrum, short_window_m, NodalHistory};
    /// Two sines of 780 and 1460 Hz in a 40 ms record at 20 kHz: the peaks are found at
    /// their frequencies within a tenth of the resolution 1/T, the stronger first; the short
    /// window gives the coarser resolution 1/T of its own duration.
    #[test]
    fn finds_the_frequencies_of_sines_with_the_record_resolution() {
        let dt = 5e-5;
        let v = 40.0;
        let n = 800;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * dt).collect();
        let x: Vec<f64> = t.iter().map(|t| 1.0 + v * t).collect();
        let u: Vec<f64> = t
            .iter()
            .map(|&t| {
                1e-6 * (2.0 * std::f64::consts::PI * 780.0 * t).sin()
                    + 0.4e-6 * (2.0 * std::f64::consts::PI * 1460.0 * t).sin()
            })
            .collect();
        let h = NodalHistory {
            point_x_m: 1.5,
            t_s: &t,
            x_contact_m: &x,
            ux_m: &u,
        };
        let s = nodal_spectrum(&h, "zone", [0.0, 10.0], [200.0, 3000.0], 5).unwrap();
        let res = s.resolution_hz;
        assert!((res - 1.0 / (n as f64 * dt)).abs() < 1e-9);
        assert_eq!(s.peaks.len(), 2, "{s:?}");
        assert!((s.peaks[0].frequency_hz - 780.0).abs() < 0.1 * res, "{s:?}");
        assert!(
            (s.peaks[1].frequency_hz - 1460.0).abs() < 0.1 * res,
            "{s:?}"
        );
        let w = short_window_m(1.5);
        let sh = nodal_spectrum(&h, "short", w, [200.0, 3000.0], 5).unwrap();
        assert!((sh.contact_from_to_m[0] - 1.4).abs() < v * dt);
        assert!(sh.resolution_hz > 5.0 * res, "{sh:?}");
        assert!(nodal_spectrum(&h, "x", [50.0, 60.0], [200.0, 3000.0], 5).is_err());
    }
}
