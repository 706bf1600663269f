//! The kernel: preemption model, RT throttling, clock source, swap.

use super::check::{Check, Context, Status};

const PREEMPT: &str = "kernel-preemption";
const PREEMPT_T: &str = "kernel preemption model";

/// PREEMPT_RT passes; full (or lazy) preemption warns; none or voluntary fails.
pub fn preemption(cx: &Context<'_>) -> Check {
    let host = &cx.host;
    let version = host.read("/proc/version").unwrap_or_default();
    let words: Vec<&str> = version.split_whitespace().collect();
    let realtime = host.read("/sys/kernel/realtime").as_deref() == Some("1");
    let rt_word = words.contains(&"PREEMPT_RT")
        || words
            .windows(2)
            .any(|pair| pair[0] == "PREEMPT" && pair[1] == "RT");
    let rt_fix = "install a PREEMPT_RT kernel (Debian: `apt install linux-image-rt-amd64` or \
                  `linux-image-rt-arm64`; Ubuntu: `pro enable realtime-kernel`; Raspberry Pi OS: a \
                  PREEMPT_RT build) and reboot into it";
    if realtime || rt_word {
        return Check::pass(
            PREEMPT,
            PREEMPT_T,
            if realtime {
                "PREEMPT_RT (/sys/kernel/realtime = 1)"
            } else {
                "PREEMPT_RT (/proc/version)"
            },
        );
    }
    if words.contains(&"PREEMPT_DYNAMIC") {
        // The mode in force: `none voluntary (full) lazy` (debugfs, root only), else the
        // `preempt=` boot parameter.
        let debugfs = host
            .read("/sys/kernel/debug/sched/preempt")
            .and_then(|text| {
                text.split_whitespace()
                    .find(|w| w.starts_with('('))
                    .map(|w| w.trim_matches(|c| c == '(' || c == ')').to_owned())
            });
        let cmdline = host.read("/proc/cmdline").and_then(|text| {
            text.split_whitespace()
                .find_map(|w| w.strip_prefix("preempt="))
                .map(str::to_owned)
        });
        let (mode, source) = match (debugfs, cmdline) {
            (Some(mode), _) => (Some(mode), "/sys/kernel/debug/sched/preempt"),
            (None, Some(mode)) => (Some(mode), "preempt= on the kernel command line"),
            (None, None) => (None, ""),
        };
        return match mode.as_deref() {
            Some("full" | "lazy") => Check::warn(
                PREEMPT,
                PREEMPT_T,
                format!(
                    "PREEMPT_DYNAMIC, {} ({source}): preemptible, not real-time",
                    mode.unwrap_or_default()
                ),
                rt_fix,
            ),
            Some(other) => Check::fail(
                PREEMPT,
                PREEMPT_T,
                format!(
                    "PREEMPT_DYNAMIC, {other} ({source}): kernel code runs to completion before the tick thread gets its core"
                ),
                format!("boot with `preempt=full` on the kernel command line, or better {rt_fix}"),
            ),
            None => Check::warn(
                PREEMPT,
                PREEMPT_T,
                "PREEMPT_DYNAMIC, mode unknown (/sys/kernel/debug/sched/preempt is root's, no preempt= on the command line: the build's default, often voluntary)",
                format!(
                    "boot with `preempt=full`, or better {rt_fix}; `sudo cat /sys/kernel/debug/sched/preempt` shows the mode in force"
                ),
            ),
        };
    }
    if words.contains(&"PREEMPT") {
        return Check::warn(
            PREEMPT,
            PREEMPT_T,
            "PREEMPT (full preemption, not real-time)",
            rt_fix,
        );
    }
    if version.is_empty() {
        return Check::warn(
            PREEMPT,
            PREEMPT_T,
            "unknown (/proc/version unreadable)",
            "run the doctor on the machine itself, with /proc mounted",
        );
    }
    Check::fail(
        PREEMPT,
        PREEMPT_T,
        "no forced preemption (PREEMPT_NONE or PREEMPT_VOLUNTARY): kernel code runs to completion before the tick thread gets its core",
        rt_fix,
    )
}

const THROTTLE: &str = "rt-throttling";
const THROTTLE_T: &str = "RT throttling (sched_rt_runtime_us)";

