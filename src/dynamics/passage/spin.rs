//! A second thread for the fine-grained two-core split of a passage that runs alone
//! ([`super::PassageOptions::overlap`]): it waits by spinning for a bounded time, then parks,
//! and the pair falls back to one thread while the machine is oversubscribed.
//!
//! `rayon::join` costs a wake-up of a sleeping worker (a futex, several microseconds, and a
//! scheduler round trip) every time the worker has gone to sleep between two joins; at one
//! join per contact step (about 250 µs) the worker is asleep at every step, and the wake-ups
//! cost about what the damping product beside the contact saves. [`SpinPair`] keeps one
//! scoped thread waiting on an atomic, so that handing it a job costs a cache-line transfer
//! (well under a microsecond) while the machine has a core for it.
//!
//! A spinning thread is only cheap while it has a core of its own. When other work takes the
//! cores (a laptop doing anything, a shared cluster node, passages side by side), a spinner
//! burns the time slice that the calling thread needs, and a descheduled worker holds up the
//! step that waits for it. Three rules keep the pair from ever being slower than one thread
//! by more than a few steps:
//! * **Bounded spinning.** The worker spins at most [`WORKER_SPIN`] for a job and the caller
//!   at most [`CALLER_SPIN`] for the worker's result; then each parks (`std::thread::park`,
//!   a futex on Linux) until the other unparks it.
//! * **Stealing.** A job that the worker has not started when the caller has finished its own
//!   half is taken back and run by the caller, so a descheduled worker never delays a step.
//! * **Falling back.** A join is *late* when its job was stolen or the caller had to park.
//!   When more than [`LATE_LIMIT`] of a window of [`WINDOW`] joins are late, the pair runs
//!   both halves on the calling thread for [`ALONE_FIRST`] joins (the worker parks), then
//!   tries the split again for one window; each failed try doubles the time alone (up to
//!   [`ALONE_MAX`]).
//!
//! The arithmetic of both halves does not depend on which thread runs them, so results are
//! the same bits whichever way each step goes.
//!
//! The job is a borrowed closure (no allocation per hand-over); [`SpinPair::join`] returns
//! only after the job has finished or has been taken back, so the borrow outlives its use. A
//! job that panics is caught on the worker and resumed on the calling thread. [`SpinPair`] is
//! neither `Send` nor `Sync`: only the thread that started it calls `join`.

use std::cell::{Cell, UnsafeCell};
use std::marker::PhantomData;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use std::sync::Arc;
use std::thread::{Scope, Thread};
use std::time::{Duration, Instant};

/// No job; the worker waits.
const IDLE: u8 = 0;
/// A job is in the slot, not started: the worker may take it, or the caller take it back.
const JOB: u8 = 1;
/// The worker is running the job.
const RUNNING: u8 = 2;
/// The job is done (or panicked: the payload is in the slot).
const DONE: u8 = 3;
/// The worker returns.
const QUIT: u8 = 4;

/// Longest time the worker spins for a job before it parks: 1 ms, several contact steps, so
/// that a passage alone on an idle machine never parks between steps.
pub(super) const WORKER_SPIN: Duration = Duration::from_millis(1);
/// Longest time the caller spins for the worker's result before it parks: 50 µs, a fifth of
/// a contact step. On an idle machine the worker's half (the damping product) ends well
/// before the caller's (the contact step), so the caller does not wait at all.
pub(super) const CALLER_SPIN: Duration = Duration::from_micros(50);
/// Joins per window of the fall-back rule.
pub(super) const WINDOW: u32 = 32;
/// Late joins in a window above which the pair falls back to one thread.
pub(super) const LATE_LIMIT: u32 = WINDOW / 8;
/// Joins run on the calling thread after the first fall-back (about 64 ms of steps).
pub(super) const ALONE_FIRST: u32 = 256;
/// Longest run of joins on the calling thread between two tries of the split.
pub(super) const ALONE_MAX: u32 = 1 << 14;

