//! What this user may do: real-time priority, locked memory, SCHED_FIFO for real, and how
//! late a sleeper at the configured priority and core wakes up.

use core::time::Duration;

use motion_bench::format_ns;

use super::check::{Check, Context, Status};
use super::host::{CAP_IPC_LOCK, CAP_SYS_NICE, Limit, soft_limit};

const UNIT_FIX: &str = "under systemd: LimitRTPRIO= and LimitMEMLOCK=infinity with \
                        AmbientCapabilities=CAP_SYS_NICE CAP_IPC_LOCK (deploy/motiond.service); for a \
                        login: /etc/security/limits.d/motion.conf with `motion - rtprio 99` and \
                        `motion - memlock unlimited`, then log in again";

const RTPRIO: &str = "rtprio-limit";
const RTPRIO_T: &str = "real-time priority limit (RLIMIT_RTPRIO, CAP_SYS_NICE)";

/// The user may set SCHED_FIFO at the configured `rt_priority`: CAP_SYS_NICE, or an rtprio
/// limit at least that high.
pub fn rtprio(cx: &Context<'_>) -> Check {
    let limit = cx
        .host
        .limits()
        .and_then(|t| soft_limit(&t, "Max realtime priority"));
    let cap = cx
        .identity
        .as_ref()
        .is_ok_and(|id| id.has_cap(CAP_SYS_NICE));
    let limit_text = limit.map_or("unknown".to_owned(), |l| l.to_string());
    let reach = if cap {
        format!("CAP_SYS_NICE (limit {limit_text})")
    } else {
        format!("limit {limit_text}, no CAP_SYS_NICE")
    };
    match cx.config.server.rt_priority {
        None => Check::warn(
            RTPRIO,
            RTPRIO_T,
            format!("{reach}; no rt_priority in the config: the tick runs SCHED_OTHER"),
            "set [server] rt_priority (e.g. 80) for a real-time tick",
        ),
        Some(priority) => {
            let enough = cap
                || match limit {
                    Some(Limit::Unlimited) => true,
                    Some(Limit::Value(v)) => v >= u64::from(priority),
                    None => false,
                };
            if enough {
                Check::pass(
                    RTPRIO,
                    RTPRIO_T,
                    format!("{reach} ≥ rt_priority {priority}"),
                )
            } else {
                Check::fail(
                    RTPRIO,
                    RTPRIO_T,
                    format!("{reach} < rt_priority {priority}: motiond's tick stays SCHED_OTHER"),
                    UNIT_FIX,
                )
            }
        }
    }
}

const MEMLOCK: &str = "memlock-limit";
const MEMLOCK_T: &str = "locked memory limit (RLIMIT_MEMLOCK, CAP_IPC_LOCK)";

/// With `lock_memory`, motiond calls `mlockall(MCL_FUTURE)` after its services exist: under
/// a finite limit every later mapping (a client's shared memory joining) can fail with
/// EAGAIN, so only `unlimited` or CAP_IPC_LOCK pass.
pub fn memlock(cx: &Context<'_>) -> Check {
    let limit = cx
        .host
        .limits()
        .and_then(|t| soft_limit(&t, "Max locked memory"));
    let cap = cx
        .identity
        .as_ref()
        .is_ok_and(|id| id.has_cap(CAP_IPC_LOCK));
    let limit_text = match limit {
        Some(Limit::Value(bytes)) => super::host::format_bytes(bytes),
        Some(Limit::Unlimited) => "unlimited".to_owned(),
        None => "unknown".to_owned(),
    };
    let reach = if cap {
        format!("CAP_IPC_LOCK (limit {limit_text})")
    } else {
        format!("limit {limit_text}, no CAP_IPC_LOCK")
    };
    if !cx.config.server.lock_memory {
        return Check::warn(
            MEMLOCK,
            MEMLOCK_T,
            format!("{reach}; lock_memory is off: a page fault can delay a tick"),
            format!("set [server] lock_memory = true; {UNIT_FIX}"),
        );
    }
    if cap || limit == Some(Limit::Unlimited) {
        Check::pass(MEMLOCK, MEMLOCK_T, reach)
    } else {
        Check::fail(
            MEMLOCK,
            MEMLOCK_T,
            format!(
                "{reach}: mlockall fails, or later mappings (clients joining) fail with EAGAIN"
            ),
            UNIT_FIX,
        )
    }
}

