//! The counters of one bridged topic, shared with the Python side: it allocates the struct
//! (ctypes, the fields of `TopicStats` of stats.py in this order) and reads it when it
//! reports; the core adds to it.  The order is written once here and exported as NAMES
//! (lnz_counter_names), which native.py checks against its own when it loads the core.

use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

/// Declares Counters and NAMES, its field names in order, from one list.
macro_rules! counters {
    ($($name:ident),* $(,)?) => {
        #[repr(C)]
        pub struct Counters {
            $(pub $name: AtomicU64,)*
        }

        /// The fields of Counters, space-separated, NUL-terminated.
        pub const NAMES: &str = concat!($(stringify!($name), " ",)* "\0");
    };
}

counters! {
    read, sent, unmatched, rate_limited, overruns, received, published, bad_attachment,
    bad_size, refused, md_unavailable, superseded, gaps, bytes, errors, last_seq, forced, batches,
    bad_batches,
}

/// A pointer to the Python side's counters, valid until the object using it is closed.
#[derive(Clone, Copy)]
pub struct Shared(pub *const Counters);

// SAFETY: only atomic operations go through it, and the owner outlives every user (the core
// stops using it before the close call that releases it returns).
unsafe impl Send for Shared {}
unsafe impl Sync for Shared {}

impl Shared {
    pub fn get(&self) -> &Counters {
        // SAFETY: see above.
        unsafe { &*self.0 }
    }
}

pub fn add(counter: &AtomicU64, n: u64) {
    counter.fetch_add(n, Relaxed);
}

pub fn set(counter: &AtomicU64, n: u64) {
    counter.store(n, Relaxed);
}

pub fn get(counter: &AtomicU64) -> u64 {
    counter.load(Relaxed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_follow_the_struct() {
        let n = NAMES.trim_end_matches('\0').split_whitespace().count();
        assert_eq!(n, 19);
        assert_eq!(std::mem::size_of::<Counters>(), n * 8);
        assert!(NAMES.starts_with("read sent ") && NAMES.ends_with(" forced batches bad_batches \0"));
    }
}
