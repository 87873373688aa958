//! Initiation comparison (docs/theory.md §11.4): several models (e.g. RPM1–RPM5) on
//! the smooth rail, tabulated by the band RMS and the strongest PSD peaks of `F_L`, `F_N` and
//! the differential wear, and whether each initiates corrugation.
//!
//! # Initiation criterion
//! A model **initiates** corrugation at a speed when both hold:
//! 1. the differential wear is significant: `wear_band_rms / wear_mean ≥ min_relative_wear`
//!    (the RMS of the 20–80 mm band-passed frictional work relative to its mean along the
//!    rail; default [`InitiationCriterion::DEFAULT_MIN_RELATIVE_WEAR`] = 1 %), and
//! 2. the wear follows the longitudinal force (docs/theory.md §2.4, "on the smooth rail the
//!    differential wear follows F_L"): the dominant wavelength of `F_L` deviates from the
//!    dominant wear wavelength by at most `max_wavelength_deviation` (default 3 %, the
//!    consistency limit of docs/theory.md §10.2), deviation = `|λ_FL − λ_W| / λ_W`.
//!
//! The 1 % threshold is a stated engineering choice, not a published value (docs/theory.md
//! §11.4 says what it rests on and what the shipped models give); it is the model key
//! `wear.initiation_threshold` (`--min-relative-wear` overrides it for one run). A model
//! without a wear or `F_L` peak in the band does not initiate.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::panic_text;
use super::StudiesError;
use crate::dynamics::{PassageRunner, PassageSummary, WavelengthComponent};
use crate::progress::{Counter, Progress};
use crate::report::doc::Document;
use crate::units::Speed;

/// The default number of PSD peaks per signal in the initiation table.
pub const DEFAULT_PEAKS: usize = 3;

/// The stated initiation criterion (module doc).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitiationCriterion {
    /// Minimum `wear_band_rms / wear_mean` (−).
    pub min_relative_wear: f64,
    /// Maximum relative deviation of `F_L`'s dominant wavelength from the wear's (−).
    pub max_wavelength_deviation: f64,
}

impl InitiationCriterion {
    /// Default threshold on the relative band RMS of the wear (1 %,
    /// [`crate::model::Wear::initiation_threshold`]).
    pub const DEFAULT_MIN_RELATIVE_WEAR: f64 = crate::model::DEFAULT_INITIATION_THRESHOLD;

    /// The criterion of a model: its `wear.initiation_threshold` and the default wavelength
    /// match tolerance.
    pub fn from_model(model: &crate::model::Model) -> Self {
        Self {
            min_relative_wear: model.wear.initiation_threshold,
            ..Self::default()
        }
    }
    /// Default wavelength match tolerance (3 %, docs/theory.md §10.2).
    pub const DEFAULT_MAX_WAVELENGTH_DEVIATION: f64 = 0.03;

    /// Checks the criterion: the relative-wear threshold in [0, 1], the wavelength tolerance
    /// finite and ≥ 0 (named by the `initiation` command's flags).
    pub fn check(&self) -> Result<(), StudiesError> {
        let v = self.min_relative_wear;
        if !(v.is_finite() && (0.0..=1.0).contains(&v)) {
            return Err(StudiesError::Argument {
                flag: "--min-relative-wear",
                given: v.to_string(),
                reason: "must be a number from 0 to 1".into(),
            });
        }
        let v = self.max_wavelength_deviation;
        if !(v.is_finite() && v >= 0.0) {
            return Err(StudiesError::Argument {
                flag: "--max-wavelength-deviation",
                given: v.to_string(),
                reason: "must be a finite number ≥ 0".into(),
            });
        }
        Ok(())
    }
}

/// Most PSD peaks per signal in the initiation table.
pub(crate) const MAX_PEAKS: usize = 20;

/// Checks the number of PSD peaks per signal: 1 to `MAX_PEAKS`.
pub fn check_peaks(peaks: usize) -> Result<(), StudiesError> {
    if (1..=MAX_PEAKS).contains(&peaks) {
        return Ok(());
    }
    Err(StudiesError::Argument {
        flag: "--peaks",
        given: peaks.to_string(),
        reason: format!("must be 1 … {MAX_PEAKS}"),
    })
}

/// Checks a speed of the initiation table (km/h): the range of `run.speed_kmh`.
pub fn check_speed_kmh(speed_kmh: f64) -> Result<(), StudiesError> {
    let [lo, hi] = crate::model::SPEED_KMH;
    if speed_kmh.is_finite() && (lo..=hi).contains(&speed_kmh) {
        return Ok(());
    }
    Err(StudiesError::OutOfRange {
        name: "--speed",
        value: speed_kmh,
        lo,
        hi,
        unit: "km/h (as run.speed_kmh)",
    })
}

