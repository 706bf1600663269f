//! `motionctl group …` end to end against the fake server with groups (`xy` = x y, `all` =
//! x y a; see `FakeConfig::with_groups`).

mod common;

use std::process::Stdio;

use common::*;
use motion_client::ipc::{CommandKind, GroupAbort, Target};
use motion_client::testing::FakeConfig;
use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;
use serde_json::Value;

fn groups(prefix: &str) -> Result<motion_client::testing::FakeServer> {
    fake_with(prefix, |config: &mut FakeConfig| {
        *config = config.clone().with_groups();
    })
}

fn csv(name: &str, text: &str) -> Result<std::path::PathBuf> {
    let dir = std::env::temp_dir().join(motion_client::testing::unique_name("group-csv"));
    std::fs::create_dir_all(&dir)?;
    let path = dir.join(name);
    std::fs::write(&path, text)?;
    Ok(path)
}

/// Waits until the fake received a `Run` for a group.
fn wait_for_run(server: &motion_client::testing::FakeServer) -> Result {
    let until = std::time::Instant::now() + DEADLINE;
    while !server.requests().iter().any(|request| {
        request.kind() == Ok(CommandKind::Run) && request.target() == Ok(Target::Group)
    }) {
        if std::time::Instant::now() > until {
            return Err("no run sent".into());
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    Ok(())
}

#[test]
fn group_list_names_axes_and_tolerances() -> Result {
    let server = groups("glist")?;
    let list = json_of(&run(server.name(), &["group", "list", "--json"])?)?;
    let all = &list["groups"][1];
    assert_eq!(all["name"], "all");
    let names: Vec<&str> = all["axes"]
        .as_array()
        .ok_or("axes")?
        .iter()
        .filter_map(|axis| axis["name"].as_str())
        .collect();
    assert_eq!(names, ["x", "y", "a"]);
    assert_eq!(all["axes"][2]["unit"], "deg");
    assert_eq!(all["axes"][0]["path_tolerance"], 0.5);
    assert_eq!(all["axes"][0]["goal_tolerance"], 0.05);
    assert_eq!(all["goal_time_tolerance"], 0.5);
    let text = stdout(&run(server.name(), &["group", "list"])?);
    assert!(text.contains("xy: x y (goal time 0.5 s)"), "{text}");
    assert!(text.contains("goal tolerance 0.05 deg"), "{text}");
    Ok(())
}

#[test]
fn group_move_wait_json_prints_one_object_with_every_axis() -> Result {
    let server = groups("gmove")?;
    let output = run(
        server.name(),
        &[
            "group",
            "move",
            "xy",
            "y=-20",
            "x=10",
            "--wait",
            "--json",
            "--velocity-scale",
            "0.5",
        ],
    )?;
    let report = json_of(&output)?;
    assert_eq!(report["state"], "done", "{report}");
    assert_eq!(report["abort"], Value::Null);
    assert_eq!(report["group"], "xy");
    let axes = report["axes"].as_object().ok_or("axes")?;
    assert_eq!(axes.len(), 2);
    for (name, target) in [("x", 10.0), ("y", -20.0)] {
        let axis = &axes[name];
        assert!(axis["arrived_tick"].as_u64().is_some(), "{report}");
        assert!(axis["max_path_error"].as_f64().is_some(), "{report}");
        assert_eq!(axis["target"], target);
    }
    assert_eq!(stdout(&output).lines().count(), 1, "one JSON object");
    // Sent as a line with the scales.
    let status = status_json(server.name())?;
    assert_eq!(axis_field(&status, 0, "position"), 10.0);
    // In words.
    let output = run(
        server.name(),
        &["group", "move", "xy", "x=0", "y=0", "--wait"],
    )?;
    assert!(output.status.success(), "{output:?}");
    let text = stdout(&output);
    assert!(text.starts_with("xy: done in tick"), "{text}");
    assert!(text.contains("arrived in tick"), "{text}");
    Ok(())
}

#[test]
fn group_move_refuses_unknown_missing_and_repeated_axes() -> Result {
    let server = groups("gargs")?;
    let output = run(server.name(), &["group", "move", "xy", "x=1", "z=2"])?;
    assert_fails(
        &output,
        2,
        "`z` is not an axis of group xy (its axes: x, y)",
    );
    let output = run(server.name(), &["group", "move", "xy", "x=1"])?;
    assert_fails(&output, 2, "missing: y");
    let output = run(server.name(), &["group", "move", "xy", "x=1", "y=2", "x=3"])?;
    assert_fails(&output, 2, "`x` is given twice");
    let output = run(server.name(), &["group", "move", "arm", "x=1"])?;
    assert_fails(
        &output,
        4,
        "no group named \"arm\" on this server; its groups: xy, all",
    );
    let output = run(server.name(), &["group", "move", "xy", "x=1", "y=500"])?;
    assert_fails(
        &output,
        4,
        "run on group xy refused at point 0, axis `y`: position 500.0000 mm, limit 100.0000 mm",
    );
    let runs = server
        .requests()
        .iter()
        .filter(|request| request.kind() == Ok(CommandKind::Run))
        .count();
    assert_eq!(
        runs, 1,
        "bad arguments send nothing; the out-of-range line was sent"
    );
    Ok(())
}

#[test]
fn group_follow_runs_a_csv_and_reports_csv_errors_with_their_line() -> Result {
    let server = groups("gfollow")?;
    let good = csv(
        "all.csv",
        "time,x,y,a\n0.1,1,2,3\n0.2,2,4,6\n0.25,2.5,5,7.5\n",
    )?;
    let good = good.to_str().ok_or("path")?;
    let report = json_of(&run(
        server.name(),
        &["group", "follow", "all", good, "--wait", "--json"],
    )?)?;
    assert_eq!(report["state"], "done", "{report}");
    assert_eq!(report["axes"]["a"]["target"], 7.5);
    assert!(
        report["axes"]["a"]["arrived_tick"].as_u64().is_some(),
        "{report}"
    );
    let bad = csv("bad.csv", "time,x,y,a\n0.1,1,2,3\n0.1,2,4,6\n")?;
    let output = run(
        server.name(),
        &["group", "follow", "all", bad.to_str().ok_or("path")?],
    )?;
    assert_fails(
        &output,
        1,
        "bad.csv: line 3: time 0.1 s is not after the previous row's 0.1 s",
    );
    let missing = csv("missing.csv", "time,x,y\n0.1,1,2\n")?;
    let output = run(
        server.name(),
        &["group", "follow", "all", missing.to_str().ok_or("path")?],
    )?;
    assert_fails(
        &output,
        1,
        "line 1: every axis of the group needs a position column; missing: a",
    );
    let far = csv("far.csv", "time,x,y,a\n0.1,1,2,3\n0.2,1,2,300\n")?;
    let output = run(
        server.name(),
        &[
            "group",
            "follow",
            "all",
            far.to_str().ok_or("path")?,
            "--wait",
        ],
    )?;
    assert_fails(
        &output,
        4,
        "at point 1, axis `a`: position 300.0000 deg, limit 180.0000 deg",
    );
    Ok(())
}

#[test]
fn an_aborted_wait_prints_its_outcome_and_exits_5() -> Result {
    let server = groups("gabort")?;
    let child = command(
        server.name(),
        &[
            "group",
            "move",
            "all",
            "x=90",
            "y=90",
            "a=90",
            "--velocity-scale",
            "0.05",
            "--wait",
            "--json",
        ],
    )
    .stdin(Stdio::null())
    .stdout(Stdio::piped())
    .stderr(Stdio::piped())
    .spawn()?;
    wait_for_run(&server)?;
    server.abort_group(1, GroupAbort::PathTolerance, Some(1), 0.75, 0.5);
    let output = finish(child, DEADLINE)?;
    assert_fails(
        &output,
        5,
        "axis `y` was 0.7500 mm from its path, tolerance 0.5000 mm",
    );
    let report: Value = serde_json::from_slice(&output.stdout)?;
    assert_eq!(report["state"], "aborted");
    assert_eq!(report["abort"], "path-tolerance");
    assert_eq!(report["abort_axis"], "y");
    Ok(())
}

#[test]
fn ctrl_c_during_a_group_wait_stops_the_group() -> Result {
    let server = groups("gint")?;
    let child = command(
        server.name(),
        &[
            "group",
            "move",
            "xy",
            "x=90",
            "y=90",
            "--velocity-scale",
            "0.05",
            "--wait",
        ],
    )
    .stdin(Stdio::null())
    .stdout(Stdio::piped())
    .stderr(Stdio::piped())
    .spawn()?;
    wait_for_run(&server)?;
    kill(Pid::from_raw(i32::try_from(child.id())?), Signal::SIGINT)?;
    let output = finish(child, DEADLINE)?;
    assert_fails(&output, 130, "group xy stopped");
    let stop = server
        .requests()
        .into_iter()
        .rev()
        .find(|r| r.kind() == Ok(CommandKind::Stop));
    assert_eq!(
        stop.map(|r| (r.target(), r.axis)),
        Some((Ok(Target::Group), 0))
    );
    Ok(())
}

#[test]
fn hold_resume_feed_and_cancel_answer_for_a_running_group() -> Result {
    let server = groups("gsteer")?;
    let output = run(server.name(), &["group", "hold", "xy"])?;
    assert_fails(&output, 4, "the group has no motion running");
    let output = run(server.name(), &["group", "feed", "xy", "200%"])?;
    assert_eq!(output.status.code(), Some(2), "{output:?}");
    let started = run(
        server.name(),
        &[
            "group",
            "move",
            "xy",
            "x=90",
            "y=90",
            "--velocity-scale",
            "0.05",
            "--json",
        ],
    )?;
    assert_eq!(json_of(&started)?["state"], "moving");
    for (args, words) in [
        (&["group", "hold", "xy"][..], "xy: hold (tick"),
        (&["group", "resume", "xy"][..], "xy: resume (tick"),
        (&["group", "feed", "xy", "50%"][..], "xy: feed 50% (tick"),
        (&["group", "feed", "xy", "1.25"][..], "xy: feed 125% (tick"),
        (&["group", "cancel", "xy"][..], "xy: cancel (tick"),
    ] {
        let output = run(server.name(), args)?;
        assert!(output.status.success(), "{args:?}: {output:?}");
        assert!(stdout(&output).starts_with(words), "{args:?}: {output:?}");
    }
    let feeds: Vec<f64> = server
        .requests()
        .iter()
        .filter(|r| r.kind() == Ok(CommandKind::Feed))
        .map(|r| r.values[0])
        .collect();
    assert_eq!(feeds, [0.5, 1.25]);
    let output = run(server.name(), &["group", "stop", "xy"])?;
    assert!(stdout(&output).starts_with("xy: stop (tick"), "{output:?}");
    Ok(())
}

#[test]
fn a_group_claim_holds_every_axis_and_names_itself_to_others() -> Result {
    let server = groups("gclaim")?;
    let child = command(server.name(), &["group", "claim", "xy", "--duration", "2s"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()?;
    poll_json(server.name(), &["status", "--json"], |status| {
        status["axes"][1]["flags"]
            .as_array()
            .is_some_and(|flags| flags.contains(&"claimed".into()))
    })?;
    let output = run(
        server.name(),
        &["group", "move", "all", "x=1", "y=1", "a=1"],
    )?;
    assert_fails(&output, 4, "axis `x` is claimed by client 0x");
    let output = finish(child, DEADLINE)?;
    assert!(output.status.success(), "{output:?}");
    assert!(
        stderr(&output).contains("claimed group xy (x, y)"),
        "{output:?}"
    );
    assert!(stderr(&output).contains("released group xy"), "{output:?}");
    Ok(())
}

#[test]
fn watch_shows_a_line_per_group() -> Result {
    let server = groups("gwatch")?;
    let (output, screen) = in_pty(server.name(), &["watch"], "quits", b"q")?;
    assert!(output.status.success(), "{output:?}");
    for text in ["group", "xy", "all", "idle", "feed"] {
        assert!(screen.contains(text), "missing {text:?}");
    }
    let child = command(server.name(), &["watch", "--json", "--interval", "20ms"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()?;
    std::thread::sleep(std::time::Duration::from_millis(300));
    kill(Pid::from_raw(i32::try_from(child.id())?), Signal::SIGINT)?;
    let output = finish(child, DEADLINE)?;
    let first: Value = serde_json::from_str(stdout(&output).lines().next().ok_or("no line")?)?;
    assert_eq!(first["groups"][0]["name"], "xy");
    assert_eq!(first["groups"][0]["motion"], "idle");
    Ok(())
}

#[test]
fn group_move_wait_right_after_start_waits_for_readiness() -> Result {
    let server = fake_with("gready", |config: &mut FakeConfig| {
        *config = config.clone().with_groups().starting_for(300);
    })?;
    let output = run(
        server.name(),
        &["group", "move", "xy", "x=1", "y=2", "--wait", "--json"],
    )?;
    let report = json_of(&output)?;
    assert_eq!(report["state"], "done", "{report}");
    Ok(())
}
