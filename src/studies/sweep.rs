//! Speed sweeps: passages over many speeds in parallel, resumable, and the frequency-selection
//! maps (docs/theory.md §2.3 and §11.2).
//!
//! # Files of a sweep directory `DIR`
//! - `speeds/<stem>.json` — the [`PassageSummary`] of each speed ([`speed_file_stem`]), written
//!   atomically the moment the passage finishes. A rerun reuses every speed whose file parses
//!   as a complete summary of that speed and recomputes only the others, so a killed sweep
//!   resumes where it stopped. Temp files (`*.tmp.<pid>`) of a killed run never parse as a
//!   speed file (other name) and are ignored; a truncated or foreign `<stem>.json` does not
//!   parse (every field is required) and is recomputed.
//! - `speeds/run.key` — what produced the speed files (a hash of the resolved model and the
//!   program version, given by the caller): a rerun with another key is refused
//!   ([`check_run_key`]), so a resume never mixes models; shards must share it to merge.
//! - `speeds/shard.json` — [`ShardPlan`]: which shard `I/N` of which speeds the directory
//!   holds (written by the `sweep` command, `0/1` for an unsharded sweep); [`merge`] takes
//!   only directories that form every shard of one sweep once, each finished.
//! - `sweep.json` — [`SweepRecord`]: the speeds, dominant wavelength and frequency per speed,
//!   the range ratios, `seconds`, the map options. `seconds` is the **sum of the passages'
//!   own wall times** (`PassageSummary::seconds`, read from the speed files), so the file
//!   depends only on the speed files and merged shards reproduce it byte for byte; the wall
//!   time of one invocation is reported by the CLI's `--json` as `wall_seconds`.
//! - `dominant.csv` (`speed_kmh, dominant_wavelength_mm, dominant_frequency_hz`; `NaN` where
//!   the wear has no peak in the band) and the plots `dominant_wavelength.{svg,png}`,
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
//!   horizontal lines on the frequency maps.
//! - `report.md`, `report.html` — the ratios, the dominant components and the plots.
//!
//! The speed range ratio is `v_max / v_min`, the wavelength range ratio `λ_max / λ_min` over
//! the dominant wavelengths (speeds without one are left out). Frequency selection shows as a
//! wavelength range ratio much smaller than the speed range ratio.
//!
//! Every output file is a deterministic function of the speed files and the [`MapOptions`],
//! which is what makes [`merge`] of shard directories equal to the unsharded sweep.

use std::io::Write;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::speeds::speed_file_stem;
use super::StudiesError;
use crate::dynamics::{PassageRunner, PassageSummary, WavelengthSpectrum};
use crate::progress::{Counter, Progress};
use crate::report::doc::Document;
use crate::report::plot::{heat_map, line_plot, HeatMap, OverlayLine, Series};

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
    /// [`crate::dynamics::passage::PreparedModel::wheel_contact_modes_hz`]).
    #[serde(default)]
    pub wheel_lines_hz: Vec<f64>,
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
        }
    }
}

impl MapOptions {
    fn check(&self) -> Result<(), StudiesError> {
        let bad = |r: &str| StudiesError::Invalid(format!("map options: {r}"));
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
        Ok(())
    }

