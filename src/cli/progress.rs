//! Renders the progress of long work on stderr: a named bar with an ETA on a terminal, and
//! plain lines (stage, count, elapsed time, ETA) every few seconds when stderr is not a
//! terminal (batch jobs, logs). The library reports its progress through
//! [`corrugation::progress::Progress`] (implemented here); this module is the only place
//! that prints it.
//!
//! The interval of the plain lines is `CORRUGATION_PROGRESS_SECONDS` (s, default 10, from
//! 0.1 to 3600).

use std::io::IsTerminal;
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Environment variable: seconds between plain progress lines when stderr is not a terminal.
pub(crate) const INTERVAL_VAR: &str = "CORRUGATION_PROGRESS_SECONDS";
/// Default seconds between plain progress lines.
const DEFAULT_INTERVAL_S: f64 = 10.0;

/// The plain-line interval: [`INTERVAL_VAR`] when it is a number in [0.1, 3600] s, else the
/// default (a bad value is reported once per run, however many indicators the command makes).
fn interval() -> Duration {
    static INTERVAL: std::sync::OnceLock<Duration> = std::sync::OnceLock::new();
    *INTERVAL.get_or_init(read_interval)
}

/// [`interval`] read from the environment.
fn read_interval() -> Duration {
    match std::env::var(INTERVAL_VAR) {
        Err(_) => Duration::from_secs_f64(DEFAULT_INTERVAL_S),
        Ok(v) => match v.trim().parse::<f64>() {
            Ok(s) if (0.1..=3600.0).contains(&s) => Duration::from_secs_f64(s),
            _ => {
                eprintln!(
                    "warning: {INTERVAL_VAR}={v:?} is not a number of seconds in 0.1 … 3600; using {DEFAULT_INTERVAL_S} s"
                );
                Duration::from_secs_f64(DEFAULT_INTERVAL_S)
            }
        },
    }
}

/// The stage currently shown: its name and start.
struct Stage {
    name: String,
    start: Instant,
    /// Its closing line has been printed (a stage ends once, however often it is finished).
    ended: bool,
}

/// A named progress indicator (see the module doc). Dropping it stops the plain lines.
pub struct Progress {
    bar: indicatif::ProgressBar,
    tty: bool,
    stage: Arc<Mutex<Stage>>,
    stop: Option<mpsc::Sender<()>>,
    ticker: Option<JoinHandle<()>>,
}

/// Bar style when the total is known.
fn counted_style() -> indicatif::ProgressStyle {
    indicatif::ProgressStyle::with_template(
        "{spinner} {msg} [{elapsed_precise}] {wide_bar} {pos}/{len} (ETA {eta})",
    )
    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
}

/// Spinner style while the total is not known (never "0/0").
fn uncounted_style() -> indicatif::ProgressStyle {
    indicatif::ProgressStyle::with_template("{spinner} {msg} [{elapsed_precise}]")
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner())
}

/// One plain progress line of `bar` in the stage `stage` (the count only when known).
fn plain_line(stage: &Stage, bar: &indicatif::ProgressBar) -> String {
    let el = stage.start.elapsed().as_secs_f64();
    let (k, n) = (bar.position(), bar.length().unwrap_or(0));
    if n == 0 {
        return format!("{}: running, {el:.0} s", stage.name);
    }
    let eta = if k > 0 && k <= n {
        format!(", ETA {:.0} s", el * (n - k) as f64 / k as f64)
    } else {
        String::new()
    };
    format!("{}: {k}/{n} after {el:.0} s{eta}", stage.name)
}

/// A progress indicator named `name` (what runs and what is counted). On a terminal a bar
/// (a spinner until the total is known); otherwise a line `name ...` now and a plain
/// progress line every interval.
pub fn bar(name: &str) -> Progress {
    make(name)
}

