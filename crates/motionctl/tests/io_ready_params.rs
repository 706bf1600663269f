//! motionctl's second-wave commands end to end against the fake server (ipc, in this test
//! process): io, off, wait-ready and readiness before --wait, list with machine
//! parameters, status with device states and fault sentences, signals in record and watch.
//! Outputs are read as JSON wherever the command has --json.

mod common;

use std::process::Stdio;

use common::*;
use motion_client::ipc::{CommandKind, DeviceState, FaultCode, Reason};
use motion_client::testing::unique_name;
use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;
use serde_json::Value;

fn signal<'a>(list: &'a Value, name: &str) -> Result<&'a Value> {
    list["signals"]
        .as_array()
        .and_then(|signals| signals.iter().find(|s| s["name"] == name))
        .ok_or_else(|| format!("no signal {name} in {list}").into())
}

#[test]
fn io_list_get_and_set() -> Result {
    let server = fake("io")?;
    let list = json_of(&run(server.name(), &["io", "list", "--json"])?)?;
    let names: Vec<&str> = list["signals"]
        .as_array()
        .ok_or("signals")?
        .iter()
        .filter_map(|s| s["name"].as_str())
        .collect();
    assert_eq!(names, ["door", "lamp", "pressure", "valve"]);
    let pressure = signal(&list, "pressure")?;
    assert_eq!(
        (
            &pressure["device"],
            &pressure["pin"],
            &pressure["kind"],
            &pressure["unit"]
        ),
        (
            &"aux".into(),
            &"ain0".into(),
            &"analog-in".into(),
            &"bar".into()
        )
    );
    assert_eq!(signal(&list, "lamp")?["safe"], "off");
    assert_eq!(signal(&list, "valve")?["invert"], true);

    let set = run(server.name(), &["io", "set", "lamp", "on"])?;
    assert!(set.status.success(), "{set:?}");
    assert!(stdout(&set).contains("lamp: set on"), "{set:?}");
    let lamp = json_of(&run(server.name(), &["io", "get", "lamp", "--json"])?)?;
    assert_eq!((&lamp["on"], &lamp["value"]), (&true.into(), &1.0.into()));

    server.set_input(2, 250.0);
    let pressure = poll_json(server.name(), &["io", "get", "pressure", "--json"], |p| {
        p["raw"] == 250.0
    })?;
    assert!((pressure["value"].as_f64().ok_or("value")? - 2.5).abs() < 1e-9);
    assert_eq!(pressure["on"], Value::Null);
    let text = run(server.name(), &["io", "get", "pressure"])?;
    assert!(stdout(&text).contains("pressure: 2.5 bar"), "{text:?}");

    assert_fails(
        &run(server.name(), &["io", "set", "door", "on"])?,
        4,
        Reason::NotAnOutput.message(),
    );
    assert_fails(
        &run(server.name(), &["io", "get", "nope"])?,
        4,
        "no signal named \"nope\"",
    );
    let usage = run(server.name(), &["io", "set", "lamp", "maybe"])?;
    assert_eq!(usage.status.code(), Some(2), "{usage:?}");
    Ok(())
}

#[test]
fn io_watch_json_streams_the_signals_until_interrupted() -> Result {
    let server = fake("iowatch")?;
    let child = command(
        server.name(),
        &["io", "watch", "--json", "--interval", "20ms"],
    )
    .stdin(Stdio::null())
    .stdout(Stdio::piped())
    .stderr(Stdio::piped())
    .spawn()?;
    std::thread::sleep(std::time::Duration::from_millis(400));
    kill(Pid::from_raw(i32::try_from(child.id())?), Signal::SIGINT)?;
    let output = finish(child, DEADLINE)?;
    assert!(output.status.success(), "{output:?}");
    let lines: Vec<Value> = stdout(&output)
        .lines()
        .map(serde_json::from_str)
        .collect::<core::result::Result<_, _>>()?;
    assert!(lines.len() >= 2, "{lines:?}");
    assert_eq!(lines[0]["signals"].as_array().map(Vec::len), Some(4));
    Ok(())
}

