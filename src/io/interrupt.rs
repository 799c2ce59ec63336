//! Ctrl-C and termination: the first SIGINT or SIGTERM only raises a flag,
//! so that a run stops after its current batches and writes what it has
//! (atomically, with honest error bars); a second one ends the process as
//! usual.

#![allow(unsafe_code)]

use std::sync::atomic::{AtomicBool, Ordering};

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

#[cfg(unix)]
extern "C" fn on_signal(_sig: libc::c_int) {
    // Async-signal-safe: an atomic store and `signal` itself.
    INTERRUPTED.store(true, Ordering::SeqCst);
    // SAFETY: restoring the default disposition is async-signal-safe.
    unsafe {
        libc::signal(libc::SIGINT, libc::SIG_DFL);
        libc::signal(libc::SIGTERM, libc::SIG_DFL);
    }
}

/// Catch SIGINT and SIGTERM (once each; a no-op where signals do not exist).
pub fn install() {
    #[cfg(unix)]
    // SAFETY: the handler only stores to an atomic and resets the handlers.
    unsafe {
        let h = on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
        libc::signal(libc::SIGINT, h);
        libc::signal(libc::SIGTERM, h);
    }
}

/// Whether a SIGINT or SIGTERM arrived since [`install`].
pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}
