//! `motionctl doctor`: is this machine set up for motiond's real-time tick? Each check says
//! pass, warn or fail, what it measured, and the exact fix. Files are read under `--root`
//! (`/`; a fake tree in the tests), so every branch of every check is tested on any machine;
//! what only a live system can answer (SCHED_FIFO for real, the wake-up measurement, free
//! space) goes through [`host::Probe`].

mod check;
mod config;
mod cpu;
mod devices;
#[cfg(test)]
mod fake;
mod host;
mod kernel;
mod privileges;
mod shm;

use core::time::Duration;
use std::path::PathBuf;

use clap::Args;
use serde_json::json;

pub use check::{Check, Context, Status};
pub use config::{DEPLOYED_CONFIG, DoctorConfig};
use host::{Host, LiveProbe};

use motion_base::parse_duration;

/// `motionctl doctor`'s options.
#[derive(Debug, Clone, Args)]
pub struct DoctorArgs {
    /// The server's config: its cpu, rt_priority, lock_memory, tick_hz and link paths are
    /// checked (default: /etc/motiond/motiond.toml when it exists).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// How long the wake-up latency is measured (0s skips it).
    #[arg(long, default_value = "5s", value_parser = parse_duration, value_name = "DURATION")]
    pub wakeup: Duration,
    /// Read /proc, /sys, /etc, /dev and /tmp under DIR instead of / (tests).
    #[arg(long, hide = true, default_value = "/", value_name = "DIR")]
    pub root: PathBuf,
}

/// Every check, in the order printed.
pub const CHECKS: [fn(&Context<'_>) -> Check; 16] = [
    kernel::preemption,
    kernel::rt_throttling,
    cpu::governor,
    cpu::isolation,
    cpu::irq_affinity,
    devices::dma_latency,
    privileges::rtprio,
    privileges::memlock,
    privileges::sched_fifo,
    devices::latency_timer,
    devices::access,
    shm::iceoryx2,
    shm::remove_ipc,
    kernel::clocksource,
    kernel::swap,
    privileges::wakeup,
];

/// Runs every check and prints them; fails (exit status 1) when any check failed.
pub fn run(args: &DoctorArgs) -> anyhow::Result<()> {
    let probe = LiveProbe;
    let host = Host {
        root: args.root.clone(),
        probe: &probe,
    };
    let config_path = match &args.config {
        Some(path) => Some(path.clone()),
        None => Some(host.path(DEPLOYED_CONFIG)).filter(|p| p.is_file()),
    };
    let config = match &config_path {
        Some(path) => DoctorConfig::load(path).map_err(anyhow::Error::msg)?,
        None => DoctorConfig::default(),
    };
    let identity = host.identity();
    let cx = Context {
        host,
        config,
        config_path,
        identity,
        wakeup: args.wakeup,
    };
    if !args.json && !cx.wakeup.is_zero() {
        eprintln!(
            "motionctl doctor: measuring wake-up latency for {:?} at the end…",
            cx.wakeup
        );
    }
    let checks: Vec<Check> = CHECKS.iter().map(|check| check(&cx)).collect();
    let count = |status: Status| checks.iter().filter(|c| c.status == status).count();
    let (pass, warn, fail) = (
        count(Status::Pass),
        count(Status::Warn),
        count(Status::Fail),
    );
    if args.json {
        out!(
            "{:#}",
            json!({
                "config": cx.config_path.as_ref().map(|p| p.display().to_string()),
                "user": cx.who(),
                "checks": checks.iter().map(Check::json).collect::<Vec<_>>(),
                "summary": {"pass": pass, "warn": warn, "fail": fail},
            })
        );
    } else {
        out!("{}", heading(&cx));
        for check in &checks {
            out!(
                "{:<5} {:<18} {}",
                check.status.word().to_ascii_uppercase(),
                check.id,
                check.value
            );
            if !check.fix.is_empty() {
                out!("{:<24} fix: {}", "", check.fix);
            }
        }
        out!("{pass} pass, {warn} warn, {fail} fail");
    }
    if fail > 0 {
        anyhow::bail!("{fail} check(s) failed");
    }
    Ok(())
}

fn heading(cx: &Context<'_>) -> String {
    let server = &cx.config.server;
    let config = match &cx.config_path {
        None => format!(
            "no config (none given, no {DEPLOYED_CONFIG}): checked against motiond's defaults; pass --config FILE"
        ),
        Some(path) => format!(
            "config {} (instance `{}`, {} Hz, rt_priority {}, cpu {}, lock_memory {}, {} link(s))",
            path.display(),
            server.name,
            server.tick_hz,
            server
                .rt_priority
                .map_or("none".to_owned(), |p| p.to_string()),
            server.cpu.map_or("none".to_owned(), |c| c.to_string()),
            if server.lock_memory { "on" } else { "off" },
            cx.config.link.len()
        ),
    };
    format!("motionctl doctor: {config}; {}", cx.who())
}