    /// The wavelength grid (mm), ascending.
    pub fn wavelength_grid_mm(&self) -> Vec<f64> {
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

/// Path of a speed's summary file in a sweep directory.
pub fn speed_file(dir: &Path, speed_kmh: f64) -> PathBuf {
    dir.join("speeds")
        .join(format!("{}.json", speed_file_stem(speed_kmh)))
}

/// Reads a summary file; `BadFile` if it does not parse as a complete [`PassageSummary`].
pub fn read_summary(path: &Path) -> Result<PassageSummary, StudiesError> {
    let text = std::fs::read_to_string(path).map_err(StudiesError::io(path))?;
    serde_json::from_str(&text).map_err(|e| StudiesError::BadFile {
        path: path.to_path_buf(),
        reason: format!("not a complete passage summary ({e}); delete it to recompute"),
    })
}

fn same_speed(a: f64, b: f64) -> bool {
    speed_file_stem(a) == speed_file_stem(b)
}

/// Writes a summary as pretty JSON, atomically.
pub fn write_summary(path: &Path, s: &PassageSummary) -> Result<(), StudiesError> {
    crate::io::write_atomic(path, |w| {
        serde_json::to_writer_pretty(&mut *w, s).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })
    .map_err(StudiesError::io(path))
}

/// Runs the passages of the speeds that have no complete file in `dir/speeds` yet, in
/// parallel (rayon), each saved the moment it finishes; each finished passage is reported to
/// `progress` (stage "sweep passages (speeds)"). A passage that fails or panics is reported in [`StudiesError::Passages`]
/// after all others have finished and been saved.
pub fn run_passages(
    runner: &dyn PassageRunner,
    speeds_kmh: &[f64],
    dir: &Path,
    run_key: &str,
    progress: &dyn Progress,
) -> Result<PassageStats, StudiesError> {
    check_run_key(dir, run_key)?;
    let mut stats = PassageStats::default();
    let mut todo = Vec::new();
    for &v in speeds_kmh {
        let path = speed_file(dir, v);
        match path.exists().then(|| read_summary(&path)) {
            Some(Ok(s)) if same_speed(s.speed_kmh, v) => stats.reused.push(v),
            _ => todo.push(v),
        }
    }
    let bar = Counter::start(progress, "sweep passages (speeds)", todo.len() as u64);
    let results: Vec<Result<f64, String>> = todo
        .par_iter()
        .map(|&v| {
            let out = catch_unwind(AssertUnwindSafe(|| runner.run(v, None)));
            let r = match out {
                Ok(Ok(s)) if same_speed(s.speed_kmh, v) => write_summary(&speed_file(dir, v), &s)
                    .map(|_| v)
                    .map_err(|e| format!("{v} km/h: {e}")),
                Ok(Ok(s)) => Err(format!(
                    "{v} km/h: the runner returned a summary for {} km/h",
                    s.speed_kmh
                )),
                Ok(Err(e)) => Err(format!("{v} km/h: {e}")),
                Err(p) => Err(format!("{v} km/h: passage panicked: {}", panic_text(&*p))),
            };
            bar.inc();
            r
        })
        .collect();
    bar.finish();
    let mut failures = Vec::new();
    for r in results {
        match r {
            Ok(v) => stats.computed.push(v),
            Err(e) => failures.push(e),
        }
    }
    if failures.is_empty() {
        Ok(stats)
    } else {
        Err(StudiesError::Passages { failures })
    }
}

pub(crate) fn panic_text(p: &(dyn std::any::Any + Send)) -> String {
    p.downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into())
}

/// File (in `DIR/speeds`) naming what produced the speed files: see [`check_run_key`].
pub const RUN_KEY_FILE: &str = "run.key";

/// Guards resume against mixing models: the first run into `dir` writes `run_key` (e.g. a
/// hash of the resolved model and the program version) to `dir/speeds/run.key`; a later run
/// with another key is refused, so speed files of another model are never reused.
pub fn check_run_key(dir: &Path, run_key: &str) -> Result<(), StudiesError> {
    let speeds = dir.join("speeds");
    std::fs::create_dir_all(&speeds).map_err(StudiesError::io(&speeds))?;
    let p = speeds.join(RUN_KEY_FILE);
    match std::fs::read_to_string(&p) {
        Ok(old) if old.trim_end() == run_key => Ok(()),
        Ok(old) => Err(StudiesError::BadFile {
            path: p,
            reason: format!(
                "this directory holds passages of another model or program version (key {}, \
                 now {run_key}); use another --out or delete the directory",
                old.trim_end()
            ),
        }),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            crate::io::write_text(&p, &format!("{run_key}\n")).map_err(StudiesError::io(&p))
        }
        Err(e) => Err(StudiesError::Io { path: p, source: e }),
    }
}

/// Runs the missing passages ([`run_passages`]) and assembles the outputs ([`assemble`]).
/// `run_key` identifies the model (see [`check_run_key`]).
pub fn sweep(
    runner: &dyn PassageRunner,
    speeds_kmh: &[f64],
    dir: &Path,
    opts: &MapOptions,
    run_key: &str,
    progress: &dyn Progress,
) -> Result<SweepOutcome, StudiesError> {
    opts.check()?;
    let stats = run_passages(runner, speeds_kmh, dir, run_key, progress)?;
    let (record, maps) = assemble(dir, speeds_kmh, opts)?;
    Ok(SweepOutcome {
        record,
        maps,
        stats,
    })
}

fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| a + (b - a) * i as f64 / (n - 1) as f64)
        .collect()
}

/// PSD per wavenumber of `s` at wavenumber `k` (1/m): linear interpolation in `k` between
/// the spectrum's samples; 0 outside them.
pub fn psd_at_wavenumber(s: &WavelengthSpectrum, k: f64) -> f64 {
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
        return Err(StudiesError::Invalid("no speeds to assemble".into()));
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
    let record = SweepRecord {
        speed_range_ratio: speeds[speeds.len() - 1] / speeds[0],
        speeds_kmh: speeds,
        dominant_wavelength_mm,
        dominant_frequency_hz,
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
    let (lmin, lmax) = (opts.wavelength_min_mm * 1e-3, opts.wavelength_max_mm * 1e-3);
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
            let k = 1.0 / (l * 1e-3);
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

fn nan_none(v: Option<f64>) -> f64 {
    v.unwrap_or(f64::NAN)
}

/// Writes the assembled outputs. `sweep.json` is the commit marker: it is removed first and
/// written last, so a run killed in between leaves no complete-looking sweep beside missing
/// or stale maps; temp files of killed earlier runs are removed first.
fn write_outputs(dir: &Path, r: &SweepRecord, m: &SweepMaps) -> Result<(), StudiesError> {
    let io = StudiesError::io;
    for d in [dir.to_path_buf(), dir.join("speeds")] {
        crate::io::remove_stale_temp_files(&d).map_err(io(&d))?;
    }
    let json = dir.join("sweep.json");
    match std::fs::remove_file(&json) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(io(&json)(e)),
        _ => {}
    }
    write_maps(dir, r, m)?;
    crate::io::write_atomic(&json, |w| {
        serde_json::to_writer_pretty(&mut *w, r).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })
    .map_err(io(&json))
}

/// Every output of [`write_outputs`] but `sweep.json`.
fn write_maps(dir: &Path, r: &SweepRecord, m: &SweepMaps) -> Result<(), StudiesError> {
    let io = StudiesError::io;
    let p = dir.join("dominant.csv");
    crate::io::write_csv(
        &p,
        &[
            "speed_kmh",
            "dominant_wavelength_mm",
            "dominant_frequency_hz",
        ],
        r.speeds_kmh.iter().enumerate().map(|(i, &v)| {
            vec![
                v,
                nan_none(r.dominant_wavelength_mm[i]),
                nan_none(r.dominant_frequency_hz[i]),
            ]
        }),
    )
    .map_err(io(&p))?;
    let (ns, nl, nf) = (
        m.speeds_kmh.len(),
        m.wavelength_mm.len(),
        m.frequency_hz.len(),
    );
    for (name, shape, data) in [
        ("speeds_kmh.npy", vec![ns], &m.speeds_kmh),
        ("wavelength_mm.npy", vec![nl], &m.wavelength_mm),
        ("frequency_hz.npy", vec![nf], &m.frequency_hz),
        ("map_wear_wavelength.npy", vec![ns, nl], &m.wear_wavelength),
        ("map_fl_wavelength.npy", vec![ns, nl], &m.fl_wavelength),
        ("map_wear_frequency.npy", vec![ns, nf], &m.wear_frequency),
        ("map_fl_frequency.npy", vec![ns, nf], &m.fl_frequency),
    ] {
        let p = dir.join(name);
        crate::io::write_npy(&p, &shape, data).map_err(io(&p))?;
    }
    let p = dir.join("map_wavelength.csv");
    crate::io::write_csv(
        &p,
        &[
            "speed_kmh",
            "wavelength_mm",
            "wear_psd_j2_per_m",
            "fl_psd_n2_m",
        ],
        (0..ns).flat_map(|i| {
            (0..nl).map(move |j| {
                vec![
                    m.speeds_kmh[i],
                    m.wavelength_mm[j],
                    m.wear_wavelength[i * nl + j],
                    m.fl_wavelength[i * nl + j],
                ]
            })
        }),
    )
    .map_err(io(&p))?;
    let p = dir.join("map_frequency.csv");
    crate::io::write_csv(
        &p,
        &[
            "speed_kmh",
            "frequency_hz",
            "wear_psd_j2_per_m2_hz",
            "fl_psd_n2_per_hz",
        ],
        (0..ns).flat_map(|i| {
            (0..nf).map(move |j| {
                vec![
                    m.speeds_kmh[i],
                    m.frequency_hz[j],
                    m.wear_frequency[i * nf + j],
                    m.fl_frequency[i * nf + j],
                ]
            })
        }),
    )
    .map_err(io(&p))?;

    // Heat maps with the eigenfrequency lines.
    let (v0, v1) = (m.speeds_kmh[0], m.speeds_kmh[ns - 1]);
    let (vlo, vhi) = if v1 > v0 {
        (v0, v1)
    } else {
        (v0 * 0.95, v0 * 1.05)
    };
    let curve_v = linspace(vlo, vhi, 200);
    // The track's LC lines solid, the wheel's dashed (at 5 kHz there are ~30 wheel lines).
    let labelled: Vec<(String, f64, bool)> = r
        .map
        .frequency_lines_hz
        .iter()
        .map(|&f| (format!("LC {f:.0} Hz"), f, false))
        .chain(
            r.map
                .wheel_lines_hz
                .iter()
                .map(|&f| (format!("wheel {f:.0} Hz"), f, true)),
        )
        .collect();
    let lines_lambda: Vec<OverlayLine> = labelled
        .iter()
        .map(|(name, f, dashed)| OverlayLine {
            name: name.clone(),
            x: curve_v.clone(),
            y: curve_v
                .iter()
                .map(|&v| crate::units::kmh_to_ms(v) / f * 1e3)
                .collect(),
            dashed: *dashed,
        })
        .collect();
    let lines_f: Vec<OverlayLine> = labelled
        .iter()
        .map(|(name, f, dashed)| OverlayLine {
            dashed: *dashed,
            ..OverlayLine::horizontal(name.clone(), *f, vlo, vhi)
        })
        .collect();
    // A single speed has no x extent: the map is still drawn, one column wide.
    for (stem, title, ylab, y, z, lines, unit) in [
        (
            "map_wear_wavelength",
            "Differential wear PSD: speed × wavelength",
            "wavelength (mm)",
            &m.wavelength_mm,
            &m.wear_wavelength,
            &lines_lambda,
            "PSD ((J/m)²·m)",
        ),
        (
            "map_fl_wavelength",
            "F_L PSD: speed × wavelength",
            "wavelength (mm)",
            &m.wavelength_mm,
            &m.fl_wavelength,
            &lines_lambda,
            "PSD (N²·m)",
        ),
        (
            "map_wear_frequency",
            "Differential wear PSD: speed × frequency",
            "frequency (Hz)",
            &m.frequency_hz,
            &m.wear_frequency,
            &lines_f,
            "PSD ((J/m)²/Hz)",
        ),
        (
            "map_fl_frequency",
            "F_L PSD: speed × frequency",
            "frequency (Hz)",
            &m.frequency_hz,
            &m.fl_frequency,
            &lines_f,
            "PSD (N²/Hz)",
        ),
    ] {
        heat_map(
            &dir.join(stem),
            &HeatMap {
                title,
                x_label: "speed (km/h)",
                y_label: ylab,
                colour_label: unit,
                x: &m.speeds_kmh,
                y,
                z,
                lines,
                log_colour: true,
            },
        )?;
    }
    let dom_l: Vec<f64> = r
        .dominant_wavelength_mm
        .iter()
        .map(|v| nan_none(*v))
        .collect();
    let dom_f: Vec<f64> = r
        .dominant_frequency_hz
        .iter()
        .map(|v| nan_none(*v))
        .collect();
    line_plot(
        &dir.join("dominant_wavelength"),
        "Dominant wear wavelength vs speed",
        "speed (km/h)",
        "wavelength (mm)",
        &[Series::new(
            "dominant wavelength",
            r.speeds_kmh.clone(),
            dom_l,
        )],
    )?;
    // Only the mode lines near the dominant frequencies (within 15 % of their range; at most
    // eight, nearest first), so that the dominant curve and its legend stay readable; the
    // maps show all lines. Mode lines first, so the dominant frequency is drawn on top.
    let df: Vec<f64> = dom_f.iter().copied().filter(|v| v.is_finite()).collect();
    let (flo, fhi) = df
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let dist = |f: f64| {
        if f < flo {
            (flo - f) / flo
        } else if f > fhi {
            (f - fhi) / fhi
        } else {
            0.0
        }
    };
    let mut near: Vec<(&OverlayLine, f64)> = lines_f
        .iter()
        .filter_map(|l| l.y.first().map(|&f| (l, dist(f))))
        .filter(|(_, d)| *d <= 0.15)
        .collect();
    near.sort_by(|a, b| a.1.total_cmp(&b.1));
    near.truncate(8);
    let mut fs: Vec<Series> = near
        .iter()
        .map(|(l, _)| Series::new(l.name.clone(), l.x.clone(), l.y.clone()))
        .collect();
    fs.push(Series::new(
        "dominant frequency",
        r.speeds_kmh.clone(),
        dom_f,
    ));
    line_plot(
        &dir.join("dominant_frequency"),
        "Dominant wear frequency vs speed, with the nearest modes",
        "speed (km/h)",
        "frequency (Hz)",
        &fs,
    )?;
    write_report(dir, r)?;
    Ok(())
}

fn fmt_opt(v: Option<f64>, digits: usize) -> String {
    v.map_or_else(|| "–".into(), |x| format!("{x:.digits$}"))
}

fn write_report(dir: &Path, r: &SweepRecord) -> Result<(), StudiesError> {
    let mut d = Document::new("Speed sweep: frequency selection");
    d.paragraph(format!(
        "{} speeds from {} to {} km/h. Speed range ratio {:.3}; wavelength range ratio of the \
         dominant wear wavelength {}. Frequency selection shows as a wavelength range ratio \
         much smaller than the speed range ratio (docs/theory.md §2.3).",
        r.speeds_kmh.len(),
        r.speeds_kmh[0],
        r.speeds_kmh[r.speeds_kmh.len() - 1],
        r.speed_range_ratio,
        fmt_opt(r.wavelength_range_ratio, 3)
    ));
    if !r.map.frequency_lines_hz.is_empty() {
        let f: Vec<String> = r
            .map
            .frequency_lines_hz
            .iter()
            .map(|f| format!("{f:.1}"))
            .collect();
        d.paragraph(format!(
            "Longitudinal-compression eigenfrequencies drawn on the maps (Hz, `LC`): {}.",
            f.join(", ")
        ));
    }
    if !r.map.wheel_lines_hz.is_empty() {
        let f: Vec<String> = r
            .map
            .wheel_lines_hz
            .iter()
            .map(|f| format!("{f:.1}"))
            .collect();
        d.paragraph(format!(
            "Wheel eigenfrequencies with a large modal displacement at the contact point drawn \
             on the maps (Hz, `wheel`): {}. On the default Dutch track the ridges fall on \
             these, not on the rail's longitudinal-compression modes \
             (validation/frequency_selection.md in the source tree).",
            f.join(", ")
        ));
    }
    d.heading(2, "Maps");
    for (alt, file) in [
        (
            "Differential wear PSD, speed × wavelength",
            "map_wear_wavelength.png",
        ),
        (
            "Differential wear PSD, speed × frequency",
            "map_wear_frequency.png",
        ),
        ("F_L PSD, speed × wavelength", "map_fl_wavelength.png"),
        ("F_L PSD, speed × frequency", "map_fl_frequency.png"),
        ("Dominant wavelength vs speed", "dominant_wavelength.png"),
        ("Dominant frequency vs speed", "dominant_frequency.png"),
    ] {
        d.image(alt, file);
    }
    d.heading(2, "Dominant wear component per speed");
    d.table(
        &["speed (km/h)", "wavelength (mm)", "frequency (Hz)"],
        r.speeds_kmh
            .iter()
            .enumerate()
            .map(|(i, v)| {
                vec![
                    format!("{v}"),
                    fmt_opt(r.dominant_wavelength_mm[i], 2),
                    fmt_opt(r.dominant_frequency_hz[i], 1),
                ]
            })
            .collect(),
    );
    d.write(&dir.join("report"))?;
    Ok(())
}

/// Reads `sweep.json` of a sweep directory.
pub fn read_record(dir: &Path) -> Result<SweepRecord, StudiesError> {
    let p = dir.join("sweep.json");
    let text = std::fs::read_to_string(&p).map_err(StudiesError::io(&p))?;
    serde_json::from_str(&text).map_err(|e| StudiesError::BadFile {
        path: p,
        reason: format!("not a sweep record ({e}); rerun the sweep of this shard"),
    })
}

/// The shard plan file in `DIR/speeds`: which shard of which sweep the directory holds
/// ([`ShardPlan`]), written by [`write_shard_plan`] before the passages and checked by
/// [`merge`].
pub const SHARD_PLAN_FILE: &str = "shard.json";

/// Which shard of which sweep a sweep directory holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShardPlan {
    /// Shard index `I` (0 … count−1).
    pub index: usize,
    /// Shard count `N`.
    pub count: usize,
    /// Every speed of the whole sweep (km/h), ascending.
    pub speeds_kmh: Vec<f64>,
}

