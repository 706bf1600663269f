//! motionctl end to end against the fake server of `motion_client::testing`, which runs in
//! this test process over inter-process shared memory (`ipc::Service`) while the motionctl
//! binary runs as a child. Every child has a deadline and is killed past it; every test
//! has its own server name.

mod common;

use core::time::Duration;
use std::process::Stdio;
use std::time::Instant;

use common::*;
use motion_base::{LinkKind, ModelFacts};
use motion_client::ipc::{CommandKind, DeviceModel, Reason};
use motion_client::testing::{FakeDevice, unique_name};
use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;
use serde_json::Value;

#[test]
fn help_documents_the_exit_codes() -> Result {
    let output = run("unused", &["--help"])?;
    assert!(output.status.success());
    let help = stdout(&output);
    for line in [
        "Exit status:",
        "3    no motiond server",
        "4    the server refused",
    ] {
        assert!(help.contains(line), "missing {line:?} in\n{help}");
    }
    let output = run("unused", &["move"])?;
    assert_eq!(output.status.code(), Some(2), "usage error");
    Ok(())
}

#[test]
fn no_server_is_one_line_and_exit_3() -> Result {
    let output = run(
        &unique_name("absent"),
        &["--connect-timeout", "100ms", "list"],
    )?;
    assert_eq!(output.status.code(), Some(3), "{output:?}");
    let message = stderr(&output);
    assert_eq!(message.trim_end().lines().count(), 1, "{message}");
    assert!(message.contains("no motiond server named"), "{message}");
    Ok(())
}

#[test]
fn list_json_shows_every_axis() -> Result {
    let server = fake("list")?;
    let output = run(server.name(), &["list", "--json"])?;
    assert!(output.status.success(), "{output:?}");
    let list: Value = serde_json::from_slice(&output.stdout)?;
    let names: Vec<&str> = list["axes"]
        .as_array()
        .ok_or("axes")?
        .iter()
        .filter_map(|axis| axis["name"].as_str())
        .collect();
    assert_eq!(names, ["x", "y", "a"]);
    assert_eq!(list["axes"][2]["unit"], "deg");
    assert_eq!(list["axes"][0]["max"], 100.0);
    assert_eq!(list["tick_hz"], 500);
    let text = run(server.name(), &["list"])?;
    assert!(stdout(&text).contains("max vel"), "{text:?}");
    Ok(())
}

/// A board outside `DeviceModel::BUILT_IN` (no client was built with it).
static WIDGET: ModelFacts = ModelFacts {
    id: "widget",
    code: 99,
    link_kind: LinkKind::Stream,
    title: "Widget",
};

#[test]
fn a_board_no_client_knows_is_named_by_its_model_id() -> Result {
    let server = fake_with("widget", |config| {
        let widget = FakeDevice::new("gizmo", DeviceModel::new(&WIDGET), "widget 0.1");
        config.devices.push(widget);
    })?;
    let list = json_of(&run(server.name(), &["list", "--json"])?)?;
    for (index, model) in ["tmcpack", "qsb", "widget"].into_iter().enumerate() {
        assert_eq!(list["devices"][index]["model"], model, "{list}");
    }
    assert_eq!(list["devices"][3], Value::Null, "three devices");
    let text = stdout(&run(server.name(), &["list"])?);
    let gizmo = text.lines().find(|line| line.starts_with("gizmo"));
    assert!(gizmo.is_some_and(|line| line.contains("widget")), "{text}");
    let status = json_of(&run(server.name(), &["status", "--json"])?)?;
    assert_eq!(status["devices"][2]["model"], "widget", "{status}");
    assert_eq!(status["devices"][0]["model"], "tmcpack", "{status}");
    Ok(())
}

#[test]
fn move_wait_ends_at_the_target() -> Result {
    let server = fake("move")?;
    let output = run(
        server.name(),
        &["move", "x", "7.5", "--velocity", "40", "--wait"],
    )?;
    assert!(output.status.success(), "{output:?}");
    assert!(stdout(&output).contains("x: arrived at 7.5"), "{output:?}");
    let status = status_json(server.name())?;
    assert_eq!(axis_field(&status, 0, "position"), 7.5);
    let flags = axis_field(&status, 0, "flags");
    assert!(
        flags.as_array().ok_or("flags")?.contains(&"arrived".into()),
        "{flags}"
    );
    Ok(())
}

