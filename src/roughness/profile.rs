//! A measured roughness profile (height along the rail) and its one-third-octave band
//! spectrum, processed as EN 15610 describes for its Fourier method.
//!
//! The record may be irregularly sampled, hold gaps (missing rows, or `nan` heights where a
//! joint or a weld was edited out) and a trend (the trolley's datum drifting). The processing:
//!
//! 1. **Continuous parts.** The record is split wherever a height is missing or two samples
//!    are more than [`SpectrumOptions::gap_factor`] times the median spacing apart.
//! 2. **Resampling.** Each part is interpolated linearly to the record's median spacing.
//! 3. **Segments.** Each part is cut into segments of [`SpectrumOptions::segment_length_m`]
//!    overlapping by half (a part shorter than one segment is left out); each segment loses
//!    its mean and its linear trend (least squares) and is weighted by a Hann window.
//! 4. **Spectrum.** The one-sided spectrum of every segment, normalised so that it sums to
//!    the segment's mean square (Parseval, with the window's power), is averaged over all
//!    segments of all parts, and the lines are summed into bands: a line `Δk = 1/L` wide is
//!    shared between two bands in proportion to its width on each side of their edge.
//!
//! Bands are reported from the longest wavelength a segment holds four times
//! (`segment_length / 4`) down to four samples per wavelength.

use std::path::Path;

use rustfft::num_complex::Complex64;
use rustfft::FftPlanner;

use super::bands::{third_octave_bands, BandSpectrum, REFERENCE_ROUGHNESS_M};
use super::RoughnessError;

/// The lines of the segment's spectrum a band must hold at least: a band of centre `λ` is
/// `0.23/λ` wide in wavenumber, so with segments of length `L` (lines `1/L` apart) the
/// longest band reported has `λ ≤ 0.23·L/4 ≈ L/17.3`.
const LINES_PER_BAND: f64 = 4.0 / 0.2306;

/// The samples per wavelength the shortest band reported needs (linear resampling of an
/// irregular record loses about 2 % of the amplitude at 10 samples per wavelength).
const SAMPLES_PER_WAVELENGTH: f64 = 10.0;

/// Default segment length of the band analysis (m).
pub const DEFAULT_SEGMENT_LENGTH_M: f64 = 4.0;

/// Settings of the band analysis of a profile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpectrumOptions {
    /// Segment length (m), default 4 m (EN 15610 asks for at least 1 m; 4 m resolve bands up
    /// to 0.2 m); range 0.1–20 m.
    pub segment_length_m: f64,
    /// A spacing larger than this many median spacings is a gap (−), default 5; range ≥ 1.5.
    pub gap_factor: f64,
}

impl Default for SpectrumOptions {
    fn default() -> Self {
        Self {
            segment_length_m: DEFAULT_SEGMENT_LENGTH_M,
            gap_factor: 5.0,
        }
    }
}

/// A measured rail roughness profile: heights along the rail, in the order measured.
#[derive(Clone, Debug, PartialEq)]
pub struct MeasuredProfile {
    /// Position along the rail (m), strictly ascending.
    pub x_m: Vec<f64>,
    /// Height (m), positive up; `NaN` where the record has a gap.
    pub height_m: Vec<f64>,
    /// What the profile is called in messages (its file, or "profile").
    pub name: String,
}

impl MeasuredProfile {
    /// A profile from positions `x_m` (m, strictly ascending) and heights `height_m` (m; `NaN`
    /// marks a gap).
    pub fn new(x_m: Vec<f64>, height_m: Vec<f64>, name: &str) -> Result<Self, RoughnessError> {
        let bad = |reason: String| RoughnessError::Format {
            path: name.to_string(),
            reason,
        };
        if x_m.len() != height_m.len() {
            return Err(bad(format!(
                "{} positions but {} heights",
                x_m.len(),
                height_m.len()
            )));
        }
        if let Some(i) = x_m.iter().position(|x| !x.is_finite()) {
            return Err(bad(format!("position {i} is not a finite number")));
        }
        if let Some(reason) = crate::lists::strictly_ascending_error(&x_m) {
            return Err(bad(reason));
        }
        if let Some(h) = height_m.iter().find(|h| h.is_infinite()) {
            return Err(bad(format!(
                "a height is {h}: give a number or nan for a gap"
            )));
        }
        if height_m.iter().filter(|h| h.is_finite()).count() < 8 {
            return Err(bad("fewer than 8 heights: not a profile".into()));
        }
        Ok(Self {
            x_m,
            height_m,
            name: name.to_string(),
        })
    }

    /// Reads a profile from CSV: a header `x_m, height_um`, then one row per sample
    /// (position in m, height in µm; `nan` or an empty cell for a gap). `#` starts a comment.
    pub fn read_csv(path: &Path) -> Result<Self, RoughnessError> {
        Self::parse_csv(&super::read_text(path)?, &path.display().to_string())
    }

