//! Campaign 5, slow and many consumers: 16 frame subscribers of their own nodes (12 reading
//! every millisecond, 4 never reading) and 64 motion-client clients each connecting, reading
//! a frame, sending a command and disconnecting in a loop, against a server with the default
//! `max_clients` (32). The 64 exceed it on purpose: every connection that fails must fail
//! with the error that names `max_clients` (motion-client's `PortsExhausted`), the server must
//! log the full service once with the key that raises it and count it, and nothing else may
//! fail. The tick latency (deadline → frame sent, from every frame) under that load is
//! compared with a quiet run of the same server.

use core::time::Duration;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use anyhow::bail;
use board_qsb::sim::{QsbSim, QsbSimConfig};
use board_spimotor::sim::{SpimotorSim, SpimotorSimConfig};
use iceoryx2::prelude::*;
use motion_client::ClientBuilder;
use motion_sim::rng::SimRng;
use motion_testkit::RawClient;
use motion_testkit::pty_board::{PtyBoard, PtyOptions};
use motion_testkit::socket_board::SocketBoard;
use nix::sys::signal::Signal;

use crate::boards::{qsb_section, server_section, spimotor_section};
use crate::c1_dead_clients::online;
use crate::harness::{Harness, TickMeter, server_stats};
use crate::report::Row;

const SUBSCRIBERS: usize = 16;
const SILENT: usize = 4;
const CHURNERS: usize = 64;
const MAX_CLIENTS: u32 = 32;

#[derive(Debug, Default)]
struct Churn {
    connected: AtomicU64,
    refused: AtomicU64,
    other: AtomicU64,
    examples: Mutex<Vec<String>>,
}

impl Churn {
    fn outcome(&self, result: Result<(), String>) {
        match result {
            Ok(()) => {
                self.connected.fetch_add(1, Ordering::Relaxed);
            }
            Err(text) if text.contains("max_clients") => {
                self.refused.fetch_add(1, Ordering::Relaxed);
                if let Ok(mut examples) = self.examples.lock()
                    && examples.is_empty()
                {
                    examples.push(format!("refusal: {text}"));
                }
            }
            Err(text) => {
                self.other.fetch_add(1, Ordering::Relaxed);
                if let Ok(mut examples) = self.examples.lock()
                    && examples.len() < 4
                {
                    examples.push(format!("unclear failure: {text}"));
                }
            }
        }
    }
}

/// One client's life: connect, read frames for `hold`, command, disconnect.
fn one_client(name: &str, hold: Duration) -> Result<(), String> {
    let client: motion_client::Client<ipc::Service> = ClientBuilder::new(name)
        .connect_timeout(Duration::from_secs(1))
        .connect()
        .map_err(|e| e.to_string())?;
    let end = Instant::now() + hold;
    loop {
        client
            .next_frame(Duration::from_secs(1))
            .map_err(|e| e.to_string())?;
        if Instant::now() >= end {
            break;
        }
    }
    // A harmless command (the axis stands): a stop.
    client
        .axis("feeder")
        .and_then(|axis| axis.stop())
        .map_err(|e| e.to_string())?;
    Ok(())
}