#[test]
fn out_of_limit_move_is_refused_with_the_reason_and_nothing_moves() -> Result {
    let server = fake("limit")?;
    let output = run(server.name(), &["move", "x", "1000"])?;
    assert_eq!(output.status.code(), Some(4), "{output:?}");
    let message = stderr(&output);
    assert_eq!(message.trim_end().lines().count(), 1, "{message}");
    assert!(message.contains(Reason::OutOfRange.message()), "{message}");
    let status = status_json(server.name())?;
    assert_eq!(axis_field(&status, 0, "position"), 0.0);
    assert_eq!(axis_field(&status, 0, "mode"), "hold");
    let unknown = run(server.name(), &["move", "nope", "1"])?;
    assert_eq!(unknown.status.code(), Some(4), "{unknown:?}");
    assert!(stderr(&unknown).contains("no axis named \"nope\""));
    Ok(())
}

#[test]
fn estop_refuses_moves_until_reset() -> Result {
    let server = fake("estop")?;
    assert!(run(server.name(), &["estop"])?.status.success());
    assert_eq!(status_json(server.name())?["estop"], true);
    let refused = run(server.name(), &["move", "y", "3"])?;
    assert_eq!(refused.status.code(), Some(4), "{refused:?}");
    assert!(
        stderr(&refused).contains("e-stop is latched"),
        "{refused:?}"
    );
    assert!(run(server.name(), &["reset"])?.status.success());
    let moved = run(server.name(), &["move", "y", "3", "--wait"])?;
    assert!(moved.status.success(), "{moved:?}");
    assert_eq!(axis_field(&status_json(server.name())?, 1, "position"), 3.0);
    Ok(())
}

#[test]
fn record_writes_one_row_per_tick_with_units() -> Result {
    let server = fake("record")?;
    let dir = std::env::temp_dir().join(unique_name("motionctl-record"));
    std::fs::create_dir_all(&dir)?;
    let out = dir.join("run.csv");
    let out_arg = out.to_str().ok_or("path")?;
    let output = run(
        server.name(),
        &["record", "--duration", "1s", "--out", out_arg],
    )?;
    assert!(output.status.success(), "{output:?}");
    let csv = std::fs::read_to_string(&out)?;
    std::fs::remove_dir_all(&dir)?;
    let mut lines = csv.lines();
    let header = lines.next().ok_or("empty csv")?;
    assert!(
        header.starts_with("tick,time_s,x.position[mm],x.velocity[mm/s]"),
        "{header}"
    );
    assert!(header.contains("a.position[deg]"), "{header}");
    let ticks: Vec<u64> = lines
        .map(|line| line.split(',').next().unwrap_or("").parse())
        .collect::<core::result::Result<_, _>>()?;
    // 1 s at 500 Hz: ticks first .. first + 499, one row each (a descheduled child may
    // lose a tick or two on a loaded machine; it says so and leaves the row out).
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
    assert!(missed < 50, "missed {missed} ticks");
    Ok(())
}