#[test]
fn off_reports_each_axis_and_exits_4_when_one_refuses() -> Result {
    let server = fake("off")?;
    let output = run(server.name(), &["off", "x"])?;
    assert!(output.status.success(), "{output:?}");
    assert_eq!(axis_field(&status_json(server.name())?, 0, "mode"), "off");
    let all = run(server.name(), &["off", "--all"])?;
    assert_fails(&all, 4, "not de-energised: a");
    assert!(
        stdout(&all).contains("x: off") && stdout(&all).contains("y: off"),
        "{all:?}"
    );
    let offs: Vec<u32> = server
        .requests()
        .iter()
        .filter(|request| request.kind() == Ok(CommandKind::Off))
        .map(|request| request.axis)
        .collect();
    assert_eq!(offs, [0, 0, 1, 2]);
    Ok(())
}

#[test]
fn move_wait_right_after_start_waits_for_readiness() -> Result {
    // Devices start for 3 s (500 Hz): long enough for the first, refused, move to be
    // sent while starting even on a loaded machine.
    let server = fake_with("startmove", |config| config.starting_ticks = 1500)?;
    let refused = run(server.name(), &["move", "x", "5"])?;
    assert_fails(&refused, 4, "device `pack` is starting");
    let output = run(
        server.name(),
        &["move", "x", "5", "--wait", "--timeout", "10s"],
    )?;
    assert!(output.status.success(), "{output:?}");
    assert!(stdout(&output).contains("x: arrived at 5"), "{output:?}");
    Ok(())
}

#[test]
fn home_wait_right_after_start_waits_for_readiness() -> Result {
    let server = fake_with("starthome", |config| config.starting_ticks = 250)?;
    let output = run(server.name(), &["home", "y", "--wait", "--timeout", "10s"])?;
    assert!(output.status.success(), "{output:?}");
    assert!(stdout(&output).contains("y: homed"), "{output:?}");
    Ok(())
}

#[test]
fn wait_ready_names_what_is_not_ready() -> Result {
    let server = fake("ready")?;
    let ready = run(server.name(), &["wait-ready"])?;
    assert!(ready.status.success(), "{ready:?}");
    assert!(stdout(&ready).contains("pack, aux"), "{ready:?}");
    server.set_device_state(1, DeviceState::Offline);
    poll_json(server.name(), &["status", "--json"], |status| {
        status["devices"][1]["state"] == "offline"
    })?;
    let output = run(server.name(), &["wait-ready", "--timeout", "300ms"])?;
    assert_fails(&output, 5, "device `aux` is offline");
    assert!(!stderr(&output).contains("`pack`"), "{output:?}");
    let x_only = run(server.name(), &["wait-ready", "x", "--timeout", "300ms"])?;
    assert!(x_only.status.success(), "{x_only:?}");
    Ok(())
}

#[test]
fn list_shows_device_states_supervision_and_machine_parameters() -> Result {
    let server = fake("params")?;
    let list = json_of(&run(server.name(), &["list", "--json"])?)?;
    let pack = &list["devices"][0];
    assert_eq!(
        (&pack["name"], &pack["state"]),
        (&"pack".into(), &"online".into())
    );
    assert_eq!(pack["firmware"], "fake pack 1.0");
    let params = pack["params"].as_array().ok_or("device params")?;
    assert!(
        params.contains(&serde_json::json!({"key": "address", "value": "1", "from_config": true}))
    );
    assert!(params.contains(
        &serde_json::json!({"key": "baud", "value": "19200 baud", "from_config": false})
    ));
    let x = &list["axes"][0];
    assert_eq!(
        (&x["following_error"], &x["overspeed_factor"]),
        (&0.5.into(), &1.2.into())
    );
    assert_eq!(
        (&x["home_max_travel"], &x["estop"]),
        (&250.0.into(), &"stop-off".into())
    );
    assert_eq!(x["params"][0]["key"], "current.run");
    let a = &list["axes"][2];
    assert_eq!(
        (&a["following_error"], &a["estop"]),
        (&Value::Null, &"hold".into())
    );
    assert_eq!(list["signals"].as_array().map(Vec::len), Some(4));
    let text = stdout(&run(server.name(), &["list"])?);
    for expected in [
        "foll err",
        "stop-off",
        "firmware",
        "current.standstill",
        "default",
        "config",
    ] {
        assert!(text.contains(expected), "{expected:?} not in\n{text}");
    }
    Ok(())
}

