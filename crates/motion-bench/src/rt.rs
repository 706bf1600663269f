//! The monotonic clock and the real-time knobs the bench applies to its own threads, the
//! same ones motiond applies to its tick thread (crate motion-rt).

use core::time::Duration;

use motion_rt::{monotonic_now, pin_to, set_fifo, set_timer_slack, sleep_until};

/// CLOCK_MONOTONIC now, in ns (the clock of `MotionFrame::publish_ns` and `time_ns`).
pub fn now_ns() -> u64 {
    u64::try_from(monotonic_now().as_nanos()).unwrap_or(u64::MAX)
}

/// Sleeps until the absolute CLOCK_MONOTONIC instant `deadline_ns` (TIMER_ABSTIME).
pub fn sleep_until_ns(deadline_ns: u64) {
    sleep_until(Duration::from_nanos(deadline_ns));
}

/// What a thread's set-up achieved, one line for the report.
#[derive(Debug, Clone, Default)]
pub struct ThreadSetup {
    /// Words that describe what is in force ("SCHED_FIFO 80", "cpu 1", "slack 1ns").
    pub applied: Vec<String>,
    /// What could not be done.
    pub problems: Vec<String>,
}

impl ThreadSetup {
    /// `SCHED_FIFO 80, cpu 1, slack 1ns` or `SCHED_OTHER, slack 1ns`.
    pub fn describe(&self) -> String {
        let mut words = self.applied.clone();
        if !words.iter().any(|w| w.starts_with("SCHED_FIFO")) {
            words.insert(0, "SCHED_OTHER".to_owned());
        }
        let mut line = words.join(", ");
        if !self.problems.is_empty() {
            line.push_str(" (");
            line.push_str(&self.problems.join("; "));
            line.push(')');
        }
        line
    }
}

/// The SCHED_FIFO priority of the bench's simulated boards' threads (0: normal policy).
static BOARD_PRIORITY: std::sync::atomic::AtomicU8 = std::sync::atomic::AtomicU8::new(0);

/// Runs the threads that simulate boards (started after this call) at SCHED_FIFO
/// `priority`: with `--rt-priority` they stand for external hardware, which has processors
/// of its own and is never kept waiting by the server it talks to.
pub fn set_board_priority(priority: Option<u8>) {
    BOARD_PRIORITY.store(priority.unwrap_or(0), std::sync::atomic::Ordering::Relaxed);
}

/// The priority [`set_board_priority`] gave.
pub fn board_priority() -> Option<u8> {
    let priority = BOARD_PRIORITY.load(std::sync::atomic::Ordering::Relaxed);
    (priority > 0).then_some(priority)
}

/// Applies timer slack 1 ns, then SCHED_FIFO `priority` and the pinning to `cpu` when given,
/// to the calling thread.
pub fn set_up_thread(priority: Option<u8>, cpu: Option<usize>) -> ThreadSetup {
    let mut setup = ThreadSetup::default();
    match set_timer_slack() {
        Ok(()) => setup.applied.push("slack 1ns".to_owned()),
        Err(e) => setup.problems.push(e.to_string()),
    }
    if let Some(priority) = priority {
        match set_fifo(priority) {
            Ok(()) => setup.applied.insert(0, format!("SCHED_FIFO {priority}")),
            Err(e) => setup.problems.push(e.to_string()),
        }
    }
    if let Some(cpu) = cpu {
        match pin_to(cpu) {
            Ok(()) => setup.applied.push(format!("cpu {cpu}")),
            Err(e) => setup.problems.push(e.to_string()),
        }
    }
    setup
}

/// Holds `/dev/cpu_dma_latency` at 0 while alive, as motiond and cyclictest do.
#[derive(Debug)]
pub struct DmaLatency {
    _guard: motion_rt::DmaLatencyGuard,
}

impl DmaLatency {
    /// Asks for 0 µs exit latency; the error says why not (usually: not root).
    pub fn hold() -> Result<Self, String> {
        motion_rt::DmaLatencyGuard::hold()
            .map(|guard| Self { _guard: guard })
            .map_err(|e| e.to_string())
    }
}

/// A small deterministic xorshift generator (request pacing; no dependency needed).
#[derive(Debug, Clone)]
pub struct XorShift(u64);

impl XorShift {
    /// Seeded; a zero seed is replaced.
    pub fn new(seed: u64) -> Self {
        Self(if seed == 0 {
            0x9E37_79B9_7F4A_7C15
        } else {
            seed
        })
    }

    /// Uniform in `0..bound` (`bound` > 0).
    pub fn below(&mut self, bound: u64) -> u64 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x % bound.max(1)
    }
}
