//! Running a study's cases (resumable) and saving each case as it finishes.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::parse::key_error;
use super::report::write_study;
use super::{Case, CaseResult, Study};
use crate::dynamics::PassageRunner;
use crate::model::Model;
use crate::progress::{Counter, Progress};
use crate::studies::initiation::evaluate;
use crate::studies::panic_text;
use crate::studies::speeds::Shard;
use crate::studies::{BoxError, StudiesError};

/// Builds the passage runner `R` of a model (the CLI passes its engine's prepared model).
pub(crate) type RunnerFactory<'a, R> = &'a (dyn Fn(&Model) -> Result<R, BoxError> + Sync);

/// The growth loop of one case, handed the case's runner as the factory built it (so a
/// prepared model's loaded modal bases are reused): named scalar results (e.g.
/// `limiting_amplitude_um`), added as columns to the study table.
pub(crate) type GrowthHook<'a, R> =
    &'a (dyn Fn(&Model, &R) -> Result<BTreeMap<String, f64>, BoxError> + Sync);

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
pub(crate) fn model_hash(model: &Model) -> Result<String, StudiesError> {
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

/// What became of one case in [`run_study`].
enum CaseOutcome {
    /// Read back from an earlier run's case file.
    Reused(CaseResult),
    /// Computed by this run (and saved).
    Computed(CaseResult),
    /// Failed: the message names the case.
    Failed(String),
}

/// The parts of [`run_study`] every case reads.
struct CaseContext<'a, R> {
    study: &'a Study,
    factory: RunnerFactory<'a, R>,
    growth: Option<GrowthHook<'a, R>>,
    out: &'a Path,
}

impl<R: PassageRunner> CaseContext<'_, R> {
    /// The case's result: reused from its case file when that matches, else computed and
    /// saved (a failure or a panic becomes [`CaseOutcome::Failed`]).
    fn run(&self, case: &Case, model: &Model) -> Result<CaseOutcome, StudiesError> {
        let study = self.study;
        let overrides = study.case_overrides(case);
        let hash = model_hash(model)?;
        let speeds = study
            .speeds_kmh
            .clone()
            .unwrap_or_else(|| vec![model.run.speed_kmh]);
        let path = case_file(self.out, case.index);
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
            return Ok(CaseOutcome::Reused(r));
        }
        let run = || -> Result<CaseResult, String> {
            let runner = (self.factory)(model).map_err(|e| e.to_string())?;
            let mut rows = Vec::new();
            for &v in &speeds {
                let s = runner
                    .run(crate::units::Speed::from_kmh(v), None)
                    .map_err(|e| format!("{v} km/h: {e}"))?;
                let criterion = study.criterion.for_model(model);
                rows.push(evaluate(&case.label(), &s, &criterion, study.peaks));
            }
            let g = match (study.growth, self.growth) {
                (true, Some(h)) => h(model, &runner).map_err(|e| format!("growth: {e}"))?,
                _ => BTreeMap::new(),
            };
            Ok(CaseResult {
                overrides: overrides.clone(),
                model_hash: hash.clone(),
                rows,
                growth: g,
            })
        };
        Ok(
            match std::panic::catch_unwind(std::panic::AssertUnwindSafe(run)) {
                Ok(Ok(r)) => {
                    let text =
                        serde_json::to_string_pretty(&r).map_err(|e| StudiesError::BadFile {
                            path: path.clone(),
                            reason: e.to_string(),
                        })?;
                    crate::io::write_text(&path, &(text + "\n"))
                        .map_err(StudiesError::io(&path))?;
                    CaseOutcome::Computed(r)
                }
                Ok(Err(e)) => {
                    CaseOutcome::Failed(format!("case {} ({}): {e}", case.index, case.label()))
                }
                Err(p) => CaseOutcome::Failed(format!(
                    "case {} ({}): panicked: {}",
                    case.index,
                    case.label(),
                    panic_text(&*p)
                )),
            },
        )
    }
}

/// Runs `f(i)` for `i = 0 … n − 1` and returns the results in index order: `f(0)` alone
/// first (it fills the caches and memos the later cases share), then the rest on up to
/// `workers` threads, each taking the next index when it is free. The results do not depend
/// on `workers` when each `f(i)` does not depend on the others' timing. Plain scoped threads
/// rather than a rayon pool: a case's own parallel work would let rayon's work stealing start
/// further cases while a thread waits inside it, so the number of cases in memory at once
/// (a few GB each) would not be bounded by `workers`.
fn in_order<T: Send>(n: usize, workers: usize, f: &(dyn Fn(usize) -> T + Sync)) -> Vec<T> {
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::Mutex;
    if n == 0 {
        return Vec::new();
    }
    let first = f(0);
    let workers = workers.min(n - 1);
    if workers <= 1 {
        return std::iter::once(first).chain((1..n).map(f)).collect();
    }
    let next = AtomicUsize::new(1);
    let slots: Mutex<Vec<Option<T>>> = Mutex::new((0..n).map(|_| None).collect());
    std::thread::scope(|s| {
        for _ in 0..workers {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::SeqCst);
                if i >= n {
                    break;
                }
                let r = f(i);
                slots.lock().unwrap_or_else(|p| p.into_inner())[i] = Some(r);
            });
        }
    });
    let mut slots = slots.into_inner().unwrap_or_else(|p| p.into_inner());
    slots[0] = Some(first);
    slots
        .into_iter()
        .map(|r| r.expect("every index was run"))
        .collect()
}

