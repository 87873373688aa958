//! Design studies (docs/theory.md §11.5): a TOML study file names a base model and parameters to
//! vary; every case gets the initiation indicators ([`super::initiation`]) and optionally the
//! growth loop (a hook supplied by the caller); the output is one table and plots of the
//! indicators vs the parameters.
//!
//! # Study file
//! ```toml
//! title = "Railpad stiffness × damping"   # optional
//! model = "builtin:dutch"                  # or a model file, relative to the study file
//! set = ["fastening.model=\"RPM3\""]       # optional overrides applied to every case
//! speeds_kmh = [140.0]                     # optional; default: the model's run.speed_kmh
//! combine = "grid"                         # "grid" (full product, default) or "zip"
//! growth = false                           # run the growth loop per case (optional)
//! peaks = 3                                # PSD peaks per signal in the table (optional)
//! basis = "full"                           # track basis: "full" (Lanczos per distinct track,
//!                                          # default) or "substructured" (theory §5.6)
//! # substructure = { cutoff_factor = 1.5, pattern_degree = 3 }  # only with "substructured"
//!
//! [criterion]                              # optional, see initiation::InitiationCriterion
//! min_relative_wear = 0.01
//! max_wavelength_deviation = 0.03
//!
//! [[parameter]]
//! key = "fastening.vertical_stiffness"     # a dotted model key, as for --set
//! values = [0.65e9, 1.3e9, 2.6e9]          # any TOML values ...
//!
//! [[parameter]]
//! key = "fastening.vertical_damping"
//! range = { start = 15e3, stop = 75e3, step = 30e3 }   # ... or a numeric range
//! ```
//! A range is `start + k·step`, `k = 0 … ⌊(stop − start)/step + 10⁻⁹⌋` (the stop is included
//! when on the grid, never appended — the same rule as the sweep speeds). With
//! `combine = "grid"` the cases are the Cartesian product of the parameters (the last
//! parameter varies fastest); with `"zip"` the parameters must have equally many values and
//! case `i` takes the `i`-th value of each.
//!
//! Every case's model is the base model with `set` and then the case's `key=value` overrides
//! applied through the model's `--set` machinery ([`crate::model::load_model`]), so a key or
//! value the model does not accept is reported (naming the study file, the case and the key)
//! **before** anything runs. The study file itself is read with unknown keys denied; errors
//! name the file and the dotted key (`parameter[1].range.step`).
//!
//! # Outputs (in the output directory)
//! - `cases/<NNNN>.json` — each finished case (its overrides, model hash and indicators),
//!   written atomically; a rerun reuses the cases whose file matches their overrides, resolved
//!   model ([`model_hash`]) and speeds (resume), and recomputes the others;
//! - `study.csv` — one row per case and speed: `case`, the parameter values, the indicators
//!   ([`super::initiation::indicator_header`]) and the growth hook's columns;
//! - `study.md`, `study.html` — the criterion, a readable table and the plots;
//! - `study_<indicator>.{svg,png}` — each indicator vs the first parameter (one curve per
//!   combination of the other parameters and speed); the case index is the abscissa when the
//!   first parameter is not numeric.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::initiation::{
    criterion_text, evaluate, indicator_cells, indicator_header, readable_cells, readable_header,
    write_table_csv, InitiationCriterion, InitiationRow,
};
use super::sweep::{panic_text, progress_bar};
use super::{BoxError, StudiesError};

pub mod bases;
pub use bases::{basis_plan, BasisPlan, CaseRunners, StudyBasis};
use crate::dynamics::PassageRunner;
use crate::eigen::substructure::SubstructureOptions;
use crate::model::{load_model, Model, ModelSource};
use crate::report::doc::Document;
use crate::report::plot::{line_plot, Series};

/// Most cases of one study.
pub const MAX_CASES: usize = 10_000;

/// How the parameters are combined into cases.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Combine {
    /// Full Cartesian product (last parameter fastest).
    #[default]
    Grid,
    /// Parallel lists of equal length.
    Zip,
}

