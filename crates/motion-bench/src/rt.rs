//! The monotonic clock and the real-time knobs the bench applies to its own threads, the
//! same ones motiond applies to its tick thread (crates/motiond/src/rt.rs).
#![allow(unsafe_code)] // sched_setscheduler has no safe wrapper in nix; see the SAFETY note

use std::fs::File;
use std::io::Write;

use nix::sys::time::TimeSpec;
use nix::time::{ClockId, ClockNanosleepFlags, clock_gettime, clock_nanosleep};

/// CLOCK_MONOTONIC now, in ns (the clock of `MotionFrame::publish_ns` and `time_ns`).
pub fn now_ns() -> u64 {
    clock_gettime(ClockId::CLOCK_MONOTONIC).map_or(0, |t| {
        (t.tv_sec() as u64)
            .saturating_mul(1_000_000_000)
            .saturating_add(t.tv_nsec() as u64)
    })
}

/// Sleeps until the absolute CLOCK_MONOTONIC instant `deadline_ns` (TIMER_ABSTIME).
pub fn sleep_until_ns(deadline_ns: u64) {
    let target = TimeSpec::new(
        (deadline_ns / 1_000_000_000) as libc::time_t,
        (deadline_ns % 1_000_000_000) as libc::c_long,
    );
    while let Err(nix::errno::Errno::EINTR) = clock_nanosleep(
        ClockId::CLOCK_MONOTONIC,
        ClockNanosleepFlags::TIMER_ABSTIME,
        &target,
    ) {}
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
    match nix::sys::prctl::set_timerslack(1) {
        Ok(()) => setup.applied.push("slack 1ns".to_owned()),
        Err(e) => setup.problems.push(format!("PR_SET_TIMERSLACK: {e}")),
    }
    if let Some(priority) = priority {
        match set_fifo(priority) {
            Ok(()) => setup.applied.insert(0, format!("SCHED_FIFO {priority}")),
            Err(e) => setup.problems.push(e),
        }
    }
    if let Some(cpu) = cpu {
        match pin_to(cpu) {
            Ok(()) => setup.applied.push(format!("cpu {cpu}")),
            Err(e) => setup.problems.push(e),
        }
    }
    setup
}

fn set_fifo(priority: u8) -> Result<(), String> {
    let param = libc::sched_param {
        sched_priority: i32::from(priority),
    };
    // SAFETY: `param` is a valid, initialised sched_param that outlives the call; pid 0 is
    // the calling thread; the call only reads `param`.
    let result = unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) };
    if result == 0 {
        Ok(())
    } else {
        Err(format!(
            "SCHED_FIFO {priority}: {} (needs CAP_SYS_NICE or an rtprio limit)",
            std::io::Error::last_os_error()
        ))
    }
}

fn pin_to(cpu: usize) -> Result<(), String> {
    let mut set = nix::sched::CpuSet::new();
    set.set(cpu).map_err(|e| format!("cpu {cpu}: {e}"))?;
    nix::sched::sched_setaffinity(nix::unistd::Pid::from_raw(0), &set)
        .map_err(|e| format!("cpu {cpu}: sched_setaffinity: {e}"))
}

/// Holds `/dev/cpu_dma_latency` at 0 while alive, as motiond and cyclictest do.
#[derive(Debug)]
pub struct DmaLatency {
    _file: File,
}

impl DmaLatency {
    /// Asks for 0 µs exit latency; the error says why not (usually: not root).
    pub fn hold() -> Result<Self, String> {
        let mut file = File::options()
            .write(true)
            .open("/dev/cpu_dma_latency")
            .map_err(|e| format!("/dev/cpu_dma_latency: {e}"))?;
        file.write_all(&0i32.to_ne_bytes())
            .map_err(|e| format!("/dev/cpu_dma_latency: write: {e}"))?;
        Ok(Self { _file: file })
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
