//! The wake-up baseline (the cyclictest method): a bare `clock_nanosleep(TIMER_ABSTIME)`
//! loop at the server's tick rate, with the same policy, priority, core and timer slack,
//! recording actual wake − deadline.

use core::time::Duration;

use crate::delivery::duration_ns;
use crate::dist::Dist;
use crate::rt::{self, now_ns, sleep_until_ns};

/// What the sleeper saw.
#[derive(Debug)]
pub struct WakeupRun {
    /// Wake − deadline, ns.
    pub latency: Dist,
    /// Deadlines missed by more than a period (skipped, as motiond skips them).
    pub overruns: u64,
    /// The sleeper thread's set-up.
    pub thread: String,
}

/// Sleeps to `period_ns` deadlines for `duration` on a thread of its own.
pub fn measure(
    period_ns: u64,
    duration: Duration,
    rt_priority: Option<u8>,
    cpu: Option<usize>,
) -> Result<WakeupRun, String> {
    std::thread::scope(|scope| {
        scope
            .spawn(move || {
                let thread = rt::set_up_thread(rt_priority, cpu).describe();
                let mut run = WakeupRun {
                    latency: Dist::new(),
                    overruns: 0,
                    thread,
                };
                let period = period_ns.max(1);
                let end = now_ns() + duration_ns(duration);
                let mut deadline = now_ns() + period;
                while deadline < end {
                    sleep_until_ns(deadline);
                    let wake = now_ns();
                    run.latency.record(wake.saturating_sub(deadline));
                    deadline += period;
                    if wake >= deadline {
                        run.overruns += 1;
                        while deadline <= wake {
                            deadline += period;
                        }
                    }
                }
                run
            })
            .join()
            .map_err(|_| "the wake-up baseline thread panicked".to_owned())
    })
}
