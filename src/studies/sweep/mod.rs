//! Speed sweeps: passages over many speeds in parallel, resumable, and the frequency-selection
//! maps (docs/theory.md §2.3 and §11.2).
//!
//! # Files of a sweep directory `DIR`
//! - `speeds/<stem>.json` — the `PassageSummary` of each speed (`speed_file_stem`), written
//!   atomically the moment the passage finishes. A rerun reuses every speed whose file parses
//!   as a complete summary of that speed and recomputes only the others, so a killed sweep
//!   resumes where it stopped. Temp files (`*.tmp.<pid>`) of a killed run never parse as a
//!   speed file (other name) and are ignored; a truncated or foreign `<stem>.json` does not
//!   parse (every field is required) and is recomputed.
//! - `speeds/run.key` — what produced the speed files (a hash of the resolved model and the
//!   program version, given by the caller): a rerun with another key is refused
//!   (`check_run_key`), so a resume never mixes models; shards must share it to merge.
//! - `speeds/shard.json` — `ShardPlan`: which shard `I/N` of which speeds the directory
//!   holds (written by the `sweep` command, `0/1` for an unsharded sweep); [`merge`] takes
//!   only directories that form every shard of one sweep once, each finished.
//! - `sweep.json` — [`SweepRecord`]: the speeds, dominant wavelength and frequency per speed,
//!   the range ratios, `seconds`, the map options. `seconds` is the **sum of the passages'
//!   own wall times** (`PassageSummary::seconds`, read from the speed files), so the file
//!   depends only on the speed files and merged shards reproduce it byte for byte; the wall
//!   time of one invocation is reported by the CLI's `--json` as `wall_seconds`.
//! - `dominant.csv` (`speed_kmh, dominant_wavelength_mm, dominant_frequency_hz,
//!   fl_dominant_frequency_hz`, then the coupled mode each speed's dominant wear frequency is
//!   attributed to, `crate::studies::coupled::attribution_columns`: `coupled_mode_hz,
//!   coupled_damping_ratio, coupled_wheel_share, …, coupled_rail_x_to_n`, and the same for
//!   F_L prefixed `fl_`; `NaN` where the signal has no peak in the band or the map options
//!   hold no coupled modes) and the plots `dominant_wavelength.{svg,png}`,
//!   `dominant_frequency.{svg,png}`.
//! - The maps, as `.npy` (`[n_speeds, n_grid]`, C order) with the axes `speeds_kmh.npy`,
//!   `wavelength_mm.npy`, `frequency_hz.npy`:
//!   `map_wear_wavelength`, `map_fl_wavelength` — the one-sided PSD per unit wavenumber of the
//!   band-passed wear ((J/m)²·m) and of `F_L` (N²·m) interpolated (linearly in wavenumber
//!   `1/λ`) onto a common wavelength grid; `map_wear_frequency`, `map_fl_frequency` — the
//!   same spectra per unit frequency, `S_f(f) = S_k(f/v) / v` (`v` in m/s, so
//!   `∫S_f df = ∫S_k dk`), on a common frequency grid spanning `v_min/λ_max … v_max/λ_min`.
//!   Outside a speed's band (or its spectrum's range) the map is 0. The same data as long
//!   CSV tables `map_wavelength.csv` and `map_frequency.csv`, and heat maps
//!   (`*.svg`, `*.png`, log colour scale) with the given longitudinal-compression
//!   eigenfrequencies `f_i` drawn as curves `λ = v / f_i` on the wavelength maps and as
//!   horizontal lines on the frequency maps (solid), the wheel modes at the contact
//!   (dashed) and the coupled modes the contact sees (short dashes, red, `coupled <part>`).
//! - `report.md`, `report.html` — the ratios, the dominant components, the plots and which
//!   coupled modes select over which speed ranges.
//!
//! The speed range ratio is `v_max / v_min`, the wavelength range ratio `λ_max / λ_min` over
//! the dominant wavelengths (speeds without one are left out). Frequency selection shows as a
//! wavelength range ratio much smaller than the speed range ratio.
//!
//! Every output file is a deterministic function of the speed files and the [`MapOptions`],
//! which is what makes [`merge`] of shard directories equal to the unsharded sweep.

//!
//! # Code
//! `run` runs and resumes the passages, `maps` assembles the maps from the speed files,
//! `report` writes the outputs, [`merge`] joins shard directories.

mod maps;
mod merge;
mod report;
mod run;

pub use maps::assemble;
pub use merge::{merge, write_shard_plan};
pub use report::summary_lines;
pub(crate) use run::RUN_KEY_FILE;
pub use run::{read_summary, run_passages, speed_file, sweep, sweep_beside};

use serde::{Deserialize, Serialize};

use super::StudiesError;
use crate::dynamics::coupled::{CoupledMode, ModeAttribution};

