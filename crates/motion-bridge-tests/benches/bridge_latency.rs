//! Latency through the bridge over loopback, every figure beside zenoh's own figures
//! measured in the same run, with the ratio (STYLE.md habit 12: only ratios to a same-run
//! baseline mean anything on a shared machine). Run it against a live server:
//!
//! ```text
//! cargo run --release -p motiond -- --config config/sim.toml &      # instance `demo`
//! cargo bench -p motion-bridge-tests --bench bridge_latency -- --server demo [--samples 2000]
//! ```
//!
//! It measures, in one process:
//! - zenoh alone, two sessions over loopback TCP (a listening peer and a client, as the
//!   bridge and a remote client are): pub/sub round trip (ping on one key, pong on another)
//!   with a command-sized (64 B) and a frame-sized (13392 B) payload, and a query round
//!   trip (64 B out, 32 B back);
//! - motiond through shared memory (a local client): command round trip (a `stop` of one
//!   axis: the server answers in its next tick) and frame delivery (`publish_ns` of the
//!   frame to its receipt, same CLOCK_MONOTONIC);
//! - the same through a bridge started here (a remote client over loopback).
//!
//! The ratios: bridge command round trip over zenoh's query round trip plus the local one,
//! and over zenoh's pub/sub round trip; bridge frame delivery over half the frame-sized
//! pub/sub round trip plus the local delivery.

use core::time::Duration;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use iceoryx2::prelude::ipc;
use motion_bridge::Bridge;
use motion_bridge::config::{BridgeConfig, Overrides};
use motion_client::ipc::CommandKind;
use motion_client::{Client, ClientBuilder};
use nix::time::{ClockId, clock_gettime};
use zenoh::Wait as _;

type Result<T = ()> = core::result::Result<T, Box<dyn std::error::Error>>;

/// Round trips run and thrown away before each measured series.
const WARM_UP: usize = 200;

/// zenoh's errors as this bench's errors.
trait Z<T> {
    fn z(self) -> Result<T>;
}

impl<T> Z<T> for zenoh::Result<T> {
    fn z(self) -> Result<T> {
        self.map_err(|error| error.to_string().into())
    }
}

struct Args {
    server: String,
    samples: usize,
    frame_rate: f64,
}

fn args() -> Result<Args> {
    let mut parsed = Args {
        server: "demo".to_owned(),
        samples: 2000,
        frame_rate: 100.0,
    };
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        let mut value = || args.next().ok_or(format!("{arg} needs a value"));
        match arg.as_str() {
            "--server" => parsed.server = value()?,
            "--samples" => parsed.samples = value()?.parse()?,
            "--frame-rate" => parsed.frame_rate = value()?.parse()?,
            // cargo bench passes --bench to every bench binary.
            "--bench" => {}
            "--help" | "-h" => {
                println!(
                    "bridge_latency [--server NAME] [--samples N] [--frame-rate HZ]\n\
                     Needs a running motiond (cargo run --release -p motiond -- --config \
                     config/sim.toml)."
                );
                std::process::exit(0);
            }
            other => return Err(format!("unknown argument {other}").into()),
        }
    }
    Ok(parsed)
}

fn now_ns() -> u64 {
    clock_gettime(ClockId::CLOCK_MONOTONIC).map_or(0, |t| {
        u64::try_from(t.tv_sec()).unwrap_or(0) * 1_000_000_000
            + u64::try_from(t.tv_nsec()).unwrap_or(0)
    })
}

fn free_endpoint() -> Result<String> {
    let listener = std::net::TcpListener::bind("127.0.0.1:0")?;
    Ok(format!("tcp/127.0.0.1:{}", listener.local_addr()?.port()))
}

/// Percentiles of a set of nanosecond samples.
#[derive(Debug, Clone, Copy)]
struct Summary {
    count: usize,
    p50: f64,
    p99: f64,
    max: f64,
}

impl Summary {
    fn of(mut samples: Vec<u64>) -> Self {
        samples.sort_unstable();
        let at = |q: f64| {
            let index = ((samples.len() as f64 - 1.0) * q).round() as usize;
            samples.get(index).copied().unwrap_or(0) as f64
        };
        Self {
            count: samples.len(),
            p50: at(0.5),
            p99: at(0.99),
            max: samples.last().copied().unwrap_or(0) as f64,
        }
    }
}

fn us(ns: f64) -> String {
    format!("{:.1} µs", ns / 1000.0)
}