/// Writes `dir/speeds/shard.json`: `dir` holds shard `shard` of the sweep of `all_speeds_kmh`.
pub fn write_shard_plan(
    dir: &Path,
    all_speeds_kmh: &[f64],
    shard: super::speeds::Shard,
) -> Result<(), StudiesError> {
    let p = dir.join("speeds").join(SHARD_PLAN_FILE);
    let plan = ShardPlan {
        index: shard.index,
        count: shard.count,
        speeds_kmh: all_speeds_kmh.to_vec(),
    };
    let text =
        serde_json::to_string_pretty(&plan).map_err(|e| StudiesError::Invalid(e.to_string()))?;
    if let Some(parent) = p.parent() {
        std::fs::create_dir_all(parent).map_err(StudiesError::io(parent))?;
    }
    crate::io::write_text(&p, &text).map_err(StudiesError::io(&p))
}

fn read_shard_plan(dir: &Path) -> Result<ShardPlan, StudiesError> {
    let p = dir.join("speeds").join(SHARD_PLAN_FILE);
    let text = std::fs::read_to_string(&p).map_err(StudiesError::io(&p))?;
    serde_json::from_str(&text).map_err(|e| StudiesError::BadFile {
        path: p,
        reason: format!("not a shard plan ({e}); rerun the sweep of this shard"),
    })
}