/// Grids of the frequency-selection maps and the eigenfrequency lines drawn on them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MapOptions {
    /// Shortest wavelength of the map (mm).
    pub wavelength_min_mm: f64,
    /// Longest wavelength of the map (mm).
    pub wavelength_max_mm: f64,
    /// Points of the wavelength grid (uniform in wavelength).
    pub wavelength_points: usize,
    /// Points of the frequency grid (uniform in frequency).
    pub frequency_points: usize,
    /// Longitudinal-compression eigenfrequencies drawn on the maps (Hz), labelled `LC`.
    pub frequency_lines_hz: Vec<f64>,
    /// Wheel eigenfrequencies with a large modal displacement at the contact point drawn
    /// on the maps (Hz), labelled `wheel` (see
    /// [`crate::dynamics::prepared::PreparedModel::wheel_contact_modes_hz`]).
    #[serde(default)]
    pub wheel_lines_hz: Vec<f64>,
    /// Speed at which [`Self::coupled_modes`] were computed (km/h); `None` without them.
    #[serde(default)]
    pub coupled_speed_kmh: Option<f64>,
    /// The coupled wheel–track modes (docs/theory.md §7.10) the dominant frequencies are
    /// attributed to: those the contact moves ([`CoupledModes::visible`]), computed once
    /// at [`Self::coupled_speed_kmh`]. The ones the contact sees
    /// ([`crate::dynamics::coupled::seen_by_contact`]) are drawn on the maps, labelled
    /// `coupled` with the part that holds most of their energy. Empty: no attribution.
    ///
    /// [`CoupledModes::visible`]: crate::dynamics::coupled::CoupledModes::visible
    #[serde(default)]
    pub coupled_modes: Vec<CoupledMode>,
}

impl Default for MapOptions {
    /// The 20–80 mm band of docs/theory.md §9.2 at 0.25 mm, 401 frequencies, no lines.
    fn default() -> Self {
        Self {
            wavelength_min_mm: 20.0,
            wavelength_max_mm: 80.0,
            wavelength_points: 241,
            frequency_points: 401,
            frequency_lines_hz: Vec::new(),
            wheel_lines_hz: Vec::new(),
            coupled_speed_kmh: None,
            coupled_modes: Vec::new(),
        }
    }
}

impl MapOptions {
    fn check(&self) -> Result<(), StudiesError> {
        let bad = StudiesError::MapOptions;
        let ok = self.wavelength_min_mm > 0.0
            && self.wavelength_max_mm > self.wavelength_min_mm
            && self.wavelength_max_mm.is_finite();
        if !ok {
            return Err(bad("need 0 < wavelength_min_mm < wavelength_max_mm"));
        }
        if self.wavelength_points < 2 || self.frequency_points < 2 {
            return Err(bad("need at least 2 grid points"));
        }
        if self
            .frequency_lines_hz
            .iter()
            .chain(&self.wheel_lines_hz)
            .any(|f| !f.is_finite() || *f <= 0.0)
        {
            return Err(bad("eigenfrequency lines must be positive and finite"));
        }
        let ok_speed = self
            .coupled_speed_kmh
            .is_none_or(|v| v.is_finite() && v > 0.0);
        if !ok_speed || (self.coupled_speed_kmh.is_none() && !self.coupled_modes.is_empty()) {
            return Err(bad(
                "coupled modes need the positive, finite speed they were computed at",
            ));
        }
        if self
            .coupled_modes
            .iter()
            .any(|m| !(m.frequency_hz.is_finite() && m.frequency_hz > 0.0))
        {
            return Err(bad("coupled-mode frequencies must be positive and finite"));
        }
        Ok(())
    }

    /// Whether two shards' options describe the same maps: equal grids and lines, and the
    /// same coupled modes to within 1e-9 relative (a dense eigensolver run on another
    /// machine or thread count may differ in the last bits); the merge uses the first
    /// shard's.
    pub(crate) fn same_as(&self, other: &Self) -> bool {
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs());
        let strip = |o: &Self| Self {
            coupled_modes: Vec::new(),
            ..o.clone()
        };
        strip(self) == strip(other)
            && self.coupled_modes.len() == other.coupled_modes.len()
            && self
                .coupled_modes
                .iter()
                .zip(&other.coupled_modes)
                .all(|(a, b)| {
                    close(a.frequency_hz, b.frequency_hz)
                        && close(a.position_m, b.position_m)
                        && a.dominant == b.dominant
                })
    }

    /// The wavelength grid (mm), ascending.
    pub(crate) fn wavelength_grid_mm(&self) -> Vec<f64> {
        linspace(
            self.wavelength_min_mm,
            self.wavelength_max_mm,
            self.wavelength_points,
        )
    }
}