impl Default for InitiationCriterion {
    fn default() -> Self {
        Self {
            min_relative_wear: Self::DEFAULT_MIN_RELATIVE_WEAR,
            max_wavelength_deviation: Self::DEFAULT_MAX_WAVELENGTH_DEVIATION,
        }
    }
}

/// The initiation indicators of one model (or study case) at one speed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InitiationRow {
    /// Model or case name.
    pub name: String,
    /// Speed (km/h).
    pub speed_kmh: f64,
    /// Mean normal force (N).
    pub mean_fn_n: f64,
    /// Mean longitudinal force (N).
    pub mean_fl_n: f64,
    /// Band RMS of `F_L` (N).
    pub fl_band_rms_n: f64,
    /// Band RMS of `F_N` (N).
    pub fn_band_rms_n: f64,
    /// Band RMS of the wear (J/m).
    pub wear_band_rms: f64,
    /// Mean wear (J/m).
    pub wear_mean: f64,
    /// `wear_band_rms / wear_mean` (−); `None` when the mean wear is not positive.
    pub relative_wear: Option<f64>,
    /// Strongest wear components (at most the requested number).
    pub wear_peaks: Vec<WavelengthComponent>,
    /// Strongest `F_L` components.
    pub fl_peaks: Vec<WavelengthComponent>,
    /// Strongest `F_N` components.
    pub fn_peaks: Vec<WavelengthComponent>,
    /// `|λ_FL − λ_W| / λ_W` of the two dominant components (−); `None` if either is missing.
    pub fl_wear_deviation: Option<f64>,
    /// The threshold on `relative_wear` it was judged against (−).
    #[serde(default)]
    pub threshold: Option<f64>,
    /// Whether the criterion holds.
    pub initiates: bool,
    /// Why (which condition failed, or that both hold).
    pub reason: String,
}

fn strongest(c: &[WavelengthComponent]) -> Option<&WavelengthComponent> {
    c.iter().max_by(|a, b| a.psd.total_cmp(&b.psd))
}

fn top(c: &[WavelengthComponent], n: usize) -> Vec<WavelengthComponent> {
    let mut v = c.to_vec();
    v.sort_by(|a, b| b.psd.total_cmp(&a.psd));
    v.truncate(n);
    v
}

/// Evaluates the criterion on one passage summary, keeping the `peaks` strongest components
/// of each signal.
pub fn evaluate(
    name: &str,
    s: &PassageSummary,
    criterion: &InitiationCriterion,
    peaks: usize,
) -> InitiationRow {
    let relative_wear =
        (s.wear_mean > 0.0 && s.wear_band_rms.is_finite()).then(|| s.wear_band_rms / s.wear_mean);
    let w = strongest(&s.wear_components);
    let fl = strongest(&s.fl_components);
    let fl_wear_deviation = match (w, fl) {
        (Some(w), Some(fl)) if w.wavelength_mm > 0.0 => {
            Some((fl.wavelength_mm - w.wavelength_mm).abs() / w.wavelength_mm)
        }
        _ => None,
    };
    let (initiates, reason) = match (relative_wear, fl_wear_deviation) {
        (None, _) => (false, "mean wear is not positive".to_string()),
        (Some(r), _) if r < criterion.min_relative_wear => (
            false,
            format!(
                "relative wear {:.3} % below {:.3} %",
                100.0 * r,
                100.0 * criterion.min_relative_wear
            ),
        ),
        (Some(_), None) => (false, "no wear or F_L peak in the band".to_string()),
        (Some(_), Some(d)) if d > criterion.max_wavelength_deviation => (
            false,
            format!(
                "F_L's dominant wavelength deviates {:.2} % from the wear's (> {:.2} %)",
                100.0 * d,
                100.0 * criterion.max_wavelength_deviation
            ),
        ),
        (Some(r), Some(d)) => (
            true,
            format!(
                "relative wear {:.3} %, F_L matches the wear within {:.2} %",
                100.0 * r,
                100.0 * d
            ),
        ),
    };
    InitiationRow {
        name: name.to_string(),
        speed_kmh: s.speed_kmh,
        mean_fn_n: s.mean_fn_n,
        mean_fl_n: s.mean_fl_n,
        fl_band_rms_n: s.fl_band_rms_n,
        fn_band_rms_n: s.fn_band_rms_n,
        wear_band_rms: s.wear_band_rms,
        wear_mean: s.wear_mean,
        relative_wear,
        wear_peaks: top(&s.wear_components, peaks),
        fl_peaks: top(&s.fl_components, peaks),
        fn_peaks: top(&s.fn_components, peaks),
        fl_wear_deviation,
        threshold: Some(criterion.min_relative_wear),
        initiates,
        reason,
    }
}