/// Runs a study: validates every case's model, then per case (each case's runner built by
/// `factory`, which may itself be parallel) the passages at the study's speeds, the
/// initiation indicators and, when the study asks for it, `growth`; then writes the table,
/// the plots and the report into `out`. The first case runs alone; the others run up to
/// [`Study::concurrent_cases`] at a time, and the table, the report and the returned cases
/// are in case order whatever the concurrency (each case's numbers are its own: the same
/// with one case at a time). Finished cases are saved at once and reused by a rerun.
/// Failing cases are reported together after the others ran; a case not yet started when
/// `progress` is [cancelled](Progress::cancelled) is not run (a failure "cancelled by the
/// caller"; a rerun resumes it).
///
/// With a `shard` other than [`Shard::ALL`] only that shard's cases run (every N-th from the
/// I-th, in case order) and their case files are saved, but no table, plot or report is
/// written: the shards of a cluster job write into one shared `out`, and a last run of the
/// whole study there reuses every case and writes the outputs (the same files as one run).
pub fn run_study<R: PassageRunner>(
    study: &Study,
    factory: RunnerFactory<'_, R>,
    growth: Option<GrowthHook<'_, R>>,
    out: &Path,
    shard: Shard,
    progress: &dyn Progress,
) -> Result<StudyOutcome, StudiesError> {
    if study.growth && growth.is_none() {
        return Err(key_error(
            &study.file,
            "growth",
            "the growth loop is not available to studies in this build; set growth = false",
        ));
    }
    let models = study.case_models_of(shard)?;
    let bar = Counter::start(progress, "study cases", models.len() as u64);
    let ctx = CaseContext {
        study,
        factory,
        growth,
        out,
    };
    let outcomes = in_order(models.len(), study.concurrent_cases, &|i| {
        let (case, model) = &models[i];
        if progress.cancelled() {
            bar.inc();
            return Ok(CaseOutcome::Failed(format!(
                "case {} ({}): {}",
                case.index,
                case.label(),
                crate::progress::Cancelled
            )));
        }
        let r = ctx.run(case, model);
        // a case that computed modal bases showed their stages on the same sink
        bar.resume();
        bar.inc();
        r
    });
    bar.finish();
    let mut done = Vec::new();
    let mut failures = Vec::new();
    let (mut computed, mut reused) = (0, 0);
    for ((case, _), o) in models.iter().zip(outcomes) {
        match o? {
            CaseOutcome::Reused(r) => {
                reused += 1;
                done.push((case.clone(), r));
            }
            CaseOutcome::Computed(r) => {
                computed += 1;
                done.push((case.clone(), r));
            }
            CaseOutcome::Failed(e) => failures.push(e),
        }
    }
    if !failures.is_empty() {
        return Err(StudiesError::Passages { failures });
    }
    if shard.is_all() {
        write_study(study, &done, out)?;
    }
    Ok(StudyOutcome {
        cases: done,
        computed,
        reused,
    })
}

#[cfg(test)]
mod tests {
    use super::in_order;
    use std::sync::Mutex;

    /// Results come back in index order for any worker count, the first index runs alone
    /// before any other starts, and every index runs once.
    #[test]
    fn in_order_returns_index_order_with_the_first_alone() {
        for workers in [1, 2, 3, 8] {
            let log = Mutex::new(Vec::new());
            let f = |i: usize| {
                log.lock().unwrap().push(("start", i));
                // uneven work so that later indices may finish first
                std::thread::sleep(std::time::Duration::from_millis(((7 - i) % 4) as u64 * 3));
                log.lock().unwrap().push(("end", i));
                i * i
            };
            let r = in_order(7, workers, &f);
            assert_eq!(r, (0..7).map(|i| i * i).collect::<Vec<_>>(), "{workers}");
            let log = log.into_inner().unwrap();
            assert_eq!(&log[..2], &[("start", 0), ("end", 0)], "{workers}");
            let mut started: Vec<usize> =
                log.iter().filter(|e| e.0 == "start").map(|e| e.1).collect();
            started.sort_unstable();
            assert_eq!(started, (0..7).collect::<Vec<_>>());
        }
        assert!(in_order(0, 2, &|i| i).is_empty());
        assert_eq!(in_order(1, 2, &|i| i + 1), vec![1]);
    }
}
