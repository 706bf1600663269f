//! motionctl end to end against a real `motiond` running `config/sim.toml` under a unique
//! instance name. They need a motiond binary: `MOTIOND_BIN`, or beside the motionctl binary
//! (`cargo build -p motiond` puts it there; so does `cargo test --workspace`):
//! `cargo build -p motiond && cargo test -p motionctl --test real_server`.
//!
//! The tests of the second wave (readiness, off, io, machine parameters, e-stop paths, a
//! server crash and restart) need the server side of motion-ipc schema 2 (params and estop
//! services, SIGUSR1, device states, takeover after a crash).
//!
//! The tests on a server without devices skip (with a note) when no motiond binary is
//! found.

mod common;

use core::time::Duration;
use std::process::Stdio;
use std::time::Instant;

use common::real::{RealServer, configured, configured_axes, motiond_binary, sim_config};
use common::*;
use motion_client::ipc::Reason;
use motion_client::testing::unique_name;
use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;
use serde_json::Value;

fn axis_index(status: &Value, name: &str) -> Result<usize> {
    status["axes"]
        .as_array()
        .and_then(|axes| axes.iter().position(|axis| axis["name"] == name))
        .ok_or_else(|| format!("no axis {name} in {status}").into())
}

fn position(server: &str, axis: &str) -> Result<f64> {
    let status = status_json(server)?;
    let index = axis_index(&status, axis)?;
    axis_field(&status, index, "position")
        .as_f64()
        .ok_or_else(|| "position is not a number".into())
}

#[test]
fn real_list_json_shows_every_configured_axis() -> Result {
    let server = RealServer::start()?;
    let output = run(&server.name, &["list", "--json"])?;
    assert!(output.status.success(), "{output:?}");
    let list: Value = serde_json::from_slice(&output.stdout)?;
    let names: Vec<String> = list["axes"]
        .as_array()
        .ok_or("axes")?
        .iter()
        .filter_map(|axis| axis["name"].as_str().map(str::to_owned))
        .collect();
    assert_eq!(names, configured_axes(&sim_config()?));
    Ok(())
}

#[test]
fn real_move_wait_ends_at_the_target() -> Result {
    let server = RealServer::start()?;
    let output = run(
        &server.name,
        &["move", "x", "10", "--wait", "--timeout", "30s"],
    )?;
    assert!(output.status.success(), "{output:?}\n{}", server.log());
    let status = status_json(&server.name)?;
    let x = axis_index(&status, "x")?;
    let reached = axis_field(&status, x, "position")
        .as_f64()
        .ok_or("position")?;
    assert!((reached - 10.0).abs() < 0.1, "x at {reached}");
    let flags = axis_field(&status, x, "flags");
    assert!(
        flags.as_array().ok_or("flags")?.contains(&"arrived".into()),
        "{flags}"
    );
    Ok(())
}

#[test]
fn real_out_of_limit_move_is_refused_and_nothing_moves() -> Result {
    let server = RealServer::start()?;
    let before = position(&server.name, "x")?;
    let output = run(&server.name, &["move", "x", "1000"])?;
    assert_eq!(output.status.code(), Some(4), "{output:?}");
    assert!(
        stderr(&output).contains(Reason::OutOfRange.message()),
        "{output:?}"
    );
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(position(&server.name, "x")?, before);
    Ok(())
}

#[test]
fn real_estop_refuses_moves_until_reset() -> Result {
    let server = RealServer::start()?;
    assert!(run(&server.name, &["estop"])?.status.success());
    let refused = run(&server.name, &["move", "y", "5"])?;
    assert_eq!(refused.status.code(), Some(4), "{refused:?}");
    assert!(stderr(&refused).contains(Reason::EstopLatched.message()));
    assert!(run(&server.name, &["reset"])?.status.success());
    let moved = run(
        &server.name,
        &["move", "y", "5", "--wait", "--timeout", "30s"],
    )?;
    assert!(moved.status.success(), "{moved:?}");
    Ok(())
}

#[test]
fn real_record_writes_one_row_per_tick() -> Result {
    let server = RealServer::start()?;
    let out = std::env::temp_dir().join(format!("{}.csv", unique_name("real-record")));
    let out_arg = out.to_str().ok_or("path")?;
    let output = run(
        &server.name,
        &["record", "--duration", "1s", "--out", out_arg],
    )?;
    assert!(output.status.success(), "{output:?}");
    let csv = std::fs::read_to_string(&out)?;
    std::fs::remove_file(&out)?;
    let ticks: Vec<u64> = csv
        .lines()
        .skip(1)
        .map(|line| line.split(',').next().unwrap_or("").parse())
        .collect::<core::result::Result<_, _>>()?;
    let first = *ticks.first().ok_or("no rows")?;
    assert!(
        ticks
            .iter()
            .all(|tick| (first..first + 1000).contains(tick)),
        "1 s at 1 kHz"
    );
    let missed = 1000 - ticks.len();
    assert!(
        missed == 0 || stderr(&output).contains(&format!("{missed} ticks were missed")),
        "{output:?}"
    );
    Ok(())
}