const FIFO: &str = "sched-fifo";
const FIFO_T: &str = "SCHED_FIFO obtainable";

/// Really switches a scratch thread to SCHED_FIFO at the configured priority (1 when none is
/// configured) on the configured core: limits are not the only gate (RT group scheduling,
/// containers, seccomp).
pub fn sched_fifo(cx: &Context<'_>) -> Check {
    let configured = cx.config.server.rt_priority;
    let priority = configured.unwrap_or(1);
    let cpu = cx.config.server.cpu;
    let at = match cpu {
        Some(cpu) => format!("priority {priority} on cpu {cpu}"),
        None => format!("priority {priority}"),
    };
    match (cx.host.probe.try_fifo(priority, cpu), configured) {
        (Ok(()), Some(_)) => Check::pass(FIFO, FIFO_T, format!("obtained at {at}")),
        (Ok(()), None) => Check::warn(
            FIFO,
            FIFO_T,
            format!("obtained at {at}, but no rt_priority in the config"),
            "set [server] rt_priority (e.g. 80) for a real-time tick",
        ),
        (Err(e), Some(_)) => Check::fail(
            FIFO,
            FIFO_T,
            format!("refused at {at}: {e}"),
            format!(
                "{UNIT_FIX}; inside a container or with RT group scheduling, give the group \
                 real-time runtime (cpu.rt_runtime_us)"
            ),
        ),
        (Err(e), None) => Check::warn(
            FIFO,
            FIFO_T,
            format!("refused at {at}: {e}; no rt_priority in the config"),
            format!("set [server] rt_priority (e.g. 80); {UNIT_FIX}"),
        ),
    }
}

const WAKEUP: &str = "wakeup-latency";
const WAKEUP_T: &str = "wake-up latency at the tick's rate, priority and core";

/// A `clock_nanosleep(TIMER_ABSTIME)` loop at the tick rate (the bench's sleeper, the
/// cyclictest method) for a few seconds: p99 within a tenth of a period passes, within half
/// warns, later fails (motiond would overrun).
pub fn wakeup(cx: &Context<'_>) -> Check {
    if cx.wakeup.is_zero() {
        return Check::warn(
            WAKEUP,
            WAKEUP_T,
            "not measured (--wakeup 0s)",
            "run `motionctl doctor` without --wakeup 0s",
        );
    }
    let server = &cx.config.server;
    let period = Duration::from_secs(1) / server.tick_hz.max(1);
    let measured = cx
        .host
        .probe
        .wakeup(period, cx.wakeup, server.rt_priority, server.cpu);
    let (summary, thread) = match measured {
        Ok(done) => done,
        Err(e) => {
            return Check::fail(
                WAKEUP,
                WAKEUP_T,
                format!("could not measure: {e}"),
                "run the doctor on the machine itself",
            );
        }
    };
    if summary.is_empty() {
        return Check::fail(
            WAKEUP,
            WAKEUP_T,
            "no samples",
            "run the doctor for longer (--wakeup 5s)",
        );
    }
    let period_ns = u64::try_from(period.as_nanos()).unwrap_or(u64::MAX);
    let status = if summary.p99 <= period_ns / 10 {
        Status::Pass
    } else if summary.p99 <= period_ns / 2 {
        Status::Warn
    } else {
        Status::Fail
    };
    Check::with(
        WAKEUP,
        WAKEUP_T,
        status,
        format!(
            "p50 {} / p99 {} / p99.9 {} / max {} over {} wake-ups every {} ({thread}); p99 {}",
            format_ns(summary.p50),
            format_ns(summary.p99),
            format_ns(summary.p999),
            format_ns(summary.max),
            summary.samples,
            format_ns(period_ns),
            match status {
                Status::Pass => "within a tenth of the period",
                Status::Warn => "beyond a tenth of the period",
                Status::Fail => "beyond half the period: motiond would overrun",
            },
        ),
        "fix the warnings and failures above first (PREEMPT_RT, rt_priority with its limits, an \
         isolated cpu, cpu_dma_latency, the performance governor), then measure again",
    )
}

#[cfg(test)]
mod tests {
    use super::super::fake::{FakeRoot, UID};
    use super::*;
    use motion_bench::Summary;

