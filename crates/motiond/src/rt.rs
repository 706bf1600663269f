//! Real-time set-up of the tick thread and the monotonic clock.
//!
//! Each measure is one that docs/ARCHITECTURE.md reports measured on our machines: SCHED_FIFO,
//! pinning, `mlockall` (after the shared memory exists), `/dev/cpu_dma_latency` held at 0,
//! and a 1 ns timer slack. Every step reports what it achieved; a missing privilege is a
//! warning unless the operator asked for `--require-rt`.

use crate::error::{RtError, StartError};
use motion_config::ServerSettings;
pub use motion_rt::{
    DmaLatencyGuard, lock_memory, monotonic_now, pin_to, set_fifo, set_timer_slack, sleep_until,
};

/// What the real-time set-up achieved.
#[derive(Debug, Default)]
pub struct RtStatus {
    /// SCHED_FIFO priority in force.
    pub fifo: Option<u8>,
    /// SCHED_FIFO priority of the links' I/O threads.
    pub io_fifo: Option<u8>,
    /// Core the links' I/O threads are pinned to.
    pub io_pinned: Option<usize>,
    /// Core the tick thread is pinned to.
    pub pinned: Option<usize>,
    /// mlockall succeeded.
    pub locked: bool,
    /// `/dev/cpu_dma_latency` is held at 0.
    pub dma_latency: bool,
    /// Timer slack is 1 ns.
    pub timer_slack: bool,
    /// What could not be done.
    pub problems: Vec<RtError>,
}

impl RtStatus {
    /// Bits for `ServerStats::rt_flags`.
    pub fn flags(&self) -> u32 {
        use motion_ipc::ServerStats as S;
        let mut flags = 0;
        if self.fifo.is_some() {
            flags |= S::RT_FIFO;
        }
        if self.locked {
            flags |= S::RT_LOCKED;
        }
        if self.pinned.is_some() {
            flags |= S::RT_PINNED;
        }
        if self.dma_latency {
            flags |= S::RT_DMA_LATENCY;
        }
        flags
    }

    /// One line for the start-up summary.
    pub fn summary(&self) -> String {
        format!(
            "SCHED_FIFO {} | I/O threads {} | pinned {} | memory {} | cpu_dma_latency {} | \
             timer slack {}",
            self.fifo.map_or("off".into(), |p| format!("prio {p}")),
            match (self.io_fifo, self.io_pinned) {
                (None, None) => "normal policy".to_owned(),
                (fifo, cpu) => format!(
                    "{}{}",
                    fifo.map_or("normal policy".into(), |p| format!("SCHED_FIFO prio {p}")),
                    cpu.map_or(String::new(), |c| format!(" on cpu {c}"))
                ),
            },
            self.pinned.map_or("no".into(), |c| format!("cpu {c}")),
            if self.locked { "locked" } else { "not locked" },
            if self.dma_latency {
                "0 µs held"
            } else {
                "not held"
            },
            if self.timer_slack { "1 ns" } else { "default" },
        )
    }
}

/// What the I/O threads' real-time set-up achieved (each thread sets its own policy as it
/// starts: [`crate::io::IoThreadOptions::rt_priority`]).
#[derive(Debug, Default)]
pub struct IoRt {
    /// SCHED_FIFO priority every I/O thread runs at.
    pub fifo: Option<u8>,
    /// Core every I/O thread is pinned to.
    pub pinned: Option<usize>,
    /// What could not be done (the first thread's: they share the process's limits).
    pub problems: Vec<RtError>,
}

/// Touches `bytes` of stack so its pages are faulted in (and locked) before the loop.
pub fn prefault_stack() {
    const STACK_PREFAULT: usize = 256 * 1024;
    let mut buffer = [0u8; STACK_PREFAULT];
    for page in buffer.chunks_mut(4096) {
        page[0] = 1;
    }
    std::hint::black_box(&buffer);
}

/// The tick thread's real-time set-up as `settings` ask (each step's result in the
/// status; with `require_rt`, a step that failed is an error).
pub fn set_up(
    settings: &ServerSettings,
    require_rt: bool,
    io_rt: IoRt,
) -> Result<(RtStatus, Option<DmaLatencyGuard>), StartError> {
    let mut status = RtStatus {
        io_fifo: io_rt.fifo,
        io_pinned: io_rt.pinned,
        problems: io_rt.problems,
        ..RtStatus::default()
    };
    let problem = |status: &mut RtStatus, error: RtError| status.problems.push(error);
    if let Some(priority) = settings.rt_priority {
        match set_fifo(priority) {
            Ok(()) => status.fifo = Some(priority),
            Err(e) => problem(&mut status, e),
        }
    }
    if let Some(cpu) = settings.cpu {
        match pin_to(cpu) {
            Ok(()) => status.pinned = Some(cpu),
            Err(e) => problem(&mut status, e),
        }
    }
    match set_timer_slack() {
        Ok(()) => status.timer_slack = true,
        Err(e) => problem(&mut status, e),
    }
    let guard = match DmaLatencyGuard::hold() {
        Ok(guard) => {
            status.dma_latency = true;
            Some(guard)
        }
        Err(e) => {
            problem(&mut status, e);
            None
        }
    };
    if settings.lock_memory {
        match lock_memory() {
            Ok(()) => status.locked = true,
            Err(e) => problem(&mut status, e),
        }
    }
    prefault_stack();
    let wanted_fifo = (settings.rt_priority.is_some() && status.fifo.is_none())
        || (settings.io_rt_priority.is_some() && status.io_fifo.is_none());
    let wanted_pin = (settings.cpu.is_some() && status.pinned.is_none())
        || (settings.io_cpu.is_some() && status.io_pinned.is_none());
    let wanted_lock = settings.lock_memory && !status.locked;
    if require_rt && (wanted_fifo || wanted_pin || wanted_lock || settings.rt_priority.is_none()) {
        let missing = if settings.rt_priority.is_none() {
            "set [server] rt_priority".to_owned()
        } else {
            let problems: Vec<String> = status.problems.iter().map(ToString::to_string).collect();
            problems.join("; ")
        };
        return Err(StartError::RtIncomplete {
            summary: status.summary(),
            missing,
        });
    }
    Ok((status, guard))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_flags_follow_what_was_achieved() {
        let status = RtStatus {
            fifo: Some(80),
            locked: true,
            ..RtStatus::default()
        };
        let flags = status.flags();
        assert_eq!(
            flags,
            motion_ipc::ServerStats::RT_FIFO | motion_ipc::ServerStats::RT_LOCKED
        );
        assert!(status.summary().contains("prio 80"));
    }
}
