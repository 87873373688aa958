//! A second thread that waits by spinning, for the fine-grained two-core split of a passage
//! that runs alone ([`super::PassageOptions::overlap`]).
//!
//! `rayon::join` costs a wake-up of a sleeping worker (a futex, several microseconds, and a
//! scheduler round trip) every time the worker has gone to sleep between two joins; at one
//! join per contact step (about 250 µs) the worker is asleep at every step, and the wake-ups
//! cost about what the damping product beside the contact saves. [`SpinPair`] keeps one
//! scoped thread busy-waiting on an atomic for the whole time loop, so that handing it a job
//! costs a cache-line transfer (well under a microsecond). The thread spins at 100 % of its
//! core while the loop runs: for a passage alone, never for sweeps and studies (whose
//! passages already fill the cores).
//!
//! The job is a borrowed closure (no allocation per hand-over); [`SpinPair::join`] returns
//! only after the worker has finished it, so the borrow outlives its use. A job that panics is
//! caught on the worker and resumed on the calling thread.

use std::cell::UnsafeCell;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;
use std::thread::Scope;

/// No job; the worker spins.
const IDLE: u8 = 0;
/// A job is in the slot; the worker runs it.
const JOB: u8 = 1;
/// The job is done (or panicked: the payload is in the slot).
const DONE: u8 = 2;
/// The worker returns.
const QUIT: u8 = 3;

/// A type-erased pointer to the job's closure (valid while [`SpinPair::join`] waits).
type JobPtr = *mut (dyn FnMut() + Send + 'static);

/// A panic's payload, carried from the worker to the calling thread.
type Payload = Box<dyn std::any::Any + Send + 'static>;

/// State shared by the calling thread and the worker.
struct Shared {
    state: AtomicU8,
    job: UnsafeCell<Option<JobPtr>>,
    panic: UnsafeCell<Option<Payload>>,
}

// SAFETY: `job` and `panic` are written by one thread at a time, handed over by `state`
// (Release on the store that publishes, Acquire on the load that takes): the calling thread
// writes `job` before storing JOB and reads `panic` after loading DONE; the worker reads
// `job` after loading JOB and writes `panic` before storing DONE.
unsafe impl Sync for Shared {}
// SAFETY: as for `Sync`: the pointer in `job` is dereferenced only by the thread the state
// hands it to, while the closure it points to is alive.
unsafe impl Send for Shared {}

/// The calling thread's handle of a spinning worker in a [`std::thread::scope`]. Dropping it
/// stops the worker.
pub(super) struct SpinPair {
    shared: Arc<Shared>,
}

impl SpinPair {
    /// Starts the worker in `scope`; `None` when the system refuses a thread (the caller
    /// then runs both halves itself).
    pub(super) fn start<'scope>(scope: &'scope Scope<'scope, '_>) -> Option<Self> {
        let shared = Arc::new(Shared {
            state: AtomicU8::new(IDLE),
            job: UnsafeCell::new(None),
            panic: UnsafeCell::new(None),
        });
        let s = shared.clone();
        std::thread::Builder::new()
            .name("passage-spin".into())
            .spawn_scoped(scope, move || worker(&s))
            .ok()?;
        Some(SpinPair { shared })
    }

    /// Runs `a` on the calling thread and `b` on the worker, and returns both results when
    /// both are done.
    pub(super) fn join<A, B, RA, RB>(&self, a: A, b: B) -> (RA, RB)
    where
        A: FnOnce() -> RA,
        B: FnOnce() -> RB + Send,
        RB: Send,
    {
        let mut b = Some(b);
        let mut rb = None;
        let mut call = || {
            if let Some(f) = b.take() {
                rb = Some(f());
            }
        };
        let ptr: *mut (dyn FnMut() + Send + '_) = &mut call;
        // SAFETY: only the lifetime is erased; the worker calls the closure before storing
        // DONE, and `Wait` below does not let this frame go (return or unwind) before DONE.
        let ptr: JobPtr = unsafe { std::mem::transmute(ptr) };
        // SAFETY: the state is IDLE (every join waits for DONE and resets it), so the worker
        // touches neither slot now. A payload left by a join whose own half panicked first
        // is dropped here, so that it is not taken for this job's.
        unsafe {
            *self.shared.panic.get() = None;
            *self.shared.job.get() = Some(ptr);
        }
        self.shared.state.store(JOB, Ordering::Release);
        let wait = Wait(&self.shared);
        let ra = a();
        drop(wait);
        // SAFETY: DONE was loaded (Acquire) in `Wait::drop`: the worker no longer touches it.
        if let Some(p) = unsafe { (*self.shared.panic.get()).take() } {
            resume_unwind(p);
        }
        let rb = rb.take();
        (ra, rb.expect("the worker ran the job"))
    }
}

impl Drop for SpinPair {
    fn drop(&mut self) {
        self.shared.state.store(QUIT, Ordering::Release);
    }
}

/// Waits for the worker's DONE (also while unwinding from a panic of the calling thread's
/// half, so that the job's borrow is never released early) and resets the state to IDLE.
struct Wait<'a>(&'a Shared);

impl Drop for Wait<'_> {
    fn drop(&mut self) {
        while self.0.state.load(Ordering::Acquire) != DONE {
            std::hint::spin_loop();
        }
        self.0.state.store(IDLE, Ordering::Relaxed);
    }
}

/// The worker: spins until a job or QUIT arrives.
fn worker(s: &Shared) {
    loop {
        match s.state.load(Ordering::Acquire) {
            JOB => {
                // SAFETY: JOB was loaded (Acquire): the slot holds a pointer to a closure the
                // calling thread keeps alive until it loads DONE.
                let job = unsafe { (*s.job.get()).take() };
                if let Some(f) = job {
                    // SAFETY: as above; nobody else calls it.
                    let r = catch_unwind(AssertUnwindSafe(|| unsafe { (*f)() }));
                    if let Err(p) = r {
                        // SAFETY: the calling thread reads `panic` only after DONE.
                        unsafe { *s.panic.get() = Some(p) };
                    }
                }
                s.state.store(DONE, Ordering::Release);
            }
            QUIT => return,
            _ => std::hint::spin_loop(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
            let r = catch_unwind(AssertUnwindSafe(|| pair.join(|| 1, || panic!("job"))));
            assert!(r.is_err());
            // the pair still works afterwards
            assert_eq!(pair.join(|| 1, || 2), (1, 2));
        });
    }
}
