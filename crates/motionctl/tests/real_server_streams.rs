//! Streaming setpoints against a real `motiond` on `config/sim.toml` (group `base` =
//! wheel_left wheel_right, `stream_timeout = 50` ticks at 1 kHz; see `real_server.rs` for
//! how the server is found and started), driven by motion-client's `closed_loop` example
//! (built by this test with cargo into the same target directory, or `CLOSED_LOOP_BIN`):
//! every setpoint it sends is applied once and never before its tick; a streaming client
//! killed with SIGKILL leaves the base stopped and holding; another client's setpoints are
//! dropped and counted while the stream goes on.
//!
//! A 1 kHz loop on a loaded machine can be descheduled for longer than `stream_timeout`:
//! the server then stops the group (stale), which is its rule, not a fault of the client.
//! A run that ended so, with the client's own figures showing it was not scheduled for
//! that long, is run again (a few times at most).

mod common;

use core::time::Duration;
use std::path::PathBuf;
use std::process::{Child, Command, Output, Stdio};
use std::sync::OnceLock;
use std::time::Instant;

use common::real::RealServer;
use common::*;
use iceoryx2::prelude::{NodeBuilder, ServiceName, ipc};
use motion_client::ipc::{AxisMode, GroupAbort, Reason, Setpoint, StreamMode, StreamState};
use motion_client::{Client, StreamStatus};

/// Runs of the example the load of the machine may spoil before the test gives up.
const ATTEMPTS: usize = 4;

/// The `closed_loop` example: `CLOSED_LOOP_BIN`, or built now with the cargo running the
/// tests into the target directory motionctl was built in (same profile).
fn closed_loop_binary() -> Result<PathBuf> {
    static BUILT: OnceLock<core::result::Result<PathBuf, String>> = OnceLock::new();
    if let Some(path) = std::env::var_os("CLOSED_LOOP_BIN") {
        return Ok(path.into());
    }
    let built = BUILT.get_or_init(|| {
        let motionctl = PathBuf::from(env!("CARGO_BIN_EXE_motionctl"));
        let profile_dir = motionctl.parent().ok_or("no profile directory")?;
        let target_dir = profile_dir.parent().ok_or("no target directory")?;
        let release = profile_dir
            .file_name()
            .is_some_and(|name| name == "release");
        let mut build = Command::new(option_env!("CARGO").unwrap_or("cargo"));
        build
            .args([
                "build",
                "-q",
                "-p",
                "motion-client",
                "--example",
                "closed_loop",
            ])
            .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
            .env("CARGO_TARGET_DIR", target_dir);
        if release {
            build.arg("--release");
        }
        let output = build.output().map_err(|e| format!("cargo: {e}"))?;
        if !output.status.success() {
            return Err(format!(
                "building the closed_loop example failed: {}",
                String::from_utf8_lossy(&output.stderr)
            ));
        }
        let binary = profile_dir.join("examples").join("closed_loop");
        if binary.exists() {
            Ok(binary)
        } else {
            Err(format!("no {} after the build", binary.display()))
        }
    });
    built.clone().map_err(Into::into)
}

fn spawn_closed_loop(server: &str, seconds: &str) -> Result<Child> {
    Ok(Command::new(closed_loop_binary()?)
        .args([server, seconds])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()?)
}

/// The number after `label` in `text` ("applied 4999" → 4999).
fn figure(text: &str, label: &str) -> Option<u64> {
    let at = text.find(label)? + label.len();
    let digits: String = text[at..]
        .trim_start()
        .chars()
        .take_while(char::is_ascii_digit)
        .collect();
    digits.parse().ok()
}

fn printed(output: &Output) -> String {
    format!("{}{}", stdout(output), stderr(output))
}

/// Why a failed run is the machine's load and not the stream's fault, if it is: the stream
/// went stale while the client had read no frame for `stream_timeout` ticks, or the server
/// overran its tick (which faults every axis; cleared with a reset).
fn spoiled_by_load(server: &str, text: &str) -> Result<Option<String>> {
    if text.contains("stream stale")
        && let (Some(ended), Some(last)) =
            (figure(text, "ended in tick"), figure(text, "last frame"))
        && ended >= last + 50
    {
        return Ok(Some(format!(
            "the client read no frame from tick {last} to {ended}: stale"
        )));
    }
    if text.contains("axis-fault") || text.contains("faulted") {
        let status = status_json(server)?;
        let overrun = status["axes"]
            .as_array()
            .is_some_and(|axes| axes.iter().any(|axis| axis["fault"] == "overrun"));
        if overrun {
            run(server, &["reset"])?;
            return Ok(Some("the server overran its tick".to_owned()));
        }
    }
    Ok(None)
}

