//! The few libln calls the core makes, as function pointers the Python bridge hands over
//! (it has libln loaded already, so the core needs no link-time dependency on it), and the
//! codes of ln.h's error table it tells apart.

use std::ffi::{c_char, c_int, c_void, CStr};

pub const LN_ETIMEOUT: c_int = -3;
pub const LN_EAGAIN: c_int = -4;
pub const LN_EOVERRUN: c_int = -15;

/// struct ln_sample_info of ln.h.
#[repr(C)]
#[derive(Default, Clone, Copy)]
pub struct SampleInfo {
    pub seq: u64,
    pub timestamp_ns: i64,
    pub overruns: u64,
}

type ReadBorrow = unsafe extern "C" fn(*mut c_void, *mut *const c_void, f64, *mut SampleInfo) -> c_int;
type ReadRelease = unsafe extern "C" fn(*mut c_void) -> c_int;
type Write = unsafe extern "C" fn(*mut c_void, *const c_void, usize, f64) -> c_int;
type StrError = unsafe extern "C" fn(c_int) -> *const c_char;
type WriteLoan = unsafe extern "C" fn(*mut c_void, *mut *mut c_void, f64) -> c_int;
type WriteEnd = unsafe extern "C" fn(*mut c_void) -> c_int;

/// ln_read_borrow, ln_read_release, ln_write, ln_strerror, ln_write_loan, ln_write_commit and
/// ln_write_abort of the caller's libln (this order: native.py's LnFns).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct LnFns {
    pub read_borrow: ReadBorrow,
    pub read_release: ReadRelease,
    pub write: Write,
    pub strerror: StrError,
    pub write_loan: WriteLoan,
    pub write_commit: WriteEnd,
    pub write_abort: WriteEnd,
}

impl LnFns {
    /// The text of an LN_E* code.
    pub fn error_text(&self, code: c_int) -> String {
        // SAFETY: ln_strerror returns a static NUL-terminated string for any code.
        let text = unsafe { (self.strerror)(code) };
        if text.is_null() {
            return format!("error {code}");
        }
        unsafe { CStr::from_ptr(text) }.to_string_lossy().into_owned()
    }
}

/// An ln_inport or ln_outport owned by the Python side; the core uses it from one thread at
/// a time (ln.h allows that from any thread) and never after the call that gave it up.
#[derive(Clone, Copy)]
pub struct Port(pub *mut c_void);

// SAFETY: libln ports may be used from any thread, one at a time; the core guarantees the
// "one at a time" (one reader thread per outbound port, the write lock of an inbound topic).
unsafe impl Send for Port {}
unsafe impl Sync for Port {}
