//! Reading and checking a study file, expanding its cases and their models.

use std::path::Path;

use serde::Deserialize;

use super::StudyCriterion;
use super::{Case, Combine, Parameter, Range, Study, StudyBasis, MAX_CASES};

/// Largest `concurrent_cases` of a study file (each concurrent case holds its own basis and
/// engine in memory).
const MAX_CONCURRENT_CASES: usize = 4;
use crate::eigen::substructure::SubstructureOptions;
use crate::model::{load_model_shown, Assignment, Model, ModelSource};
use crate::studies::StudiesError;

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
    criterion: Option<StudyCriterion>,
    #[serde(default)]
    basis: StudyBasis,
    #[serde(default)]
    substructure: Option<SubstructureOptions>,
    #[serde(default)]
    concurrent_cases: Option<usize>,
    parameter: Vec<ParamFile>,
}

pub(super) fn key_error(
    file: &str,
    key: impl Into<String>,
    message: impl Into<String>,
) -> StudiesError {
    StudiesError::StudyKey {
        file: file.into(),
        key: key.into(),
        message: message.into(),
    }
}

/// `start + k·step` for `k = 0 … ⌊(stop − start)/step + 10⁻⁹⌋`.
pub(crate) fn expand_range(r: &Range) -> Result<Vec<f64>, String> {
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

/// The study file's TOML read into its schema; a syntax error or an unknown or mistyped key
/// names the key.
fn read_study_file(text: &str, file: &str) -> Result<StudyFile, StudiesError> {
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
    })
}

/// The varied parameters of `raw`: at least one, each a dotted model key varied once, with
/// exactly one of a non-empty `values` list and a `range`.
fn parameters(raw: &StudyFile, file: &str) -> Result<Vec<Parameter>, StudiesError> {
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
    Ok(parameters)
}