fn make(name: &str) -> Progress {
    let tty = std::io::stderr().is_terminal();
    let bar = if tty {
        let pb = indicatif::ProgressBar::new(0);
        pb.set_style(uncounted_style());
        pb.set_message(name.to_string());
        pb.enable_steady_tick(Duration::from_millis(200));
        pb
    } else {
        indicatif::ProgressBar::hidden()
    };
    let stage = Arc::new(Mutex::new(Stage {
        name: name.to_string(),
        start: Instant::now(),
        ended: false,
    }));
    let (stop, ticker) = if tty {
        (None, None)
    } else {
        eprintln!("{name} ...");
        let (tx, rx) = mpsc::channel::<()>();
        let (b, s, every) = (bar.clone(), stage.clone(), interval());
        let h = std::thread::spawn(move || {
            while let Err(mpsc::RecvTimeoutError::Timeout) = rx.recv_timeout(every) {
                if let Ok(st) = s.lock() {
                    if !st.ended {
                        eprintln!("{}", plain_line(&st, &b));
                    }
                }
            }
        });
        (Some(tx), Some(h))
    };
    Progress {
        bar,
        tty,
        stage,
        stop,
        ticker,
    }
}

impl Progress {
    /// Starts a new stage named `msg` (count and clock restart; total unknown).
    pub(crate) fn set_message(&self, msg: &str) {
        if let Ok(mut s) = self.stage.lock() {
            s.name = msg.to_string();
            s.start = Instant::now();
            s.ended = false;
        }
        // A stage after a finished one restarts the bar (and its ticker) on a terminal.
        if self.bar.is_finished() && !self.bar.is_hidden() {
            self.bar.reset();
            self.bar.enable_steady_tick(Duration::from_millis(200));
        }
        self.bar.set_style(uncounted_style());
        self.bar.set_length(0);
        self.bar.set_position(0);
        self.bar.set_message(msg.to_string());
        if !self.tty {
            eprintln!("{msg} ...");
        }
    }

    /// The total count of the current stage.
    pub(crate) fn set_length(&self, n: u64) {
        if self.bar.length() != Some(n) {
            self.bar.set_length(n);
            if n > 0 {
                self.bar.set_style(counted_style());
            }
        }
    }

    /// The count done in the current stage.
    pub(crate) fn set_position(&self, k: u64) {
        self.bar.set_position(k);
    }

    /// Ends the current stage: clears the bar, or prints a closing line off a terminal.
    pub(crate) fn finish_and_clear(&self) {
        self.bar.finish_and_clear();
        if !self.tty {
            if let Ok(mut s) = self.stage.lock() {
                if std::mem::replace(&mut s.ended, true) {
                    return;
                }
                let n = self.bar.length().unwrap_or(0);
                let count = if n > 0 {
                    format!("{n}/{n}, ")
                } else {
                    String::new()
                };
                eprintln!(
                    "{}: done ({count}{:.1} s)",
                    s.name,
                    s.start.elapsed().as_secs_f64()
                );
            }
        }
    }
}

impl corrugation::progress::Progress for Progress {
    fn stage(&self, name: &str, total: u64) {
        self.set_message(name);
        self.set_length(total);
    }

    fn done(&self, done: u64) {
        self.set_position(done);
    }

    fn total(&self, total: u64) {
        self.set_length(total);
    }

    fn warn(&self, message: &str) {
        self.bar.suspend(|| eprintln!("warning: {message}"));
    }

    fn finish(&self) {
        self.finish_and_clear();
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        drop(self.stop.take());
        if let Some(h) = self.ticker.take() {
            let _ = h.join();
        }
        self.bar.finish_and_clear();
    }
}

#[cfg(test)]
mod tests {
    use super::{plain_line, Duration, Instant, Stage};
    #[test]
    fn plain_line_shows_the_count_only_when_known_and_an_eta_once_started() {
        let st = Stage {
            name: "sweep passages (speeds)".into(),
            start: Instant::now() - Duration::from_secs(20),
            ended: false,
        };
        let b = indicatif::ProgressBar::hidden();
        assert_eq!(
            plain_line(&st, &b),
            "sweep passages (speeds): running, 20 s"
        );
        b.set_length(4);
        assert_eq!(
            plain_line(&st, &b),
            "sweep passages (speeds): 0/4 after 20 s"
        );
        b.set_position(1);
        // 20 s for one of four: 60 s to go.
        assert_eq!(
            plain_line(&st, &b),
            "sweep passages (speeds): 1/4 after 20 s, ETA 60 s"
        );
    }
}
