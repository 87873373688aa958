//! Analyses on top of the passage engine, written against the [`PassageRunner`] interface so
//! that their logic is tested with cheap stand-in runners (docs/theory.md §11):
//!
//! - [`speeds`]: the speed list of a sweep (`54.8:219:2` or `60,80,100`) and its shards
//!   (`--shard I/N`).
//! - [`sweep`]: passages over the speeds in parallel, one JSON file per finished speed
//!   (atomic, resumable), and the assembly of the frequency-selection maps, the dominant
//!   wavelength / frequency vs speed and the range ratios (docs/theory.md §2.3,
//!   "frequency selection"); [`sweep::merge`] joins shard directories into the unsharded result.
//! - [`coupled`]: the selected frequencies attributed to the coupled wheel–track modes, and
//!   the coupled-mode files.
//! - [`grow`]: the trial-amplitude growth's run, verdict check and output files, shared by
//!   `grow` and [`predict`].
//! - [`predict`]: the prediction product (smooth passage, growth, short sweep, report).
//! - [`initiation`]: the initiation table of several models on the smooth rail (band RMS, PSD
//!   peaks, a stated initiation criterion; docs/theory.md §11.4).
//! - [`study`]: design-study files (TOML): a base model, parameters varied as lists, ranges
//!   or a full grid through the model's `--set` machinery, the initiation indicators per case,
//!   one table and plots.
//!
//! [`PassageRunner`]: crate::dynamics::PassageRunner

pub mod compliance;
pub mod coupled;
pub mod grow;
pub mod initiation;
pub mod mesh;
pub mod modes;
pub mod nodal;
pub mod passage;
pub mod predict;
pub mod receptance;
pub mod roughness;
pub mod speeds;
pub mod study;
pub mod sweep;

use std::path::PathBuf;