/// The content of `sweep.json` (and the core of the CLI's `--json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SweepRecord {
    /// Speeds (km/h), ascending.
    pub speeds_kmh: Vec<f64>,
    /// Dominant wear wavelength per speed (mm); `null` without a peak in the band.
    pub dominant_wavelength_mm: Vec<Option<f64>>,
    /// Dominant wear frequency per speed (Hz); `null` without a peak in the band.
    pub dominant_frequency_hz: Vec<Option<f64>>,
    /// Frequency of the strongest F_L component per speed (Hz); `null` without one.
    #[serde(default)]
    pub fl_dominant_frequency_hz: Vec<Option<f64>>,
    /// The dominant wear frequency of each speed attributed to a coupled mode of
    /// [`MapOptions::coupled_modes`]; `null` without a frequency or without coupled modes.
    #[serde(default)]
    pub wear_coupled: Vec<Option<ModeAttribution>>,
    /// The same for the strongest F_L component.
    #[serde(default)]
    pub fl_coupled: Vec<Option<ModeAttribution>>,
    /// `v_max / v_min` (−).
    pub speed_range_ratio: f64,
    /// `λ_max / λ_min` over the dominant wavelengths (−); `null` if no speed has one.
    pub wavelength_range_ratio: Option<f64>,
    /// Sum of the passages' wall times (s), see the module doc.
    pub seconds: f64,
    /// Grids and eigenfrequency lines of the maps.
    pub map: MapOptions,
}

/// Which speeds a run computed and which it reused from earlier runs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PassageStats {
    /// Speeds computed by this run (km/h).
    pub computed: Vec<f64>,
    /// Speeds whose files were already complete (km/h).
    pub reused: Vec<f64>,
}

/// The assembled maps, in memory (the same numbers as the `.npy` files).
#[derive(Clone, Debug, PartialEq)]
pub struct SweepMaps {
    /// Speeds (km/h), ascending.
    pub speeds_kmh: Vec<f64>,
    /// Wavelength grid (mm).
    pub wavelength_mm: Vec<f64>,
    /// Frequency grid (Hz).
    pub frequency_hz: Vec<f64>,
    /// Wear PSD per wavenumber, `[speed][wavelength]` row-major ((J/m)²·m).
    pub wear_wavelength: Vec<f64>,
    /// `F_L` PSD per wavenumber, `[speed][wavelength]` (N²·m).
    pub fl_wavelength: Vec<f64>,
    /// Wear PSD per frequency, `[speed][frequency]` ((J/m)²/Hz).
    pub wear_frequency: Vec<f64>,
    /// `F_L` PSD per frequency, `[speed][frequency]` (N²/Hz).
    pub fl_frequency: Vec<f64>,
}

/// The map options of a sweep of the reduced engine `prepared`: the default grids, its
/// longitudinal-compression eigenfrequencies and its wheel modes at the contact
/// ([`crate::studies::grow::WHEEL_LINE_SHARE`]) as lines, and the coupled wheel–track modes
/// at `coupled_speed_kmh` (km/h; [`crate::studies::coupled::sweep_reference_speed_kmh`]
/// gives the sweep's) for the attribution (several seconds of serial work).
pub fn map_options(
    prepared: &crate::dynamics::prepared::PreparedModel,
    coupled_speed_kmh: f64,
) -> Result<MapOptions, crate::studies::BoxError> {
    let coupled = prepared.coupled_modes(crate::units::kmh_to_ms(coupled_speed_kmh), &[])?;
    Ok(MapOptions {
        frequency_lines_hz: prepared.longitudinal_compression_hz(),
        wheel_lines_hz: prepared.wheel_contact_modes_hz(crate::studies::grow::WHEEL_LINE_SHARE),
        coupled_speed_kmh: Some(coupled_speed_kmh),
        coupled_modes: coupled.visible(),
        ..MapOptions::default()
    })
}

/// The result of [`sweep`].
#[derive(Clone, Debug, PartialEq)]
pub struct SweepOutcome {
    /// `sweep.json`.
    pub record: SweepRecord,
    /// The maps.
    pub maps: SweepMaps,
    /// Computed and reused speeds.
    pub stats: PassageStats,
}

/// `n ≥ 2` points evenly spaced from `a` to `b`, both included.
fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| a + (b - a) * i as f64 / (n - 1) as f64)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::{CoupledMode, MapOptions};
    use crate::dynamics::coupled::ModeShares;

    fn mode(f: f64) -> CoupledMode {
        CoupledMode {
            position_m: 0.5,
            frequency_hz: f,
            damping_ratio: 0.01,
            shares: ModeShares::default(),
            dominant: "support".into(),
            contact_amplitudes_m_per_sqrt_j: [1.0, 0.0, 0.0, 0.0],
            rail_x_to_n: 1.0,
        }
    }

    /// Shards whose coupled modes differ in the last bits merge; other modes or lines do not.
    #[test]
    fn shards_agree_on_coupled_modes_to_rounding_only() {
        let a = MapOptions {
            coupled_speed_kmh: Some(140.0),
            coupled_modes: vec![mode(1000.0), mode(1400.0)],
            ..MapOptions::default()
        };
        let mut b = a.clone();
        b.coupled_modes[0].frequency_hz *= 1.0 + 1e-13;
        b.coupled_modes[1].damping_ratio += 1e-15;
        assert!(a.same_as(&b));
        let mut c = a.clone();
        c.coupled_modes[1].frequency_hz = 1401.0;
        assert!(!a.same_as(&c));
        let mut d = a.clone();
        d.wheel_lines_hz.push(1065.0);
        assert!(!a.same_as(&d));
        let e = MapOptions {
            coupled_speed_kmh: Some(100.0),
            ..a.clone()
        };
        assert!(!a.same_as(&e));
    }
}
