//! `corrugation cache` removes only the cache's own entries, refuses a directory that is not
//! a cache, and no command writes its `--out` into the cache directory. These run the real
//! binary.

mod common;

use std::fs;
use std::path::{Path, PathBuf};

use common::{is_one_line_error, run};
use corrugation::eigen::cache::{CacheKey, CacheMeta, ModalCache, TAG_FILE};
use faer::Mat;

/// Stores a small basis under `label` in `cache`; returns its key (hex).
fn store(cache: &ModalCache, label: &str) -> String {
    let key = CacheKey::new().str("cli-cache-test", label);
    let f = vec![1.0, 2.0];
    let m = Mat::<f64>::from_fn(4, 2, |i, j| (i + j) as f64);
    let meta = CacheMeta {
        key: String::new(),
        crate_version: String::new(),
        n_dofs: 0,
        n_modes: 0,
        f_min_hz: 0.0,
        f_max_hz: 100.0,
        sturm_count: 2,
        relative_residuals: vec![1e-12; 2],
        m_orthonormality_error: 1e-14,
        frequencies_blake3: String::new(),
        modes_blake3: String::new(),
        classification: serde_json::json!({"kinds": ["bending", "bending"]}),
    };
    cache.store(&key, &f, &m, meta).unwrap();
    key.hex()
}

/// A user's folders and files: a project's sources, an output folder with results, notes.
/// Returns the files, to check they survive.
fn user_files(d: &Path) -> Vec<PathBuf> {
    let files = [
        d.join("src/main.rs"),
        d.join("results/run1/forces.csv"),
        d.join("results/summary.json"),
        d.join("notes.txt"),
    ];
    for f in &files {
        fs::create_dir_all(f.parent().unwrap()).unwrap();
        fs::write(f, b"the user's work").unwrap();
    }
    files.to_vec()
}

fn assert_survive(files: &[PathBuf]) {
    for f in files {
        assert_eq!(
            fs::read(f).ok().as_deref(),
            Some(&b"the user's work"[..]),
            "{} was removed or changed",
            f.display()
        );
    }
}

const PRUNE_ALL: [&str; 4] = ["--max-size-gb", "0", "--max-idle-days", "0"];

/// A mistyped `--cache` (a project folder with subfolders, no tag) is refused with the
/// directory and the reason, and nothing in it is deleted; with `--force` its cache entries
/// are pruned and the user's folders still survive.
#[test]
fn a_folder_that_is_not_a_cache_is_refused_and_force_removes_only_entries() {
    let tmp = tempfile::tempdir().unwrap();
    let project = tmp.path().join("project");
    let files = user_files(&project);
    let cache = ModalCache::new(&project);
    let key = store(&cache, "in-project");
    assert!(!project.join(TAG_FILE).exists(), "a user folder is tagged");
    let dir = project.to_str().unwrap();
    for extra in [&[][..], &PRUNE_ALL, &["--dry-run"]] {
        let mut args = vec!["cache", "--cache", dir];
        args.extend(extra);
        let (code, _out, err) = run(&args);
        assert_ne!(code, 0, "{args:?} must fail");
        assert!(!err.contains("panicked"), "{err}");
        assert!(is_one_line_error(&err), "{err}");
        for s in [
            dir,
            "does not look like a modal cache",
            "CACHEDIR.TAG",
            "--force",
        ] {
            assert!(err.contains(s), "`{err}` lacks `{s}`");
        }
        assert_survive(&files);
        assert!(project.join(&key).join("modes.npy").is_file());
    }
    let mut args = vec!["cache", "--cache", dir, "--force", "--json"];
    args.extend(PRUNE_ALL);
    let (code, out, err) = run(&args);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("left alone"), "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["prune"]["removed"], serde_json::json!([key]), "{out}");
    assert_eq!(
        v["not_entries"],
        serde_json::json!(["notes.txt", "results", "src"])
    );
    assert_survive(&files);
    assert!(!project.join(&key).exists());
    assert!(!project.join(TAG_FILE).exists(), "a user folder is tagged");
}

/// In a tagged cache, a user's folder and file survive pruning with size and age limits of
/// 0, which remove every entry.
#[test]
fn user_items_in_a_cache_survive_pruning_everything() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("cache");
    let cache = ModalCache::new(&dir);
    let keys = [store(&cache, "a"), store(&cache, "b")];
    assert!(dir.join(TAG_FILE).is_file());
    let files = user_files(&dir);
    let mut args = vec!["cache", "--cache", dir.to_str().unwrap(), "--json"];
    args.extend(PRUNE_ALL);
    let (code, out, err) = run(&args);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["entries"].as_array().map(Vec::len), Some(2), "{out}");
    assert_eq!(v["prune"]["removed"].as_array().map(Vec::len), Some(2));
    for k in &keys {
        assert!(!dir.join(k).exists());
    }
    assert_survive(&files);
    assert!(dir.join(TAG_FILE).is_file());
}

/// A cache written before tags (entries only) is accepted and tagged by a prune.
#[test]
fn a_legacy_cache_without_a_tag_is_accepted() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("cache");
    let cache = ModalCache::new(&dir);
    let key = store(&cache, "legacy");
    fs::remove_file(dir.join(TAG_FILE)).unwrap();
    let d = dir.to_str().unwrap();
    let (code, out, err) = run(&["cache", "--cache", d]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains(&key[..16]), "{out}");
    let (code, _out, err) = run(&["cache", "--cache", d, "--max-size-gb", "10"]);
    assert_eq!(code, 0, "{err}");
    assert!(dir.join(TAG_FILE).is_file());
    assert!(dir.join(&key).is_dir());
}

/// Every command that takes `--out` and `--cache` refuses an `--out` that is the cache
/// directory or inside it (given, or the default one under XDG_CACHE_HOME), naming both,
/// before creating anything.
#[test]
fn an_out_directory_inside_the_cache_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let cache = tmp.path().join("cache");
    fs::create_dir_all(&cache).unwrap();
    let c = cache.to_str().unwrap();
    let out = cache.join("out");
    let o = out.to_str().unwrap();
    let commands = [
        "modes",
        "passage",
        "predict",
        "sweep",
        "grow",
        "receptance",
        "initiation",
        "coupled-modes",
    ];
    for cmd in commands {
        for (out_arg, named) in [(o, o), (c, c)] {
            let t = std::time::Instant::now();
            let (code, _o, err) = run(&[cmd, "--out", out_arg, "--cache", c]);
            assert_ne!(code, 0, "{cmd} must fail");
            assert!(!err.contains("panicked"), "{err}");
            assert!(is_one_line_error(&err), "{err}");
            for s in ["--out", named, c, "modal cache"] {
                assert!(err.contains(s), "{cmd}: `{err}` lacks `{s}`");
            }
            assert!(t.elapsed().as_secs_f64() < 10.0, "{cmd} computed first");
        }
        assert!(!out.exists(), "{cmd} created {o}");
    }
    // The default cache directory counts too.
    let xdg = tmp.path().join("xdg");
    let default_out = xdg.join("corrugation/results");
    let res = std::process::Command::new(env!("CARGO_BIN_EXE_corrugation"))
        .args(["modes", "--out", default_out.to_str().unwrap()])
        .env("XDG_CACHE_HOME", &xdg)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&res.stderr);
    assert!(!res.status.success(), "{err}");
    assert!(err.contains("inside the modal cache"), "{err}");
    assert!(!default_out.exists());
}