/// A type-erased pointer to the job's closure (valid while [`SpinPair::join`] waits).
type JobPtr = *mut (dyn FnMut() + Send + 'static);

/// A panic's payload, carried from the worker to the calling thread.
type Payload = Box<dyn std::any::Any + Send + 'static>;

/// State shared by the calling thread and the worker.
struct Shared {
    state: AtomicU8,
    job: UnsafeCell<Option<JobPtr>>,
    panic: UnsafeCell<Option<Payload>>,
    /// The worker is parked (or about to park): the caller unparks it after posting a job.
    worker_parked: AtomicBool,
    /// The caller is parked (or about to park): the worker unparks it after DONE.
    caller_parked: AtomicBool,
    /// The calling thread (the one that started the pair).
    caller: Thread,
}

// SAFETY: `job` and `panic` are written by one thread at a time, handed over by `state`:
// the calling thread writes `job` before storing JOB and reads `panic` after loading DONE;
// the worker reads `job` only after winning JOB → RUNNING and writes `panic` before storing
// DONE; a caller that wins JOB → IDLE (takes the job back) clears `job` itself, and the
// worker, having lost that exchange, does not touch the slots.
unsafe impl Sync for Shared {}
// SAFETY: as for `Sync`: the pointer in `job` is dereferenced only by the thread the state
// hands it to, while the closure it points to is alive.
unsafe impl Send for Shared {}

/// How the pair runs its joins now.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Mode {
    /// Jobs go to the worker; `joins` and `late` count the current window.
    Split {
        /// Joins in the window so far.
        joins: u32,
        /// Late joins (stolen, or the caller parked) in the window so far.
        late: u32,
    },
    /// Both halves on the calling thread for `left` more joins.
    Alone {
        /// Joins left before the split is tried again.
        left: u32,
    },
}

/// The fall-back rule as a state machine (module docs): the mode, and the length of the next
/// run alone.
#[derive(Clone, Copy, Debug)]
pub(super) struct FallBack {
    mode: Mode,
    next_alone: u32,
}

impl Default for FallBack {
    fn default() -> Self {
        Self {
            mode: Mode::Split { joins: 0, late: 0 },
            next_alone: ALONE_FIRST,
        }
    }
}

impl FallBack {
    /// Whether the next join splits.
    pub(super) fn splits(&self) -> bool {
        matches!(self.mode, Mode::Split { .. })
    }

    /// Records one join: `late` for a split join whose job was stolen or whose caller parked
    /// (ignored for a join run alone).
    pub(super) fn record(&mut self, late: bool) {
        self.mode = match self.mode {
            Mode::Split { joins, late: l } => {
                let (joins, l) = (joins + 1, l + u32::from(late));
                if l > LATE_LIMIT {
                    let left = self.next_alone;
                    self.next_alone = (2 * self.next_alone).min(ALONE_MAX);
                    Mode::Alone { left }
                } else if joins >= WINDOW {
                    // a clean window: the split pays, and the next fall-back starts short
                    self.next_alone = ALONE_FIRST;
                    Mode::Split { joins: 0, late: 0 }
                } else {
                    Mode::Split { joins, late: l }
                }
            }
            Mode::Alone { left } if left > 1 => Mode::Alone { left: left - 1 },
            Mode::Alone { .. } => Mode::Split { joins: 0, late: 0 },
        };
    }
}

/// Counts of a pair's joins (for tests and benchmarks).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct JoinCounts {
    /// Joins whose job the worker ran.
    pub split: u64,
    /// Split joins whose job the caller took back.
    pub stolen: u64,
    /// Split joins in which the caller parked waiting for the worker.
    pub parked: u64,
    /// Joins run on the calling thread by the fall-back rule.
    pub alone: u64,
}

/// The calling thread's handle of a worker in a [`std::thread::scope`]. Dropping it stops the
/// worker. Neither `Send` nor `Sync`.
pub(super) struct SpinPair {
    shared: Arc<Shared>,
    worker: Thread,
    rule: Cell<FallBack>,
    counts: Cell<JoinCounts>,
    /// Keeps the pair on the thread that started it (`*const ()` is neither Send nor Sync).
    _here: PhantomData<*const ()>,
}

/// Compile-time check that [`SpinPair`] is not `Sync` (two threads calling `join` at once
/// would hand out one slot twice): the call below is ambiguous, and fails to compile, for a
/// `Sync` type.
#[allow(dead_code)]
const _: () = {
    trait AmbiguousIfSync<A> {
        fn check() {}
    }
    impl<T: ?Sized> AmbiguousIfSync<()> for T {}
    impl<T: ?Sized + Sync> AmbiguousIfSync<u8> for T {}
    fn not_sync() {
        <SpinPair as AmbiguousIfSync<_>>::check();
    }
};

