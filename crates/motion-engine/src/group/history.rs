//! Where the path was at each recent tick: so that a measurement a board took some time ago
//! is compared with where the path had the axis *then* (its link's stamp), not now.

use core::time::Duration;

/// Ticks remembered: longer than any board's refresh (the slowest, a Trinamic pack polled
/// round-robin on a shared 19200-baud bus, refreshes every ~135 ms); a measurement older
/// than this is not checked.
pub(crate) const HISTORY_TICKS: usize = 1024;

/// A ring of (tick time, path time) pairs, newest last. Fixed size, no allocation.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub(crate) struct PathHistory {
    #[serde(with = "motion_base::serde_boxed_array")]
    entries: Box<[(Duration, f64); HISTORY_TICKS]>,
    /// Index of the next entry written.
    next: usize,
    len: usize,
}

impl PathHistory {
    pub fn new() -> Self {
        Self {
            entries: Box::new([(Duration::ZERO, 0.0); HISTORY_TICKS]),
            next: 0,
            len: 0,
        }
    }

    pub fn clear(&mut self) {
        self.len = 0;
        self.next = 0;
    }

    /// At engine time `now` the path was at path time `tau`.
    pub fn push(&mut self, now: Duration, tau: f64) {
        self.entries[self.next] = (now, tau);
        self.next = (self.next + 1) % HISTORY_TICKS;
        self.len = (self.len + 1).min(HISTORY_TICKS);
    }

    /// The path time at instant `at`: interpolated between the ticks around it; `None`
    /// when `at` is before the oldest entry (before the motion started, or too long ago)
    /// or there is none. After the newest entry: the newest.
    pub fn at(&self, at: Duration) -> Option<f64> {
        if self.len == 0 {
            return None;
        }
        let index = |back: usize| (self.next + HISTORY_TICKS - 1 - back) % HISTORY_TICKS;
        let (newest_at, newest_tau) = self.entries[index(0)];
        if at >= newest_at {
            return Some(newest_tau);
        }
        for back in 1..self.len {
            let (then, tau) = self.entries[index(back)];
            if then <= at {
                let (later, later_tau) = self.entries[index(back - 1)];
                let span = (later - then).as_secs_f64();
                if span <= 0.0 {
                    return Some(later_tau);
                }
                let fraction = (at - then).as_secs_f64() / span;
                return Some(tau + (later_tau - tau) * fraction);
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ms(value: u64) -> Duration {
        Duration::from_millis(value)
    }

    #[test]
    fn interpolates_between_ticks_and_refuses_what_it_never_saw() {
        let mut history = PathHistory::new();
        assert_eq!(history.at(ms(5)), None);
        for tick in 10..20 {
            history.push(ms(tick), (tick - 10) as f64 / 1000.0);
        }
        assert_eq!(history.at(ms(9)), None);
        assert_eq!(history.at(ms(10)), Some(0.0));
        let between = history.at(Duration::from_micros(12_500)).expect("inside");
        assert!((between - 0.0025).abs() < 1e-12, "{between}");
        assert_eq!(history.at(ms(40)), Some(9.0 / 1000.0));
    }

    #[test]
    fn forgets_the_oldest_when_full() {
        let mut history = PathHistory::new();
        for tick in 0..(HISTORY_TICKS as u64 + 10) {
            history.push(ms(tick), tick as f64);
        }
        assert_eq!(history.at(ms(5)), None);
        assert_eq!(history.at(ms(10)), Some(10.0));
        history.clear();
        assert_eq!(history.at(ms(500)), None);
    }
}