/// A numeric range `start:stop:step`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Range {
    /// First value.
    pub start: f64,
    /// Last value (included when on the grid).
    pub stop: f64,
    /// Step (> 0).
    pub step: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ParamFile {
    key: String,
    #[serde(default)]
    values: Option<Vec<toml::Value>>,
    #[serde(default)]
    range: Option<Range>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct StudyFile {
    #[serde(default)]
    title: Option<String>,
    model: String,
    #[serde(default)]
    set: Vec<String>,
    #[serde(default)]
    speeds_kmh: Option<Vec<f64>>,
    #[serde(default)]
    combine: Combine,
    #[serde(default)]
    growth: bool,
    #[serde(default)]
    peaks: Option<usize>,
    #[serde(default)]
    criterion: Option<InitiationCriterion>,
    #[serde(default)]
    basis: StudyBasis,
    #[serde(default)]
    substructure: Option<SubstructureOptions>,
    parameter: Vec<ParamFile>,
}

/// One varied parameter: a dotted model key and its values.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    /// Dotted model key (as for `--set`).
    pub key: String,
    /// Its values, in order.
    pub values: Vec<toml::Value>,
}

/// One case: the value of every parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// Position in the study (0-based).
    pub index: usize,
    /// `(key, value)` per parameter, in the study's parameter order.
    pub assignments: Vec<(String, toml::Value)>,
}

impl Case {
    /// The case's `key=value` overrides.
    pub fn overrides(&self) -> Vec<String> {
        self.assignments
            .iter()
            .map(|(k, v)| format!("{k}={}", value_text(v)))
            .collect()
    }

    /// A readable label: `key=value, key=value`.
    pub fn label(&self) -> String {
        self.overrides().join(", ")
    }
}

/// A value as TOML text (`1300000000.0`, `"RPM1"`, `[0, 2]`).
pub fn value_text(v: &toml::Value) -> String {
    v.to_string()
}

/// A parsed, checked study file.
#[derive(Clone, Debug, PartialEq)]
pub struct Study {
    /// The study file (for messages).
    pub file: String,
    /// Title (default: the file stem).
    pub title: String,
    /// The base model.
    pub base: ModelSource,
    /// Overrides applied to every case before the case's own.
    pub set: Vec<String>,
    /// Speeds (km/h); `None` = the model's `run.speed_kmh`.
    pub speeds_kmh: Option<Vec<f64>>,
    /// How parameters combine.
    pub combine: Combine,
    /// Run the growth loop per case.
    pub growth: bool,
    /// PSD peaks per signal in the table.
    pub peaks: usize,
    /// The initiation criterion.
    pub criterion: InitiationCriterion,
    /// The track basis of the cases (default full).
    pub basis: StudyBasis,
    /// Options of the component bases when `basis = "substructured"` (defaults otherwise).
    pub substructure: SubstructureOptions,
    /// The varied parameters.
    pub parameters: Vec<Parameter>,
}

fn key_error(file: &str, key: impl Into<String>, message: impl Into<String>) -> StudiesError {
    StudiesError::StudyKey {
        file: file.into(),
        key: key.into(),
        message: message.into(),
    }
}

/// `start + k·step` for `k = 0 … ⌊(stop − start)/step + 10⁻⁹⌋`.
pub fn expand_range(r: &Range) -> Result<Vec<f64>, String> {
    if !(r.start.is_finite() && r.stop.is_finite() && r.step.is_finite()) {
        return Err("start, stop and step must be finite".into());
    }
    if r.step <= 0.0 {
        return Err(format!("step {} must be positive", r.step));
    }
    if r.stop < r.start {
        return Err(format!("stop {} is below start {}", r.stop, r.start));
    }
    let k = ((r.stop - r.start) / r.step + 1e-9).floor();
    if k + 1.0 > MAX_CASES as f64 {
        return Err(format!("{} values; at most {MAX_CASES}", k + 1.0));
    }
    Ok((0..=k as usize)
        .map(|i| {
            let v = r.start + i as f64 * r.step;
            // Round to 12 significant digits so 0.1-steps print as written.
            if v == 0.0 {
                0.0
            } else {
                let s = 10f64.powi(11 - v.abs().log10().floor() as i32);
                (v * s).round() / s
            }
        })
        .collect())
}