#[test]
fn a_claim_held_by_one_process_refuses_another() -> Result {
    let server = fake("claim")?;
    let holder = command(server.name(), &["claim", "y", "--duration", "10s"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()?;
    let until = Instant::now() + DEADLINE;
    loop {
        let flags = axis_field(&status_json(server.name())?, 1, "flags");
        if flags
            .as_array()
            .is_some_and(|f| f.contains(&"claimed".into()))
        {
            break;
        }
        assert!(Instant::now() < until, "never claimed");
        std::thread::sleep(Duration::from_millis(20));
    }
    let refused = run(server.name(), &["move", "y", "1"])?;
    assert_eq!(refused.status.code(), Some(4), "{refused:?}");
    assert!(
        stderr(&refused).contains("claimed by another client"),
        "{refused:?}"
    );
    kill(Pid::from_raw(i32::try_from(holder.id())?), Signal::SIGINT)?;
    let output = finish(holder, DEADLINE)?;
    assert!(output.status.success(), "{output:?}");
    assert!(stderr(&output).contains("released y"), "{output:?}");
    assert!(
        run(server.name(), &["move", "y", "1", "--wait"])?
            .status
            .success()
    );
    Ok(())
}

#[test]
fn jog_runs_past_the_deadman_and_ctrl_c_stops_the_axis() -> Result {
    let server = fake("jog")?;
    let child = command(server.name(), &["jog", "x", "-5"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()?;
    // Twice the fake server's 250 ms deadman.
    std::thread::sleep(Duration::from_millis(700));
    let status = status_json(server.name())?;
    assert_eq!(axis_field(&status, 0, "mode"), "ramp-velocity", "{status}");
    assert!(
        axis_field(&status, 0, "position")
            .as_f64()
            .ok_or("position")?
            < -1.0
    );
    kill(Pid::from_raw(i32::try_from(child.id())?), Signal::SIGINT)?;
    let output = finish(child, DEADLINE)?;
    assert!(output.status.success(), "{output:?}");
    assert!(stderr(&output).contains("x: stopped at"), "{output:?}");
    let requests = server.requests();
    let jogs = requests
        .iter()
        .filter(|request| request.kind() == Ok(CommandKind::RampVelocity))
        .count();
    assert!(jogs >= 3, "renewed: {jogs}");
    let stop = requests
        .iter()
        .rev()
        .find(|request| request.kind() == Ok(CommandKind::Stop))
        .ok_or("no stop")?;
    assert_eq!(stop.axis, 0);
    assert_eq!(axis_field(&status_json(server.name())?, 0, "mode"), "hold");
    Ok(())
}

#[test]
fn watch_draws_a_live_table_and_quits_on_q() -> Result {
    let server = fake("watch")?;
    // ratatui skips blank cells, so only look for single words.
    let (output, screen) = in_pty(server.name(), &["watch"], "quits", b"q")?;
    assert!(output.status.success(), "{output:?}");
    for text in ["position", "velocity", "flags", "tick", "deadman"] {
        assert!(screen.contains(text), "missing {text:?}");
    }
    Ok(())
}

#[test]
fn scope_plots_and_quits_on_ctrl_c() -> Result {
    let server = fake("scope")?;
    let (output, screen) = in_pty(server.name(), &["scope", "x", "y"], "quits", b"\x03")?;
    assert!(output.status.success(), "{output:?}");
    assert!(
        screen.contains("position") && screen.contains("velocity"),
        "{screen:?}"
    );
    Ok(())
}

#[test]
fn watch_needs_a_terminal() -> Result {
    let server = fake("notty")?;
    let output = run(server.name(), &["watch"])?;
    assert_eq!(output.status.code(), Some(1), "{output:?}");
    assert!(stderr(&output).contains("watch --json"), "{output:?}");
    Ok(())
}

#[test]
fn ctrl_c_during_move_wait_stops_the_axis_and_exits_130() -> Result {
    let server = fake("abort")?;
    let child = command(
        server.name(),
        &["move", "x", "90", "--velocity", "1", "--wait"],
    )
    .stdin(Stdio::null())
    .stdout(Stdio::piped())
    .stderr(Stdio::piped())
    .spawn()?;
    let until = Instant::now() + DEADLINE;
    while !server
        .requests()
        .iter()
        .any(|request| request.kind() == Ok(CommandKind::RampPosition))
    {
        assert!(Instant::now() < until, "move never sent");
        std::thread::sleep(Duration::from_millis(10));
    }
    kill(Pid::from_raw(i32::try_from(child.id())?), Signal::SIGINT)?;
    let output = finish(child, DEADLINE)?;
    assert_eq!(output.status.code(), Some(130), "{output:?}");
    assert!(stderr(&output).contains("axis stopped"), "{output:?}");
    let last = server.requests().last().copied().ok_or("no requests")?;
    assert_eq!((last.kind(), last.axis), (Ok(CommandKind::Stop), 0));
    Ok(())
}