    /// [`Self::read_csv`] on text; `name` names it in messages.
    pub fn parse_csv(text: &str, name: &str) -> Result<Self, RoughnessError> {
        let bad = |reason: String| RoughnessError::Format {
            path: name.to_string(),
            reason,
        };
        let (header, lines) = super::csv_lines(text, name, "x_m, height_um")?;
        if header.len() < 2 || header[0] != "x_m" || header[1] != "height_um" {
            return Err(bad(format!(
                "the header `{}` must be `x_m, height_um` (position in m, height in µm)",
                header.join(", ")
            )));
        }
        let (mut xs, mut hs) = (Vec::new(), Vec::new());
        for (i, line) in lines.into_iter().enumerate() {
            let cells: Vec<&str> = line.split(',').map(str::trim).collect();
            let x = cells
                .first()
                .and_then(|c| c.parse::<f64>().ok())
                .ok_or_else(|| {
                    bad(format!(
                        "data row {}: x `{}` is not a number",
                        i + 1,
                        cells[0]
                    ))
                })?;
            let h = match cells.get(1).copied().unwrap_or("") {
                "" => f64::NAN,
                c if c.eq_ignore_ascii_case("nan") => f64::NAN,
                c => c.parse::<f64>().map_err(|_| {
                    bad(format!(
                        "data row {}: height `{c}` (µm) is not a number",
                        i + 1
                    ))
                })?,
            };
            xs.push(x);
            hs.push(crate::units::um_to_m(h));
        }
        Self::new(xs, hs, name)
    }

    /// A warning when the heights look like a unit slip: an RMS above 1 mm (heights written
    /// in nm are read as µm, 1000 times too large) or below 1 nm (heights in mm or m).
    pub fn unit_slip(&self) -> Option<String> {
        let h: Vec<f64> = self
            .height_m
            .iter()
            .copied()
            .filter(|h| h.is_finite())
            .collect();
        let mean = h.iter().sum::<f64>() / h.len() as f64;
        let rms = (h.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / h.len() as f64).sqrt();
        (!(1e-9..=1e-3).contains(&rms)).then(|| {
            format!(
                "{}: the heights' RMS is {:.3e} µm; rail roughness is about 0.1 to 100 µm: are the heights in µm (height_um)?",
                self.name,
                rms * 1e6
            )
        })
    }

    /// Median sample spacing (m).
    pub(crate) fn median_spacing_m(&self) -> f64 {
        let mut d: Vec<f64> = self.x_m.windows(2).map(|w| w[1] - w[0]).collect();
        d.sort_by(f64::total_cmp);
        d[d.len() / 2]
    }

    /// The continuous parts of the record, each resampled to the median spacing `dx`:
    /// `(x of the first sample (m), heights (m))`.
    pub(crate) fn continuous_parts(&self, opts: &SpectrumOptions) -> Vec<(f64, Vec<f64>)> {
        let dx = self.median_spacing_m();
        let n = self.x_m.len();
        let mut ranges = Vec::new();
        let mut start = None::<usize>;
        for i in 0..n {
            let sampled = self.height_m[i].is_finite();
            let gap_before = i > 0 && self.x_m[i] - self.x_m[i - 1] > opts.gap_factor * dx;
            if let Some(a) = start {
                if !sampled || gap_before {
                    ranges.push(a..i);
                    start = None;
                }
            }
            if sampled && start.is_none() {
                start = Some(i);
            }
        }
        if let Some(a) = start {
            ranges.push(a..n);
        }
        ranges
            .into_iter()
            .filter_map(|r| self.resample(r.start, r.end, dx))
            .collect()
    }

    /// Samples `[a, b)` interpolated linearly at spacing `dx` from the first one.
    fn resample(&self, a: usize, b: usize, dx: f64) -> Option<(f64, Vec<f64>)> {
        if b - a < 2 {
            return None;
        }
        let (x, h) = (&self.x_m[a..b], &self.height_m[a..b]);
        let m = ((x[x.len() - 1] - x[0]) / dx + 1e-9).floor() as usize + 1;
        let mut out = Vec::with_capacity(m);
        let mut j = 0;
        for k in 0..m {
            let xk = x[0] + k as f64 * dx;
            while j + 2 < x.len() && x[j + 1] < xk {
                j += 1;
            }
            let t = ((xk - x[j]) / (x[j + 1] - x[j])).clamp(0.0, 1.0);
            out.push(h[j] + t * (h[j + 1] - h[j]));
        }
        Some((x[0], out))
    }