#[test]
fn real_claim_refuses_the_other_client() -> Result {
    let server = RealServer::start()?;
    let holder = command(&server.name, &["claim", "y", "--duration", "20s"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()?;
    let until = Instant::now() + DEADLINE;
    loop {
        let status = status_json(&server.name)?;
        let flags = axis_field(&status, axis_index(&status, "y")?, "flags");
        if flags
            .as_array()
            .is_some_and(|f| f.contains(&"claimed".into()))
        {
            break;
        }
        assert!(Instant::now() < until, "never claimed");
        std::thread::sleep(Duration::from_millis(50));
    }
    let refused = run(&server.name, &["move", "y", "1"])?;
    assert_eq!(refused.status.code(), Some(4), "{refused:?}");
    assert!(stderr(&refused).contains(Reason::ClaimedByOther.message()));
    kill(Pid::from_raw(i32::try_from(holder.id())?), Signal::SIGINT)?;
    assert!(finish(holder, DEADLINE)?.status.success());
    Ok(())
}

/// Polls until `axis` no longer moves; returns how long that took.
fn wait_stopped(server: &str, axis: &str, within: Duration) -> Result<Duration> {
    let started = Instant::now();
    loop {
        let status = status_json(server)?;
        let index = axis_index(&status, axis)?;
        let mode = axis_field(&status, index, "mode");
        if mode != "ramp-velocity" && mode != "velocity" {
            return Ok(started.elapsed());
        }
        if started.elapsed() > within {
            return Err(format!("{axis} still jogging after {within:?}: {status}").into());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn real_jog_stops_on_ctrl_c_and_when_the_client_is_killed() -> Result {
    let server = RealServer::start()?;
    for signal in [Signal::SIGINT, Signal::SIGKILL] {
        let child = command(&server.name, &["jog", "conveyor", "50"])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()?;
        // Longer than the 250 ms deadman: the guard renews it.
        std::thread::sleep(Duration::from_millis(800));
        let status = status_json(&server.name)?;
        let conveyor = axis_index(&status, "conveyor")?;
        assert_eq!(
            axis_field(&status, conveyor, "mode"),
            "ramp-velocity",
            "{status}"
        );
        kill(Pid::from_raw(i32::try_from(child.id())?), signal)?;
        let output = finish(child, DEADLINE)?;
        if signal == Signal::SIGINT {
            assert!(output.status.success(), "{output:?}");
        }
        // Deadman (250 ms) plus the server's liveness check bound a killed client's jog.
        wait_stopped(&server.name, "conveyor", Duration::from_secs(3))?;
    }
    Ok(())
}

/// The smallest server motiond accepts (a config needs a board and an axis or a signal):
/// one simulated SPI_motor stepper, axis `a`.
const EMPTY_CONFIG: &str = "[server]\nname = \"demo\"\ntick_hz = 1000\ncommand_timeout_ms = 250\n\n[[link]]\nname = \"spi\"\ntype = \"sim\"\n\n[[device]]\nname = \"m\"\nlink = \"spi\"\nmodel = \"spimotor\"\n\n[[axis]]\nname = \"a\"\ndevice = \"m\"\nchannel = 0\nunit = \"step\"\ncounts_per_unit = 1.0\nmin = -100.0\nmax = 100.0\nmax_velocity = 100.0\nmax_accel = 1000.0\n";

/// `Some(server)` when a motiond binary exists; `None` (with a note) when this run did not
/// build one (`cargo test -p motionctl` alone; `cargo test --workspace` builds it).
fn empty_server() -> Result<Option<RealServer>> {
    if motiond_binary().is_err() {
        eprintln!("skipped: no motiond binary (build it, or run cargo test --workspace)");
        return Ok(None);
    }
    RealServer::start_with(EMPTY_CONFIG).map(Some)
}

#[test]
fn real_server_without_devices_answers_list_status_and_commands() -> Result {
    let Some(server) = empty_server()? else {
        return Ok(());
    };
    let output = run(&server.name, &["list", "--json"])?;
    assert!(output.status.success(), "{output:?}");
    let list: Value = serde_json::from_slice(&output.stdout)?;
    assert_eq!(list["server"], server.name.as_str());
    assert_eq!(list["tick_hz"], 1000);
    assert_eq!(list["axes"].as_array().map(Vec::len), Some(1));
    let status = status_json(&server.name)?;
    assert!(status["tick"].as_u64().ok_or("tick")? > 0, "{status}");
    assert!(run(&server.name, &["estop"])?.status.success());
    assert_eq!(status_json(&server.name)?["estop"], true);
    assert!(run(&server.name, &["reset"])?.status.success());
    assert_eq!(status_json(&server.name)?["estop"], false);
    let unknown = run(&server.name, &["move", "x", "1"])?;
    assert_eq!(unknown.status.code(), Some(4), "{unknown:?}");
    Ok(())
}

#[test]
fn real_server_without_devices_records_one_row_per_tick() -> Result {
    let Some(server) = empty_server()? else {
        return Ok(());
    };
    let out = std::env::temp_dir().join(format!("{}.csv", unique_name("real-empty")));
    let out_arg = out.to_str().ok_or("path")?;
    let output = run(
        &server.name,
        &["record", "--duration", "500ms", "--out", out_arg],
    )?;
    assert!(output.status.success(), "{output:?}");
    let csv = std::fs::read_to_string(&out)?;
    std::fs::remove_file(&out)?;
    let ticks: Vec<u64> = csv
        .lines()
        .skip(1)
        .map(|line| line.split(',').next().unwrap_or("").parse())
        .collect::<core::result::Result<_, _>>()?;
    let first = *ticks.first().ok_or("no rows")?;
    assert!(
        ticks.iter().all(|tick| (first..first + 500).contains(tick)),
        "{ticks:?}"
    );
    assert!(ticks.windows(2).all(|pair| pair[1] > pair[0]));
    // Ticks the client was too slow for (the server keeps 2 frames) are reported, not faked.
    let missed = 500 - ticks.len();
    assert!(
        missed == 0 || stderr(&output).contains(&format!("{missed} ticks were missed")),
        "{output:?}"
    );
    Ok(())
}

// --- Second wave: readiness, off, io, machine parameters, e-stop paths, restarts ---------

fn json_array<'a>(value: &'a Value, key: &str) -> Result<&'a Vec<Value>> {
    value[key]
        .as_array()
        .ok_or_else(|| format!("no array {key} in {value}").into())
}

#[test]
fn real_move_wait_right_after_start_succeeds() -> Result {
    // No waiting for the boards: the command's own --wait waits for readiness. One fresh
    // server per board kind: Trinamic, QuadQuad2Drv, SPI_motor, QSB-M.
    for (axis, target) in [
        ("x", "10"),
        ("wheel_left", "30"),
        ("focus", "100"),
        ("feeder", "5"),
    ] {
        let server = RealServer::spawn_sim()?;
        let output = run(
            &server.name,
            &[
                "--connect-timeout",
                "10s",
                "move",
                axis,
                target,
                "--wait",
                "--timeout",
                "30s",
            ],
        )?;
        assert!(
            output.status.success(),
            "{axis}: {output:?}\n{}",
            server.log()
        );
        assert!(
            stdout(&output).contains(&format!("{axis}: arrived at")),
            "{output:?}"
        );
    }
    Ok(())
}

#[test]
fn real_wait_ready_then_every_device_is_online() -> Result {
    let server = RealServer::spawn_sim()?;
    let ready = run(
        &server.name,
        &["--connect-timeout", "10s", "wait-ready", "--timeout", "30s"],
    )?;
    assert!(ready.status.success(), "{ready:?}\n{}", server.log());
    let status = status_json(&server.name)?;
    for device in json_array(&status, "devices")? {
        assert_eq!(device["state"], "online", "{device}");
    }
    for axis in json_array(&status, "axes")? {
        assert_eq!(axis["device_state"], "online", "{axis}");
        assert_eq!(axis["fault"], Value::Null, "{axis}");
    }
    Ok(())
}

#[test]
fn real_list_shows_device_states_supervision_and_machine_parameters() -> Result {
    let server = RealServer::start()?;
    let list = json_of(&run(&server.name, &["list", "--json"])?)?;
    assert_eq!(list.get("params_error"), None, "{list}");
    let devices = json_array(&list, "devices")?;
    assert_eq!(
        devices
            .iter()
            .filter_map(|d| d["name"].as_str())
            .collect::<Vec<_>>(),
        configured(&sim_config()?, "device")
    );
    let (mut from_config, mut defaults) = (0, 0);
    let mut count = |params: &Vec<Value>| {
        from_config += params.iter().filter(|p| p["from_config"] == true).count();
        defaults += params.iter().filter(|p| p["from_config"] == false).count();
    };
    for device in devices {
        assert_eq!(device["state"], "online", "{device}");
        assert_ne!(device["firmware"], "", "{device}");
        count(json_array(device, "params")?);
    }
    for axis in json_array(&list, "axes")? {
        assert!(
            ["hold", "stop-off", "off"].contains(&axis["estop"].as_str().unwrap_or("")),
            "{axis}"
        );
        let params = json_array(axis, "params")?;
        assert!(
            !params.is_empty(),
            "every axis has machine parameters: {axis}"
        );
        count(params);
        for key in ["following_error", "overspeed_factor", "home_max_travel"] {
            assert!(
                axis[key].is_null() || axis[key].as_f64().is_some_and(|v| v > 0.0),
                "{axis}"
            );
        }
    }
    assert!(
        from_config > 0 && defaults > 0,
        "sim.toml sets some keys and leaves others at their default"
    );
    let text = stdout(&run(&server.name, &["list"])?);
    assert!(text.contains("machine parameters (source:"), "{text}");
    Ok(())
}

#[test]
fn real_off_de_energises_or_says_why_per_axis() -> Result {
    let server = RealServer::start()?;
    let output = run(&server.name, &["off", "--all"])?;
    assert!(matches!(output.status.code(), Some(0 | 4)), "{output:?}");
    std::thread::sleep(Duration::from_millis(300));
    let status = status_json(&server.name)?;
    let said = stdout(&output);
    let mut offs = 0;
    for axis in json_array(&status, "axes")? {
        let name = axis["name"].as_str().ok_or("name")?;
        if said.lines().any(|line| line == format!("{name}: off")) {
            assert_eq!(axis["mode"], "off", "{axis}");
            offs += 1;
        }
    }
    assert!(
        offs > 0,
        "no axis of the sim robot could be de-energised: {output:?}"
    );
    Ok(())
}

/// `config/sim.toml` with its QSB jam sensor (DIG I/O 0) turned into an output, for a sim
/// config that has no `digital-out` signal of its own (the QSB-M's io1/io2 are its
/// step/direction lines and io3 its drive enable).
fn sim_config_with_an_output() -> Result<String> {
    let config = sim_config()?;
    let at = config
        .find("name = \"feeder_jam\"")
        .ok_or("config/sim.toml has no feeder_jam signal")?;
    let (head, tail) = config.split_at(at);
    if !tail.contains("kind = \"digital-in\"") {
        return Err("feeder_jam is not a digital-in".into());
    }
    Ok(format!(
        "{head}{}",
        tail.replacen("kind = \"digital-in\"", "kind = \"digital-out\"", 1)
    ))
}

/// The name of the first signal of `kind` in an `io list --json`.
fn first_of_kind<'a>(list: &'a Value, kind: &str) -> Option<&'a str> {
    list["signals"]
        .as_array()?
        .iter()
        .find(|s| s["kind"] == kind)
        .and_then(|s| s["name"].as_str())
}

#[test]
fn real_io_lists_the_configured_signals_and_sets_an_output() -> Result {
    let config = sim_config()?;
    let mut server = RealServer::start()?;
    // Inputs are read within their board's refresh budget once the boards answered (an
    // output never set has nothing to acknowledge yet); a loaded machine may need a few
    // reads to see them all fresh at once.
    let stale = |list: &Value| -> Vec<String> {
        list["signals"]
            .as_array()
            .map(|signals| {
                signals
                    .iter()
                    .filter(|s| s["kind"] != "digital-out")
                    .filter(|s| {
                        s["flags"]
                            .as_array()
                            .is_some_and(|f| f.contains(&"stale".into()))
                    })
                    .map(|s| s.to_string())
                    .collect()
            })
            .unwrap_or_default()
    };
    let mut list = json_of(&run(&server.name, &["io", "list", "--json"])?)?;
    let end = std::time::Instant::now() + Duration::from_secs(5);
    while !stale(&list).is_empty() && std::time::Instant::now() < end {
        std::thread::sleep(Duration::from_millis(100));
        list = json_of(&run(&server.name, &["io", "list", "--json"])?)?;
    }
    assert!(stale(&list).is_empty(), "{:?}", stale(&list));
    let signals = json_array(&list, "signals")?;
    let names: Vec<&str> = signals.iter().filter_map(|s| s["name"].as_str()).collect();
    assert_eq!(names, configured(&config, "signal"));
    let input = first_of_kind(&list, "digital-in").ok_or("no digital-in in config/sim.toml")?;
    let refused = run(&server.name, &["io", "set", input, "on"])?;
    assert_fails(&refused, 4, Reason::NotAnOutput.message());
    let output = match first_of_kind(&list, "digital-out") {
        Some(name) => name.to_owned(),
        None => {
            drop(server);
            server = RealServer::start_with(&sim_config_with_an_output()?)?;
            "feeder_jam".to_owned()
        }
    };
    for (word, on) in [("on", true), ("off", false), ("on", true)] {
        let set = run(&server.name, &["io", "set", &output, word])?;
        assert!(set.status.success(), "{set:?}");
        poll_json(&server.name, &["io", "get", &output, "--json"], |s| {
            s["on"] == on
                && !s["flags"]
                    .as_array()
                    .is_some_and(|f| f.contains(&"pending".into()))
        })?;
    }
    Ok(())
}

#[test]
fn real_estop_gets_through_every_exhausted_path() -> Result {
    use iceoryx2::node::NodeBuilder;
    use iceoryx2::prelude::{ServiceName, ipc};
    use motion_client::ipc::{CommandReply, CommandRequest, MotionFrame, ServiceNames};

    let server = RealServer::start()?;
    let names = ServiceNames::new(&server.name);
    let hog = NodeBuilder::new().create::<ipc::Service>()?;
    let frames = hog
        .service_builder(&ServiceName::new(&names.frame())?)
        .publish_subscribe::<MotionFrame>()
        .open()?;
    let mut held_frames = Vec::new();
    while let Ok(subscriber) = frames.subscriber_builder().create() {
        held_frames.push(subscriber);
    }
    let estop = run(&server.name, &["estop"])?;
    assert!(estop.status.success(), "{estop:?}");
    assert!(
        stdout(&estop).contains("via the command service"),
        "{estop:?}"
    );
    assert!(run(&server.name, &["reset"])?.status.success());

    let commands = hog
        .service_builder(&ServiceName::new(&names.command())?)
        .request_response::<CommandRequest, CommandReply>()
        .open()?;
    let mut held_clients = Vec::new();
    while let Ok(client) = commands.client_builder().create() {
        held_clients.push(client);
    }
    // Every frame slot taken: the event goes out, but nothing can show it latched.
    let estop = run(&server.name, &["estop"])?;
    assert_fails(&estop, 5, "sent via the estop event service");
    assert_fails(&estop, 5, "NOT confirmed");
    held_clients.pop();
    assert!(run(&server.name, &["reset"])?.status.success());
    held_clients.push(commands.client_builder().create()?);
    // One frame slot free: confirmed by a frame.
    drop(held_frames.pop());
    let estop = run(&server.name, &["estop"])?;
    assert!(estop.status.success(), "{estop:?}\n{}", server.log());
    assert!(
        stdout(&estop).contains("via the estop event service"),
        "{estop:?}"
    );
    assert!(
        stdout(&estop).contains("latched in the frame of tick"),
        "{estop:?}"
    );
    held_clients.pop();
    assert!(run(&server.name, &["reset"])?.status.success());
    held_clients.push(commands.client_builder().create()?);

    let event = hog
        .service_builder(&ServiceName::new(&names.estop())?)
        .event()
        .open()?;
    let mut held_notifiers = Vec::new();
    while let Ok(notifier) = event.notifier_builder().create() {
        held_notifiers.push(notifier);
    }
    // Everything taken but one frame slot: SIGUSR1 to the pid file's process, confirmed.
    let estop = run(&server.name, &["estop"])?;
    assert!(estop.status.success(), "{estop:?}");
    let pid = server.pid()?;
    assert!(
        stdout(&estop).contains(&format!("via SIGUSR1 to the server process (pid {pid})")),
        "{estop:?}"
    );
    assert!(
        stdout(&estop).contains("latched in the frame of tick"),
        "{estop:?}"
    );
    drop(held_frames);
    let status = poll_json(&server.name, &["status", "--json"], |s| s["estop"] == true)?;
    assert_eq!(status["estop"], true);
    Ok(())
}

#[test]
fn real_jog_ends_cleanly_when_the_server_crashes_and_restarts() -> Result {
    let mut server = RealServer::start()?;
    let child = command(&server.name, &["jog", "conveyor", "50"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()?;
    std::thread::sleep(Duration::from_millis(800));
    server.crash_and_restart()?;
    let output = finish(child, DEADLINE)?;
    assert_fails(&output, 1, "restarted");
    let status = status_json(&server.name)?;
    let conveyor = axis_index(&status, "conveyor")?;
    let mode = axis_field(&status, conveyor, "mode");
    assert!(mode != "ramp-velocity" && mode != "velocity", "{status}");
    Ok(())
}
