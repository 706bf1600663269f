//! The tick's work phase by phase, by the counting-clock method: with the `tick-profile`
//! feature (`cargo run --release --features tick-profile`) the tick thread reads
//! CLOCK_MONOTONIC at each phase boundary, sums the laps in a fixed array (no allocation)
//! and every [`REPORT_EVERY`] ticks hands the means to the main thread, which logs them.
//! Without the feature every call is empty and compiles away: the production tick reads
//! no extra clock.

use core::time::Duration;

/// The phases of one tick, in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Link events, write reports and received bytes to the engine.
    Input = 0,
    /// Dead clients, the e-stop event and signal, the liveness check.
    Clients = 1,
    /// Loan the frame, `Engine::step` (commands, drivers, supervision), publish, notify.
    Step = 2,
    /// The drivers' messages into the I/O threads' rings, their wake-ups.
    Output = 3,
    /// Fault reports, the stats once a second, device state changes.
    Reports = 4,
}

/// How many phases.
pub const PHASES: usize = 5;

/// What each phase is called in the log.
pub const PHASE_NAMES: [&str; PHASES] = [
    "link input",
    "clients and e-stops",
    "step and publish",
    "link output and wake-ups",
    "reports",
];

/// Ticks between two reports.
pub const REPORT_EVERY: u64 = 5000;

/// The mean of each phase over the last [`REPORT_EVERY`] ticks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PhaseMeans {
    /// Ticks measured.
    pub ticks: u64,
    /// Mean time of each [`Phase`], ns.
    pub mean_ns: [u64; PHASES],
}

impl PhaseMeans {
    /// One log line: each phase's mean and the sum.
    pub fn line(&self) -> String {
        let parts: Vec<String> = PHASE_NAMES
            .iter()
            .zip(self.mean_ns)
            .map(|(name, ns)| format!("{name} {:.1} µs", ns as f64 / 1000.0))
            .collect();
        let total: u64 = self.mean_ns.iter().sum();
        format!(
            "tick phases, mean of {} ticks: {} | sum {:.1} µs",
            self.ticks,
            parts.join(" | "),
            total as f64 / 1000.0
        )
    }
}

/// The counting clock of the tick thread.
#[derive(Debug, Default)]
pub struct PhaseClock {
    #[cfg(feature = "tick-profile")]
    lap_from: Duration,
    #[cfg(feature = "tick-profile")]
    sums: [u64; PHASES],
    #[cfg(feature = "tick-profile")]
    ticks: u64,
}

#[cfg(feature = "tick-profile")]
impl PhaseClock {
    /// The tick's work begins at `now`.
    pub fn begin(&mut self, now: Duration) {
        self.lap_from = now;
    }

    /// `phase` ended now.
    pub fn lap(&mut self, phase: Phase) {
        let now = crate::rt::monotonic_now();
        let ns = u64::try_from(now.saturating_sub(self.lap_from).as_nanos()).unwrap_or(u64::MAX);
        if let Some(sum) = self.sums.get_mut(phase as usize) {
            *sum = sum.saturating_add(ns);
        }
        self.lap_from = now;
    }

    /// The tick is done; every [`REPORT_EVERY`] ticks, the means (and a fresh start).
    pub fn end_tick(&mut self) -> Option<PhaseMeans> {
        self.ticks += 1;
        if self.ticks < REPORT_EVERY {
            return None;
        }
        let means = PhaseMeans {
            ticks: self.ticks,
            mean_ns: self.sums.map(|sum| sum / self.ticks),
        };
        self.sums = [0; PHASES];
        self.ticks = 0;
        Some(means)
    }
}

#[cfg(not(feature = "tick-profile"))]
impl PhaseClock {
    /// The tick's work begins at `now` (nothing to do without `tick-profile`).
    #[inline(always)]
    pub fn begin(&mut self, _now: Duration) {}

    /// `phase` ended now (nothing to do without `tick-profile`).
    #[inline(always)]
    pub fn lap(&mut self, _phase: Phase) {}

    /// The tick is done (never a report without `tick-profile`).
    #[inline(always)]
    pub fn end_tick(&mut self) -> Option<PhaseMeans> {
        None
    }
}

#[cfg(all(test, feature = "tick-profile"))]
mod tests {
    use super::*;

    #[test]
    fn laps_add_up_per_phase_and_are_reported_as_means() {
        let mut clock = PhaseClock::default();
        for _ in 0..REPORT_EVERY - 1 {
            clock.begin(crate::rt::monotonic_now());
            clock.lap(Phase::Input);
            clock.lap(Phase::Step);
            assert!(clock.end_tick().is_none());
        }
        clock.begin(crate::rt::monotonic_now());
        std::thread::sleep(Duration::from_millis(5));
        clock.lap(Phase::Output);
        let means = clock.end_tick().expect("a report every REPORT_EVERY ticks");
        assert_eq!(means.ticks, REPORT_EVERY);
        // 5 ms in one tick of 5000: at least 1 µs on average.
        assert!(means.mean_ns[Phase::Output as usize] >= 1000, "{means:?}");
        assert_eq!(means.mean_ns[Phase::Clients as usize], 0);
        assert!(means.line().contains("link output and wake-ups"));
        // And it starts over.
        clock.begin(crate::rt::monotonic_now());
        assert!(clock.end_tick().is_none());
    }
}