    /// The one-third-octave band spectrum (see the module documentation).
    pub fn band_spectrum(&self, opts: &SpectrumOptions) -> Result<BandSpectrum, RoughnessError> {
        check_options(opts)?;
        let dx = self.median_spacing_m();
        let n = (opts.segment_length_m / dx).round() as usize;
        if n < 16 {
            return Err(RoughnessError::OutOfRange {
                what: "segment length / median sample spacing",
                value: n as f64,
                expected: format!(
                    "at least 16 samples per segment: the median spacing of {} is {dx} m",
                    self.name
                ),
            });
        }
        let seg_len = n as f64 * dx;
        let window: Vec<f64> = (0..n)
            .map(|i| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / n as f64).cos())
            .collect();
        let w2: f64 = window.iter().map(|w| w * w).sum();
        let fft = FftPlanner::<f64>::new().plan_fft_forward(n);
        let mut lines = vec![0.0; n / 2 + 1];
        let mut count = 0usize;
        let mut buf = vec![Complex64::new(0.0, 0.0); n];
        for (_, h) in self.continuous_parts(opts) {
            let mut s = 0;
            while s + n <= h.len() {
                let seg = detrend(&h[s..s + n]);
                for (b, (v, w)) in buf.iter_mut().zip(seg.iter().zip(&window)) {
                    *b = Complex64::new(v * w, 0.0);
                }
                fft.process(&mut buf);
                for (j, l) in lines.iter_mut().enumerate() {
                    // one-sided: every line but 0 and n/2 doubled
                    let two = if j == 0 || 2 * j == n { 1.0 } else { 2.0 };
                    *l += two * buf[j].norm_sqr() / (n as f64 * w2);
                }
                count += 1;
                s += n / 2;
            }
        }
        if count == 0 {
            return Err(RoughnessError::OutOfRange {
                what: "longest continuous part (m)",
                value: self
                    .continuous_parts(opts)
                    .iter()
                    .map(|(_, h)| h.len() as f64 * dx)
                    .fold(0.0, f64::max),
                expected: format!(
                    "at least one segment of {seg_len} m without a gap in {} (shorten the segment, or check the gaps)",
                    self.name
                ),
            });
        }
        for l in &mut lines {
            *l /= count as f64;
        }
        let dk = 1.0 / seg_len;
        let bands = third_octave_bands(seg_len / LINES_PER_BAND, SAMPLES_PER_WAVELENGTH * dx);
        let level_db = bands
            .iter()
            .map(|b| {
                let [k0, k1] = b.wavenumbers();
                let ms: f64 = lines
                    .iter()
                    .enumerate()
                    .skip(1)
                    .map(|(j, p)| {
                        let (a, c) = ((j as f64 - 0.5) * dk, (j as f64 + 0.5) * dk);
                        let inside = (c.min(k1) - a.max(k0)).max(0.0) / dk;
                        p * inside
                    })
                    .sum();
                10.0 * (ms / (REFERENCE_ROUGHNESS_M * REFERENCE_ROUGHNESS_M)).log10()
            })
            .collect();
        Ok(BandSpectrum { bands, level_db })
    }

    /// The first `length_m` (m) of the longest continuous part as a rail profile on the
    /// track, placed with its first sample at `x0_m` (m) along the rail, mean and linear trend
    /// removed: the measured rail to run a passage over.
    pub fn longest_part_on_track(
        &self,
        x0_m: f64,
        length_m: f64,
        opts: &SpectrumOptions,
    ) -> Option<crate::dynamics::RailProfile> {
        let dx = self.median_spacing_m();
        let (_, h) = self
            .continuous_parts(opts)
            .into_iter()
            .max_by_key(|(_, h)| h.len())?;
        let keep = ((length_m / dx).ceil() as usize + 1).clamp(2, h.len());
        let h = detrend(&h[..keep]);
        let x: Vec<f64> = (0..h.len()).map(|i| x0_m + i as f64 * dx).collect();
        crate::dynamics::RailProfile::new(x, h).ok()
    }
}

fn check_options(o: &SpectrumOptions) -> Result<(), RoughnessError> {
    if !(o.segment_length_m.is_finite() && (0.1..=20.0).contains(&o.segment_length_m)) {
        return Err(RoughnessError::OutOfRange {
            what: "segment length (m)",
            value: o.segment_length_m,
            expected: "0.1 to 20 m (EN 15610 asks for at least 1 m)".into(),
        });
    }
    if !(o.gap_factor.is_finite() && o.gap_factor >= 1.5) {
        return Err(RoughnessError::OutOfRange {
            what: "gap factor (−)",
            value: o.gap_factor,
            expected: "at least 1.5 median spacings".into(),
        });
    }
    Ok(())
}

/// `h` minus its least-squares straight line (mean and trend).
fn detrend(h: &[f64]) -> Vec<f64> {
    let n = h.len() as f64;
    let xm = (n - 1.0) / 2.0;
    let ym = h.iter().sum::<f64>() / n;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (i, y) in h.iter().enumerate() {
        let dx = i as f64 - xm;
        sxy += dx * (y - ym);
        sxx += dx * dx;
    }
    let b = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    h.iter()
        .enumerate()
        .map(|(i, y)| y - ym - b * (i as f64 - xm))
        .collect()
}
