//! What one passage reports to the analyses built on top of it (growth loop, sweeps, studies):
//! scalar indicators, the wavelength components and the band-limited spectra of the
//! differential wear `W_f`, the longitudinal force `F_L` and the normal force `F_N` in the
//! solution zone (docs/theory.md §9). No time histories: a summary is small enough to keep one per
//! speed of a sweep and to store as JSON.
//!
//! Units: forces N, lengths in SI except the fields whose name ends in `_mm` (wavelengths in
//! mm at this output boundary, as the users read them), frequencies Hz, speeds km/h only in
//! `speed_kmh`. PSDs are one-sided, per unit wavenumber: N²·m for forces, (J/m)²·m for the
//! wear (frictional work per metre of rail, see [`PassageSummary::wear_band_rms`]).

use serde::{Deserialize, Serialize};

/// One wavelength component (a PSD peak) of a signal along the rail.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WavelengthComponent {
    /// Wavelength (mm).
    pub wavelength_mm: f64,
    /// Frequency `f = v / λ` at the passage speed (Hz).
    pub frequency_hz: f64,
    /// PSD at the peak (signal unit² · m).
    pub psd: f64,
}

/// A one-sided PSD in the wavelength domain, restricted to the analysis band.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
pub struct WavelengthSpectrum {
    /// Wavelengths (m), descending (ascending wavenumber).
    pub wavelength_m: Vec<f64>,
    /// PSD values (signal unit² · m), one per wavelength.
    pub psd: Vec<f64>,
}

/// Scalar indicators and spectra of one passage (the `--json` of `corrugation passage`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PassageSummary {
    /// Train speed (km/h).
    pub speed_kmh: f64,
    /// Mean normal force in the solution zone (N).
    pub mean_fn_n: f64,
    /// Mean longitudinal force on the wheel in the solution zone (N).
    pub mean_fl_n: f64,
    /// RMS of the 20–80 mm band-passed longitudinal force (N).
    pub fl_band_rms_n: f64,
    /// RMS of the 20–80 mm band-passed normal force (N).
    pub fn_band_rms_n: f64,
    /// RMS of the band-passed frictional work per metre of rail, `W_f` integrated across the
    /// rail head (J/m).
    pub wear_band_rms: f64,
    /// RMS of `F_L` strictly inside 20–80 mm (N): filtered with the band's roll-offs inside
    /// it (gain 0 outside 20–80 mm, 1 on 22.2–57.1 mm). `fl_band_rms_n` also counts part of
    /// 80–133 mm and 18.2–20 mm through its roll-offs outside the band (docs/theory.md §9.2).
    pub fl_inside_band_rms_n: f64,
    /// RMS of `F_N` strictly inside 20–80 mm (N), as [`Self::fl_inside_band_rms_n`].
    pub fn_inside_band_rms_n: f64,
    /// RMS of `W_f` strictly inside 20–80 mm (J/m), as [`Self::fl_inside_band_rms_n`].
    pub wear_inside_band_rms: f64,
    /// Mean of `W_f` in the solution zone (J/m), for normalising `wear_band_rms`.
    pub wear_mean: f64,
    /// PSD peaks of the band-passed wear, strongest first.
    pub wear_components: Vec<WavelengthComponent>,
    /// PSD peaks of the band-passed `F_L`, strongest first.
    pub fl_components: Vec<WavelengthComponent>,
    /// PSD peaks of the band-passed `F_N`, strongest first.
    pub fn_components: Vec<WavelengthComponent>,
    /// Wavelength of the strongest wear component (mm), `None` if the wear has no peak in
    /// the band.
    pub dominant_wavelength_mm: Option<f64>,
    /// Frequency of the strongest wear component (Hz).
    pub dominant_frequency_hz: Option<f64>,
    /// PSD of the wear in the 20–80 mm band.
    pub wear_psd: WavelengthSpectrum,
    /// PSD of `F_L` in the 20–80 mm band.
    pub fl_psd: WavelengthSpectrum,
    /// PSD of `F_N` in the 20–80 mm band.
    pub fn_psd: WavelengthSpectrum,
    /// Time steps of the passage.
    pub steps: usize,
    /// Wall time of the passage (s), excluding the modal basis.
    pub seconds: f64,
    /// The contact grid the passage ran on when its contact patch reached the boundary of the
    /// model's grid and the passage was rerun on a wider one
    /// ([`super::setup::run_widening_grid`]); absent on the model's grid.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact_grid_widened: Option<super::record::WidenedGrid>,
}
