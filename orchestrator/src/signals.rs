//! Ctrl-C / SIGTERM: the first asks the run to stop cleanly; which one it was gives the exit
//! code of the interrupted run (128 + the signal's number, the shell's convention).

use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};

static INTERRUPTED: AtomicBool = AtomicBool::new(false);
/// The first stop signal received (0: none, or a stop asked for by the program).
static SIGNAL: AtomicI32 = AtomicI32::new(0);

/// The shell's exit code of a command ended by signal `sig`: 128 + `sig`.
pub const SIGNAL_EXIT_BASE: i32 = 128;

extern "C" fn on_signal(sig: libc::c_int) {
    let _ = SIGNAL.compare_exchange(0, sig, Ordering::SeqCst, Ordering::SeqCst);
    INTERRUPTED.store(true, Ordering::SeqCst);
}

pub fn install() {
    // SAFETY: the handler only stores to atomics.
    unsafe {
        libc::signal(libc::SIGINT, on_signal as *const () as libc::sighandler_t);
        libc::signal(libc::SIGTERM, on_signal as *const () as libc::sighandler_t);
    }
}

pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

/// The exit code of a run stopped by a signal: 130 for SIGINT (Ctrl-C), 143 for SIGTERM
/// (SIGINT's code for a stop that came from no signal).
pub fn exit_code() -> i32 {
    match SIGNAL.load(Ordering::SeqCst) {
        0 => SIGNAL_EXIT_BASE + libc::SIGINT,
        s => SIGNAL_EXIT_BASE + s,
    }
}

/// Asks the run to stop as a Ctrl-C would (`bench restart` ends its run so).
pub fn request_stop() {
    INTERRUPTED.store(true, Ordering::SeqCst);
}

/// Forgets a stop request (after the run it ended).
pub fn clear() {
    INTERRUPTED.store(false, Ordering::SeqCst);
    SIGNAL.store(0, Ordering::SeqCst);
}