/// Checks that the shard directories form one complete sweep: the same sweep (speeds and
/// shard count) in each, every shard `0 … N−1` exactly once, and each finished with its
/// shard's speeds (from its `sweep.json`).
fn check_shards(dirs: &[PathBuf], records: &[SweepRecord]) -> Result<(), StudiesError> {
    let plans = dirs
        .iter()
        .map(|d| read_shard_plan(d))
        .collect::<Result<Vec<_>, _>>()?;
    let first = &plans[0];
    let count = first.count;
    let mut given: Vec<Option<&PathBuf>> = vec![None; count];
    for ((d, p), rec) in dirs.iter().zip(&plans).zip(records) {
        if p.count != count
            || p.speeds_kmh.len() != first.speeds_kmh.len()
            || p.speeds_kmh
                .iter()
                .zip(&first.speeds_kmh)
                .any(|(a, b)| !same_speed(*a, *b))
            || p.index >= count
        {
            return Err(StudiesError::ShardsOfDifferentSweeps {
                first: dirs[0].clone(),
                second: d.clone(),
            });
        }
        if let Some(prev) = given[p.index] {
            return Err(StudiesError::ShardTwice {
                index: p.index,
                count,
                first: prev.clone(),
                second: d.clone(),
            });
        }
        given[p.index] = Some(d);
        let want = super::speeds::Shard {
            index: p.index,
            count,
        }
        .select(&p.speeds_kmh);
        let same = want.len() == rec.speeds_kmh.len()
            && want
                .iter()
                .zip(&rec.speeds_kmh)
                .all(|(a, b)| same_speed(*a, *b));
        if !same {
            return Err(StudiesError::ShardUnfinished {
                dir: d.clone(),
                index: p.index,
                count,
                have: rec.speeds_kmh.len(),
                want: want.len(),
            });
        }
    }
    let missing: Vec<usize> = (0..count).filter(|&i| given[i].is_none()).collect();
    if !missing.is_empty() {
        return Err(StudiesError::ShardsMissing { count, missing });
    }
    Ok(())
}

