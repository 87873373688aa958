//! The suite's runner: a case is one run of the real binary in a scratch directory of its
//! own, with an expected outcome; the runner runs the cases two at a time with a time limit,
//! gives each a verdict and counts the verdicts by class.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// What a case must do.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Expect {
    /// Exit non-zero with a clear error: `error: …` on one line (clap's usage errors: their
    /// first line), naming every needle; no panic, abort or hang.
    Refused,
    /// Exit 0 (the input is valid, however odd), within the time limit.
    Runs,
}

/// A check of the case's directory and output after the run (files left or not left).
pub type After = fn(&Path, &Output) -> Result<(), String>;

/// One run of the binary.
pub struct Case {
    /// The class it is counted in (the table's rows).
    pub class: &'static str,
    /// What it tries, one line.
    pub name: String,
    /// The arguments; `{dir}` is replaced by the case's scratch directory.
    pub args: Vec<String>,
    /// Files written into the scratch directory before the run (path relative to it, bytes).
    pub files: Vec<(String, Vec<u8>)>,
    /// The outcome required.
    pub expect: Expect,
    /// Texts the error must contain (the key or flag, its unit or range, the path).
    pub needles: Vec<String>,
    /// A further check after the run.
    pub after: Option<After>,
    /// Time limit (s); beyond it the case is a hang.
    pub timeout_s: f64,
}

impl Case {
    /// A case refused with an error that names each of `needles`.
    pub fn refused(class: &'static str, args: &[&str], needles: &[&str]) -> Case {
        Case {
            class,
            name: args.join(" "),
            args: args.iter().map(|s| s.to_string()).collect(),
            files: Vec::new(),
            expect: Expect::Refused,
            needles: needles.iter().map(|s| s.to_string()).collect(),
            after: None,
            timeout_s: 20.0,
        }
    }

    /// A case that must run to its end (exit 0).
    pub fn runs(class: &'static str, args: &[&str]) -> Case {
        Case {
            expect: Expect::Runs,
            ..Case::refused(class, args, &[])
        }
    }

    /// With a file written into the scratch directory first.
    pub fn file(mut self, path: &str, bytes: impl Into<Vec<u8>>) -> Case {
        self.files.push((path.to_string(), bytes.into()));
        self
    }

    /// With a check after the run.
    pub fn after(mut self, f: After) -> Case {
        self.after = Some(f);
        self
    }

    /// With a time limit of `s` seconds.
    pub fn timeout(mut self, s: f64) -> Case {
        self.timeout_s = s;
        self
    }
}

/// What a run gave.
pub struct Output {
    /// Exit code; `None` when killed by a signal (an abort) or by the time limit.
    pub code: Option<i32>,
    /// Standard output.
    pub stdout: String,
    /// Standard error.
    pub stderr: String,
    /// Whether the time limit ended it.
    pub timed_out: bool,
    /// Wall time (s).
    pub seconds: f64,
}

/// A case's verdict.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Verdict {
    /// As expected.
    Pass,
    /// A Rust panic (exit 101 or a panic message).
    Panic,
    /// Killed by a signal (an abort, e.g. a failed allocation).
    Abort,
    /// Still running at the time limit.
    Hang,
    /// A bad input accepted: exit 0 where a refusal was expected (silently wrong).
    Accepted,
    /// A valid input refused.
    Refused,
    /// Refused, but the error is not one clear line naming the key or flag, unit and range.
    Unclear,
    /// The check after the run failed (files left behind, something removed).
    After,
}

impl Verdict {
    /// The table's column names, in order.
    pub const ALL: [Verdict; 8] = [
        Verdict::Pass,
        Verdict::Panic,
        Verdict::Abort,
        Verdict::Hang,
        Verdict::Accepted,
        Verdict::Refused,
        Verdict::Unclear,
        Verdict::After,
    ];

    fn name(&self) -> &'static str {
        match self {
            Verdict::Pass => "pass",
            Verdict::Panic => "panic",
            Verdict::Abort => "abort",
            Verdict::Hang => "hang",
            Verdict::Accepted => "bad input accepted",
            Verdict::Refused => "good input refused",
            Verdict::Unclear => "unclear error",
            Verdict::After => "files wrong after",
        }
    }
}

/// Runs `args` with a time limit, output to files in `dir` (no pipes to fill).
fn run_binary(dir: &Path, args: &[String], timeout: Duration) -> Output {
    let (out_path, err_path) = (dir.join(".stdout"), dir.join(".stderr"));
    let t0 = Instant::now();
    let spawned = Command::new(env!("CARGO_BIN_EXE_corrugation"))
        .args(args)
        .current_dir(dir)
        .env("NO_COLOR", "1")
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out_path).expect("stdout file"))
        .stderr(std::fs::File::create(&err_path).expect("stderr file"))
        .spawn();
    let mut child = match spawned {
        Ok(c) => c,
        Err(e) => {
            return Output {
                code: Some(-1),
                stdout: String::new(),
                stderr: format!("cannot start the binary: {e}"),
                timed_out: false,
                seconds: 0.0,
            }
        }
    };
    let mut timed_out = false;
    let status = loop {
        match child.try_wait() {
            Ok(Some(s)) => break Some(s),
            Ok(None) if t0.elapsed() > timeout => {
                let _ = child.kill();
                let _ = child.wait();
                timed_out = true;
                break None;
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(5)),
            Err(_) => break None,
        }
    };
    let read =
        |p: &Path| String::from_utf8_lossy(&std::fs::read(p).unwrap_or_default()).into_owned();
    Output {
        code: status.and_then(|s| s.code()),
        stdout: read(&out_path),
        stderr: read(&err_path),
        timed_out,
        seconds: t0.elapsed().as_secs_f64(),
    }
}

