//! Wire faults requested on the command line, applied through the link's `SimFaults`.

use std::time::Duration;

use motion_link::sim::{Direction, SimFaults};

/// What to do to the bytes between the client and the boards.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaultPlan {
    /// Probability that a byte is lost, each direction.
    pub drop_rate: f64,
    /// One random byte put on the wire to the client this often.
    pub noise_every: Option<Duration>,
    /// Extra delay before every reply starts.
    pub reply_delay: Duration,
    next_noise: Duration,
}

impl FaultPlan {
    /// A plan; `noise_every` of zero means none.
    pub fn new(drop_rate: f64, noise_every: Duration, reply_delay: Duration) -> Self {
        Self {
            drop_rate,
            noise_every: (!noise_every.is_zero()).then_some(noise_every),
            reply_delay,
            next_noise: noise_every,
        }
    }

    /// Whether any fault is asked for.
    pub fn is_active(&self) -> bool {
        self.drop_rate > 0.0 || self.noise_every.is_some() || !self.reply_delay.is_zero()
    }

    /// One line for the log.
    pub fn describe(&self) -> String {
        let noise = self
            .noise_every
            .map_or_else(|| "none".to_owned(), |d| format!("1 byte every {d:?}"));
        format!(
            "faults: drop rate {}, noise {noise}, reply delay {:?}",
            self.drop_rate, self.reply_delay
        )
    }

    /// Sets the standing faults on a wire.
    pub fn apply(&self, faults: &SimFaults) {
        faults.set_drop_probability(Direction::ToHost, self.drop_rate);
        faults.set_drop_probability(Direction::ToDevice, self.drop_rate);
        faults.set_reply_delay(self.reply_delay);
    }

    /// Injects the noise due by `now`, at most `max_burst` bytes (missed ones are skipped).
    pub fn tick(&mut self, now: Duration, faults: &SimFaults, max_burst: usize) {
        let Some(every) = self.noise_every else {
            return;
        };
        let mut due = 0;
        while self.next_noise <= now && due < max_burst {
            self.next_noise += every;
            due += 1;
        }
        if due > 0 {
            faults.inject_noise(due);
        }
        if self.next_noise <= now {
            // Far behind (an idle socket, a stopped process): skip ahead, do not flood.
            self.next_noise = now + every;
        }
    }

    /// The next instant `tick` has work.
    pub fn next_event(&self) -> Option<Duration> {
        self.noise_every.map(|_| self.next_noise)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_comes_on_schedule_and_an_empty_plan_is_inactive() {
        assert!(!FaultPlan::new(0.0, Duration::ZERO, Duration::ZERO).is_active());
        let mut plan = FaultPlan::new(0.0, Duration::from_millis(10), Duration::ZERO);
        assert!(plan.is_active());
        assert_eq!(plan.next_event(), Some(Duration::from_millis(10)));
        let link = motion_link::sim::SimLink::spi("t", 1_000_000, Box::new(Idle));
        let faults = link.faults();
        plan.tick(Duration::from_millis(35), &faults, 100);
        assert_eq!(plan.next_event(), Some(Duration::from_millis(40)));
        plan.tick(Duration::from_millis(1000), &faults, 1);
        assert_eq!(plan.next_event(), Some(Duration::from_millis(1010)));
    }

    struct Idle;

    impl motion_link::sim::SpiDevice for Idle {
        fn transfer(&mut self, _now: Duration, _mosi: &[u8], _miso: &mut [u8]) -> bool {
            false
        }
        fn advance(&mut self, _now: Duration) {}
    }
}