    fn limits(fake: &FakeRoot, rtprio: &str, memlock: &str) {
        fake.file(
            "/proc/self/limits",
            &format!(
                "Limit                     Soft Limit           Hard Limit           Units     \n\
                 Max locked memory         {memlock}              {memlock}              bytes     \n\
                 Max realtime priority     {rtprio}                    {rtprio}                    \n"
            ),
        );
    }

    #[test]
    fn rtprio_pass_warn_fail() {
        let fake = FakeRoot::new();
        limits(&fake, "0", "8388608");
        let check = fake.check(rtprio);
        assert_eq!(check.status, Status::Warn, "{check:?}");
        assert!(
            check.value.contains("limit 0, no CAP_SYS_NICE"),
            "{check:?}"
        );
        fake.set_config("[server]\nrt_priority = 80\n");
        let check = fake.check(rtprio);
        assert_eq!(check.status, Status::Fail, "{check:?}");
        assert!(check.fix.contains("LimitRTPRIO"));
        limits(&fake, "80", "8388608");
        assert_eq!(fake.check(rtprio).status, Status::Pass);
        limits(&fake, "50", "8388608");
        assert_eq!(fake.check(rtprio).status, Status::Fail);
        fake.identity(UID, &[], 1 << CAP_SYS_NICE);
        let check = fake.check(rtprio);
        assert_eq!(check.status, Status::Pass, "{check:?}");
        assert!(check.value.contains("CAP_SYS_NICE"));
    }

    #[test]
    fn memlock_pass_warn_fail() {
        let fake = FakeRoot::new();
        limits(&fake, "0", "8388608");
        let check = fake.check(memlock);
        assert_eq!(check.status, Status::Warn, "lock_memory off: {check:?}");
        fake.set_config("[server]\nlock_memory = true\n");
        let check = fake.check(memlock);
        assert_eq!(check.status, Status::Fail, "{check:?}");
        assert!(check.value.contains("limit 8 MiB"), "{check:?}");
        limits(&fake, "0", "unlimited");
        assert_eq!(fake.check(memlock).status, Status::Pass);
        limits(&fake, "0", "65536");
        fake.identity(UID, &[], 1 << CAP_IPC_LOCK);
        assert_eq!(fake.check(memlock).status, Status::Pass);
    }

    #[test]
    fn sched_fifo_pass_warn_fail() {
        let fake = FakeRoot::new();
        let check = fake.check(sched_fifo);
        assert_eq!(check.status, Status::Warn, "not configured: {check:?}");
        assert_eq!(*fake.probe.fifo_asked.borrow(), [1]);
        fake.set_config("[server]\nrt_priority = 70\ncpu = 1\n");
        let check = fake.check(sched_fifo);
        assert_eq!(check.status, Status::Pass, "{check:?}");
        assert!(check.value.contains("priority 70 on cpu 1"));
        *fake.probe.fifo.borrow_mut() = Err("Operation not permitted".to_owned());
        let check = fake.check(sched_fifo);
        assert_eq!(check.status, Status::Fail, "{check:?}");
        assert!(check.value.contains("Operation not permitted"));
        fake.set_config("");
        assert_eq!(fake.check(sched_fifo).status, Status::Warn);
    }

    #[test]
    fn wakeup_pass_warn_fail() {
        let fake = FakeRoot::new();
        let set = |p99: u64| {
            *fake.probe.wakeup.borrow_mut() = Ok((
                Summary {
                    samples: 5000,
                    p50: 15_000,
                    p99,
                    p999: p99 * 2,
                    max: 900_000,
                },
                "SCHED_OTHER, slack 1ns".to_owned(),
            ));
        };
        set(60_000); // 1 kHz: 60 µs ≤ 100 µs
        let check = fake.check(wakeup);
        assert_eq!(check.status, Status::Pass, "{check:?}");
        assert!(check.value.contains("p99 60.0µs"), "{check:?}");
        set(300_000);
        assert_eq!(fake.check(wakeup).status, Status::Warn);
        set(700_000);
        assert_eq!(fake.check(wakeup).status, Status::Fail);
        // At 100 Hz the same 700 µs is well within a tenth of the period.
        fake.set_config("[server]\ntick_hz = 100\n");
        assert_eq!(fake.check(wakeup).status, Status::Pass);
        *fake.probe.wakeup.borrow_mut() = Err("no thread".to_owned());
        assert_eq!(fake.check(wakeup).status, Status::Fail);
    }
}