/// Group `base`'s stream in the newest frame.
fn base_stream(client: &Client<ipc::Service>) -> Result<StreamStatus> {
    let base = client.group("base")?;
    let frame = client.latest()?;
    Ok(StreamStatus::from_state(
        frame.tick,
        &frame.groups()[base.index() as usize],
    ))
}

/// Waits until `base` streams for a client other than `client`, while `child` runs.
fn wait_streaming(client: &Client<ipc::Service>, child: &mut Child) -> Result<StreamStatus> {
    let until = Instant::now() + DEADLINE;
    loop {
        let status = base_stream(client)?;
        if status.state == StreamState::Streaming && status.applied > 100 {
            return Ok(status);
        }
        if let Some(exit) = child.try_wait()? {
            return Err(format!("the streaming client exited ({exit}) before streaming").into());
        }
        if Instant::now() > until {
            return Err(format!("base never streamed: {status:?}").into());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn real_closed_loop_every_setpoint_applied_once_never_early() -> Result {
    closed_loop_binary()?;
    let server = RealServer::start()?;
    let client = Client::<ipc::Service>::connect(&server.name)?;
    for attempt in 1..=ATTEMPTS {
        let child = spawn_closed_loop(&server.name, "5")?;
        let output = finish(child, Duration::from_secs(120))?;
        let text = printed(&output);
        println!("closed_loop, attempt {attempt}:\n{text}");
        if !output.status.success() {
            if let Some(why) = spoiled_by_load(&server.name, &text)?
                && attempt < ATTEMPTS
            {
                println!("run again: {why}");
                // The wheels decelerate before the next stream may start.
                std::thread::sleep(Duration::from_millis(500));
                continue;
            }
            return Err(format!("closed_loop failed ({}):\n{text}", output.status).into());
        }
        let sent = figure(&text, "sent").ok_or("sent")?;
        let applied = figure(&text, "server: applied").ok_or("applied")?;
        let late = figure(&text, "late").ok_or("late")?;
        let last_tick = figure(&text, "..=").ok_or("last tick")?;
        let before = figure(&text, "before it").ok_or("before")?;
        // 5 s at 1 kHz: a setpoint per frame read, a frame missed now and then.
        assert!(sent > 2500, "{text}");
        // Each applied on its own time, or dropped as late when it reached the server more
        // than stream_buffer ticks after its tick (the client descheduled that long).
        assert_eq!(applied + late, sent, "{text}");
        assert_eq!(before, 0, "{text}");
        // The frames say the same after the client cancelled its stream.
        let status = base_stream(&client)?;
        assert_eq!(status.state, StreamState::Idle, "{status:?}");
        assert_eq!(status.mode, StreamMode::Velocity);
        assert_eq!((status.applied, status.late), (applied, late), "{status:?}");
        assert_eq!((status.early, status.refused), (0, 0), "{status:?}");
        assert_eq!(
            Some(status.last_sequence),
            figure(&text, "last sequence"),
            "{status:?}"
        );
        assert!(status.last_applied_tick >= last_tick, "{status:?} {text}");
        // The server's receive stamp of that setpoint (schema 8), on the frames' clock.
        assert!(status.last_received_ns > 0, "{status:?}");
        println!(
            "sent {sent}, applied {applied}, late {late}; last for tick {last_tick}, applied in \
             tick {}",
            status.last_applied_tick
        );
        return Ok(());
    }
    Err("never ran".into())
}

#[test]
fn real_sigkill_of_a_streaming_client_stops_the_base() -> Result {
    closed_loop_binary()?;
    let server = RealServer::start()?;
    let client = Client::<ipc::Service>::connect(&server.name)?;
    let mut child = spawn_closed_loop(&server.name, "120")?;
    let streaming = wait_streaming(&client, &mut child)?;
    let owner = streaming.owner.ok_or("no owner")?;
    assert_ne!(owner, client.id());
    child.kill()?; // SIGKILL: no Cancel, no release
    child.wait()?;
    let killed_at = client.latest()?.tick;
    let base = client.group("base")?;
    let members: Vec<usize> = base.info().axes().iter().map(|&a| a as usize).collect();
    let until = Instant::now() + DEADLINE;
    loop {
        let status = base_stream(&client)?;
        let frame = client.latest()?;
        let holding = members
            .iter()
            .all(|&axis| frame.axes()[axis].mode == AxisMode::Hold as u8);
        let tick = frame.tick;
        drop(frame);
        if status.state != StreamState::Streaming && holding {
            assert!(
                matches!(status.state, StreamState::Stale | StreamState::Aborted),
                "{status:?}"
            );
            // Stale after stream_timeout, or client-dead when the server noticed first that
            // the node died or that its command port was gone (which ends its claims and
            // the motions it ran under them): a plain stop either way.
            assert!(
                matches!(
                    status.abort,
                    GroupAbort::StreamStale | GroupAbort::ClientDead
                ),
                "{status:?}"
            );
            println!(
                "killed in tick {killed_at}; base {} ({}) and holding in tick {tick}, {} ticks \
                 later (last setpoint applied in tick {})",
                status.state.name(),
                status.abort.name(),
                tick - killed_at,
                status.last_applied_tick
            );
            return Ok(());
        }
        if Instant::now() > until {
            return Err(format!("base still {status:?}, holding {holding}").into());
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

#[test]
fn real_setpoints_of_another_client_are_refused_and_the_stream_goes_on() -> Result {
    closed_loop_binary()?;
    let server = RealServer::start()?;
    let client = Client::<ipc::Service>::connect(&server.name)?;
    for attempt in 1..=ATTEMPTS {
        let mut child = spawn_closed_loop(&server.name, "120")?;
        let before = wait_streaming(&client, &mut child)?;
        let outcome = intrude(&client, &before);
        let _ = nix::sys::signal::kill(
            nix::unistd::Pid::from_raw(i32::try_from(child.id())?),
            nix::sys::signal::Signal::SIGINT,
        );
        let output = finish(child, DEADLINE)?;
        let text = printed(&output);
        match outcome {
            Ok(()) => {
                // Interrupted, the client dropped its stream: Cancel, the stream idle.
                let after = base_stream(&client)?;
                assert_eq!(after.state, StreamState::Idle, "{after:?}\n{text}");
                return Ok(());
            }
            Err(error) => {
                println!("attempt {attempt}: {error}\n{text}");
                if attempt < ATTEMPTS && spoiled_by_load(&server.name, &text)?.is_some() {
                    std::thread::sleep(Duration::from_millis(500));
                    continue;
                }
                return Err(error);
            }
        }
    }
    Err("never ran".into())
}

/// Another client: `Stream` on base is refused (claimed), and setpoints it publishes on the
/// service, right in all but their sender, are dropped and counted while the owner's
/// stream goes on.
fn intrude(client: &Client<ipc::Service>, before: &StreamStatus) -> Result {
    let base = client.group("base")?;
    let refused = base
        .stream(StreamMode::Velocity)
        .expect_err("base is claimed by the streaming client");
    assert_eq!(refused.reason(), Some(Reason::ClaimedByOther), "{refused}");
    let node = NodeBuilder::new().create::<ipc::Service>()?;
    let publisher = node
        .service_builder(&ServiceName::new(&client.service_names().setpoints())?)
        .publish_subscribe::<Setpoint>()
        .open()?
        .publisher_builder()
        .create()?;
    let intruded = 20;
    for step in 0..intruded {
        let tick = client.latest()?.tick;
        let mut setpoint = Setpoint {
            group: base.index(),
            sequence: u64::MAX - 100 + step,
            for_tick: tick + 1,
            mode: StreamMode::Velocity as u32,
            ..Setpoint::EMPTY
        };
        setpoint.values[..2].copy_from_slice(&[90.0, 90.0]);
        publisher.send_copy(setpoint)?;
        std::thread::sleep(Duration::from_millis(3));
    }
    let until = Instant::now() + DEADLINE;
    loop {
        let now = base_stream(client)?;
        if now.state != StreamState::Streaming {
            return Err(format!("the stream ended: {now:?}").into());
        }
        if now.refused >= before.refused + intruded && now.applied > before.applied + 50 {
            assert_eq!(now.refused, before.refused + intruded, "{now:?}");
            assert!(now.last_sequence < u64::MAX - 200, "{now:?}");
            println!(
                "refused {} of another node's setpoints; the owner's applied {} → {}",
                now.refused - before.refused,
                before.applied,
                now.applied
            );
            return Ok(());
        }
        if Instant::now() > until {
            return Err(format!("not refused: {before:?} → {now:?}").into());
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}