impl Study {
    /// Reads and checks a study file; a relative `model` path is taken relative to it.
    pub fn load(path: &Path) -> Result<Self, StudiesError> {
        let text = std::fs::read_to_string(path).map_err(StudiesError::io(path))?;
        let dir = path.parent().unwrap_or(Path::new("."));
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        Self::parse_str(&text, &path.display().to_string(), dir, &stem)
    }

    /// Parses study TOML text; `file` names it in messages, `dir` resolves a relative model
    /// path, `default_title` is used without a `title` key.
    pub fn parse_str(
        text: &str,
        file: &str,
        dir: &Path,
        default_title: &str,
    ) -> Result<Self, StudiesError> {
        let table: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            key_error(
                file,
                "(syntax)",
                format!(
                    "TOML syntax error: {}",
                    e.to_string().trim().replace('\n', " ")
                ),
            )
        })?;
        let raw: StudyFile =
            serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
                let mut key = e.path().to_string();
                let message = e.into_inner().message().to_string();
                if let Some(rest) = message.strip_prefix("unknown field `") {
                    if let Some(name) = rest.split('`').next() {
                        key = if key == "." {
                            name.to_string()
                        } else {
                            format!("{key}.{name}")
                        };
                    }
                }
                key_error(file, key, message)
            })?;
        let base = if raw.model == "builtin:dutch" {
            ModelSource::Builtin
        } else {
            ModelSource::File(dir.join(&raw.model))
        };
        if raw.parameter.is_empty() {
            return Err(key_error(
                file,
                "parameter",
                "give at least one [[parameter]]",
            ));
        }
        let mut parameters = Vec::new();
        for (i, p) in raw.parameter.iter().enumerate() {
            let k = format!("parameter[{i}]");
            if p.key.trim().is_empty() || p.key.split('.').any(|s| s.trim().is_empty()) {
                return Err(key_error(
                    file,
                    format!("{k}.key"),
                    "must be a dotted model key, e.g. fastening.vertical_stiffness",
                ));
            }
            if parameters.iter().any(|q: &Parameter| q.key == p.key) {
                return Err(key_error(
                    file,
                    format!("{k}.key"),
                    format!("`{}` is varied twice", p.key),
                ));
            }
            let values = match (&p.values, &p.range) {
                (Some(_), Some(_)) | (None, None) => {
                    return Err(key_error(
                        file,
                        k,
                        "give exactly one of `values` and `range`",
                    ))
                }
                (Some(v), None) if v.is_empty() => {
                    return Err(key_error(file, format!("{k}.values"), "is empty"))
                }
                (Some(v), None) => v.clone(),
                (None, Some(r)) => expand_range(r)
                    .map_err(|m| key_error(file, format!("{k}.range"), m))?
                    .into_iter()
                    .map(toml::Value::Float)
                    .collect(),
            };
            parameters.push(Parameter {
                key: p.key.trim().to_string(),
                values,
            });
        }
        if raw.combine == Combine::Zip {
            let n = parameters[0].values.len();
            if let Some(i) = parameters.iter().position(|p| p.values.len() != n) {
                return Err(key_error(
                    file,
                    format!("parameter[{i}]"),
                    format!(
                        "has {} values, parameter[0] has {n}; combine = \"zip\" needs equal lengths",
                        parameters[i].values.len()
                    ),
                ));
            }
        }
        let n_cases: f64 = match raw.combine {
            Combine::Grid => parameters.iter().map(|p| p.values.len() as f64).product(),
            Combine::Zip => parameters[0].values.len() as f64,
        };
        if n_cases > MAX_CASES as f64 {
            return Err(key_error(
                file,
                "parameter",
                format!("{n_cases} cases; at most {MAX_CASES}"),
            ));
        }
        if let Some(v) = &raw.speeds_kmh {
            if v.is_empty() {
                return Err(key_error(file, "speeds_kmh", "is empty"));
            }
            if let Some(s) = v.iter().find(|s| {
                !(s.is_finite()
                    && **s >= super::speeds::MIN_SPEED_KMH
                    && **s <= super::speeds::MAX_SPEED_KMH)
            }) {
                return Err(key_error(
                    file,
                    "speeds_kmh",
                    format!(
                        "speed {s} km/h out of range, allowed {} to {} km/h (as run.speed_kmh)",
                        super::speeds::MIN_SPEED_KMH,
                        super::speeds::MAX_SPEED_KMH
                    ),
                ));
            }
        }
        let criterion = raw.criterion.unwrap_or_default();
        if !(criterion.min_relative_wear >= 0.0 && criterion.min_relative_wear.is_finite()) {
            return Err(key_error(
                file,
                "criterion.min_relative_wear",
                "must be ≥ 0 and finite",
            ));
        }
        if !(criterion.max_wavelength_deviation >= 0.0
            && criterion.max_wavelength_deviation.is_finite())
        {
            return Err(key_error(
                file,
                "criterion.max_wavelength_deviation",
                "must be ≥ 0 and finite",
            ));
        }
        let peaks = raw.peaks.unwrap_or(3);
        if !(1..=20).contains(&peaks) {
            return Err(key_error(file, "peaks", format!("{peaks}: allowed 1 … 20")));
        }
        let substructure = raw.substructure.unwrap_or_default();
        if raw.substructure.is_some() && raw.basis != StudyBasis::Substructured {
            return Err(key_error(
                file,
                "substructure",
                "only allowed with basis = \"substructured\"",
            ));
        }
        substructure
            .validate()
            .map_err(|e| key_error(file, "substructure", e.to_string()))?;
        Ok(Study {
            file: file.to_string(),
            title: raw.title.unwrap_or_else(|| default_title.to_string()),
            base,
            set: raw.set,
            speeds_kmh: raw.speeds_kmh,
            combine: raw.combine,
            growth: raw.growth,
            peaks,
            criterion,
            basis: raw.basis,
            substructure,
            parameters,
        })
    }

    /// The cases, in order (grid: last parameter fastest; zip: position by position).
    pub fn cases(&self) -> Vec<Case> {
        let p = &self.parameters;
        match self.combine {
            Combine::Zip => (0..p[0].values.len())
                .map(|i| Case {
                    index: i,
                    assignments: p
                        .iter()
                        .map(|q| (q.key.clone(), q.values[i].clone()))
                        .collect(),
                })
                .collect(),
            Combine::Grid => {
                let n: usize = p.iter().map(|q| q.values.len()).product();
                (0..n)
                    .map(|mut i| {
                        let index = i;
                        let mut a = vec![(String::new(), toml::Value::Boolean(false)); p.len()];
                        for (j, q) in p.iter().enumerate().rev() {
                            a[j] = (q.key.clone(), q.values[i % q.values.len()].clone());
                            i /= q.values.len();
                        }
                        Case {
                            index,
                            assignments: a,
                        }
                    })
                    .collect()
            }
        }
    }

    /// The overrides of a case: the study's `set`, then the case's own.
    pub fn case_overrides(&self, case: &Case) -> Vec<String> {
        let mut o = self.set.clone();
        o.extend(case.overrides());
        o
    }

    /// Builds and validates every case's model (nothing runs until all are valid).
    pub fn case_models(&self) -> Result<Vec<(Case, Model)>, StudiesError> {
        self.cases()
            .into_iter()
            .map(|c| {
                let m = load_model(&self.base, &self.case_overrides(&c)).map_err(|e| {
                    StudiesError::StudyCase {
                        file: self.file.clone(),
                        case: format!("{} ({})", c.index, c.label()),
                        message: e.to_string(),
                    }
                })?;
                Ok((c, m))
            })
            .collect()
    }
}