/// Runs every `(name, runner)` on the smooth rail at `speed_kmh` (in parallel) and evaluates
/// the criterion. Failed or panicking runners are reported together after all others.
pub fn run_initiation(
    cases: &[(String, &dyn PassageRunner)],
    speed_kmh: f64,
    criterion: &InitiationCriterion,
    peaks: usize,
    progress: &dyn Progress,
) -> Result<Vec<InitiationRow>, StudiesError> {
    criterion.check()?;
    check_peaks(peaks)?;
    check_speed_kmh(speed_kmh)?;
    let bar = Counter::start(progress, "initiation passages (models)", cases.len() as u64);
    let out: Vec<Result<InitiationRow, String>> = cases
        .par_iter()
        .map(|(name, runner)| {
            let r = match catch_unwind(AssertUnwindSafe(|| {
                runner.run(Speed::from_kmh(speed_kmh), None)
            })) {
                Ok(Ok(s)) => Ok(evaluate(name, &s, criterion, peaks)),
                Ok(Err(e)) => Err(format!("{name}: {e}")),
                Err(p) => Err(format!("{name}: passage panicked: {}", panic_text(&*p))),
            };
            bar.inc();
            r
        })
        .collect();
    bar.finish();
    let mut rows = Vec::new();
    let mut failures = Vec::new();
    for r in out {
        match r {
            Ok(row) => rows.push(row),
            Err(e) => failures.push(e),
        }
    }
    if failures.is_empty() {
        Ok(rows)
    } else {
        Err(StudiesError::Passages { failures })
    }
}

/// Column names of the indicator part of a table with `peaks` peaks per signal.
pub(crate) fn indicator_header(peaks: usize) -> Vec<String> {
    let mut h: Vec<String> = [
        "speed_kmh",
        "mean_fn_n",
        "mean_fl_n",
        "fl_band_rms_n",
        "fn_band_rms_n",
        "wear_band_rms_j_per_m",
        "wear_mean_j_per_m",
        "relative_wear",
        "fl_wear_deviation",
        "initiates",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    for sig in ["wear", "fl", "fn"] {
        for i in 1..=peaks {
            h.push(format!("{sig}_peak{i}_wavelength_mm"));
            h.push(format!("{sig}_peak{i}_frequency_hz"));
        }
    }
    h
}

fn num(v: f64) -> String {
    format!("{v}")
}

fn opt(v: Option<f64>) -> String {
    v.map(num).unwrap_or_default()
}

/// The indicator cells of one row (full precision; empty cells for missing values).
pub(crate) fn indicator_cells(r: &InitiationRow, peaks: usize) -> Vec<String> {
    let mut c = vec![
        num(r.speed_kmh),
        num(r.mean_fn_n),
        num(r.mean_fl_n),
        num(r.fl_band_rms_n),
        num(r.fn_band_rms_n),
        num(r.wear_band_rms),
        num(r.wear_mean),
        opt(r.relative_wear),
        opt(r.fl_wear_deviation),
        (if r.initiates { "yes" } else { "no" }).to_string(),
    ];
    for p in [&r.wear_peaks, &r.fl_peaks, &r.fn_peaks] {
        for i in 0..peaks {
            c.push(opt(p.get(i).map(|c| c.wavelength_mm)));
            c.push(opt(p.get(i).map(|c| c.frequency_hz)));
        }
    }
    c
}

/// Writes a table (header + string rows) as CSV, atomically.
pub(crate) fn write_table_csv(
    path: &Path,
    header: &[String],
    rows: &[Vec<String>],
) -> Result<(), StudiesError> {
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    crate::io::write_text_csv(path, &header, rows).map_err(StudiesError::io(path))
}

fn peaks_text(p: &[WavelengthComponent]) -> String {
    let v: Vec<String> = p
        .iter()
        .map(|c| format!("{:.1} mm / {:.0} Hz", c.wavelength_mm, c.frequency_hz))
        .collect();
    if v.is_empty() {
        "–".into()
    } else {
        v.join("; ")
    }
}

/// Short Markdown/HTML table rows of the indicators (rounded for reading).
pub(crate) fn readable_header() -> Vec<&'static str> {
    vec![
        "name",
        "speed (km/h)",
        "F_L band RMS (N)",
        "F_N band RMS (N)",
        "wear band RMS / mean (%)",
        "initiation threshold (%)",
        "wear peaks",
        "F_L peaks",
        "F_N peaks",
        "initiates",
        "reason",
    ]
}

