//! Running a study's cases (resumable) and saving each case as it finishes.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::parse::key_error;
use super::report::write_study;
use super::{Case, Study};
use crate::dynamics::PassageRunner;
use crate::model::Model;
use crate::progress::{Counter, Progress};
use crate::studies::initiation::{evaluate, InitiationRow};
use crate::studies::sweep::panic_text;
use crate::studies::{BoxError, StudiesError};

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

/// blake3 of the program version and the model's whole identity
/// ([`crate::model::identity::model_identity`], [`IdentityScope::Run`](crate::model::identity::IdentityScope::Run)), hex.
pub fn model_hash(model: &Model) -> Result<String, StudiesError> {
    let json =
        crate::model::identity::model_identity(model, crate::model::identity::IdentityScope::Run)
            .map_err(|source| StudiesError::Json {
            what: "model",
            source,
        })?;
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
    progress: &dyn Progress,
) -> Result<StudyOutcome, StudiesError> {
    if study.growth && growth.is_none() {
        return Err(key_error(
            &study.file,
            "growth",
            "the growth loop is not available to studies in this build; set growth = false",
        ));
    }
    let models = study.case_models()?;
    let bar = Counter::start(progress, "study cases", models.len() as u64);
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
            bar.inc();
            continue;
        }
        let run = || -> Result<CaseResult, String> {
            let runner = factory(model).map_err(|e| e.to_string())?;
            let mut rows = Vec::new();
            for &v in &speeds {
                let s = runner
                    .run(crate::units::Speed::from_kmh(v), None)
                    .map_err(|e| format!("{v} km/h: {e}"))?;
                let criterion = study.criterion.for_model(model);
                rows.push(evaluate(&case.label(), &s, &criterion, study.peaks));
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
        bar.inc();
    }
    bar.finish();
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