/// Whether `stderr` holds one clear error: our own (`error: …` as its last line and no other
/// error line) or clap's usage error (exit 2: `error: …` first, then its usage hint).
fn one_clear_error(code: i32, stderr: &str) -> bool {
    let lines: Vec<&str> = stderr.trim_end().lines().collect();
    let errors = lines.iter().filter(|l| l.starts_with("error")).count();
    if code == 2 {
        return errors == 1 && lines.iter().any(|l| l.starts_with("error: "));
    }
    errors == 1 && lines.last().is_some_and(|l| l.starts_with("error: "))
}

/// The verdict of `case` from its output.
fn verdict(case: &Case, dir: &Path, out: &Output) -> (Verdict, String) {
    if out.stderr.contains("panicked at") || out.code == Some(101) {
        return (Verdict::Panic, out.stderr.clone());
    }
    if out.timed_out {
        return (
            Verdict::Hang,
            format!("still running after {} s", case.timeout_s),
        );
    }
    let Some(code) = out.code else {
        return (Verdict::Abort, out.stderr.clone());
    };
    match (case.expect, code == 0) {
        (Expect::Refused, true) => return (Verdict::Accepted, out.stdout.clone()),
        (Expect::Runs, false) => return (Verdict::Refused, out.stderr.clone()),
        (Expect::Refused, false) => {
            let d = dir.display().to_string();
            let missing: Vec<String> = case
                .needles
                .iter()
                .map(|n| n.replace("{dir}", &d))
                .filter(|n| !out.stderr.contains(n.as_str()))
                .collect();
            if !one_clear_error(code, &out.stderr) || !missing.is_empty() {
                return (
                    Verdict::Unclear,
                    format!("lacks {missing:?}: {}", out.stderr.trim_end()),
                );
            }
        }
        (Expect::Runs, true) => {}
    }
    if let Some(f) = case.after {
        if let Err(e) = f(dir, out) {
            return (Verdict::After, e);
        }
    }
    (Verdict::Pass, String::new())
}

/// The verdicts of a run of the suite.
pub struct Report {
    /// (class, verdict) → count.
    pub counts: BTreeMap<(&'static str, Verdict), usize>,
    /// The cases that did not pass: class, name, verdict, detail.
    pub failures: Vec<(&'static str, String, Verdict, String)>,
    /// The number of cases.
    pub cases: usize,
    /// The slowest case (s, name).
    pub slowest: (f64, String),
}

impl Report {
    /// The counts as a Markdown table: a row per class, a column per verdict.
    pub fn table(&self) -> String {
        let classes: Vec<&str> = {
            let mut c: Vec<&str> = self.counts.keys().map(|(c, _)| *c).collect();
            c.dedup();
            c
        };
        let mut s = String::from("| class | cases |");
        for v in Verdict::ALL {
            s += &format!(" {} |", v.name());
        }
        s += "\n|---|---|";
        s += &"---|".repeat(Verdict::ALL.len());
        s += "\n";
        let mut total = [0usize; 8];
        for c in &classes {
            let row: Vec<usize> = Verdict::ALL
                .iter()
                .map(|v| self.counts.get(&(*c, v.clone())).copied().unwrap_or(0))
                .collect();
            s += &format!("| {c} | {} |", row.iter().sum::<usize>());
            for (i, n) in row.iter().enumerate() {
                total[i] += n;
                s += &format!(" {n} |");
            }
            s += "\n";
        }
        s += &format!("| all | {} |", total.iter().sum::<usize>());
        for n in total {
            s += &format!(" {n} |");
        }
        s + "\n"
    }
}

/// Runs `cases` (two at a time), each in a fresh directory under `root`.
pub fn run_all(root: &Path, cases: Vec<Case>) -> Report {
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<(usize, Verdict, String, f64)>> = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(case) = cases.get(i) else { break };
                let dir: PathBuf = root.join(format!("case-{i:04}"));
                std::fs::create_dir_all(&dir).expect("case directory");
                for (p, bytes) in &case.files {
                    let p = dir.join(p);
                    if let Some(parent) = p.parent() {
                        std::fs::create_dir_all(parent).expect("case file directory");
                    }
                    std::fs::write(p, bytes).expect("case file");
                }
                let d = dir.display().to_string();
                let args: Vec<String> = case.args.iter().map(|a| a.replace("{dir}", &d)).collect();
                let out = run_binary(&dir, &args, Duration::from_secs_f64(case.timeout_s));
                let (v, detail) = verdict(case, &dir, &out);
                results.lock().unwrap().push((i, v, detail, out.seconds));
            });
        }
    });
    let mut report = Report {
        counts: BTreeMap::new(),
        failures: Vec::new(),
        cases: cases.len(),
        slowest: (0.0, String::new()),
    };
    for (i, v, detail, seconds) in results.into_inner().unwrap() {
        let case = &cases[i];
        *report.counts.entry((case.class, v.clone())).or_default() += 1;
        if seconds > report.slowest.0 {
            report.slowest = (seconds, case.name.clone());
        }
        if v != Verdict::Pass {
            report
                .failures
                .push((case.class, case.name.clone(), v, detail));
        }
    }
    report.failures.sort();
    report
}