/// Joins shard directories (each a finished `sweep` of some speeds, with its `sweep.json`)
/// into `out`: the speed files are copied byte for byte, then [`assemble`]d over the union of
/// the speeds — the same files as the unsharded sweep. The shards must have the same map
/// options; a speed present in two shards must have identical files.
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<(SweepRecord, SweepMaps), StudiesError> {
    if dirs.is_empty() {
        return Err(StudiesError::Merge("no shard directories given".into()));
    }
    let mut key: Option<(String, &PathBuf)> = None;
    for d in dirs {
        let p = d.join("speeds").join(RUN_KEY_FILE);
        let k = std::fs::read_to_string(&p).map_err(StudiesError::io(&p))?;
        match &key {
            None => key = Some((k, d)),
            Some((k0, first)) if *k0 != k => {
                return Err(StudiesError::Merge(format!(
                    "{} and {} hold passages of different models or program versions ({}); \
                     merge only shards of one sweep",
                    first.display(),
                    d.display(),
                    RUN_KEY_FILE
                )))
            }
            Some(_) => {}
        }
    }
    let (key, _) = key.expect("at least one shard");
    let kp = out.join("speeds").join(RUN_KEY_FILE);
    match std::fs::read_to_string(&kp) {
        Ok(k) if k != key => {
            return Err(StudiesError::Merge(format!(
                "{} already holds passages of another model; use an empty --out",
                out.display()
            )))
        }
        Ok(_) => {}
        Err(_) => crate::io::write_text(&kp, &key).map_err(StudiesError::io(&kp))?,
    }
    let mut opts: Option<(MapOptions, &PathBuf)> = None;
    let mut files: Vec<(f64, Vec<u8>, PathBuf)> = Vec::new();
    let records = dirs
        .iter()
        .map(|d| read_record(d))
        .collect::<Result<Vec<_>, _>>()?;
    for (d, rec) in dirs.iter().zip(&records) {
        match &opts {
            None => opts = Some((rec.map.clone(), d)),
            Some((o, first)) if *o != rec.map => {
                return Err(StudiesError::Merge(format!(
                    "{} and {} were made with different map options (grids or eigenfrequency \
                     lines); rerun the shards with the same model and options",
                    first.display(),
                    d.display()
                )))
            }
            Some(_) => {}
        }
        for &v in &rec.speeds_kmh {
            let p = speed_file(d, v);
            let bytes = std::fs::read(&p).map_err(StudiesError::io(&p))?;
            files.push((v, bytes, p));
        }
    }
    check_shards(dirs, &records)?;
    files.sort_by(|a, b| a.0.total_cmp(&b.0));
    files.dedup_by(|b, a| same_speed(a.0, b.0) && a.1 == b.1);
    if let Some(w) = files.windows(2).find(|w| same_speed(w[0].0, w[1].0)) {
        return Err(StudiesError::Merge(format!(
            "speed {} km/h is in {} and {} with different results; remove one",
            w[0].0,
            w[0].2.display(),
            w[1].2.display()
        )));
    }
    for (v, bytes, _) in &files {
        let p = speed_file(out, *v);
        crate::io::write_atomic(&p, |w| w.write_all(bytes)).map_err(StudiesError::io(&p))?;
    }
    let speeds: Vec<f64> = files.iter().map(|f| f.0).collect();
    write_shard_plan(out, &speeds, super::speeds::Shard::ALL)?;
    let (o, _) = opts.expect("at least one shard");
    assemble(out, &speeds, &o)
}

#[cfg(test)]
mod tests {
    use super::*;

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
