//! The real-time knobs a thread applies to itself, and the monotonic clock they are timed
//! by: one implementation for motiond's tick and I/O threads, the bench's threads and the
//! test kit's board threads (docs/ARCHITECTURE.md reports each measured). Each knob says
//! what went wrong ([`RtError`]); whether that stops anything is the caller's decision.
#![warn(missing_docs)]
#![deny(unsafe_code)] // two exceptions, sched_setscheduler and setpriority: SAFETY notes

use core::time::Duration;
use std::fs::File;
use std::io::{self, Write as _};

use nix::sys::time::TimeSpec;
use nix::time::{ClockId, ClockNanosleepFlags, clock_gettime, clock_nanosleep};

/// A real-time set-up step that could not be done.
#[derive(Debug, thiserror::Error)]
pub enum RtError {
    /// `/dev/cpu_dma_latency` could not be opened.
    #[error("/dev/cpu_dma_latency: {0} (needs root or a udev rule)")]
    DmaLatencyOpen(#[source] io::Error),
    /// `/dev/cpu_dma_latency` could not be written.
    #[error("/dev/cpu_dma_latency: write: {0}")]
    DmaLatencyWrite(#[source] io::Error),
    /// `PR_SET_TIMERSLACK` failed.
    #[error("PR_SET_TIMERSLACK: {0}")]
    TimerSlack(#[source] nix::Error),
    /// `sched_setscheduler(SCHED_FIFO)` failed.
    #[error(
        "SCHED_FIFO priority {priority}: {source} (needs CAP_SYS_NICE or `ulimit -r {priority}`)"
    )]
    Fifo {
        /// The priority asked for.
        priority: u8,
        /// The system's answer.
        #[source]
        source: io::Error,
    },
    /// `setpriority` failed.
    #[error("nice {nice}: {source} (needs CAP_SYS_NICE or `ulimit -e`)")]
    Nice {
        /// The nice value asked for.
        nice: i32,
        /// The system's answer.
        #[source]
        source: io::Error,
    },
    /// The core is not available to this process.
    #[error("cpu {0}: no such core available to this process")]
    NoSuchCpu(usize),
    /// `sched_setaffinity` failed.
    #[error("cpu {0}: sched_setaffinity failed")]
    Affinity(usize),
    /// `mlockall` failed.
    #[error("mlockall: {0} (raise RLIMIT_MEMLOCK, e.g. `ulimit -l unlimited`, or run as root)")]
    LockMemory(#[source] nix::Error),
}

/// CLOCK_MONOTONIC now, as a duration since the clock's own origin (the clock of
/// `MotionFrame::publish_ns`).
pub fn monotonic_now() -> Duration {
    clock_gettime(ClockId::CLOCK_MONOTONIC).map_or(Duration::ZERO, Duration::from)
}

/// Sleeps until the absolute CLOCK_MONOTONIC instant `deadline` (TIMER_ABSTIME: no drift),
/// resuming after signals.
pub fn sleep_until(deadline: Duration) {
    let target = TimeSpec::from_duration(deadline);
    while let Err(nix::errno::Errno::EINTR) = clock_nanosleep(
        ClockId::CLOCK_MONOTONIC,
        ClockNanosleepFlags::TIMER_ABSTIME,
        &target,
    ) {}
}

/// Switches the calling thread to SCHED_FIFO at `priority`.
pub fn set_fifo(priority: u8) -> Result<(), RtError> {
    let param = libc::sched_param {
        sched_priority: i32::from(priority),
    };
    #[allow(unsafe_code)]
    // SAFETY: `param` is a valid, initialised sched_param that lives across the call; pid 0
    // means the calling thread; the call only reads `param`.
    let result = unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) };
    if result == 0 {
        Ok(())
    } else {
        Err(RtError::Fifo {
            priority,
            source: io::Error::last_os_error(),
        })
    }
}

/// Sets the calling thread's nice value (it keeps the normal policy).
pub fn set_nice(nice: i32) -> Result<(), RtError> {
    let tid = nix::unistd::gettid().as_raw();
    #[allow(unsafe_code)]
    // SAFETY: plain integer arguments; PRIO_PROCESS with a thread id sets that thread's
    // nice value on Linux.
    let result = unsafe { libc::setpriority(libc::PRIO_PROCESS, tid as libc::id_t, nice) };
    if result == 0 {
        Ok(())
    } else {
        Err(RtError::Nice {
            nice,
            source: io::Error::last_os_error(),
        })
    }
}

/// Pins the calling thread to `cpu`.
pub fn pin_to(cpu: usize) -> Result<(), RtError> {
    let cores = core_affinity::get_core_ids().unwrap_or_default();
    let Some(core) = cores.into_iter().find(|core| core.id == cpu) else {
        return Err(RtError::NoSuchCpu(cpu));
    };
    if core_affinity::set_for_current(core) {
        Ok(())
    } else {
        Err(RtError::Affinity(cpu))
    }
}

/// Sets the calling thread's timer slack to 1 ns (its sleeps end when asked, not up to
/// 50 µs later).
pub fn set_timer_slack() -> Result<(), RtError> {
    nix::sys::prctl::set_timerslack(1).map_err(RtError::TimerSlack)
}

/// Locks the process's current and future memory.
pub fn lock_memory() -> Result<(), RtError> {
    use nix::sys::mman::{MlockAllFlags, mlockall};
    mlockall(MlockAllFlags::MCL_CURRENT | MlockAllFlags::MCL_FUTURE).map_err(RtError::LockMemory)
}

/// Keeps `/dev/cpu_dma_latency` at 0 while it lives (the kernel honours the request only as
/// long as the file stays open), as cyclictest does.
#[derive(Debug)]
pub struct DmaLatencyGuard {
    _file: File,
}

impl DmaLatencyGuard {
    /// Asks the kernel for 0 µs wake-up latency from deep C-states.
    pub fn hold() -> Result<Self, RtError> {
        let mut file = File::options()
            .write(true)
            .open("/dev/cpu_dma_latency")
            .map_err(RtError::DmaLatencyOpen)?;
        file.write_all(&0i32.to_ne_bytes())
            .map_err(RtError::DmaLatencyWrite)?;
        Ok(Self { _file: file })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sleep_until_an_absolute_deadline_does_not_return_early() {
        let start = monotonic_now();
        let deadline = start + Duration::from_millis(5);
        sleep_until(deadline);
        assert!(monotonic_now() >= deadline);
        // A deadline in the past returns at once.
        sleep_until(start);
    }

    #[test]
    fn a_core_that_does_not_exist_is_named() {
        let error = pin_to(usize::MAX).expect_err("no such core");
        assert!(matches!(error, RtError::NoSuchCpu(usize::MAX)), "{error}");
        assert!(error.to_string().contains("no such core"), "{error}");
    }

    #[test]
    fn a_fifo_refusal_names_the_priority_and_the_fix() {
        // Priority 100 is out of SCHED_FIFO's range for everyone, root included.
        let error = set_fifo(100).expect_err("out of range");
        let text = error.to_string();
        assert!(text.contains("SCHED_FIFO priority 100"), "{text}");
        assert!(text.contains("CAP_SYS_NICE"), "{text}");
    }

    #[test]
    fn the_timer_slack_is_set_for_the_calling_thread() {
        std::thread::spawn(|| {
            set_timer_slack().expect("PR_SET_TIMERSLACK is open to every thread");
            assert_eq!(nix::sys::prctl::get_timerslack().expect("read back"), 1);
        })
        .join()
        .expect("the thread ran");
    }
}