/// One readable row (see [`readable_header`]).
pub(crate) fn readable_cells(r: &InitiationRow) -> Vec<String> {
    vec![
        r.name.clone(),
        format!("{}", r.speed_kmh),
        format!("{:.1}", r.fl_band_rms_n),
        format!("{:.1}", r.fn_band_rms_n),
        r.relative_wear
            .map_or_else(|| "–".into(), |v| crate::growth::verdict::sig(100.0 * v, 3)),
        r.threshold
            .map_or_else(|| "–".into(), |v| crate::growth::verdict::sig(100.0 * v, 3)),
        peaks_text(&r.wear_peaks),
        peaks_text(&r.fl_peaks),
        peaks_text(&r.fn_peaks),
        (if r.initiates { "yes" } else { "no" }).into(),
        r.reason.clone(),
    ]
}

/// Writes `initiation.csv` (full precision), `initiation.json`, and `initiation.md` /
/// `initiation.html` (readable table with the criterion stated) into `dir`.
pub fn write_initiation(
    dir: &Path,
    rows: &[InitiationRow],
    criterion: &InitiationCriterion,
    peaks: usize,
) -> Result<(), StudiesError> {
    let mut header = vec!["name".to_string()];
    header.extend(indicator_header(peaks));
    let table: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let mut c = vec![r.name.clone()];
            c.extend(indicator_cells(r, peaks));
            c
        })
        .collect();
    write_table_csv(&dir.join("initiation.csv"), &header, &table)?;
    let p = dir.join("initiation.json");
    let json = serde_json::to_string_pretty(&serde_json::json!({
        "criterion": criterion,
        "rows": rows,
    }))
    .map_err(|e| StudiesError::BadFile {
        path: p.clone(),
        reason: e.to_string(),
    })?;
    crate::io::write_text(&p, &(json + "\n")).map_err(StudiesError::io(&p))?;
    let mut d = Document::new("Corrugation initiation on the smooth rail");
    d.paragraph(criterion_text(criterion));
    d.table(
        &readable_header(),
        rows.iter().map(readable_cells).collect(),
    );
    d.write(&dir.join("initiation"))?;
    Ok(())
}

/// The criterion in words, for reports.
pub(crate) fn criterion_text(c: &InitiationCriterion) -> String {
    format!(
        "Criterion: a case initiates corrugation when the RMS of the 20–80 mm band-passed \
         differential wear is at least {:.2} % of the mean wear, and the dominant wavelength of \
         F_L deviates at most {:.1} % from the dominant wear wavelength (the wear follows F_L, \
         docs/theory.md §2.4 and §11.4).",
        100.0 * c.min_relative_wear,
        100.0 * c.max_wavelength_deviation
    )
}

#[cfg(test)]
mod tests {
    use super::{check_peaks, check_speed_kmh, run_initiation, InitiationCriterion, MAX_PEAKS};
    /// The library refuses a criterion, a peak count or a speed out of range, naming the flag
    /// and the range, whoever calls it.
    #[test]
    fn criterion_peaks_and_speed_are_checked_by_the_library() {
        assert!(InitiationCriterion::default().check().is_ok());
        let bad = InitiationCriterion {
            min_relative_wear: 1.5,
            ..InitiationCriterion::default()
        };
        let e = bad.check().unwrap_err().to_string();
        assert!(
            e.contains("--min-relative-wear 1.5") && e.contains("0 to 1"),
            "{e}"
        );
        let bad = InitiationCriterion {
            max_wavelength_deviation: f64::NAN,
            ..InitiationCriterion::default()
        };
        assert!(bad.check().is_err());
        assert!(check_peaks(1).is_ok() && check_peaks(MAX_PEAKS).is_ok());
        assert!(check_peaks(0).is_err() && check_peaks(MAX_PEAKS + 1).is_err());
        let e = check_speed_kmh(600.0).unwrap_err().to_string();
        assert!(e.contains("40 to 500 km/h"), "{e}");
        let e = run_initiation(&[], 140.0, &bad, 3, &crate::progress::Silent).unwrap_err();
        assert!(e.to_string().contains("--max-wavelength-deviation"), "{e}");
    }
}
