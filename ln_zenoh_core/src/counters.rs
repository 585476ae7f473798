//! The counters of one bridged topic, shared with the Python side: it allocates the struct
//! (ctypes, the same field order as `TopicStats` of stats.py) and reads it when it reports;
//! the core adds to it.

use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

#[repr(C)]
pub struct Counters {
    pub read: AtomicU64,
    pub sent: AtomicU64,
    pub unmatched: AtomicU64,
    pub rate_limited: AtomicU64,
    pub overruns: AtomicU64,
    pub received: AtomicU64,
    pub published: AtomicU64,
    pub bad_attachment: AtomicU64,
    pub bad_size: AtomicU64,
    pub refused: AtomicU64,
    pub md_unavailable: AtomicU64,
    pub superseded: AtomicU64,
    pub gaps: AtomicU64,
    pub bytes: AtomicU64,
    pub errors: AtomicU64,
    pub last_seq: AtomicU64,
    pub forced: AtomicU64,
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