/// Builds the passage runner of a model (the CLI passes its engine).
pub type RunnerFactory<'a> =
    &'a (dyn Fn(&Model) -> Result<Box<dyn PassageRunner>, BoxError> + Sync);

/// The growth loop of one case: named scalar results (e.g. `limiting_amplitude_um`), added
/// as columns to the study table.
pub type GrowthHook<'a> =
    &'a (dyn Fn(&Model, &dyn PassageRunner) -> Result<BTreeMap<String, f64>, BoxError> + Sync);

/// The stored result of one case (`cases/<NNNN>.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CaseResult {
    /// The case's overrides (the study's `set`, then the case's own), to detect a changed
    /// study on resume.
    pub overrides: Vec<String>,
    /// blake3 hash of the case's resolved model (serde_json) and the program version: a
    /// changed base model is never taken for a finished case.
    pub model_hash: String,
    /// The indicators, one row per speed.
    pub rows: Vec<InitiationRow>,
    /// The growth hook's results (empty without growth).
    pub growth: BTreeMap<String, f64>,
}

/// The result of [`run_study`].
#[derive(Clone, Debug, PartialEq)]
pub struct StudyOutcome {
    /// The cases with their results, in order.
    pub cases: Vec<(Case, CaseResult)>,
    /// Cases computed by this run.
    pub computed: usize,
    /// Cases reused from an earlier run.
    pub reused: usize,
}

