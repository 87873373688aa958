//! The standing robustness suite: hostile and odd input to every command, run through the real
//! binary, each case with the outcome it must have. A bad value must be refused with one clear
//! error line that names the key or flag (exit code not 0, no panic, abort or hang); a valid
//! one, however odd (paths with spaces and non-ASCII letters), must run. The cases:
//!
//! - `model key`: every key of the model (read from `corrugation model --json`, plus the keys
//!   written only away from their defaults) with NaN, ±inf, ±1e30, wrong types and, per kind,
//!   zero, negative and huge values; unknown keys and sections;
//! - `flag`: every numeric and list flag of every command with NaN, ±inf, 1e30, negative, zero,
//!   tiny, text, empty and duplicate values (as `--flag value`, so negative numbers go through
//!   the parser to the range check);
//! - `input file`: hostile model TOML (empty, binary, syntax, unknown keys, `extends` cycles and
//!   missing files, directories), rail-profile CSV and study TOML; paths with spaces and
//!   non-ASCII letters;
//! - `cache`, `merge`: a cache that is not a cache, a file for a directory, merges of what is
//!   not a sweep;
//! - `campaign`: the failures an earlier fault and bad-input campaign found, one case each.
//!
//! The verdicts are counted by class and printed as a table (`cargo test --profile test-opt
//! --test robustness -- --nocapture`; the table is kept in validation/robustness.md). The
//! stateful cases (a killed sweep resumed, two processes solving one cache entry, a corrupted
//! entry) are the other tests of this file (`state.rs`). About a minute on 2 cores once the
//! small model's modes are cached.

mod cases;
#[path = "../common/mod.rs"]
mod common;
mod runner;
mod state;

/// Every case of [`cases::all`] passes; the table of verdicts is printed.
#[test]
fn hostile_input_is_refused_clearly_and_odd_valid_input_runs() {
    let root = tempfile::tempdir().expect("scratch directory");
    let cases = cases::all(root.path());
    let n = cases.len();
    assert!(n >= 600, "the suite has only {n} cases");
    let t0 = std::time::Instant::now();
    let report = runner::run_all(root.path(), cases);
    println!(
        "{} cases in {:.1} s (slowest {:.1} s: {})\n\n{}",
        report.cases,
        t0.elapsed().as_secs_f64(),
        report.slowest.0,
        report.slowest.1,
        report.table()
    );
    for (class, name, verdict, detail) in &report.failures {
        println!("FAILED [{class}] {verdict:?}: corrugation {name}\n    {detail}");
    }
    assert!(
        report.failures.is_empty(),
        "{} of {n} cases failed (listed above)",
        report.failures.len()
    );
}
