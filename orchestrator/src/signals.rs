//! Ctrl-C / SIGTERM: the first asks the run to stop cleanly.

use std::sync::atomic::{AtomicBool, Ordering};

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

extern "C" fn on_signal(_: libc::c_int) {
    INTERRUPTED.store(true, Ordering::SeqCst);
}

pub fn install() {
    // SAFETY: the handler only stores to an atomic.
    unsafe {
        libc::signal(libc::SIGINT, on_signal as *const () as libc::sighandler_t);
        libc::signal(libc::SIGTERM, on_signal as *const () as libc::sighandler_t);
    }
}

pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

/// Asks the run to stop as a Ctrl-C would (`bench restart` ends its run so).
pub fn request_stop() {
    INTERRUPTED.store(true, Ordering::SeqCst);
}

/// Forgets a stop request (after the run it ended).
pub fn clear() {
    INTERRUPTED.store(false, Ordering::SeqCst);
}