fn zenoh_session(
    mode: &str,
    listen: Option<&str>,
    connect: Option<&str>,
) -> Result<zenoh::Session> {
    let mut config = zenoh::Config::default();
    config.insert_json5("mode", &format!("\"{mode}\"")).z()?;
    config
        .insert_json5("scouting/multicast/enabled", "false")
        .z()?;
    if let Some(endpoint) = listen {
        config
            .insert_json5("listen/endpoints", &format!("[\"{endpoint}\"]"))
            .z()?;
    }
    if let Some(endpoint) = connect {
        config
            .insert_json5("connect/endpoints", &format!("[\"{endpoint}\"]"))
            .z()?;
    }
    zenoh::open(config).wait().z()
}

/// zenoh alone: pub/sub round trips of `sizes` and the query round trip.
fn zenoh_baselines(samples: usize) -> Result<Vec<(String, Summary)>> {
    let endpoint = free_endpoint()?;
    let peer = zenoh_session("peer", Some(&endpoint), None)?;
    let client = zenoh_session("client", None, Some(&endpoint))?;
    let pong = peer
        .declare_publisher("bench/pong")
        .express(true)
        .wait()
        .z()?;
    let _echo = peer
        .declare_subscriber("bench/ping")
        .callback(move |sample| {
            let _ = pong.put(sample.payload().clone()).wait();
        })
        .wait()
        .z()?;
    let _queryable = peer
        .declare_queryable("bench/query")
        .callback(|query| {
            let _ = query.reply(query.key_expr().clone(), vec![0u8; 32]).wait();
        })
        .wait()
        .z()?;
    let ping = client
        .declare_publisher("bench/ping")
        .express(true)
        .wait()
        .z()?;
    let pongs = client.declare_subscriber("bench/pong").wait().z()?;
    std::thread::sleep(Duration::from_millis(300)); // declarations propagate
    let mut rows = Vec::new();
    for size in [64usize, 13392] {
        let payload = vec![7u8; size];
        let mut rtts = Vec::with_capacity(samples);
        for round in 0..samples + WARM_UP {
            let sent = Instant::now();
            ping.put(payload.clone()).wait().z()?;
            pongs
                .recv_timeout(Duration::from_secs(2))
                .z()?
                .ok_or("no pong")?;
            if round >= WARM_UP {
                rtts.push(sent.elapsed().as_nanos() as u64);
            }
        }
        rows.push((
            format!("zenoh pub/sub round trip, {size} B"),
            Summary::of(rtts),
        ));
    }
    let mut rtts = Vec::with_capacity(samples);
    for round in 0..samples + WARM_UP {
        let sent = Instant::now();
        let replies = client
            .get("bench/query")
            .payload(vec![1u8; 64])
            .express(true)
            .wait()
            .z()?;
        replies
            .recv_timeout(Duration::from_secs(2))
            .z()?
            .ok_or("no reply")?;
        if round >= WARM_UP {
            rtts.push(sent.elapsed().as_nanos() as u64);
        }
    }
    rows.push((
        "zenoh query round trip, 64 B → 32 B".to_owned(),
        Summary::of(rtts),
    ));
    Ok(rows)
}

/// `stop` of axis 0, `samples` times: each round trip waits for the server's next tick.
/// Back to back (`spread` false), a request goes out just after the tick that answered the
/// previous one, so every round trip is about one tick; with `spread`, each first waits a
/// different fraction of a millisecond, so requests meet the tick at every phase.
fn command_rtt(client: &Client<ipc::Service>, samples: usize, spread: bool) -> Result<Summary> {
    let mut rtts = Vec::with_capacity(samples);
    for round in 0..samples + WARM_UP {
        if spread {
            std::thread::sleep(Duration::from_micros((round as u64 * 137) % 1000));
        }
        let sent = Instant::now();
        let reply = client.send(0, CommandKind::Stop, [0.0; 3])?;
        if round >= WARM_UP {
            rtts.push(sent.elapsed().as_nanos() as u64);
        }
        if reply.result().is_err() {
            return Err(format!("stop refused: {reply:?}").into());
        }
    }
    Ok(Summary::of(rtts))
}

/// `publish_ns` of each frame to its receipt.
fn delivery(client: &Client<ipc::Service>, samples: usize) -> Result<Summary> {
    let mut delays = Vec::with_capacity(samples);
    // Skip what waited before the measurement.
    while client.try_next_frame()?.is_some() {}
    while delays.len() < samples {
        let frame = client.next_frame(Duration::from_secs(2))?;
        let received = now_ns();
        if frame.publish_ns > 0 {
            delays.push(received.saturating_sub(frame.publish_ns));
        }
    }
    Ok(Summary::of(delays))
}

