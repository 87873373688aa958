//! Running and resuming the passages of a sweep: one summary file per finished speed.

use crate::progress::{Counter, Progress};
use std::io::Write;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::{assemble, MapOptions, PassageStats, StudiesError, SweepOutcome};
use crate::dynamics::{PassageRunner, PassageSummary};
use crate::studies::panic_text;
use crate::studies::speeds::speed_file_stem;
use crate::studies::BoxError;

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

pub(super) fn same_speed(a: f64, b: f64) -> bool {
    speed_file_stem(a) == speed_file_stem(b)
}

/// Writes a summary as pretty JSON, atomically.
pub(crate) fn write_summary(path: &Path, s: &PassageSummary) -> Result<(), StudiesError> {
    crate::io::write_atomic(path, |w| {
        serde_json::to_writer_pretty(&mut *w, s).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })
    .map_err(StudiesError::io(path))
}

/// Runs the passages of the speeds that have no complete file in `dir/speeds` yet, in
/// parallel (rayon), each saved the moment it finishes; each finished passage is reported to
/// `progress` (stage "sweep passages (speeds)"). A passage that fails or panics is reported in [`StudiesError::Passages`]
/// after all others have finished and been saved. A speed not yet started when
/// `progress` is [cancelled](Progress::cancelled) is not run (a failure "cancelled by the
/// caller"); a rerun resumes it.
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
            if progress.cancelled() {
                return Err(format!("{v} km/h: {}", crate::progress::Cancelled));
            }
            let out = catch_unwind(AssertUnwindSafe(|| {
                runner.run(crate::units::Speed::from_kmh(v), None)
            }));
            let r = match out {
                Ok(Ok(s)) if same_speed(s.speed_kmh, v) => {
                    if let Some(g) = &s.contact_grid_widened {
                        progress.warn(&format!(
                            "{v} km/h: the contact patch reached the boundary of the model's contact grid; the passage was rerun on {g}"
                        ));
                    }
                    write_summary(&speed_file(dir, v), &s)
                        .map(|_| v)
                        .map_err(|e| format!("{v} km/h: {e}"))
                }
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

/// File (in `DIR/speeds`) naming what produced the speed files: see [`check_run_key`].
pub(crate) const RUN_KEY_FILE: &str = "run.key";

/// Guards resume against mixing models: the first run into `dir` writes `run_key` (e.g. a
/// hash of the resolved model and the program version) to `dir/speeds/run.key`; a later run
/// with another key is refused, so speed files of another model are never reused.
pub(crate) fn check_run_key(dir: &Path, run_key: &str) -> Result<(), StudiesError> {
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
/// `run_key` identifies the model (see `check_run_key`).
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

/// [`sweep`] with the map options made by `options` beside the passages: `options` (e.g.
/// the coupled wheel–track modes, several seconds of serial work) runs on one thread of
/// the rayon pool while the passages start on the others, and the maps are assembled when
/// both are done. The options enter only the assembly, so the outputs are those of
/// [`sweep`] with the same options. When `options` fails, the passages still finish and
/// are saved (a rerun resumes) and its error is returned.
pub fn sweep_beside(
    runner: &dyn PassageRunner,
    speeds_kmh: &[f64],
    dir: &Path,
    options: impl FnOnce() -> Result<MapOptions, BoxError> + Send,
    run_key: &str,
    progress: &dyn Progress,
) -> Result<SweepOutcome, StudiesError> {
    let (opts, stats) = rayon::join(options, || {
        run_passages(runner, speeds_kmh, dir, run_key, progress)
    });
    let opts = opts.map_err(StudiesError::MapLines)?;
    opts.check()?;
    let stats = stats?;
    let (record, maps) = assemble(dir, speeds_kmh, &opts)?;
    Ok(SweepOutcome {
        record,
        maps,
        stats,
    })
}
