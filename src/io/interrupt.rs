//! Ctrl-C and termination: the first SIGINT or SIGTERM only raises a flag,
//! so that a run stops after its current batches and writes what it has
//! (atomically, with honest error bars); a second one ends the process as
//! usual, unless it comes within [`GRACE_NS`] of the first. Launchers send
//! the same signal twice at once: GNU `timeout -s INT` signals the child
//! and then its whole process group, and batch systems and MPI launchers
//! forward a signal to every process they started. Taking that echo for a
//! user's second Ctrl-C killed a third of such runs (4 of 12 under
//! `timeout`) with nothing written.

#![allow(unsafe_code)]

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// When the first signal came (`CLOCK_MONOTONIC` \[ns\], at least 1; 0:
/// none yet).
static FIRST_NS: AtomicU64 = AtomicU64::new(0);

/// A second signal this soon after the first \[ns\] is taken for the
/// first's echo and ignored: 2 s, far longer than a launcher takes to
/// repeat a signal and shorter than a user waits before pressing Ctrl-C
/// again.
pub const GRACE_NS: u64 = 2_000_000_000;

/// The monotonic clock \[ns\] (`clock_gettime` is async-signal-safe).
#[cfg(unix)]
fn now_ns() -> u64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid timespec to write to.
    unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut ts) };
    (ts.tv_sec as u64)
        .saturating_mul(1_000_000_000)
        .saturating_add(ts.tv_nsec as u64)
        .max(1)
}

#[cfg(unix)]
extern "C" fn on_signal(sig: libc::c_int) {
    // Async-signal-safe: atomics, `clock_gettime`, `signal` and `raise`.
    let now = now_ns();
    match FIRST_NS.compare_exchange(0, now, Ordering::SeqCst, Ordering::SeqCst) {
        Ok(_) => INTERRUPTED.store(true, Ordering::SeqCst),
        Err(first) if now.saturating_sub(first) < GRACE_NS => {} // an echo
        Err(_) => {
            // A second signal: end as the default action would.
            // SAFETY: restoring the default disposition and raising the
            // signal again are async-signal-safe.
            unsafe {
                libc::signal(sig, libc::SIG_DFL);
                libc::raise(sig);
            }
        }
    }
}

/// Catch SIGINT and SIGTERM (a no-op where signals do not exist).
pub fn install() {
    #[cfg(unix)]
    // SAFETY: the handler only touches atomics, reads the clock and, for a
    // second signal, restores the default action and raises it.
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