/// The share of each period SCHED_FIFO threads may use. motiond's tick never spins, so the
/// kernel's default (950 ms of 1 s) costs it nothing; much less starves it under load, and
/// none at all lets a runaway real-time thread freeze its core.
pub fn rt_throttling(cx: &Context<'_>) -> Check {
    let host = &cx.host;
    let runtime = host
        .read("/proc/sys/kernel/sched_rt_runtime_us")
        .and_then(|t| t.parse::<i64>().ok());
    let period = host
        .read("/proc/sys/kernel/sched_rt_period_us")
        .and_then(|t| t.parse::<i64>().ok())
        .unwrap_or(1_000_000)
        .max(1);
    let fix = "sysctl -w kernel.sched_rt_runtime_us=950000, and keep it with \
               `echo kernel.sched_rt_runtime_us=950000 | sudo tee /etc/sysctl.d/60-motiond.conf`";
    match runtime {
        None => Check::warn(
            THROTTLE,
            THROTTLE_T,
            "unknown (/proc/sys/kernel/sched_rt_runtime_us unreadable)",
            "run the doctor on the machine itself, with /proc mounted",
        ),
        Some(-1) => Check::warn(
            THROTTLE,
            THROTTLE_T,
            "-1: off — a runaway SCHED_FIFO thread can hold its core forever (motiond's tick never spins and does not need this)",
            fix,
        ),
        Some(runtime) => {
            let share = runtime as f64 / period as f64;
            let value = format!(
                "{runtime} µs of every {period} µs ({:.0} %) for real-time threads",
                share * 100.0
            );
            let status = if share >= 0.9 {
                Status::Pass
            } else if share >= 0.5 {
                Status::Warn
            } else {
                Status::Fail
            };
            Check::with(THROTTLE, THROTTLE_T, status, value, fix)
        }
    }
}

const CLOCK: &str = "clocksource";
const CLOCK_T: &str = "clock source";

/// tsc (x86) or arch_sys_counter (ARM) read the clock in the vDSO in nanoseconds; a
/// paravirtual clock is fine but says the machine is virtual; hpet, acpi_pm and jiffies
/// cost a microsecond or more per reading, or are coarse.
pub fn clocksource(cx: &Context<'_>) -> Check {
    let host = &cx.host;
    let dir = "/sys/devices/system/clocksource/clocksource0";
    let Some(current) = host.read(&format!("{dir}/current_clocksource")) else {
        return Check::warn(
            CLOCK,
            CLOCK_T,
            "unknown (current_clocksource unreadable)",
            "run the doctor on the machine itself, with /sys mounted",
        );
    };
    let available = host
        .read(&format!("{dir}/available_clocksource"))
        .unwrap_or_default();
    let has_tsc = available.split_whitespace().any(|c| c == "tsc");
    match current.as_str() {
        "tsc" | "arch_sys_counter" => Check::pass(CLOCK, CLOCK_T, current),
        "kvm-clock" | "hyperv_clocksource_tsc_page" | "xen" | "hyperv_clocksource_msr" => {
            Check::warn(
                CLOCK,
                CLOCK_T,
                format!("{current}: a virtual machine — its host decides the latency"),
                "run motiond on bare metal for real-time work; on a VM pin its vCPUs on the host \
                 and give the guest an invariant TSC",
            )
        }
        "hpet" | "acpi_pm" | "jiffies" | "refined-jiffies" | "pit" => Check::fail(
            CLOCK,
            CLOCK_T,
            format!(
                "{current}: slow to read (no vDSO) or coarse{}",
                if has_tsc { "; tsc is available" } else { "" }
            ),
            if has_tsc {
                "echo tsc | sudo tee /sys/devices/system/clocksource/clocksource0/current_clocksource, \
                 and boot with `clocksource=tsc tsc=reliable` if the kernel marked the TSC unstable"
            } else {
                "this machine offers no fast clock source (no invariant TSC): choose other hardware \
                 for real-time work"
            },
        ),
        other => Check::warn(
            CLOCK,
            CLOCK_T,
            format!("{other}: not one the doctor knows (available: {available})"),
            "prefer tsc (x86) or arch_sys_counter (ARM) when listed in available_clocksource",
        ),
    }
}

const SWAP: &str = "swap";
const SWAP_T: &str = "swap";

/// Swap lets the kernel page the server out; `lock_memory` keeps motiond's own pages in.
pub fn swap(cx: &Context<'_>) -> Check {
    let Some(swaps) = cx.host.read("/proc/swaps") else {
        return Check::warn(
            SWAP,
            SWAP_T,
            "unknown (/proc/swaps unreadable)",
            "run the doctor on the machine itself, with /proc mounted",
        );
    };
    let devices: Vec<&str> = swaps
        .lines()
        .skip(1)
        .filter_map(|line| line.split_whitespace().next())
        .collect();
    if devices.is_empty() {
        return Check::pass(SWAP, SWAP_T, "no swap");
    }
    let value = format!("on: {}", devices.join(", "));
    if cx.config.server.lock_memory {
        Check::warn(
            SWAP,
            SWAP_T,
            format!("{value}; motiond's memory is locked (lock_memory), its clients' is not"),
            "swapoff -a and remove the swap entries from /etc/fstab, or lock the clients' memory too",
        )
    } else {
        Check::fail(
            SWAP,
            SWAP_T,
            format!("{value}, and lock_memory is off: a tick can wait for the disk"),
            "set [server] lock_memory = true (with LimitMEMLOCK=infinity, deploy/motiond.service), \
             or swapoff -a and remove the swap entries from /etc/fstab",
        )
    }
}

