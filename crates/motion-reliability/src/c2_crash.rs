//! Campaign 2, server crash: motiond SIGKILLed mid-move (a QSB-M on a pty and an SPI_motor
//! stepper on an SPI socket, both served by this process, both moving) and started again on
//! the same name, while a motion-client client and a plain iceoryx2 client stay connected.
//! Each restart must start cleanly (online, no error), stop both motors (the start-up stop),
//! leave no more iceoryx2 files than the first start made, and the clients must see the new
//! server: motion-client reports the restart and its stale jog guard refuses to renew, then
//! commands the new server after `acknowledge_restart`.

use core::time::Duration;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use anyhow::{Context, bail};
use board_qsb::sim::QsbSim;
use board_spimotor::sim::SpimotorSim;
use iceoryx2::prelude::ipc;
use motion_client::{Client, ClientBuilder, ClientError};
use motion_ipc::{AxisFlags, AxisMode};
use motion_testkit::{RawClient, Server};
use nix::sys::signal::Signal;

use crate::boards::{QsbAndStepper, server_section};
use crate::c1_dead_clients::online;
use crate::harness::{Harness, Samples};
use crate::report::Row;

struct Boards {
    qsb: Arc<Mutex<QsbSim>>,
    stepper: Arc<Mutex<SpimotorSim>>,
}

impl Boards {
    fn moving(&self) -> (bool, bool) {
        (
            self.qsb
                .lock()
                .map(|b| b.motor_velocity() != 0.0)
                .unwrap_or(true),
            self.stepper.lock().map(|b| b.is_moving()).unwrap_or(true),
        )
    }
}

/// Runs the campaign.
pub fn run(h: &Harness) -> anyhow::Result<Row> {
    let count = if h.quick { 3 } else { 100 };
    let mut row = Row::new("2 server crash");
    row.runs = format!("{count} × SIGKILL mid-move, restart on the same name");
    let name = h.name("crash");
    let epoch = Instant::now();
    let served = QsbAndStepper::serve(h, &name, epoch)?;
    let boards = Boards {
        qsb: Arc::clone(&served.qsb),
        stepper: Arc::clone(&served.stepper),
    };
    let config = h.write(
        &format!("{name}.toml"),
        &format!(
            "{}{}",
            server_section(&name, "liveness_check_ms = 100"),
            served.sections()
        ),
    )?;
    let mut server = h.server(&config)?;
    let raw = RawClient::try_connect(&name, Duration::from_secs(10))?;
    wait_online(&raw, 0).context("first start")?;
    let client: Client<ipc::Service> = ClientBuilder::new(&name)
        .connect_timeout(Duration::from_secs(10))
        .connect()?;
    // Every port the campaign uses open (motion-client opens frames and commands on first
    // use) before the files are counted.
    client.axis("feeder")?.stop()?;
    client.latest()?;
    std::thread::sleep(Duration::from_millis(300));
    let baseline_listing = h.iox_listing();
    let baseline_files = baseline_listing.len();
    let baseline_nodes = h.iox_nodes();
    let mut first_restart_files: Option<usize> = None;
    let mut ready = Samples::default();
    let mut stopped_after = Samples::default();
    let (mut clean, mut stale_runs, mut moving_after, mut reconnected, mut reported) =
        (0u32, 0u32, 0u32, 0u32, 0u32);
    let mut max_files = baseline_files;
    let mut problems: Vec<String> = Vec::new();
    for i in 0..count {
        let outcome = one_crash(h, &config, &mut server, &raw, &client, &boards, i);
        match outcome {
            Ok(run) => {
                clean += u32::from(run.clean);
                ready.push(run.ready_ms);
                match run.stopped_ms {
                    Some(ms) => stopped_after.push(ms),
                    None => moving_after += 1,
                }
                // Settled: the new server's liveness check has run, the clients reconnected.
                std::thread::sleep(Duration::from_millis(150));
                let files = h.iox_files();
                let nodes = h.iox_nodes();
                let steady = *first_restart_files.get_or_insert(files);
                max_files = max_files.max(files);
                if files > steady || nodes > baseline_nodes {
                    stale_runs += 1;
                    if problems.len() < 5 {
                        let new: Vec<String> = h
                            .iox_listing()
                            .into_iter()
                            .filter(|f| !baseline_listing.contains(f))
                            .take(8)
                            .collect();
                        problems.push(format!(
                            "restart #{i}: {files} files (first restart {steady}), {nodes} node records (first start {baseline_nodes}); among the new files: {new:?}"
                        ));
                    }
                }
                reconnected += u32::from(run.reconnected);
                reported += u32::from(run.reported);
            }
            Err(e) => {
                if problems.len() < 5 {
                    problems.push(format!("restart #{i}: {e:#}"));
                }
                moving_after += u32::from(boards.moving() != (false, false));
                if !server.is_running() {
                    let since = monotonic_ns();
                    server = h.server(&config)?;
                    let _ = wait_online(&raw, since);
                }
            }
        }
    }
    row.figure("restart → every board online", ready.p50_p99_max(1.0, "ms"));
    row.figure(
        "ready → both motors still (start-up stop)",
        stopped_after.p50_p99_max(1.0, "ms"),
    );
    row.figure(
        "iceoryx2 files",
        format!(
            "{baseline_files} after the first start, {} after the first restart, at most {max_files}",
            first_restart_files.unwrap_or(0)
        ),
    );
    row.check(
        "clean starts",
        clean == count,
        format!("{clean} of {count} restarts online without an error"),
    );
    row.check(
        "0 stale files",
        stale_runs == 0,
        format!(
            "{stale_runs} restarts left a dead node's record or more files than the first restart \
             ({baseline_nodes} node records: server, 2 clients)"
        ),
    );
    row.check(
        "0 axes left moving",
        moving_after == 0,
        format!("{moving_after} restarts left a motor moving 2 s after the server was ready"),
    );
    row.check(
        "clients reconnect",
        reconnected == count && reported == count,
        format!(
            "motion-client reported {reported} of {count} restarts and commanded the new server {reconnected} times"
        ),
    );
    let code = server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10));
    drop(client);
    drop(raw);
    h.check_clean_exit(&mut row, code);
    for problem in problems {
        row.note(problem);
    }
    Ok(row)
}

