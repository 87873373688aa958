//! Progress for long work: a bar with an ETA on a terminal, and a plain line (stage, count,
//! ETA) at most every 10 s when stderr is not a terminal (batch jobs, logs).

use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// Seconds between plain progress lines when stderr is not a terminal.
const PLAIN_INTERVAL: Duration = Duration::from_secs(10);

/// A named progress indicator.
pub struct Progress {
    bar: Option<indicatif::ProgressBar>,
    msg: std::cell::RefCell<String>,
    len: std::cell::Cell<u64>,
    start: Instant,
    last: std::cell::Cell<Instant>,
}

/// A progress indicator named `msg`.
pub fn bar(msg: &str) -> Progress {
    let bar = std::io::stderr().is_terminal().then(|| {
        let pb = indicatif::ProgressBar::new(0);
        pb.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} {msg} [{elapsed_precise}] {wide_bar} {pos}/{len} (ETA {eta})",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        pb.set_message(msg.to_string());
        pb.enable_steady_tick(Duration::from_millis(200));
        pb
    });
    if bar.is_none() {
        eprintln!("{msg} ...");
    }
    Progress {
        bar,
        msg: std::cell::RefCell::new(msg.to_string()),
        len: std::cell::Cell::new(0),
        start: Instant::now(),
        last: std::cell::Cell::new(Instant::now()),
    }
}

impl Progress {
    /// Renames the stage.
    pub fn set_message(&self, msg: &str) {
        *self.msg.borrow_mut() = msg.to_string();
        match &self.bar {
            Some(b) => b.set_message(msg.to_string()),
            None => eprintln!("{msg} ..."),
        }
    }

    /// The total count.
    pub fn set_length(&self, n: u64) {
        self.len.set(n);
        if let Some(b) = &self.bar {
            b.set_length(n);
        }
    }

    /// The count done.
    pub fn set_position(&self, k: u64) {
        match &self.bar {
            Some(b) => b.set_position(k),
            None => {
                let now = Instant::now();
                let n = self.len.get();
                if now.duration_since(self.last.get()) >= PLAIN_INTERVAL || (n > 0 && k == n) {
                    self.last.set(now);
                    let el = now.duration_since(self.start).as_secs_f64();
                    let eta = if k > 0 && n >= k {
                        format!(", ETA {:.0} s", el * (n - k) as f64 / k as f64)
                    } else {
                        String::new()
                    };
                    eprintln!("{}: {k}/{n} after {el:.0} s{eta}", self.msg.borrow());
                }
            }
        }
    }

    /// Removes the bar.
    pub fn finish_and_clear(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}