#[cfg(test)]
mod tests {
    use super::super::fake::FakeRoot;
    use super::*;

    #[test]
    fn preemption_pass_warn_fail() {
        let fake = FakeRoot::new();
        let version = |v: &str| {
            fake.file(
                "/proc/version",
                &format!("Linux version 6.1.0 #1 SMP {v} Debian"),
            )
        };
        version("PREEMPT_RT");
        assert_eq!(fake.check(preemption).status, Status::Pass);
        version("PREEMPT RT");
        assert_eq!(fake.check(preemption).status, Status::Pass);
        version("PREEMPT_DYNAMIC");
        fake.file("/sys/kernel/realtime", "1");
        assert_eq!(fake.check(preemption).status, Status::Pass);
        fake.remove("/sys/kernel/realtime");
        // Dynamic, mode unknown: warn, and it says how to find out.
        let check = fake.check(preemption);
        assert_eq!(check.status, Status::Warn, "{check:?}");
        assert!(check.fix.contains("preempt=full"));
        fake.file("/proc/cmdline", "root=/dev/sda1 preempt=voluntary quiet");
        assert_eq!(fake.check(preemption).status, Status::Fail);
        fake.file(
            "/sys/kernel/debug/sched/preempt",
            "none voluntary (full) lazy",
        );
        let check = fake.check(preemption);
        assert_eq!(check.status, Status::Warn);
        assert!(check.value.contains("full"), "{check:?}");
        fake.file("/sys/kernel/debug/sched/preempt", "(none) voluntary full");
        assert_eq!(fake.check(preemption).status, Status::Fail);
        version("PREEMPT");
        assert_eq!(fake.check(preemption).status, Status::Warn);
        version("");
        let check = fake.check(preemption);
        assert_eq!(check.status, Status::Fail);
        assert!(check.fix.contains("PREEMPT_RT"));
    }

    #[test]
    fn rt_throttling_pass_warn_fail() {
        let fake = FakeRoot::new();
        assert_eq!(fake.check(rt_throttling).status, Status::Warn, "unreadable");
        fake.file("/proc/sys/kernel/sched_rt_period_us", "1000000");
        fake.file("/proc/sys/kernel/sched_rt_runtime_us", "950000");
        let check = fake.check(rt_throttling);
        assert_eq!(check.status, Status::Pass);
        assert!(check.value.contains("95 %"), "{check:?}");
        assert!(check.fix.is_empty());
        fake.file("/proc/sys/kernel/sched_rt_runtime_us", "-1");
        assert_eq!(fake.check(rt_throttling).status, Status::Warn);
        fake.file("/proc/sys/kernel/sched_rt_runtime_us", "600000");
        assert_eq!(fake.check(rt_throttling).status, Status::Warn);
        fake.file("/proc/sys/kernel/sched_rt_runtime_us", "0");
        let check = fake.check(rt_throttling);
        assert_eq!(check.status, Status::Fail);
        assert!(check.fix.contains("sched_rt_runtime_us=950000"));
    }

    #[test]
    fn clocksource_pass_warn_fail() {
        let fake = FakeRoot::new();
        let dir = "/sys/devices/system/clocksource/clocksource0";
        fake.file(&format!("{dir}/available_clocksource"), "tsc hpet acpi_pm");
        fake.file(&format!("{dir}/current_clocksource"), "tsc");
        assert_eq!(fake.check(clocksource).status, Status::Pass);
        fake.file(&format!("{dir}/current_clocksource"), "arch_sys_counter");
        assert_eq!(fake.check(clocksource).status, Status::Pass);
        fake.file(&format!("{dir}/current_clocksource"), "kvm-clock");
        assert_eq!(fake.check(clocksource).status, Status::Warn);
        fake.file(&format!("{dir}/current_clocksource"), "hpet");
        let check = fake.check(clocksource);
        assert_eq!(check.status, Status::Fail);
        assert!(check.fix.contains("echo tsc"), "{check:?}");
        fake.file(&format!("{dir}/available_clocksource"), "hpet acpi_pm");
        let check = fake.check(clocksource);
        assert_eq!(check.status, Status::Fail);
        assert!(check.fix.contains("no fast clock"), "{check:?}");
    }

    #[test]
    fn swap_pass_warn_fail() {
        let fake = FakeRoot::new();
        let header = "Filename\t\t\t\tType\t\tSize\t\tUsed\t\tPriority\n";
        fake.file("/proc/swaps", header);
        assert_eq!(fake.check(swap).status, Status::Pass);
        fake.file(
            "/proc/swaps",
            &format!("{header}/swapfile  file  2097148  0  -2\n"),
        );
        let check = fake.check(swap);
        assert_eq!(check.status, Status::Fail);
        assert!(check.value.contains("/swapfile"));
        fake.set_config("[server]\nlock_memory = true\n");
        assert_eq!(fake.check(swap).status, Status::Warn);
    }
}
