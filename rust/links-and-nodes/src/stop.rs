//! Ending a node cleanly on SIGTERM/SIGINT (docs/rust.md "Stopping"): the manager stops a
//! process with its term signal, and a node that dies of it skips its `Drop`s.  [`StopSignal`]
//! catches both signals into a flag the control loop polls, so the loop ends, handles drop
//! and the client unregisters.  Slow system calls are restarted (SA_RESTART), so a blocking
//! read ends at its timeout: keep the loop's timeouts short.

use std::ffi::c_int;
use std::sync::atomic::{AtomicI32, Ordering};

use crate::error::{Error, Result};
use crate::sys;

const SIGINT: c_int = 2;
const SIGTERM: c_int = 15;
/// `SIG_ERR` of `signal(2)`: `(sighandler_t) -1`.
const SIG_ERR: usize = usize::MAX;

/// The signal that asked to stop (0: none yet); set by the handler, read by the loop.
static STOP: AtomicI32 = AtomicI32::new(0);

extern "C" {
    /// glibc's `signal(2)`: BSD semantics (the handler stays, SA_RESTART).
    fn signal(signum: c_int, handler: extern "C" fn(c_int)) -> usize;
}

extern "C" fn on_stop(signum: c_int) {
    // async-signal-safe: one atomic store
    STOP.store(signum, Ordering::SeqCst);
}

/// The process-wide flag of SIGTERM and SIGINT; see [`StopSignal::install`].  `Copy`,
/// `Send` and `Sync`: every thread may poll it.
#[derive(Debug, Clone, Copy)]
pub struct StopSignal(());

impl StopSignal {
    /// Catches SIGTERM and SIGINT from now on (instead of dying of them).  Installing again
    /// is harmless.
    pub fn install() -> Result<StopSignal> {
        for signum in [SIGTERM, SIGINT] {
            // SAFETY: on_stop is async-signal-safe (one atomic store) and lives forever.
            if unsafe { signal(signum, on_stop) } == SIG_ERR {
                return Err(Error::from_code(sys::LN_EINVAL));
            }
        }
        Ok(StopSignal(()))
    }

    /// Whether SIGTERM or SIGINT came.
    pub fn requested(&self) -> bool {
        STOP.load(Ordering::SeqCst) != 0
    }

    /// The signal that came ("SIGTERM" or "SIGINT"), `None` if none did.
    pub fn name(&self) -> Option<&'static str> {
        match STOP.load(Ordering::SeqCst) {
            0 => None,
            SIGINT => Some("SIGINT"),
            _ => Some("SIGTERM"),
        }
    }
}
