//! [`Error`]: one variant per entry of libln's error table `LN_ERRNO_MAP` (ln.h), generated at
//! build time through the sys crate's `ln_errno_map!`, so no code is written here as a literal.
//! Names and texts come from libln (`ln_error_name`, `ln_strerror`); each error carries the
//! context text of `ln_last_error()` taken on the thread that saw the failure.

use std::ffi::{c_int, CStr};
use std::fmt;

use crate::sys;

/// The context text of a failure (`ln_last_error()`: topic, md, sizes, errno), if any.
#[derive(Clone, Default, PartialEq, Eq)]
pub struct Detail(Option<Box<str>>);

impl Detail {
    /// No context text.
    pub const fn none() -> Detail {
        Detail(None)
    }

    /// The text, if there is one.
    pub fn as_str(&self) -> Option<&str> {
        self.0.as_deref()
    }

    pub(crate) fn from_text(text: &str) -> Detail {
        if text.is_empty() {
            Detail(None)
        } else {
            Detail(Some(text.into()))
        }
    }
}

impl From<String> for Detail {
    fn from(text: String) -> Detail {
        Detail::from_text(&text)
    }
}

impl fmt::Debug for Detail {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(&self.0, f)
    }
}

macro_rules! define_error {
    ($(($name:ident, $code:literal, $text:literal)),* $(,)?) => {
        /// A failure of libln: one variant per `LN_E*` code of ln.h's error table (the
        /// variant's documentation is libln's text for it), each with the context text of
        /// `ln_last_error()` where libln gave one.  Match with `Error::ETIMEOUT(_)` etc.
        #[derive(Clone, PartialEq, Eq)]
        #[non_exhaustive]
        #[allow(clippy::upper_case_acronyms)]
        pub enum Error {
            $(#[doc = $text] $name(Detail),)*
            /// A code that is not in this build's table (a newer libln).
            Unknown(c_int, Detail),
        }

        impl Error {
            /// The negative `LN_E*` code.
            pub fn code(&self) -> c_int {
                match self {
                    $(Error::$name(_) => $code,)*
                    Error::Unknown(code, _) => *code,
                }
            }

            /// The error of a negative libln return code with the given context text.
            pub fn with_detail(code: c_int, detail: Detail) -> Error {
                match code {
                    $($code => Error::$name(detail),)*
                    _ => Error::Unknown(code, detail),
                }
            }

            /// The context text, if libln gave one.
            pub fn detail(&self) -> Option<&str> {
                match self {
                    $(Error::$name(d) => d.as_str(),)*
                    Error::Unknown(_, d) => d.as_str(),
                }
            }
        }
    };
}

sys::ln_errno_map!(define_error);

/// `std::result::Result` with this crate's [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// The error of a negative libln return code, without context text (allocates nothing).
    pub fn from_code(code: c_int) -> Error {
        Error::with_detail(code, Detail::none())
    }

    /// The error of a negative return code of a libln call that just failed on this thread,
    /// with the thread's `ln_last_error()` text.
    pub fn last(code: c_int) -> Error {
        // SAFETY: ln_last_error never returns NULL; the text stays valid until this thread's
        // next failing libln call, and is copied here at once.
        let text = unsafe { CStr::from_ptr(sys::ln_last_error()) };
        Error::with_detail(code, Detail::from_text(&text.to_string_lossy()))
    }

    /// The table name without the `LN_` prefix ("ETIMEOUT"), from `ln_error_name`.
    pub fn name(&self) -> &'static str {
        // SAFETY: ln_error_name returns NULL or a static NUL-terminated string.
        let p = unsafe { sys::ln_error_name(self.code()) };
        if p.is_null() {
            return "unknown";
        }
        // SAFETY: static string of libln (see above).
        unsafe { CStr::from_ptr(p) }.to_str().unwrap_or("unknown")
    }

    /// libln's text for the code (`ln_strerror`).
    pub fn text(&self) -> &'static str {
        // SAFETY: ln_strerror never returns NULL; the string is static.
        unsafe { CStr::from_ptr(sys::ln_strerror(self.code())) }
            .to_str()
            .unwrap_or("unknown error")
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.detail() {
            Some(detail) if detail != self.text() => write!(f, "{}: {detail}", self.text()),
            _ => f.write_str(self.text()),
        }
    }
}

impl fmt::Debug for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}({})", self.name(), self)
    }
}

impl std::error::Error for Error {}

/// `Ok(rc)` for a libln return code >= 0, else the error with this thread's
/// `ln_last_error()` text.  Call it right after the failing call, on the same thread.
pub(crate) fn check(rc: c_int) -> Result<c_int> {
    if rc >= 0 {
        Ok(rc)
    } else {
        Err(Error::last(rc))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_code_of_the_library_maps_to_its_variant_name_and_text() {
        // SAFETY: plain queries of static data.
        let count = unsafe { sys::ln_error_count() };
        assert!(count > 0);
        for code in -count..0 {
            let err = Error::from_code(code);
            assert_eq!(err.code(), code);
            // SAFETY: static strings of libln for codes of its table.
            let name = unsafe { CStr::from_ptr(sys::ln_error_name(code)) };
            assert_eq!(err.name(), name.to_str().unwrap());
            assert!(!matches!(err, Error::Unknown(..)), "{code} has a variant");
            assert_eq!(err.to_string(), err.text());
        }
        let unknown = Error::from_code(-count - 1);
        assert!(matches!(unknown, Error::Unknown(..)));
        assert_eq!(unknown.text(), "unknown error");
    }

    #[test]
    fn display_adds_the_detail_text() {
        let err = Error::with_detail(sys::LN_ETIMEOUT, "topic t.x after 1 s".to_string().into());
        assert!(matches!(err, Error::ETIMEOUT(_)));
        assert_eq!(
            err.to_string(),
            format!("{}: topic t.x after 1 s", err.text())
        );
        assert_eq!(format!("{err:?}"), format!("ETIMEOUT({err})"));
        assert_eq!(check(3).unwrap(), 3);
    }
}