/// Errors of the studies. Each names the input (file, key, speed, case) and what to change.
#[derive(Debug, thiserror::Error)]
pub enum StudiesError {
    /// A speed list or range (`--speeds`) that cannot be used.
    #[error("--speeds `{spec}`: {reason}")]
    Speeds {
        /// The argument as given.
        spec: String,
        /// What is wrong and what to change.
        reason: String,
    },
    /// A shard argument (`--shard I/N`) that cannot be used.
    #[error("--shard `{spec}`: {reason}")]
    Shard {
        /// The argument as given.
        spec: String,
        /// What is wrong and what to change.
        reason: String,
    },
    /// Passages that failed (the other speeds were computed and saved; rerun to resume).
    #[error("{} run(s) failed (the others are saved; fix and rerun to resume): {}", failures.len(), list_failures(failures))]
    Passages {
        /// One message per failed speed or case.
        failures: Vec<String>,
    },
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// A result file (sweep.json, a speed file) that is malformed or inconsistent.
    #[error("{path}: {reason}")]
    BadFile {
        /// The file.
        path: PathBuf,
        /// What is wrong and what to change.
        reason: String,
    },
    /// Map options that cannot be used.
    #[error("map options: {0}")]
    MapOptions(&'static str),
    /// The map options made beside a sweep's passages (mode lines, coupled modes) failed.
    #[error("the sweep's mode lines: {0}")]
    MapLines(#[source] BoxError),
    /// The modal cache key of a study case's basis could not be formed.
    #[error("modal cache key: {0}")]
    CacheKey(#[source] crate::eigen::basis::BasisError),
    /// No speeds were given to assemble into maps.
    #[error("no speeds to assemble")]
    NoSpeeds,
    /// A model or a record that could not be serialised as JSON.
    #[error("{what}: {source}")]
    Json {
        /// What was serialised.
        what: &'static str,
        /// The serde error.
        source: serde_json::Error,
    },
    /// A merge without shard directories.
    #[error("merge: no shard directories given")]
    NoShards,
    /// Shards of different models or program versions (their run keys differ).
    #[error("merge: {} and {} hold passages of different models or program versions ({file}); merge only shards of one sweep", first.display(), second.display())]
    ShardsOfDifferentModels {
        /// First directory.
        first: PathBuf,
        /// The other directory.
        second: PathBuf,
        /// The run-key file compared.
        file: &'static str,
    },
    /// A merge whose output directory is one of its shard directories, lies inside one, or
    /// contains one (it would rewrite or mix with its own input).
    #[error("merge: --out {} {relation} the shard directory {}; give an output directory apart from every shard", out.display(), shard.display())]
    OutputOverlapsShard {
        /// The output directory.
        out: PathBuf,
        /// The shard directory it overlaps.
        shard: PathBuf,
        /// `is`, `lies inside` or `contains`.
        relation: &'static str,
    },
    /// A merge input that is not the output directory of a sweep.
    #[error("merge: {} is not a sweep output directory (it has no {missing}); a sweep directory holds sweep.json and speeds/ with run.key, shard.json and one <speed>.json per speed, as written by `corrugation sweep --shard I/N --out DIR`", dir.display())]
    NotASweep {
        /// The directory given.
        dir: PathBuf,
        /// The file it lacks, e.g. `speeds/run.key`.
        missing: String,
    },
    /// A merge output directory that already holds passages of another model.
    #[error("merge: {} already holds passages of another model; use an empty --out", out.display())]
    OutputOfAnotherModel {
        /// The output directory.
        out: PathBuf,
    },
    /// Shards made with different map options.
    #[error("merge: {} and {} were made with different map options (grids or eigenfrequency lines); rerun the shards with the same model and options", first.display(), second.display())]
    ShardsWithDifferentMaps {
        /// First directory.
        first: PathBuf,
        /// The other directory.
        second: PathBuf,
    },
    /// One speed in two shards with different results.
    #[error("merge: speed {speed_kmh} km/h is in {} and {} with different results; remove one", first.display(), second.display())]
    SpeedConflict {
        /// The speed (km/h).
        speed_kmh: f64,
        /// First directory.
        first: PathBuf,
        /// The other directory.
        second: PathBuf,
    },
    /// Shards of a sweep are missing from a merge.
    #[error("merge: incomplete sweep: shard(s) {missing:?} of {count} not given; pass every shard directory of the sweep")]
    ShardsMissing {
        /// Shard count of the sweep.
        count: usize,
        /// Indices not given.
        missing: Vec<usize>,
    },
    /// The same shard given twice to a merge.
    #[error("merge: shard {index}/{count} given twice ({} and {}); pass each shard once", first.display(), second.display())]
    ShardTwice {
        /// Shard index.
        index: usize,
        /// Shard count.
        count: usize,
        /// First directory.
        first: PathBuf,
        /// Second directory.
        second: PathBuf,
    },
    /// Shards of different sweeps (speeds or shard count differ).
    #[error("merge: {} and {} are shards of different sweeps (--speeds or the shard count N differ); merge only the shards of one sweep", first.display(), second.display())]
    ShardsOfDifferentSweeps {
        /// First directory.
        first: PathBuf,
        /// The other directory.
        second: PathBuf,
    },
    /// A shard directory whose sweep is not finished or has other speeds than its shard.
    #[error("merge: {} holds {have} speed(s) but shard {index}/{count} of its sweep has {want}; rerun `sweep --shard {index}/{count}` into it", dir.display())]
    ShardUnfinished {
        /// The directory.
        dir: PathBuf,
        /// Shard index.
        index: usize,
        /// Shard count.
        count: usize,
        /// Speeds in its sweep.json.
        have: usize,
        /// Speeds of the shard.
        want: usize,
    },
    /// A study file key that is unknown, missing, of the wrong type or out of range.
    #[error("{file}: key `{key}`: {message}")]
    StudyKey {
        /// The study file.
        file: String,
        /// The dotted key (`parameter[1].range.step`).
        key: String,
        /// What is wrong.
        message: String,
    },
    /// A study case whose model cannot be built (bad parameter value or key).
    #[error("{file}: case {case}: {message}")]
    StudyCase {
        /// The study file.
        file: String,
        /// The case (its overrides).
        case: String,
        /// The model error.
        message: String,
    },
    /// A plot or document could not be written.
    #[error(transparent)]
    Report(#[from] crate::report::ReportError),
    /// The coupled wheel–track modes could not be computed.
    #[error("coupled wheel–track modes: {0}")]
    Coupled(#[from] crate::dynamics::DynamicsError),
    /// A passage's record could not be analysed.
    #[error(transparent)]
    Passage(#[from] crate::passage::PassageError),
    /// A command argument that cannot be used.
    #[error("{flag} {given}: {reason}")]
    Argument {
        /// The flag, e.g. `--elastic`.
        flag: &'static str,
        /// The value as given.
        given: String,
        /// What is wrong and what is allowed.
        reason: String,
    },
    /// A list argument with a value given twice.
    #[error(transparent)]
    Repeated(#[from] crate::lists::RepeatedValue),
    /// A variant of a multi-model study (its model, its structure or its solve) failed.
    #[error("the model of --variants {name}: {source}")]
    Variant {
        /// The variant's name.
        name: String,
        /// The cause.
        source: BoxError,
    },
    /// The growth-rate spectrum could not be computed.
    #[error("growth-rate spectrum: {0}")]
    RateSpectrum(#[source] crate::dynamics::DynamicsError),
    /// The trial-amplitude or iterative growth failed.
    #[error(transparent)]
    Growth(#[from] crate::growth::procedure::ProcedureError),
    /// A passage recording a rail-top point, or its nodal spectrum, failed.
    #[error("the nodal spectrum at {x_m} m: {source}")]
    Nodal {
        /// The point (m along the rail).
        x_m: f64,
        /// The cause.
        source: BoxError,
    },
    /// A model that cannot be used as given (e.g. a position off its track).
    #[error(transparent)]
    Model(#[from] crate::model::ModelError),
    /// A numeric argument outside its range.
    #[error("{name} {value}: out of range, allowed {lo} to {hi} {unit}")]
    OutOfRange {
        /// The argument, e.g. `--fmax`.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The smallest value allowed.
        lo: f64,
        /// The largest value allowed.
        hi: f64,
        /// The unit.
        unit: &'static str,
    },
    /// A field could not be mapped between free and all DOFs (an inconsistent basis).
    #[error("FE: {0}")]
    Fe(#[from] crate::fe::FeError),
}

/// The first three failures, and how many more.
fn list_failures(f: &[String]) -> String {
    let mut s = f.iter().take(3).cloned().collect::<Vec<_>>().join("; ");
    if f.len() > 3 {
        s.push_str(&format!("; … and {} more", f.len() - 3));
    }
    s
}

impl StudiesError {
    pub(crate) fn io(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> Self + use<> {
        let path = path.to_path_buf();
        move |source| StudiesError::Io { path, source }
    }
}

/// Error type of runner factories and hooks given by the caller (the CLI's engine).
pub type BoxError = Box<dyn std::error::Error + Send + Sync>;

/// The message of a caught panic (a passage run under `catch_unwind` in a sweep or an
/// initiation table), or "unknown panic" when its payload is not text.
pub(crate) fn panic_text(p: &(dyn std::any::Any + Send)) -> String {
    p.downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into())
}