/// CLOCK_MONOTONIC now, ns (the clock of the frames' stamps).
pub fn monotonic_ns() -> u64 {
    nix::time::clock_gettime(nix::time::ClockId::CLOCK_MONOTONIC)
        .map(|t| t.tv_sec() as u64 * 1_000_000_000 + t.tv_nsec() as u64)
        .unwrap_or(0)
}

/// Waits for a frame published after `since_ns` with both boards online.
fn wait_online(raw: &RawClient, since_ns: u64) -> anyhow::Result<()> {
    match raw.try_wait_frame(Duration::from_secs(15), |f| {
        f.publish_ns > since_ns && online(f, 0) && online(f, 1)
    }) {
        Some((_, true)) => Ok(()),
        other => bail!(
            "not every board online within 15 s: {:?}",
            other.map(|(f, _)| (f.axes()[0], f.axes()[1]))
        ),
    }
}

struct CrashRun {
    clean: bool,
    ready_ms: f64,
    stopped_ms: Option<f64>,
    reconnected: bool,
    reported: bool,
}

fn one_crash(
    h: &Harness,
    config: &std::path::Path,
    server: &mut Server,
    raw: &RawClient,
    client: &Client<ipc::Service>,
    boards: &Boards,
    i: u32,
) -> anyhow::Result<CrashRun> {
    // Mid-move: long ramps on both axes, and a jog guard that must not outlive the server.
    let sign = if i.is_multiple_of(2) { 1.0 } else { -1.0 };
    let feeder = client.axis("feeder")?;
    let focus = client.axis("focus")?;
    feeder.ramp_to(sign * 400.0, 50.0, 0.0)?;
    let guard = focus.jog(sign * 400.0, 0.0)?;
    let end = Instant::now() + Duration::from_secs(5);
    while boards.moving() != (true, true) {
        client.keep_alive();
        if Instant::now() > end {
            bail!("the motors did not start: {:?}", boards.moving());
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    std::thread::sleep(Duration::from_millis(20 + u64::from(i % 7) * 10));
    if server
        .signal_and_wait(Signal::SIGKILL, Duration::from_secs(5))
        .is_some()
    {
        bail!("motiond exited by itself");
    }
    let killed = Instant::now();
    let killed_ns = monotonic_ns();
    *server = h.server(config)?;
    wait_online(raw, killed_ns)?;
    let ready_ms = killed.elapsed().as_secs_f64() * 1e3;
    let became_ready = Instant::now();
    let mut stopped_ms = None;
    while became_ready.elapsed() < Duration::from_secs(2) {
        if boards.moving() == (false, false) {
            stopped_ms = Some(became_ready.elapsed().as_secs_f64() * 1e3);
            break;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    server.drain_log();
    let errors = server
        .log
        .iter()
        .filter(|l| l.contains("ERROR") || l.contains("another motiond"))
        .count();
    let frame = raw.frame();
    let held = frame.axes().iter().all(|a| {
        !matches!(
            a.mode(),
            Ok(AxisMode::Velocity | AxisMode::RampVelocity | AxisMode::RampPosition)
        ) || !a.flags().contains(AxisFlags::MOVING)
    });
    let clean = server.is_running() && errors == 0 && held;
    // The stale guard fails safe and says why; the client reports the restart, then works.
    let reported =
        matches!(guard.check(), Err(ClientError::ServerRestarted(_))) || client.restart().is_some();
    drop(guard);
    let _ = client.check_server();
    client.acknowledge_restart();
    let reconnected = feeder.stop().is_ok() && focus.stop().is_ok();
    Ok(CrashRun {
        clean,
        ready_ms,
        stopped_ms,
        reconnected,
        reported,
    })
}