fn main() -> Result {
    iceoryx2::prelude::set_log_level(iceoryx2::prelude::LogLevel::Error);
    let args = args()?;
    let samples = args.samples.max(10);
    println!("zenoh baselines ({samples} samples each)…");
    let mut rows = zenoh_baselines(samples)?;

    let local = ClientBuilder::new(&args.server)
        .node_name("bridge-bench")
        .connect::<ipc::Service>()
        .map_err(|error| {
            format!(
                "{error}\n(start one first: cargo run --release -p motiond -- --config \
                 config/sim.toml)"
            )
        })?;
    let endpoint = free_endpoint()?;
    let config = BridgeConfig::parse(
        "[[remote]]\nidentity = \"bench\"\nallow = [\"stop\"]\nrate = 100000\nburst = 100000\n",
        std::path::Path::new("bench.toml"),
        Overrides {
            server: Some(args.server.clone()),
            listen: vec![endpoint.clone()],
            frame_rate: Some(args.frame_rate),
            // Loopback only, the bench's own rules.
            insecure: true,
            ..Overrides::default()
        },
    )?;
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    let bridge = std::thread::spawn(move || match Bridge::start(config) {
        Ok(mut bridge) => bridge.run(&flag),
        Err(error) => eprintln!("bridge: {error}"),
    });
    let remote = ClientBuilder::new(&args.server)
        .node_name("bridge-bench")
        .connect_timeout(Duration::from_secs(10))
        .remote(&endpoint)
        .identity("bench")
        .connect::<ipc::Service>()?;

    println!("commands and frames, local then through the bridge…");
    let local_cmd = command_rtt(&local, samples, false)?;
    let remote_cmd = command_rtt(&remote, samples, false)?;
    let local_spread = command_rtt(&local, samples, true)?;
    let remote_spread = command_rtt(&remote, samples, true)?;
    let frames = (samples / 4).max(50);
    let local_frames = delivery(&local, frames)?;
    let remote_frames = delivery(&remote, frames)?;
    rows.push((
        "motiond command round trip, shared memory".to_owned(),
        local_cmd,
    ));
    rows.push((
        "motiond command round trip, through the bridge".to_owned(),
        remote_cmd,
    ));
    rows.push((
        "  same, sent at spread tick phases, shared memory".to_owned(),
        local_spread,
    ));
    rows.push((
        "  same, sent at spread tick phases, through bridge".to_owned(),
        remote_spread,
    ));
    rows.push((
        "motiond frame delivery, shared memory".to_owned(),
        local_frames,
    ));
    rows.push((
        "motiond frame delivery, through the bridge".to_owned(),
        remote_frames,
    ));
    stop.store(true, Ordering::Relaxed);
    drop(remote);
    let _ = bridge.join();

    println!(
        "\n{:<52} {:>8} {:>12} {:>12} {:>12}",
        "figure", "samples", "p50", "p99", "max"
    );
    for (name, summary) in &rows {
        println!(
            "{name:<52} {:>8} {:>12} {:>12} {:>12}",
            summary.count,
            us(summary.p50),
            us(summary.p99),
            us(summary.max)
        );
    }
    let find = |prefix: &str| {
        rows.iter()
            .find(|(name, _)| name.starts_with(prefix))
            .map_or(f64::NAN, |(_, summary)| summary.p50)
    };
    let pubsub_small = find("zenoh pub/sub round trip, 64");
    let pubsub_frame = find("zenoh pub/sub round trip, 13392");
    let query = find("zenoh query");
    println!("\nratios of medians (same run):");
    println!(
        "  bridge command round trip / (zenoh query round trip + local command round trip) = {:.2}",
        remote_cmd.p50 / (query + local_cmd.p50)
    );
    println!(
        "  bridge command round trip / zenoh pub/sub round trip (64 B)                    = {:.2}",
        remote_cmd.p50 / pubsub_small
    );
    println!(
        "  bridge frame delivery / (zenoh pub/sub one way (13392 B) + local delivery)    = {:.2}",
        remote_frames.p50 / (pubsub_frame / 2.0 + local_frames.p50)
    );
    println!(
        "  bridge command round trip / local, at spread tick phases                      = {:.2}",
        remote_spread.p50 / local_spread.p50
    );
    println!(
        "  added by the bridge (medians): command {} back to back, {} at spread phases; frame {}",
        us(remote_cmd.p50 - local_cmd.p50),
        us(remote_spread.p50 - local_spread.p50),
        us(remote_frames.p50 - local_frames.p50)
    );
    Ok(())
}