/// Runs the campaign.
pub fn run(h: &Harness) -> anyhow::Result<Row> {
    let phase = Duration::from_secs(if h.quick { 3 } else { 60 });
    let mut row = Row::new("5 slow and many consumers");
    row.runs = format!(
        "{SUBSCRIBERS} subscribers ({SILENT} never reading), {CHURNERS} clients in a \
         connect/command/disconnect loop, max_clients {MAX_CLIENTS}, {} s quiet + {} s loaded",
        phase.as_secs(),
        phase.as_secs()
    );
    let name = h.name("consumers");
    let epoch = Instant::now();
    let qsb = Arc::new(Mutex::new(QsbSim::new(QsbSimConfig::default())));
    let stepper = Arc::new(Mutex::new(SpimotorSim::new(SpimotorSimConfig::default())));
    let tty = h.path(&format!("{name}.tty"));
    let socket = h.path(&format!("{name}.sock"));
    let _qsb_board = PtyBoard::try_start(&tty, qsb, epoch, 230_400, PtyOptions::default())?;
    let _stepper_board = SocketBoard::try_start(&socket, stepper, epoch)?;
    let config = h.write(
        &format!("{name}.toml"),
        &format!(
            "{}{}{}",
            server_section(
                &name,
                &format!("max_clients = {MAX_CLIENTS}\nrt_priority = 80")
            ),
            qsb_section(&tty),
            spimotor_section(&socket)
        ),
    )?;
    let mut server = h.server(&config)?;
    let watcher = RawClient::try_connect(&name, Duration::from_secs(10))?;
    if !matches!(
        watcher.try_wait_frame(Duration::from_secs(15), |f| online(f, 0) && online(f, 1)),
        Some((_, true))
    ) {
        bail!("the boards are not online");
    }
    let meter = TickMeter::start(&name)?;
    std::thread::sleep(phase);
    let quiet = meter.take();

    let stop = Arc::new(AtomicBool::new(false));
    let read = Arc::new(AtomicU64::new(0));
    let subscriber_errors = Arc::new(Mutex::new(Vec::<String>::new()));
    let (ready_tx, ready_rx) = std::sync::mpsc::channel::<()>();
    let mut threads = Vec::new();
    for index in 0..SUBSCRIBERS {
        let (stop, read, errors, name, ready) = (
            Arc::clone(&stop),
            Arc::clone(&read),
            Arc::clone(&subscriber_errors),
            name.clone(),
            ready_tx.clone(),
        );
        threads.push(std::thread::spawn(move || {
            let opened = NodeBuilder::new()
                .create::<ipc::Service>()
                .map_err(|e| format!("{e:?}"))
                .and_then(|node| {
                    motion_testkit::client::try_open_frames(&node, &name, Duration::from_secs(10))
                        .map(|s| (node, s))
                        .map_err(|e| e.to_string())
                });
            let _ = ready.send(());
            let (_node, subscriber) = match opened {
                Ok(opened) => opened,
                Err(e) => {
                    if let Ok(mut errors) = errors.lock() {
                        errors.push(format!("subscriber {index}: {e}"));
                    }
                    return;
                }
            };
            while !stop.load(Ordering::Relaxed) {
                if index >= SILENT {
                    while let Ok(Some(_)) = subscriber.receive() {
                        read.fetch_add(1, Ordering::Relaxed);
                    }
                }
                std::thread::sleep(Duration::from_millis(1));
            }
        }));
    }
    drop(ready_tx);
    for _ in 0..SUBSCRIBERS {
        let _ = ready_rx.recv_timeout(Duration::from_secs(20));
    }
    let _ = meter.take();
    let churn = Arc::new(Churn::default());
    for index in 0..CHURNERS {
        let (stop, churn, name) = (Arc::clone(&stop), Arc::clone(&churn), name.clone());
        let mut rng = SimRng::new(h.seed ^ (0xC5 + index as u64));
        threads.push(std::thread::spawn(move || {
            while !stop.load(Ordering::Relaxed) {
                let hold = Duration::from_millis(rng.range_f64(50.0, 300.0) as u64);
                churn.outcome(one_client(&name, hold));
                std::thread::sleep(Duration::from_millis(rng.range_f64(0.0, 50.0) as u64));
            }
        }));
    }
    let started = Instant::now();
    std::thread::sleep(phase);
    let loaded = meter.take();
    let loaded_time = started.elapsed();
    stop.store(true, Ordering::Relaxed);
    for thread in threads {
        let _ = thread.join();
    }
    let logged = server.wait_for_log("raise [server] max_clients", Duration::from_secs(2));
    // Past max_clients on purpose: clients that stay connected (each reading frames) until
    // one is refused.
    let mut kept = Vec::new();
    let probe = loop {
        if kept.len() > 2 * MAX_CLIENTS as usize {
            break None;
        }
        let client = ClientBuilder::new(&name)
            .connect_timeout(Duration::from_millis(300))
            .connect::<ipc::Service>();
        match client {
            Ok(client) => match client.next_frame(Duration::from_secs(1)) {
                Ok(_) => kept.push(client),
                Err(e) => break Some(e.to_string()),
            },
            Err(e) => break Some(e.to_string()),
        }
    };
    let held = kept.len();
    drop(kept);
    // Everyone left: a new client connects and commands.
    std::thread::sleep(Duration::from_millis(300));
    let after = one_client(&name, Duration::ZERO);
    let node = NodeBuilder::new()
        .create::<ipc::Service>()
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let stats = server_stats(&node, &name, Duration::from_secs(5)).ok();
    drop(meter);
    let alive = server.is_running();

    let (connected, refused, other) = (
        churn.connected.load(Ordering::Relaxed),
        churn.refused.load(Ordering::Relaxed),
        churn.other.load(Ordering::Relaxed),
    );
    let cycles = connected + refused + other;
    row.figure(
        "client cycles",
        format!(
            "{cycles} in {:.0} s ({:.0}/s): {connected} served, {refused} refused at max_clients, \
             {other} other failures",
            loaded_time.as_secs_f64(),
            cycles as f64 / loaded_time.as_secs_f64()
        ),
    );
    row.figure(
        "frames read by the 12 readers",
        format!("{}", read.load(Ordering::Relaxed)),
    );
    let q = quiet.latency.quantile(0.9999);
    let l = loaded.latency.quantile(0.9999);
    row.figure(
        "tick latency p99.99 (deadline → frame sent)",
        format!(
            "quiet {:.0} µs ({} ticks) / loaded {:.0} µs ({} ticks); p99 {:.0} / {:.0} µs",
            q / 1e3,
            quiet.latency.len(),
            l / 1e3,
            loaded.latency.len(),
            quiet.latency.quantile(0.99) / 1e3,
            loaded.latency.quantile(0.99) / 1e3
        ),
    );
    if !loaded.latency.is_empty() {
        row.target("tick latency p99.99", l, q, 1.1);
    }
    if let Some(stats) = &stats {
        row.figure(
            "server stats",
            format!(
                "{} overruns, {} frames lost, {} full-service events, tick thread {}",
                stats.overruns,
                stats.frames_lost,
                stats.full_events,
                if stats.rt_flags & motion_ipc::ServerStats::RT_FIFO != 0 {
                    "SCHED_FIFO 80"
                } else {
                    "not real-time (no privilege for rt_priority)"
                }
            ),
        );
    }
    let subscriber_errors = subscriber_errors
        .lock()
        .map(|e| e.clone())
        .unwrap_or_default();
    row.check(
        "16 subscribers opened",
        subscriber_errors.is_empty(),
        format!("{subscriber_errors:?}"),
    );
    row.check(
        "every failure of the churning clients names max_clients",
        other == 0,
        format!("{refused} refusals naming max_clients, {other} other failures"),
    );
    row.check(
        "clients kept past max_clients: refused, naming it",
        probe
            .as_ref()
            .is_some_and(|text| text.contains("max_clients"))
            && held <= MAX_CLIENTS as usize,
        format!("{held} clients connected, then: {probe:?}"),
    );
    // The server looks at its slots once a second: a service full for less is not seen.
    let counted = stats.is_some_and(|s| s.full_events > 0);
    row.check(
        "a full service the server saw is logged with the key that raises it",
        !counted || logged,
        format!(
            "full_events {:?}, log line naming max_clients {logged}",
            stats.map(|s| s.full_events)
        ),
    );
    row.check(
        "server alive and serving after the load",
        alive && after.is_ok() && stats.is_some_and(|s| s.frames_lost == 0),
        format!(
            "running {alive}, a new client: {after:?}, frames lost {:?}",
            stats.map(|s| s.frames_lost)
        ),
    );
    if let Ok(examples) = churn.examples.lock() {
        for example in examples.iter() {
            row.note(example.clone());
        }
    }
    row.note(
        "tick latency from the frames (publish_ns − time_ns: wake-up and work; frames carry \
         no separate wake-up stamp, and the server's own wake-up summary covers its whole life)",
    );
    drop(watcher);
    let code = server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10));
    if code != Some(0) {
        row.check("clean exit", false, format!("exit {code:?}"));
    }
    Ok(row)
}
