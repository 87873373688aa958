//! Progress of long work. The library never prints progress: it reports stages and counts
//! to a [`Progress`] given by the caller, and a front end (the command-line program) renders
//! them (a bar on a terminal, plain lines in a log).

use std::sync::atomic::{AtomicU64, Ordering};

/// Receives the progress of long work (a sweep's passages, a study's cases, …).
///
/// Implementations must be cheap: [`Progress::done`] may be called once per unit of work
/// from several threads.
pub trait Progress: Sync {
    /// A stage named `name` (what is counted, e.g. "sweep passages (speeds)") with `total`
    /// units of work begins; `total` = 0 when the count is not known.
    fn stage(&self, name: &str, total: u64);
    /// `done` units of the current stage are complete (0 ≤ done ≤ total).
    fn done(&self, done: u64);
    /// The total of the current stage became known after it began (e.g. the Sturm count of
    /// an eigen-solve). Default: ignored.
    fn total(&self, _total: u64) {}
    /// The current stage is over.
    fn finish(&self) {}
    /// A warning for the user that does not stop the work (e.g. a cache entry that could not
    /// be stored). Default: dropped, for work nobody watches.
    fn warn(&self, _message: &str) {}
    /// Whether the caller asks the work to stop (e.g. an interrupt in an interactive front
    /// end). Long loops ask where they report their counts (a passage every 64 time steps, a
    /// sweep before each speed) and stop with [`Cancelled`]. Default: never.
    fn cancelled(&self) -> bool {
        false
    }
}

/// The work was stopped because its [`Progress::cancelled`] said so.
#[derive(Clone, Copy, Debug, thiserror::Error)]
#[error("cancelled by the caller")]
pub struct Cancelled;

/// Progress that nobody watches (tests, library use without a front end).
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Progress for Silent {
    fn stage(&self, _: &str, _: u64) {}
    fn done(&self, _: u64) {}
}

/// Counts completed units from parallel workers and reports the count to a [`Progress`].
pub struct Counter<'a> {
    sink: &'a dyn Progress,
    count: AtomicU64,
    /// The stage's name and total when this counter began it ([`Counter::start`]).
    stage: Option<(String, u64)>,
}

impl<'a> Counter<'a> {
    /// Starts the stage `name` of `total` units on `sink`.
    pub fn start(sink: &'a dyn Progress, name: &str, total: u64) -> Self {
        sink.stage(name, total);
        Self {
            sink,
            count: AtomicU64::new(0),
            stage: Some((name.to_string(), total)),
        }
    }

    /// Counts into the stage that the caller has already begun on `sink`, from 0.
    pub fn within(sink: &'a dyn Progress) -> Self {
        Self {
            sink,
            count: AtomicU64::new(0),
            stage: None,
        }
    }

    /// Begins this counter's stage again with its count so far, after work inside one unit
    /// reported stages of its own to the same sink (a study case computing its modal bases
    /// shows "track modes …"; then "study cases k/n" again). Nothing for a counter made by
    /// [`Counter::within`].
    pub fn resume(&self) {
        if let Some((name, total)) = &self.stage {
            self.sink.stage(name, *total);
            self.sink.done(self.count.load(Ordering::Relaxed));
        }
    }

    /// One more unit is complete.
    pub fn inc(&self) {
        self.add(1);
    }

    /// `n` more units are complete.
    pub fn add(&self, n: u64) {
        let k = self.count.fetch_add(n, Ordering::Relaxed) + n;
        self.sink.done(k);
    }

    /// Ends the stage.
    pub fn finish(self) {
        self.sink.finish();
    }
}

/// An error and its chain of sources on one line, `outer: cause: root cause`, for a warning
/// (the CLI prints returned errors the same way).
pub fn error_chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut src = e.source();
    while let Some(c) = src {
        s.push_str(": ");
        s.push_str(&c.to_string());
        src = c.source();
    }
    s
}

/// An error and its causes on one line, `: `-separated, as the command-line program prints
/// it after `error: `: a cause whose text the message already holds (an error that prints
/// its source) is not repeated, and a message of several lines is joined with spaces.
pub fn one_line(e: &(dyn std::error::Error + 'static)) -> String {
    let mut msg = e.to_string();
    let mut src = e.source();
    while let Some(cause) = src {
        let c = cause.to_string();
        if !msg.contains(&c) {
            msg.push_str(": ");
            msg.push_str(&c);
        }
        src = cause.source();
    }
    msg.lines().map(str::trim).collect::<Vec<_>>().join(" ")
}

/// CPU time (user + system) of this process (s), from `/proc/self/stat`; `None` elsewhere.
pub fn cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    let rest = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let utime: f64 = f.get(11)?.parse().ok()?;
    let stime: f64 = f.get(12)?.parse().ok()?;
    // Linux reports clock ticks of 1/100 s (USER_HZ) on every supported architecture.
    Some((utime + stime) / 100.0)
}

#[cfg(test)]
mod tests {
    use super::{Counter, Progress};
    use std::sync::Mutex;

    #[derive(Default)]
    struct Log(Mutex<Vec<String>>);

    impl Progress for Log {
        fn stage(&self, name: &str, total: u64) {
            self.0.lock().unwrap().push(format!("stage {name} {total}"));
        }
        fn done(&self, done: u64) {
            self.0.lock().unwrap().push(format!("done {done}"));
        }
        fn finish(&self) {
            self.0.lock().unwrap().push("finish".into());
        }
    }

    #[test]
    fn counter_reports_every_unit_once_from_parallel_workers() {
        use rayon::prelude::*;
        let log = Log::default();
        let c = Counter::start(&log, "units", 50);
        (0..50).into_par_iter().for_each(|_| c.inc());
        c.finish();
        let v = log.0.into_inner().unwrap();
        assert_eq!(v.first().map(String::as_str), Some("stage units 50"));
        assert_eq!(v.last().map(String::as_str), Some("finish"));
        let mut counts: Vec<u64> = v
            .iter()
            .filter_map(|s| s.strip_prefix("done ").map(|n| n.parse().unwrap()))
            .collect();
        counts.sort_unstable();
        assert_eq!(counts, (1..=50).collect::<Vec<u64>>());
    }
}
