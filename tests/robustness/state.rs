//! The suite's stateful cases: a sweep killed with SIGKILL and rerun, two processes solving
//! the same cache entries at once, and corrupted cache entries, each on the small model.

use crate::common::{small_model_cache, tree, SMALL_MODEL};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The binary with `cmd`, the small model, `cache` and `out`, then `rest`.
fn small(cmd: &str, cache: &Path, out: &Path, rest: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_corrugation"));
    c.arg(cmd)
        .args(SMALL_MODEL)
        .arg("--cache")
        .arg(cache)
        .arg("--out")
        .arg(out)
        .args(rest)
        .stdin(Stdio::null());
    c
}

/// Standard output and error of a run that must have succeeded.
fn finished(o: &Output, what: &str) -> String {
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(o.status.success(), "{what} failed: {text}");
    text
}

/// The cache's entry directories (64 hexadecimal digits).
fn entries(cache: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(cache)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.is_dir()
                && p.file_name()
                    .unwrap()
                    .to_str()
                    .is_some_and(|n| n.len() == 64 && n.bytes().all(|b| b.is_ascii_hexdigit()))
        })
        .collect();
    v.sort();
    v
}

/// Flips one byte in the middle of `file`.
fn flip_a_byte(file: &Path) {
    let mut b = std::fs::read(file).unwrap();
    let i = b.len() / 2;
    b[i] ^= 0x5a;
    std::fs::write(file, b).unwrap();
}

/// Two processes that solve the same modes into one empty cache at once both finish with the
/// same modes, and leave one entry per substructure (track, wheel) with its manifest and no
/// temporary directory; a third run loads them. Each file of an entry corrupted in turn
/// (`modes.npy`, `frequencies_hz.npy`, `meta.json`, the manifest) is detected on load and the
/// entry recomputed to the same modes.
#[test]
fn two_processes_share_a_cache_and_corrupted_entries_are_recomputed() {
    let tmp = tempfile::tempdir().unwrap();
    let cache = tmp.path().join("cache");
    let out = |i: usize| tmp.path().join(format!("out{i}"));
    let modes = |i: usize| small("modes", &cache, &out(i), &["--fmax", "1000"]);
    let children: Vec<Child> = (0..2)
        .map(|i| {
            modes(i)
                .stdout(Stdio::null())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for c in children {
        finished(&c.wait_with_output().unwrap(), "a concurrent `modes`");
    }
    let table = |i: usize| std::fs::read(out(i).join("modes.csv")).unwrap();
    assert_eq!(table(0), table(1), "the two processes' modes differ");
    let e = entries(&cache);
    assert_eq!(
        e.len(),
        2,
        "one entry each for the track and the wheel: {e:?}"
    );
    for d in &e {
        assert!(
            d.join("manifest.b3").is_file(),
            "{} lacks its manifest",
            d.display()
        );
    }
    let leftovers: Vec<_> = std::fs::read_dir(&cache)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
    let s = finished(&modes(2).output().unwrap(), "`modes` on the filled cache");
    assert!(
        s.contains("(cached)"),
        "the third run did not load the cache: {s}"
    );
    // the larger entry is the track's
    let track = e
        .iter()
        .max_by_key(|d| std::fs::metadata(d.join("modes.npy")).unwrap().len())
        .unwrap();
    for (k, file) in [
        "modes.npy",
        "frequencies_hz.npy",
        "meta.json",
        "manifest.b3",
    ]
    .iter()
    .enumerate()
    {
        flip_a_byte(&track.join(file));
        let s = finished(
            &modes(3 + k).output().unwrap(),
            "`modes` on a corrupted entry",
        );
        let track_line = s.lines().find(|l| l.starts_with("track:")).unwrap_or("");
        assert!(
            !track_line.contains("(cached)"),
            "corrupted {file} was loaded: {track_line}"
        );
        assert_eq!(
            table(3 + k),
            table(0),
            "modes after corrupting {file} differ"
        );
    }
}

/// A sweep killed (SIGKILL) after its first speed is written resumes when run again: the
/// finished speeds are reused byte for byte, the others computed, and no temporary file is
/// left in its output.
#[test]
fn a_killed_sweep_resumes_keeping_what_it_finished() {
    let tmp = tempfile::tempdir().unwrap();
    let cache = small_model_cache();
    let out = tmp.path().join("sweep out");
    let sweep = || small("sweep", &cache, &out, &["--speeds", "60,100,140,180"]);
    let speed_files = || -> Vec<PathBuf> {
        std::fs::read_dir(out.join("speeds"))
            .map(|d| {
                d.map(|e| e.unwrap().path())
                    .filter(|p| {
                        let n = p.file_name().unwrap().to_string_lossy();
                        n.ends_with(".json") && n.starts_with('0')
                    })
                    .collect()
            })
            .unwrap_or_default()
    };
    let mut child = sweep()
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    let killed = loop {
        if !speed_files().is_empty() {
            child.kill().unwrap();
            child.wait().unwrap();
            break true;
        }
        if child.try_wait().unwrap().is_some() {
            break false;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(300),
            "no speed finished in 300 s"
        );
        std::thread::sleep(Duration::from_millis(20));
    };
    let before: Vec<(PathBuf, Vec<u8>)> = speed_files()
        .into_iter()
        .map(|p| {
            let b = std::fs::read(&p).unwrap();
            (p, b)
        })
        .collect();
    let s = finished(&sweep().output().unwrap(), "the resumed sweep");
    if killed && before.len() < 4 {
        assert!(s.contains(&format!("{} reused", before.len())), "{s}");
    }
    for (p, b) in &before {
        assert_eq!(
            &std::fs::read(p).unwrap(),
            b,
            "{} was rewritten",
            p.display()
        );
    }
    assert_eq!(speed_files().len(), 4);
    let temps: Vec<_> = tree(&out)
        .into_keys()
        .filter(|p| p.to_string_lossy().contains(".tmp"))
        .collect();
    assert!(temps.is_empty(), "temporary files left: {temps:?}");
}
