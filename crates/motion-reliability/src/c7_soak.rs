//! Campaign 7, soak: motiond on config/sim.toml (every board simulated by the server
//! itself), first quiet for a baseline of overruns, then random motion from one
//! motion-client client — moves to random positions, guarded jogs, stops, now and then a
//! reset of faulted axes — for 10 minutes (`--quick`: 20 s). The server's resident memory,
//! open fds, threads and the iceoryx2 files are sampled every second and the first minute
//! (quick: first quarter) compared with the last; overruns per minute are compared with the
//! quiet baseline. At the end every axis must be brought to rest, the server must exit
//! cleanly on SIGTERM and leave no iceoryx2 file.

use core::time::Duration;
use std::collections::BTreeMap;
use std::time::Instant;

use anyhow::Context;
use iceoryx2::prelude::*;
use motion_client::{Client, ClientBuilder, ClientError, JogGuard};
use motion_ipc::AxisFlags;
use motion_sim::rng::SimRng;
use nix::sys::signal::Signal;

use crate::harness::{Harness, ProcessUse, process_use, server_stats};
use crate::report::Row;

/// One sample of the server's use of the machine.
#[derive(Debug, Clone, Copy)]
struct Use {
    process: ProcessUse,
    files: usize,
}

fn maxima(samples: &[Use]) -> (u64, u64, u64, usize) {
    samples.iter().fold((0, 0, 0, 0), |m, s| {
        (
            m.0.max(s.process.rss_kib),
            m.1.max(s.process.fds),
            m.2.max(s.process.threads),
            m.3.max(s.files),
        )
    })
}

fn minima(samples: &[Use]) -> (u64, u64, u64, usize) {
    samples
        .iter()
        .fold((u64::MAX, u64::MAX, u64::MAX, usize::MAX), |m, s| {
            (
                m.0.min(s.process.rss_kib),
                m.1.min(s.process.fds),
                m.2.min(s.process.threads),
                m.3.min(s.files),
            )
        })
}

/// The iceoryx2 files a leak would grow: every file of the run's root but the black box
/// pointer (`<name>.blackbox`, one per server, written by the first save — a fault in the
/// soak saves the black box — and removed on exit, which the clean-exit check sees).
fn growing_files(h: &Harness) -> usize {
    h.iox_listing()
        .iter()
        .filter(|f| !f.ends_with(".blackbox"))
        .count()
}

