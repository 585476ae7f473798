//! Lines the core has to say go to the bridge's log through a callback of the Python side;
//! complaints about the same kind of bad sample are said at most every 5 s.

use std::collections::HashMap;
use std::ffi::{c_char, c_void, CString};
use std::sync::Mutex;
use std::time::{Duration, Instant};

pub type LogFn = unsafe extern "C" fn(ctx: *mut c_void, text: *const c_char);

const COMPLAIN_EVERY: Duration = Duration::from_secs(5);

#[derive(Clone, Copy)]
pub struct Logger {
    func: LogFn,
    ctx: *mut c_void,
}

// SAFETY: the callback is a ctypes function, callable from any thread (it takes the GIL);
// ctx is opaque to the core.
unsafe impl Send for Logger {}
unsafe impl Sync for Logger {}

impl Logger {
    pub fn new(func: LogFn, ctx: *mut c_void) -> Logger {
        Logger { func, ctx }
    }

    pub fn say(&self, text: &str) {
        let line = CString::new(text.replace('\0', "\\0")).unwrap_or_default();
        // SAFETY: a valid NUL-terminated string for the duration of the call.
        unsafe { (self.func)(self.ctx, line.as_ptr()) }
    }
}

/// Says `label: text`, but a kind of complaint at most every COMPLAIN_EVERY.
pub struct Complainer {
    logger: Logger,
    label: String,
    last: Mutex<HashMap<&'static str, Instant>>,
}

impl Complainer {
    pub fn new(logger: Logger, label: String) -> Complainer {
        Complainer { logger, label, last: Mutex::new(HashMap::new()) }
    }

    pub fn complain(&self, kind: &'static str, text: impl FnOnce() -> String) {
        let now = Instant::now();
        {
            let mut last = self.last.lock().unwrap_or_else(|e| e.into_inner());
            if let Some(t) = last.get(kind) {
                if now.duration_since(*t) < COMPLAIN_EVERY {
                    return;
                }
            }
            last.insert(kind, now);
        }
        self.logger.say(&format!("{}: {}", self.label, text()));
    }
}