impl SpinPair {
    /// Starts the worker in `scope`; `None` when the system refuses a thread (the caller
    /// then runs both halves itself).
    pub(super) fn start<'scope>(scope: &'scope Scope<'scope, '_>) -> Option<Self> {
        let shared = Arc::new(Shared {
            state: AtomicU8::new(IDLE),
            job: UnsafeCell::new(None),
            panic: UnsafeCell::new(None),
            worker_parked: AtomicBool::new(false),
            caller_parked: AtomicBool::new(false),
            caller: std::thread::current(),
        });
        let s = shared.clone();
        let handle = std::thread::Builder::new()
            .name("passage-spin".into())
            .spawn_scoped(scope, move || worker(&s))
            .ok()?;
        Some(SpinPair {
            shared,
            worker: handle.thread().clone(),
            rule: Cell::new(FallBack::default()),
            counts: Cell::new(JoinCounts::default()),
            _here: PhantomData,
        })
    }

    /// Counts of the joins so far.
    pub(super) fn counts(&self) -> JoinCounts {
        self.counts.get()
    }

    /// Runs `a` on the calling thread and `b` on the worker (or on the calling thread when
    /// the worker has not started it by the time `a` is done, or while the pair has fallen
    /// back), and returns both results when both are done.
    pub(super) fn join<A, B, RA, RB>(&self, a: A, b: B) -> (RA, RB)
    where
        A: FnOnce() -> RA,
        B: FnOnce() -> RB + Send,
        RB: Send,
    {
        let mut rule = self.rule.get();
        let mut counts = self.counts.get();
        if !rule.splits() {
            rule.record(false);
            counts.alone += 1;
            self.rule.set(rule);
            self.counts.set(counts);
            let ra = a();
            return (ra, b());
        }
        let mut b = Some(b);
        let mut rb = None;
        let mut call = || {
            if let Some(f) = b.take() {
                rb = Some(f());
            }
        };
        let ptr: *mut (dyn FnMut() + Send + '_) = &mut call;
        // SAFETY: only the lifetime is erased; the worker calls the closure only after
        // winning JOB → RUNNING and stores DONE after it, and `Wait` below does not let this
        // frame go (return or unwind) before DONE or before the job is taken back.
        let ptr: JobPtr = unsafe { std::mem::transmute(ptr) };
        // SAFETY: the state is IDLE (every join ends with it), so the worker touches neither
        // slot now. A payload left by a join whose own half panicked first is dropped here,
        // so that it is not taken for this job's.
        unsafe {
            *self.shared.panic.get() = None;
            *self.shared.job.get() = Some(ptr);
        }
        self.shared.state.store(JOB, Ordering::SeqCst);
        if self.shared.worker_parked.load(Ordering::SeqCst) {
            self.worker.unpark();
        }
        let mut wait = Wait {
            shared: &self.shared,
            outcome: Outcome::Ran,
        };
        let ra = a();
        wait.finish();
        let outcome = wait.outcome;
        drop(wait);
        match outcome {
            Outcome::Stolen => {
                counts.stolen += 1;
                call();
            }
            Outcome::Parked => counts.parked += 1,
            Outcome::Ran => {}
        }
        if outcome != Outcome::Stolen {
            counts.split += 1;
        }
        rule.record(outcome != Outcome::Ran);
        self.rule.set(rule);
        self.counts.set(counts);
        // SAFETY: DONE was loaded in `Wait::finish` (or the job was taken back before the
        // worker started it): the worker no longer touches the slot.
        if let Some(p) = unsafe { (*self.shared.panic.get()).take() } {
            resume_unwind(p);
        }
        let rb = rb.take();
        (ra, rb.expect("the job ran"))
    }
}

impl Drop for SpinPair {
    fn drop(&mut self) {
        self.shared.state.store(QUIT, Ordering::SeqCst);
        self.worker.unpark();
    }
}

/// How a split join's job went.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Outcome {
    /// The worker ran it and the caller did not park.
    Ran,
    /// The worker had not started it: the caller took it back.
    Stolen,
    /// The worker ran it and the caller parked waiting.
    Parked,
}

/// Ends a split join: takes the job back when the worker has not started it, or waits for
/// the worker's DONE (also while unwinding from a panic of the calling thread's half, so that
/// the job's borrow is never released early), and leaves the state IDLE.
struct Wait<'a> {
    shared: &'a Shared,
    outcome: Outcome,
}