/// Runs the campaign.
pub fn run(h: &Harness) -> anyhow::Result<Row> {
    let (quiet_time, soak_time, window) = if h.quick {
        (Duration::from_secs(5), Duration::from_secs(20), 5usize)
    } else {
        (Duration::from_secs(60), Duration::from_secs(600), 60usize)
    };
    let mut row = Row::new("7 soak");
    row.runs = format!(
        "{} s quiet, then {} s of random motion on config/sim.toml",
        quiet_time.as_secs(),
        soak_time.as_secs()
    );
    let name = h.name("soak");
    let config = h.write(&format!("{name}.toml"), &h.sim_toml(&name, "")?)?;
    let mut server = h.server(&config)?;
    let pid = server.pid();
    let client: Client<ipc::Service> = ClientBuilder::new(&name)
        .connect_timeout(Duration::from_secs(15))
        .connect()
        .context("connect")?;
    let axes = client.axes();
    for axis in &axes {
        axis.wait_ready(Duration::from_secs(20))
            .with_context(|| format!("axis {}", axis.name()))?;
    }
    let node = NodeBuilder::new()
        .create::<ipc::Service>()
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let overruns = |timeout| server_stats(&node, &name, timeout).map(|s| s.overruns);
    // Stats come once a second: the baseline runs from one to another.
    let quiet_start = overruns(Duration::from_secs(5))?;
    std::thread::sleep(quiet_time);
    let quiet_overruns = overruns(Duration::from_secs(5))?.saturating_sub(quiet_start);

    let mut rng = SimRng::new(h.seed ^ 0x50A4);
    let mut samples: Vec<Use> = Vec::new();
    let mut jogs: Vec<(JogGuard<'_, ipc::Service>, Instant)> = Vec::new();
    let mut outcomes: BTreeMap<String, u64> = BTreeMap::new();
    let mut errors: Vec<String> = Vec::new();
    let (mut resets, mut faults_seen) = (0u64, 0u64);
    let soak_start = overruns(Duration::from_secs(5))?;
    let started = Instant::now();
    let mut next_sample = started;
    let mut next_reset = started + Duration::from_secs(10);
    let files_at_start = h.iox_listing();
    while started.elapsed() < soak_time {
        // Reading a frame renews the jogs that are due.
        if let Err(e) = client.next_frame(Duration::from_secs(1)) {
            errors.push(format!("frame: {e}"));
        }
        jogs.retain(|(_, until)| Instant::now() < *until);
        let axis = &axes[(rng.next_u64() % axes.len() as u64) as usize];
        let info = axis.info();
        let state = axis.state();
        let position = state.as_ref().map_or(0.0, |s| s.position);
        let choice = rng.next_f64();
        let result: Result<(), ClientError> = if choice < 0.45 {
            let span = info.max_velocity * rng.range_f64(-1.0, 1.0);
            let margin = (info.max - info.min) * 0.05;
            axis.position((position + span).clamp(info.min + margin, info.max - margin))
                .map(drop)
        } else if choice < 0.8 {
            let velocity = info.max_velocity * rng.range_f64(-0.5, 0.5);
            axis.jog(velocity, 0.0).map(|guard| {
                let hold = Duration::from_millis(rng.range_f64(200.0, 1500.0) as u64);
                jogs.push((guard, Instant::now() + hold));
            })
        } else {
            axis.stop().map(drop)
        };
        let key = match &result {
            Ok(()) => "accepted".to_owned(),
            Err(ClientError::Refused { reason, .. }) => format!("{reason:?}"),
            Err(e) => {
                if errors.len() < 5 {
                    errors.push(e.to_string());
                }
                "error".to_owned()
            }
        };
        *outcomes.entry(key).or_default() += 1;
        if Instant::now() >= next_reset {
            next_reset = Instant::now() + Duration::from_secs(10);
            let faulted = axes
                .iter()
                .filter(|a| a.state().is_ok_and(|s| s.fault != 0))
                .count();
            if faulted > 0 {
                faults_seen += faulted as u64;
                jogs.clear();
                if client.reset().is_ok() {
                    resets += 1;
                }
            }
        }
        if Instant::now() >= next_sample {
            next_sample += Duration::from_secs(1);
            if let Some(process) = process_use(pid) {
                samples.push(Use {
                    process,
                    files: growing_files(h),
                });
            }
        }
        std::thread::sleep(Duration::from_millis(rng.range_f64(20.0, 120.0) as u64));
    }
    let soaked = started.elapsed();
    drop(jogs);
    let soak_overruns = overruns(Duration::from_secs(5))?.saturating_sub(soak_start);
    let _ = client.stop_all();
    // Every axis at rest within 10 s.
    let end = Instant::now() + Duration::from_secs(10);
    let mut moving = axes.len();
    while Instant::now() < end {
        let _ = client.next_frame(Duration::from_secs(1));
        moving = axes
            .iter()
            .filter(|a| {
                a.state()
                    .map_or(true, |s| s.flags().contains(AxisFlags::MOVING))
            })
            .count();
        if moving == 0 {
            break;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let alive = server.is_running();
    let files_at_end = h.iox_listing();

    let window = window.min(samples.len() / 2).max(1);
    let first = maxima(&samples[..window.min(samples.len())]);
    let last_window = &samples[samples.len().saturating_sub(window)..];
    let last = maxima(last_window);
    // A leak keeps the figure up: the last window's smallest value above the first window's
    // largest. (A transient — an fd open for a moment — shows only in the maximum.)
    let floor = minima(last_window);
    row.figure(
        "commands",
        outcomes
            .iter()
            .map(|(k, v)| format!("{k} {v}"))
            .collect::<Vec<_>>()
            .join(", "),
    );
    row.figure(
        "first → last window (max)",
        format!(
            "RSS {} → {} KiB, fds {} → {}, threads {} → {}, iceoryx2 files {} → {}",
            first.0, last.0, first.1, last.1, first.2, last.2, first.3, last.3
        ),
    );
    // Which files came and went: a leak names itself.
    let appeared: Vec<&String> = files_at_end
        .iter()
        .filter(|f| !files_at_start.contains(f))
        .collect();
    let vanished: Vec<&String> = files_at_start
        .iter()
        .filter(|f| !files_at_end.contains(f))
        .collect();
    if !appeared.is_empty() || !vanished.is_empty() {
        row.note(format!(
            "iceoryx2 files during the soak: appeared {appeared:?}, vanished {vanished:?}"
        ));
    }
    let quiet_rate = quiet_overruns as f64 / quiet_time.as_secs_f64() * 60.0;
    let soak_rate = soak_overruns as f64 / soaked.as_secs_f64() * 60.0;
    row.figure(
        "overruns per minute",
        format!("quiet {quiet_rate:.1} ({quiet_overruns}), soak {soak_rate:.1} ({soak_overruns})"),
    );
    row.figure(
        "faults",
        format!("{faults_seen} faulted axes found, {resets} resets"),
    );
    // Zero overruns beyond the baseline: a timing figure, flagged, never failing.
    row.target(
        "overruns/min soak ÷ quiet (0 quiet counts as 1)",
        soak_rate,
        quiet_rate.max(1.0),
        1.0,
    );
    let accepted = outcomes.get("accepted").copied().unwrap_or(0);
    row.check(
        "random motion ran",
        accepted > 0 && samples.len() >= 2,
        format!("{accepted} commands accepted, {} samples", samples.len()),
    );
    row.check(
        "no client error",
        errors.is_empty(),
        format!("{:?}", errors.iter().take(5).collect::<Vec<_>>()),
    );
    // RSS: flat within 1 MiB or 5 % (allocator noise); fds, threads and files exactly.
    let rss_slack = (first.0 / 20).max(1024);
    row.check(
        "RSS, fds, threads, iceoryx2 files flat (last window's minimum ≤ first window's maximum)",
        floor.0 <= first.0 + rss_slack
            && floor.1 <= first.1
            && floor.2 <= first.2
            && floor.3 <= first.3,
        format!(
            "last window's minima: RSS {} KiB (+{rss_slack} allowed), fds {}, threads {}, files {}",
            floor.0, floor.1, floor.2, floor.3
        ),
    );
    row.check(
        "0 axes left moving after stop_all",
        moving == 0,
        format!("{moving} still moving after 10 s"),
    );
    row.check("server alive", alive, format!("running {alive}"));
    drop(axes);
    drop(client);
    drop(node);
    let code = server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(15));
    h.check_clean_exit(&mut row, code);
    Ok(row)
}
