//! The few libln calls the core makes, as function pointers the Python bridge hands over
//! (it has libln loaded already, so the core needs no link-time dependency on it), and the
//! codes of ln.h's error table (LN_ETIMEOUT, ...), generated from it by build.rs.

use std::ffi::{c_char, c_int, c_void, CStr};

include!(concat!(env!("OUT_DIR"), "/ln_errors.rs"));

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

/// Declares the table and FN_NAMES, its field names in order, from one list.
macro_rules! fn_table {
    ($($name:ident: $ty:ty),* $(,)?) => {
        /// The functions `ln_<field>` of the caller's libln, in this order; the Python side
        /// builds its struct from FN_NAMES (lnz_libln_functions), so the order lives here.
        #[repr(C)]
        #[derive(Clone, Copy)]
        pub struct LnFns {
            $(pub $name: $ty,)*
        }

        /// The fields of LnFns, space-separated, NUL-terminated.
        pub const FN_NAMES: &str = concat!($(stringify!($name), " ",)* "\0");
    };
}

fn_table! {
    read_borrow: ReadBorrow,
    read_release: ReadRelease,
    write: Write,
    strerror: StrError,
    write_loan: WriteLoan,
    write_commit: WriteEnd,
    write_abort: WriteEnd,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fn_names_follow_the_struct() {
        let names: Vec<&str> = FN_NAMES.trim_end_matches('\0').split_whitespace().collect();
        assert_eq!(names, ["read_borrow", "read_release", "write", "strerror", "write_loan",
                           "write_commit", "write_abort"]);
        assert_eq!(std::mem::size_of::<LnFns>(), names.len() * std::mem::size_of::<usize>());
    }
}