#[test]
fn status_shows_device_states_and_the_fault_sentence() -> Result {
    let server = fake("faultstatus")?;
    server.fault_axis(0, FaultCode::FollowingError, 0.75, 0.5);
    let status = poll_json(server.name(), &["status", "--json"], |status| {
        status["axes"][0]["fault"] != Value::Null
    })?;
    let x = &status["axes"][0];
    assert_eq!(x["fault"], "following-error");
    assert_eq!(
        x["fault_text"],
        FaultCode::FollowingError
            .explain("x", 0.75, 0.5, "mm")
            .as_str()
    );
    assert_eq!(
        (&x["fault_value"], &x["fault_limit"]),
        (&0.75.into(), &0.5.into())
    );
    assert_eq!(x["device_state"], "online");
    assert_eq!(status["axes"][1]["fault"], Value::Null);
    assert_eq!(status["devices"][1]["name"], "aux");
    assert_eq!(status["signals"].as_array().map(Vec::len), Some(4));
    let text = stdout(&run(server.name(), &["status"])?);
    assert!(text.contains("devices: pack online, aux online"), "{text}");
    assert!(
        text.contains("fault: axis `x`: following error: 0.7500 mm"),
        "{text}"
    );
    let refused = run(server.name(), &["move", "x", "1"])?;
    assert_fails(&refused, 4, "following error");
    Ok(())
}

#[test]
fn a_fault_during_move_wait_ends_it_with_the_sentence_and_exit_5() -> Result {
    let server = fake("faultwait")?;
    let child = command(
        server.name(),
        &["move", "y", "90", "--velocity", "2", "--wait"],
    )
    .stdin(Stdio::null())
    .stdout(Stdio::piped())
    .stderr(Stdio::piped())
    .spawn()?;
    let until = std::time::Instant::now() + DEADLINE;
    while !server
        .requests()
        .iter()
        .any(|request| request.kind() == Ok(CommandKind::RampPosition))
    {
        assert!(std::time::Instant::now() < until, "move never sent");
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    server.fault_axis(1, FaultCode::Overspeed, 61.0, 60.0);
    let output = finish(child, DEADLINE)?;
    assert_fails(
        &output,
        5,
        "axis `y`: overspeed: measured 61.0000 mm/s, limit 60.0000 mm/s",
    );
    Ok(())
}

#[test]
fn record_has_a_column_per_signal_with_its_unit() -> Result {
    let server = fake("recordio")?;
    let out = std::env::temp_dir().join(format!("{}.csv", unique_name("recordio")));
    let out_arg = out.to_str().ok_or("path")?;
    let output = run(
        server.name(),
        &["record", "--duration", "100ms", "--out", out_arg, "x"],
    )?;
    assert!(output.status.success(), "{output:?}");
    let csv = std::fs::read_to_string(&out)?;
    std::fs::remove_file(&out)?;
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().ok_or("empty")?.split(',').collect();
    assert_eq!(
        &header[7..],
        [
            "door.value[0/1]",
            "door.flags",
            "lamp.value[0/1]",
            "lamp.flags",
            "pressure.value[bar]",
            "pressure.flags",
            "valve.value[0/1]",
            "valve.flags"
        ]
    );
    let row: Vec<&str> = lines.next().ok_or("no rows")?.split(',').collect();
    assert_eq!(row.len(), header.len(), "{row:?}");
    Ok(())
}

#[test]
fn watch_shows_devices_and_signals() -> Result {
    let server = fake("watchio")?;
    let (output, screen) = in_pty(server.name(), &["watch"], "quits", b"q")?;
    assert!(output.status.success(), "{output:?}");
    for text in [
        "devices:",
        "online",
        "signal",
        "door",
        "pressure",
        "digital-out",
    ] {
        assert!(screen.contains(text), "missing {text:?}");
    }
    let (output, screen) = in_pty(server.name(), &["io", "watch"], "quits", b"q")?;
    assert!(output.status.success(), "{output:?}");
    assert!(
        screen.contains("valve") && screen.contains("ain0"),
        "{screen:?}"
    );
    Ok(())
}