/// Equal lengths for `combine = "zip"`, and at most [`MAX_CASES`] cases; returns the cases.
fn check_case_count(
    parameters: &[Parameter],
    combine: Combine,
    file: &str,
) -> Result<f64, StudiesError> {
    if combine == Combine::Grid {
        for (i, p) in parameters.iter().enumerate() {
            let key = format!("parameter[{i}].values");
            crate::lists::check_no_repeats_by_key(&key, "", &p.values, |v| v.to_string())
                .map_err(|e| {
                    key_error(
                        file,
                        &key,
                        format!(
                            "{} is given twice (the grid would run its cases twice); give each value once",
                            e.value
                        ),
                    )
                })?;
        }
    }
    if combine == Combine::Zip {
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
        let cases: Vec<String> = (0..n)
            .map(|k| {
                let set: Vec<String> = parameters
                    .iter()
                    .map(|p| format!("{} = {}", p.key, p.values[k]))
                    .collect();
                set.join(", ")
            })
            .collect();
        crate::lists::check_no_repeats_by_key("parameter", "", &cases, |c| c.clone()).map_err(
            |e| {
                key_error(
                    file,
                    "parameter",
                    format!(
                        "the case `{}` is given twice (combine = \"zip\"); give each case once",
                        e.value
                    ),
                )
            },
        )?;
    }
    let n_cases: f64 = match combine {
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
    Ok(n_cases)
}

/// The study's passages, cases × speeds, at most
/// [`MAX_SPEEDS`](crate::studies::speeds::MAX_SPEEDS) (a sweep's most).
fn check_passage_count(n_cases: f64, speeds: usize, file: &str) -> Result<(), StudiesError> {
    let max = crate::studies::speeds::MAX_SPEEDS;
    if n_cases * speeds as f64 > max as f64 {
        return Err(key_error(
            file,
            "speeds_kmh",
            format!(
                "{n_cases} cases × {speeds} speeds = {} passages; at most {max} in one study (fewer speeds or parameter values)",
                n_cases * speeds as f64
            ),
        ));
    }
    Ok(())
}

/// `speeds_kmh`: not empty, every speed within the range of `run.speed_kmh`.
fn check_speeds(v: &[f64], file: &str) -> Result<(), StudiesError> {
    if v.is_empty() {
        return Err(key_error(file, "speeds_kmh", "is empty"));
    }
    crate::studies::speeds::check_speed_count(v.len() as f64)
        .map_err(|r| key_error(file, "speeds_kmh", r))?;
    if let Some(s) = v.iter().find(|s| {
        !(s.is_finite()
            && **s >= crate::studies::speeds::MIN_SPEED_KMH
            && **s <= crate::studies::speeds::MAX_SPEED_KMH)
    }) {
        return Err(key_error(
            file,
            "speeds_kmh",
            format!(
                "speed {s} km/h out of range, allowed {} to {} km/h (as run.speed_kmh)",
                crate::studies::speeds::MIN_SPEED_KMH,
                crate::studies::speeds::MAX_SPEED_KMH
            ),
        ));
    }
    crate::lists::check_no_repeats_by_key("speeds_kmh", "km/h", v, |s| {
        crate::studies::speeds::speed_file_stem(*s)
    })
    .map_err(|e| key_error(file, "speeds_kmh", e.to_string()))?;
    Ok(())
}

/// The criterion's limits: each ≥ 0 and finite when given.
fn check_criterion(criterion: &StudyCriterion, file: &str) -> Result<(), StudiesError> {
    let bad = |v: Option<f64>| v.is_some_and(|v| !(v >= 0.0 && v.is_finite()));
    if bad(criterion.min_relative_wear) {
        return Err(key_error(
            file,
            "criterion.min_relative_wear",
            "must be ≥ 0 and finite",
        ));
    }
    if bad(criterion.max_wavelength_deviation) {
        return Err(key_error(
            file,
            "criterion.max_wavelength_deviation",
            "must be ≥ 0 and finite",
        ));
    }
    Ok(())
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
    ///
    /// Phases: the TOML and its schema (`read_study_file`), the parameters
    /// (`parameters`) and the number of cases they make (`check_case_count`), the speeds
    /// (`check_speeds`), the criterion and the peaks (`check_criterion`), the
    /// substructure options, the concurrency.
    pub fn parse_str(
        text: &str,
        file: &str,
        dir: &Path,
        default_title: &str,
    ) -> Result<Self, StudiesError> {
        let raw = read_study_file(text, file)?;
        let base = if raw.model == "builtin:dutch" {
            ModelSource::Builtin
        } else {
            ModelSource::File(dir.join(&raw.model))
        };
        let set = raw
            .set
            .iter()
            .map(|a| match Assignment::parse(a) {
                Ok(parsed) => Ok((parsed, a.clone())),
                Err(e) => Err(key_error(file, "set", e.to_string())),
            })
            .collect::<Result<Vec<_>, _>>()?;
        let parameters = parameters(&raw, file)?;
        let n_cases = check_case_count(&parameters, raw.combine, file)?;
        if let Some(v) = &raw.speeds_kmh {
            check_speeds(v, file)?;
            check_passage_count(n_cases, v.len(), file)?;
        }
        let criterion = raw.criterion.unwrap_or_default();
        check_criterion(&criterion, file)?;
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
        let concurrent_cases = raw.concurrent_cases.unwrap_or(match raw.basis {
            StudyBasis::Substructured => 2,
            StudyBasis::Full => 1,
        });
        if !(1..=MAX_CONCURRENT_CASES).contains(&concurrent_cases) {
            return Err(key_error(
                file,
                "concurrent_cases",
                format!("{concurrent_cases}: allowed 1 … {MAX_CONCURRENT_CASES}"),
            ));
        }
        Ok(Study {
            file: file.to_string(),
            title: raw.title.unwrap_or_else(|| default_title.to_string()),
            base,
            set,
            speeds_kmh: raw.speeds_kmh,
            combine: raw.combine,
            growth: raw.growth,
            peaks,
            criterion,
            basis: raw.basis,
            substructure,
            concurrent_cases,
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

    /// The overrides of a case as text, recorded in its case file: the study's `set` as the
    /// file gives it, then the case's own.
    pub(crate) fn case_overrides(&self, case: &Case) -> Vec<String> {
        let mut o: Vec<String> = self.set.iter().map(|(_, t)| t.clone()).collect();
        o.extend(case.overrides());
        o
    }

    /// The assignments of a case with their text for messages: the study's `set` (as the file
    /// writes it), then the case's own parameters' values (`key=value`).
    pub(crate) fn case_assignments(&self, case: &Case) -> Vec<(Assignment, String)> {
        let mut a = self.set.clone();
        a.extend(case.assignments.iter().map(|(key, value)| {
            let a = Assignment {
                key: key.clone(),
                value: value.clone(),
            };
            let shown = a.to_string();
            (a, shown)
        }));
        a
    }

    /// The cases of `shard` with their models. Every case's model is built and checked, so
    /// a bad value anywhere in the study stops every shard before any work.
    pub fn case_models_of(
        &self,
        shard: crate::studies::speeds::Shard,
    ) -> Result<Vec<(Case, Model)>, StudiesError> {
        Ok(self
            .case_models()?
            .into_iter()
            .enumerate()
            .filter(|(i, _)| shard.holds(*i))
            .map(|(_, cm)| cm)
            .collect())
    }

    /// Builds and validates every case's model (nothing runs until all are valid).
    pub fn case_models(&self) -> Result<Vec<(Case, Model)>, StudiesError> {
        self.cases()
            .into_iter()
            .map(|c| {
                let m = load_model_shown(&self.base, &self.case_assignments(&c)).map_err(|e| {
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