impl Wait<'_> {
    fn finish(&mut self) {
        let s = self.shared;
        if s.state.load(Ordering::Acquire) == IDLE {
            return; // finished already
        }
        if s.state
            .compare_exchange(JOB, IDLE, Ordering::AcqRel, Ordering::Acquire)
            .is_ok()
        {
            // SAFETY: the caller won JOB → IDLE, so the worker will not read the slot.
            unsafe { *s.job.get() = None };
            self.outcome = Outcome::Stolen;
            return;
        }
        let t0 = Instant::now();
        let mut k = 0u32;
        loop {
            if s.state.load(Ordering::Acquire) == DONE {
                break;
            }
            k += 1;
            if k.is_multiple_of(64) && t0.elapsed() > CALLER_SPIN {
                s.caller_parked.store(true, Ordering::SeqCst);
                while s.state.load(Ordering::SeqCst) != DONE {
                    std::thread::park();
                }
                s.caller_parked.store(false, Ordering::SeqCst);
                self.outcome = Outcome::Parked;
                break;
            }
            std::hint::spin_loop();
        }
        s.state.store(IDLE, Ordering::Release);
    }
}

impl Drop for Wait<'_> {
    fn drop(&mut self) {
        self.finish();
    }
}

/// The worker: waits for a job (spinning up to [`WORKER_SPIN`], then parked) or QUIT.
fn worker(s: &Shared) {
    let mut since: Option<Instant> = None;
    let mut k = 0u32;
    loop {
        match s.state.load(Ordering::Acquire) {
            JOB => {
                if s.state
                    .compare_exchange(JOB, RUNNING, Ordering::AcqRel, Ordering::Acquire)
                    .is_err()
                {
                    continue; // taken back by the caller
                }
                // SAFETY: the worker won JOB → RUNNING: the slot holds a pointer to a closure
                // the calling thread keeps alive until it loads DONE.
                let job = unsafe { (*s.job.get()).take() };
                if let Some(f) = job {
                    // SAFETY: as above; nobody else calls it.
                    let r = catch_unwind(AssertUnwindSafe(|| unsafe { (*f)() }));
                    if let Err(p) = r {
                        // SAFETY: the calling thread reads `panic` only after DONE.
                        unsafe { *s.panic.get() = Some(p) };
                    }
                }
                s.state.store(DONE, Ordering::SeqCst);
                if s.caller_parked.load(Ordering::SeqCst) {
                    s.caller.unpark();
                }
                since = None;
            }
            QUIT => return,
            _ => {
                k = k.wrapping_add(1);
                if !k.is_multiple_of(64) {
                    std::hint::spin_loop();
                    continue;
                }
                let t0 = *since.get_or_insert_with(Instant::now);
                if t0.elapsed() <= WORKER_SPIN {
                    std::hint::spin_loop();
                    continue;
                }
                s.worker_parked.store(true, Ordering::SeqCst);
                let st = s.state.load(Ordering::SeqCst);
                if st != JOB && st != QUIT {
                    std::thread::park();
                }
                s.worker_parked.store(false, Ordering::SeqCst);
                since = None;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{
        catch_unwind, AssertUnwindSafe, AtomicBool, Duration, FallBack, Instant, Mode, Ordering,
        SpinPair, ALONE_FIRST, ALONE_MAX, LATE_LIMIT, WINDOW, WORKER_SPIN,
    };
    #[test]
    fn both_halves_run_and_return_their_results() {
        std::thread::scope(|sc| {
            let pair = SpinPair::start(sc).expect("a thread");
            let mut v = vec![0u64; 1000];
            for k in 0..200u64 {
                let (left, right) = v.split_at_mut(500);
                let (a, b) = pair.join(
                    || {
                        left.iter_mut().for_each(|x| *x += k);
                        left.iter().sum::<u64>()
                    },
                    || {
                        right.iter_mut().for_each(|x| *x += 2 * k);
                        right.iter().sum::<u64>()
                    },
                );
                let t = k * (k + 1) / 2;
                assert_eq!(a, 500 * t);
                assert_eq!(b, 1000 * t);
            }
            let c = pair.counts();
            assert_eq!(c.split + c.stolen + c.alone, 200, "{c:?}");
        });
    }

    #[test]
    fn a_parked_worker_is_woken_or_its_job_taken_back() {
        std::thread::scope(|sc| {
            let pair = SpinPair::start(sc).expect("a thread");
            for k in 0..6u64 {
                // long enough for the worker to park between joins
                std::thread::sleep(2 * WORKER_SPIN);
                let slow = || {
                    std::thread::sleep(Duration::from_millis(2));
                    k
                };
                assert_eq!(pair.join(slow, || k + 1), (k, k + 1));
                // an instant caller half: the job is likely taken back before the worker wakes
                assert_eq!(pair.join(|| k, || 2 * k), (k, 2 * k));
            }
            let c = pair.counts();
            assert_eq!(c.split + c.stolen + c.alone, 12, "{c:?}");
        });
    }

    #[test]
    fn a_slow_worker_half_parks_the_caller_and_still_returns() {
        std::thread::scope(|sc| {
            let pair = SpinPair::start(sc).expect("a thread");
            // long against the caller's 50 µs of spinning, and against a time slice lost to
            // other work on a loaded machine (3 ms was missed under load)
            let slow = || {
                std::thread::sleep(Duration::from_millis(200));
                7
            };
            // the caller's half waits until the worker has started the job
            let started = AtomicBool::new(false);
            let (a, b) = pair.join(
                || {
                    let t0 = Instant::now();
                    while !started.load(Ordering::SeqCst) && t0.elapsed() < Duration::from_secs(5) {
                        std::hint::spin_loop();
                    }
                    1
                },
                || {
                    started.store(true, Ordering::SeqCst);
                    slow()
                },
            );
            assert_eq!((a, b), (1, 7));
            assert_eq!(pair.counts().parked, 1, "{:?}", pair.counts());
        });
    }

    #[test]
    fn a_panic_on_both_sides_leaves_no_payload_for_the_next_join() {
        std::thread::scope(|sc| {
            let pair = SpinPair::start(sc).expect("a thread");
            let r = catch_unwind(AssertUnwindSafe(|| {
                pair.join(|| panic!("caller"), || panic!("job"))
            }));
            assert!(r.is_err());
            assert_eq!(pair.join(|| 3, || 4), (3, 4));
        });
    }

    #[test]
    fn a_panic_on_the_worker_reaches_the_caller() {
        std::thread::scope(|sc| {
            let pair = SpinPair::start(sc).expect("a thread");
            let r = catch_unwind(AssertUnwindSafe(|| {
                pair.join(
                    || std::thread::sleep(Duration::from_millis(1)),
                    || panic!("job"),
                )
            }));
            assert!(r.is_err());
            // the pair still works afterwards
            assert_eq!(pair.join(|| 1, || 2), (1, 2));
        });
    }

    /// The fall-back rule: a window with more than `LATE_LIMIT` late joins runs `ALONE_FIRST`
    /// joins alone, then tries one window; a failed try doubles the run alone up to
    /// `ALONE_MAX`; a clean window resets it.
    #[test]
    fn the_fall_back_rule_backs_off_and_recovers() {
        let mut r = FallBack::default();
        // a clean window keeps splitting
        for _ in 0..WINDOW {
            assert!(r.splits());
            r.record(false);
        }
        assert_eq!(r.mode, Mode::Split { joins: 0, late: 0 });
        // LATE_LIMIT late joins are tolerated, one more falls back
        for _ in 0..LATE_LIMIT {
            r.record(true);
        }
        assert!(r.splits());
        r.record(true);
        assert_eq!(r.mode, Mode::Alone { left: ALONE_FIRST });
        let mut alone = 0;
        while !r.splits() {
            r.record(true); // ignored while alone
            alone += 1;
        }
        assert_eq!(alone, ALONE_FIRST);
        // a failed try: twice as long alone
        for _ in 0..=LATE_LIMIT {
            r.record(true);
        }
        assert_eq!(
            r.mode,
            Mode::Alone {
                left: 2 * ALONE_FIRST
            }
        );
        // many failures saturate at ALONE_MAX
        for _ in 0..20 {
            while !r.splits() {
                r.record(false);
            }
            for _ in 0..=LATE_LIMIT {
                r.record(true);
            }
        }
        assert_eq!(r.mode, Mode::Alone { left: ALONE_MAX });
        // a clean window after a try resets the next run alone to ALONE_FIRST
        while !r.splits() {
            r.record(false);
        }
        for _ in 0..WINDOW {
            r.record(false);
        }
        for _ in 0..=LATE_LIMIT {
            r.record(true);
        }
        assert_eq!(r.mode, Mode::Alone { left: ALONE_FIRST });
    }
}
