//! A topic's rate limit: at most one sample per interval passes, the rest are counted.

use std::sync::Mutex;
use std::time::{Duration, Instant};

pub struct RateLimit {
    interval: Option<Duration>,
    next_ok: Mutex<Option<Instant>>,
}

impl RateLimit {
    /// `hz` samples per second; 0 (or less) is no limit.
    pub fn new(hz: f64) -> RateLimit {
        let interval = (hz > 0.0 && hz.is_finite()).then(|| Duration::from_secs_f64(1.0 / hz));
        RateLimit { interval, next_ok: Mutex::new(None) }
    }

    /// True if a sample may pass now.
    pub fn admit(&self) -> bool {
        let Some(interval) = self.interval else { return true };
        let now = Instant::now();
        let mut next = self.next_ok.lock().unwrap_or_else(|e| e.into_inner());
        if matches!(*next, Some(t) if now < t) {
            return false;
        }
        *next = Some(now + interval);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::RateLimit;

    #[test]
    fn limits_only_when_asked() {
        let none = RateLimit::new(0.0);
        assert!((0..100).all(|_| none.admit()));
        let slow = RateLimit::new(0.001); // one per 1000 s
        assert!(slow.admit());
        assert!(!slow.admit());
    }
}
