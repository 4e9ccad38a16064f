//! A request to stop, made by the program's Ctrl-C handler and read by the long loops of
//! a solve: the integrator's callbacks, the QP's iterations and the SQP's evaluations. A
//! solve asked to stop ends within a fraction of a second, inside an iteration too, at its
//! last accepted iterate. The library only reads the request; the command-line program
//! makes it.
//!
//! The request lasts for the rest of the process: a solve started after it stops at once.
//! The loops stop only while a solve runs ([`solving`]), so that the run folder of a
//! stopped solve is still written whole (its re-integration and report).

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

static REQUESTED: AtomicBool = AtomicBool::new(false);
static SOLVES_RUNNING: AtomicUsize = AtomicUsize::new(0);

/// What an evaluation or a QP that stopped on the request reports as its cause.
pub const STOPPED: &str = "stopped: an interrupt was requested";

/// Ask the running solves to stop; returns whether a stop had been asked already.
pub fn request() -> bool {
    REQUESTED.swap(true, Ordering::SeqCst)
}

/// Whether a stop has been asked.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}

/// Withdraw the request (for a program that goes on with other work after a stopped
/// solve, such as a notebook session).
pub fn clear() {
    REQUESTED.store(false, Ordering::SeqCst);
}

/// Whether a solve is running in this process.
pub fn in_solve() -> bool {
    SOLVES_RUNNING.load(Ordering::SeqCst) > 0
}

/// Whether the loop asking should stop now: a stop was asked while a solve runs. Cheap
/// (two atomic loads), for the innermost loops.
pub fn stop_now() -> bool {
    REQUESTED.load(Ordering::Relaxed) && SOLVES_RUNNING.load(Ordering::Relaxed) > 0
}

/// Marks a solve as running until dropped.
pub struct Solving(());

/// Mark a solve as running, until the returned guard is dropped.
pub fn solving() -> Solving {
    SOLVES_RUNNING.fetch_add(1, Ordering::SeqCst);
    Solving(())
}

impl Drop for Solving {
    fn drop(&mut self) {
        SOLVES_RUNNING.fetch_sub(1, Ordering::SeqCst);
    }
}