/// blake3 of the resolved model (serde_json) and the program version, hex.
pub fn model_hash(model: &Model) -> Result<String, StudiesError> {
    let json =
        serde_json::to_vec(model).map_err(|e| StudiesError::Invalid(format!("model: {e}")))?;
    let mut h = blake3::Hasher::new();
    h.update(env!("CARGO_PKG_VERSION").as_bytes());
    h.update(&json);
    Ok(h.finalize().to_hex().to_string())
}

fn case_file(out: &Path, i: usize) -> PathBuf {
    out.join("cases").join(format!("{i:04}.json"))
}

/// Runs a study: validates every case's model, then per case (in order; each case's runner
/// built by `factory`, which may itself be parallel) the passages at the study's speeds, the
/// initiation indicators and, when the study asks for it, `growth`; then writes the table,
/// the plots and the report into `out`. Finished cases are saved at once and reused by a
/// rerun. Failing cases are reported together after the others ran.
pub fn run_study(
    study: &Study,
    factory: RunnerFactory<'_>,
    growth: Option<GrowthHook<'_>>,
    out: &Path,
    progress: bool,
) -> Result<StudyOutcome, StudiesError> {
    if study.growth && growth.is_none() {
        return Err(key_error(
            &study.file,
            "growth",
            "the growth loop is not available to studies in this build; set growth = false",
        ));
    }
    let models = study.case_models()?;
    let bar = progress_bar(models.len() as u64, progress, "cases");
    let mut done = Vec::new();
    let mut failures = Vec::new();
    let (mut computed, mut reused) = (0, 0);
    for (case, model) in &models {
        let overrides = study.case_overrides(case);
        let hash = model_hash(model)?;
        let speeds = study
            .speeds_kmh
            .clone()
            .unwrap_or_else(|| vec![model.run.speed_kmh]);
        let path = case_file(out, case.index);
        let old = std::fs::read_to_string(&path)
            .ok()
            .and_then(|t| serde_json::from_str::<CaseResult>(&t).ok())
            .filter(|r| {
                r.overrides == overrides
                    && r.model_hash == hash
                    && r.rows
                        .iter()
                        .map(|x| x.speed_kmh)
                        .eq(speeds.iter().copied())
                    && (!study.growth || !r.growth.is_empty())
            });
        if let Some(r) = old {
            reused += 1;
            done.push((case.clone(), r));
            bar.inc(1);
            continue;
        }
        let run = || -> Result<CaseResult, String> {
            let runner = factory(model).map_err(|e| e.to_string())?;
            let mut rows = Vec::new();
            for &v in &speeds {
                let s = runner.run(v, None).map_err(|e| format!("{v} km/h: {e}"))?;
                rows.push(evaluate(&case.label(), &s, &study.criterion, study.peaks));
            }
            let g = match (study.growth, growth) {
                (true, Some(h)) => h(model, runner.as_ref()).map_err(|e| format!("growth: {e}"))?,
                _ => BTreeMap::new(),
            };
            Ok(CaseResult {
                overrides: overrides.clone(),
                model_hash: hash.clone(),
                rows,
                growth: g,
            })
        };
        match std::panic::catch_unwind(std::panic::AssertUnwindSafe(run)) {
            Ok(Ok(r)) => {
                let text = serde_json::to_string_pretty(&r).map_err(|e| StudiesError::BadFile {
                    path: path.clone(),
                    reason: e.to_string(),
                })?;
                crate::io::write_text(&path, &(text + "\n")).map_err(StudiesError::io(&path))?;
                computed += 1;
                done.push((case.clone(), r));
            }
            Ok(Err(e)) => failures.push(format!("case {} ({}): {e}", case.index, case.label())),
            Err(p) => failures.push(format!(
                "case {} ({}): panicked: {}",
                case.index,
                case.label(),
                panic_text(&*p)
            )),
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    if !failures.is_empty() {
        return Err(StudiesError::Passages { failures });
    }
    write_study(study, &done, out)?;
    Ok(StudyOutcome {
        cases: done,
        computed,
        reused,
    })
}

fn growth_keys(cases: &[(Case, CaseResult)]) -> Vec<String> {
    let mut k: Vec<String> = cases
        .iter()
        .flat_map(|(_, r)| r.growth.keys().cloned())
        .collect();
    k.sort();
    k.dedup();
    k
}

/// The indicators plotted against the parameters: (file suffix, label, value).
type Indicator = (
    &'static str,
    &'static str,
    fn(&InitiationRow) -> Option<f64>,
);

const INDICATORS: [Indicator; 5] = [
    ("relative_wear", "wear band RMS / mean (%)", |r| {
        r.relative_wear.map(|v| 100.0 * v)
    }),
    ("fl_band_rms", "F_L band RMS (N)", |r| Some(r.fl_band_rms_n)),
    ("fn_band_rms", "F_N band RMS (N)", |r| Some(r.fn_band_rms_n)),
    (
        "dominant_wavelength",
        "dominant wear wavelength (mm)",
        |r| r.wear_peaks.first().map(|c| c.wavelength_mm),
    ),
    ("dominant_frequency", "dominant wear frequency (Hz)", |r| {
        r.wear_peaks.first().map(|c| c.frequency_hz)
    }),
];

fn as_number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

fn write_study(
    study: &Study,
    cases: &[(Case, CaseResult)],
    out: &Path,
) -> Result<(), StudiesError> {
    let gk = growth_keys(cases);
    let mut header = vec!["case".to_string()];
    header.extend(study.parameters.iter().map(|p| p.key.clone()));
    header.extend(indicator_header(study.peaks));
    header.extend(gk.iter().cloned());
    let mut rows = Vec::new();
    let mut readable = Vec::new();
    for (c, r) in cases {
        for row in &r.rows {
            let mut cells = vec![c.index.to_string()];
            cells.extend(c.assignments.iter().map(|(_, v)| value_text(v)));
            cells.extend(indicator_cells(row, study.peaks));
            cells.extend(
                gk.iter()
                    .map(|k| r.growth.get(k).map(|v| v.to_string()).unwrap_or_default()),
            );
            rows.push(cells);
            let mut rc = vec![c.index.to_string()];
            rc.extend(readable_cells(row));
            rc.extend(gk.iter().map(|k| {
                r.growth
                    .get(k)
                    .map(|v| format!("{v:.4}"))
                    .unwrap_or_default()
            }));
            readable.push(rc);
        }
    }
    write_table_csv(&out.join("study.csv"), &header, &rows)?;

    // Plots: indicator vs the first parameter, one curve per (other parameters, speed).
    let first = &study.parameters[0];
    let numeric = first.values.iter().all(|v| as_number(v).is_some());
    let x_label = if numeric {
        first.key.clone()
    } else {
        format!("case ({} not numeric)", first.key)
    };
    let mut doc = Document::new(format!("Design study: {}", study.title));
    doc.paragraph(format!(
        "Study file {}; base model {}; {} case(s); parameters: {}.",
        study.file,
        study.base.display(),
        cases.len(),
        study
            .parameters
            .iter()
            .map(|p| p.key.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    ));
    if !study.set.is_empty() {
        doc.paragraph(format!("Overrides of every case: {}.", study.set.join(" ")));
    }
    doc.paragraph(criterion_text(&study.criterion));
    let mut extra: Vec<(String, String)> = gk.iter().map(|k| (k.clone(), k.clone())).collect();
    let mut plots = Vec::new();
    for (stem, label, f) in INDICATORS {
        plots.push((stem.to_string(), label.to_string(), Some(f), None));
    }
    for (k, l) in extra.drain(..) {
        plots.push((format!("growth_{k}"), l, None, Some(k)));
    }
    doc.heading(2, "Indicators vs parameters");
    for (stem, label, f, gkey) in plots {
        let mut series: BTreeMap<String, (Vec<f64>, Vec<f64>)> = BTreeMap::new();
        for (c, r) in cases {
            let x = if numeric {
                as_number(&c.assignments[0].1).unwrap_or(f64::NAN)
            } else {
                c.index as f64
            };
            let rest: Vec<String> = c.assignments[1..]
                .iter()
                .map(|(k, v)| format!("{}={}", k.rsplit('.').next().unwrap_or(k), value_text(v)))
                .collect();
            for row in &r.rows {
                let mut name = rest.join(", ");
                if r.rows.len() > 1 || study.speeds_kmh.as_ref().is_some_and(|s| s.len() > 1) {
                    if !name.is_empty() {
                        name.push_str(", ");
                    }
                    name.push_str(&format!("{} km/h", row.speed_kmh));
                }
                let y = match (f, &gkey) {
                    (Some(f), _) => f(row),
                    (None, Some(k)) => r.growth.get(k).copied(),
                    _ => None,
                };
                let e = series.entry(name).or_default();
                e.0.push(x);
                e.1.push(y.unwrap_or(f64::NAN));
            }
        }
        let s: Vec<Series> = series
            .into_iter()
            .map(|(n, (x, y))| Series::new(n, x, y))
            .collect();
        let file = format!("study_{stem}");
        line_plot(
            &out.join(&file),
            &format!("{label} vs {}", first.key),
            &x_label,
            &label,
            &s,
        )?;
        doc.image(format!("{label} vs {}", first.key), format!("{file}.png"));
    }
    doc.heading(2, "Cases");
    let mut rh: Vec<String> = vec!["case".into()];
    rh.extend(readable_header().iter().map(|s| s.to_string()));
    rh.extend(gk.iter().cloned());
    doc.table(&rh, readable);
    doc.write(&out.join("study"))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Study, StudiesError> {
        Study::parse_str(text, "s.toml", Path::new("/studies"), "s")
    }

    #[test]
    fn grid_expansion_is_the_cartesian_product_last_fastest() {
        let s = parse(
            r#"
            model = "builtin:dutch"
            [[parameter]]
            key = "fastening.vertical_stiffness"
            values = [1e9, 2e9]
            [[parameter]]
            key = "fastening.vertical_damping"
            range = { start = 15e3, stop = 75e3, step = 30e3 }
            "#,
        )
        .unwrap();
        assert_eq!(s.base, ModelSource::Builtin);
        let c = s.cases();
        assert_eq!(c.len(), 6);
        let o: Vec<String> = c.iter().map(|c| c.label()).collect();
        assert_eq!(
            o[0],
            "fastening.vertical_stiffness=1000000000.0, fastening.vertical_damping=15000.0"
        );
        assert_eq!(
            o[1],
            "fastening.vertical_stiffness=1000000000.0, fastening.vertical_damping=45000.0"
        );
        assert_eq!(
            o[5],
            "fastening.vertical_stiffness=2000000000.0, fastening.vertical_damping=75000.0"
        );
        assert!(c.iter().enumerate().all(|(i, c)| c.index == i));
    }

    #[test]
    fn zip_pairs_values_and_ranges_follow_the_speed_rule() {
        let s = parse(
            r#"
            model = "base.toml"
            combine = "zip"
            [[parameter]]
            key = "fastening.model"
            values = ["RPM1", "RPM3"]
            [[parameter]]
            key = "track.bays"
            values = [10, 12]
            "#,
        )
        .unwrap();
        assert_eq!(
            s.base,
            ModelSource::File(PathBuf::from("/studies/base.toml"))
        );
        let c = s.cases();
        assert_eq!(c.len(), 2);
        assert_eq!(
            c[1].overrides(),
            vec!["fastening.model=\"RPM3\"", "track.bays=12"]
        );
        let r = |a, b, c| {
            expand_range(&Range {
                start: a,
                stop: b,
                step: c,
            })
            .unwrap()
        };
        assert_eq!(r(0.1, 0.5, 0.1), vec![0.1, 0.2, 0.3, 0.4, 0.5]);
        assert_eq!(r(1.0, 2.5, 1.0), vec![1.0, 2.0]);
    }

    #[test]
    fn errors_name_the_file_and_the_key() {
        let head = "model = \"builtin:dutch\"\n";
        for (body, key) in [
            ("[[parameter]]\nkey = \"a.b\"\nvaluess = [1]\n", "parameter[0].valuess"),
            ("speed = 3\n[[parameter]]\nkey = \"a.b\"\nvalues = [1]\n", "`speed`"),
            ("[[parameter]]\nkey = \"a.b\"\nrange = { start = 1, stop = 0, step = 1 }\n", "parameter[0].range"),
            ("[[parameter]]\nkey = \"a.b\"\nrange = { start = 0, stop = 1, step = -1 }\n", "parameter[0].range"),
            ("[[parameter]]\nkey = \"a.b\"\nrange = { start = 0, stop = 1 }\n", "parameter[0].range"),
            ("[[parameter]]\nkey = \"a.b\"\nvalues = [1]\nrange = { start = 0, stop = 1, step = 1 }\n", "parameter[0]"),
            ("[[parameter]]\nkey = \"a.b\"\nvalues = []\n", "parameter[0].values"),
            ("[[parameter]]\nkey = \"a..b\"\nvalues = [1]\n", "parameter[0].key"),
            ("combine = \"zip\"\n[[parameter]]\nkey = \"a\"\nvalues = [1]\n[[parameter]]\nkey = \"b\"\nvalues = [1, 2]\n", "parameter[1]"),
            ("combine = \"diagonal\"\n[[parameter]]\nkey = \"a\"\nvalues = [1]\n", "combine"),
            ("speeds_kmh = [-1.0]\n[[parameter]]\nkey = \"a\"\nvalues = [1]\n", "speeds_kmh"),
            ("[criterion]\nmin_relative_wear = 0.1\nmax_deviation = 1\n[[parameter]]\nkey = \"a\"\nvalues = [1]\n", "criterion.max_deviation"),
            ("", "parameter"),
        ] {
            let e = parse(&format!("{head}{body}")).unwrap_err().to_string();
            assert!(e.starts_with("s.toml: key `") && e.contains(key), "{body}\n→ {e}");
        }
        let e = parse("model = 3\n").unwrap_err().to_string();
        assert!(e.contains("s.toml") && e.contains("model"), "{e}");
        let e = parse("model = [\n").unwrap_err().to_string();
        assert!(e.contains("s.toml") && e.contains("syntax"), "{e}");
    }

    #[test]
    fn case_models_apply_the_overrides_and_report_bad_keys_before_running() {
        let s = parse(
            r#"
            model = "builtin:dutch"
            set = ["fastening.model=\"RPM1\""]
            [[parameter]]
            key = "fastening.vertical_stiffness"
            values = [1.0e9, 2.0e9]
            "#,
        )
        .unwrap();
        let m = s.case_models().unwrap();
        assert_eq!(m[1].1.fastening.vertical_stiffness, 2.0e9);
        assert_eq!(m[0].1.fastening.model.name(), "RPM1");
        let bad = parse(
            "model = \"builtin:dutch\"\n[[parameter]]\nkey = \"fastening.vertical_stifness\"\nvalues = [1e9]\n",
        )
        .unwrap();
        let e = bad.case_models().unwrap_err().to_string();
        assert!(
            e.contains("s.toml: case 0") && e.contains("vertical_stifness"),
            "{e}"
        );
    }
}
