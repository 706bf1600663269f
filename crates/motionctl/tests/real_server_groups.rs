//! `motionctl group …` and the client's groups against a real `motiond` on `config/sim.toml`
//! with its groups `arm` = x y z a b c, `gantry` = x feeder lift, `base` = wheel_left
//! wheel_right (see `real_server.rs` for how the server is found and started).

mod common;

use core::time::Duration;
use std::process::Stdio;
use std::time::Instant;

use common::real::RealServer;
use common::*;
use iceoryx2::prelude::ipc;
use motion_client::ipc::{GroupMotion, Reason};
use motion_client::{Client, ClientError, Trajectory};
use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;
use serde_json::Value;

/// Per axis of `group` (from `group list --json`): (name, path tolerance, goal tolerance).
fn tolerances(server: &str, group: &str) -> Result<Vec<(String, Option<f64>, f64)>> {
    let list = json_of(&run(server, &["group", "list", "--json"])?)?;
    let entry = list["groups"]
        .as_array()
        .and_then(|groups| groups.iter().find(|g| g["name"] == group))
        .ok_or_else(|| format!("no group {group} in {list}"))?;
    entry["axes"]
        .as_array()
        .ok_or("axes")?
        .iter()
        .map(|axis| {
            Ok((
                axis["name"].as_str().ok_or("name")?.to_owned(),
                axis["path_tolerance"].as_f64(),
                axis["goal_tolerance"].as_f64().ok_or("goal tolerance")?,
            ))
        })
        .collect()
}

fn position(server: &str, axis: &str) -> Result<f64> {
    let status = status_json(server)?;
    status["axes"]
        .as_array()
        .and_then(|axes| axes.iter().find(|a| a["name"] == axis))
        .and_then(|a| a["position"].as_f64())
        .ok_or_else(|| format!("no position of {axis}").into())
}

/// Checks a `--wait --json` report: done, every axis arrived and stayed within its path
/// tolerance, and ended within its goal tolerance of `targets`.
fn assert_done(server: &str, group: &str, report: &Value, targets: &[(&str, f64)]) -> Result {
    assert_eq!(report["state"], "done", "{report}");
    assert_eq!(report["abort"], Value::Null, "{report}");
    for (name, path_tolerance, goal_tolerance) in tolerances(server, group)? {
        let axis = &report["axes"][&name];
        assert!(axis["arrived_tick"].as_u64().is_some(), "{name}: {report}");
        if let (Some(error), Some(tolerance)) = (axis["max_path_error"].as_f64(), path_tolerance) {
            assert!(
                error <= tolerance,
                "{name}: path error {error} > {tolerance}"
            );
        }
        if let Some((_, target)) = targets.iter().find(|(axis, _)| *axis == name) {
            let reached = position(server, &name)?;
            assert!(
                (reached - target).abs() <= goal_tolerance,
                "{name} at {reached}, target {target} ± {goal_tolerance}"
            );
        }
    }
    Ok(())
}

#[test]
fn real_group_list_shows_the_sim_groups() -> Result {
    let server = RealServer::start()?;
    let names = |group: &str| -> Result<Vec<String>> {
        Ok(tolerances(&server.name, group)?
            .into_iter()
            .map(|(name, ..)| name)
            .collect())
    };
    assert_eq!(names("arm")?, ["x", "y", "z", "a", "b", "c"]);
    assert_eq!(names("gantry")?, ["x", "feeder", "lift"]);
    assert_eq!(names("base")?, ["wheel_left", "wheel_right"]);
    Ok(())
}

#[test]
fn real_group_move_gantry_arrives_together() -> Result {
    let server = RealServer::start()?;
    let output = run(
        &server.name,
        &[
            "group",
            "move",
            "gantry",
            "x=200",
            "feeder=100",
            "lift=150",
            "--wait",
            "--json",
            "--timeout",
            "60s",
        ],
    )?;
    let report = json_of(&output)?;
    assert_done(
        &server.name,
        "gantry",
        &report,
        &[("x", 200.0), ("feeder", 100.0), ("lift", 150.0)],
    )?;
    // A synchronized line: the axes arrive within the group's goal_time_tolerance of
    // one another (their boards' lag and refresh apart), not each at its own speed (x
    // alone would take 4 s, the lift 15 s).
    let ticks: Vec<u64> = ["x", "feeder", "lift"]
        .iter()
        .filter_map(|axis| report["axes"][axis]["arrived_tick"].as_u64())
        .collect();
    assert_eq!(ticks.len(), 3, "{report}");
    let list = json_of(&run(&server.name, &["group", "list", "--json"])?)?;
    let goal_time = list["groups"]
        .as_array()
        .and_then(|groups| groups.iter().find(|g| g["name"] == "gantry"))
        .and_then(|g| g["goal_time_tolerance"].as_f64())
        .ok_or("goal_time_tolerance")?;
    let spread = ticks.iter().max().unwrap_or(&0) - ticks.iter().min().unwrap_or(&0);
    // 1 kHz: a tick is a millisecond.
    assert!(
        (spread as f64) <= goal_time * 1000.0,
        "arrivals {ticks:?}, goal_time_tolerance {goal_time} s"
    );
    Ok(())
}

#[test]
fn real_group_follow_arm_csv_ends_at_its_last_point() -> Result {
    let server = RealServer::start()?;
    // From where the arm is at time 0 (a first point away from it would need a lead-in
    // that reaches the second point's speed in time), out and along a line.
    let start: Vec<f64> = ["x", "y", "z", "a", "b", "c"]
        .iter()
        .map(|axis| position(&server.name, axis))
        .collect::<Result<_>>()?;
    let offsets = [20.0, 15.0, -10.0, 30.0, 10.0, -30.0];
    let mut text = "time,x,y,z,a,b,c\n".to_owned();
    // 21 rows, 10 s.
    for step in 0..=20 {
        let share = f64::from(step) / 20.0;
        let row: Vec<String> = start
            .iter()
            .zip(offsets)
            .map(|(s, o)| format!("{}", s + o * share))
            .collect();
        text.push_str(&format!("{},{}\n", 0.5 * f64::from(step), row.join(",")));
    }
    let path = std::env::temp_dir().join(format!(
        "{}.csv",
        motion_client::testing::unique_name("arm")
    ));
    std::fs::write(&path, text)?;
    let output = run(
        &server.name,
        &[
            "group",
            "follow",
            "arm",
            path.to_str().ok_or("path")?,
            "--wait",
            "--json",
            "--timeout",
            "60s",
        ],
    )?;
    std::fs::remove_file(&path)?;
    let report = json_of(&output)?;
    let names = ["x", "y", "z", "a", "b", "c"];
    let targets: Vec<(&str, f64)> = names
        .iter()
        .zip(start.iter().zip(offsets))
        .map(|(name, (s, o))| (*name, s + o))
        .collect();
    assert_done(&server.name, "arm", &report, &targets)
}

#[test]
fn real_refused_path_names_its_point_and_axis() -> Result {
    let server = RealServer::start()?;
    let path = std::env::temp_dir().join(format!(
        "{}.csv",
        motion_client::testing::unique_name("far")
    ));
    // z's soft limits are -50..0: point 2 is outside.
    std::fs::write(
        &path,
        "time,x,y,z,a,b,c\n0.5,1,1,-1,0,0,0\n1,2,2,-2,0,0,0\n1.5,3,3,10,0,0,0\n",
    )?;
    let output = run(
        &server.name,
        &["group", "follow", "arm", path.to_str().ok_or("path")?],
    )?;
    std::fs::remove_file(&path)?;
    assert_fails(&output, 4, "at point 2, axis `z`");
    assert!(
        stderr(&output).contains(Reason::OutOfRange.message()),
        "{output:?}"
    );
    Ok(())
}

#[test]
fn real_hold_resume_feed_and_cancel_through_the_client() -> Result {
    let server = RealServer::start()?;
    let client = Client::<ipc::Service>::connect(&server.name)?;
    client.wait_ready(Duration::from_secs(10))?;
    let gantry = client.group("gantry")?;
    gantry.move_to_scaled(&[300.0, 500.0, 250.0], 0.2, 0.5)?;
    let busy = client
        .axis("lift")?
        .ramp_to(0.0, 0.0, 0.0)
        .expect_err("lift follows gantry");
    assert_eq!(busy.reason(), Some(Reason::GroupBusy));
    gantry.hold()?;
    wait_motion(&client, "gantry", GroupMotion::Held)?;
    let held = gantry.state()?.time;
    std::thread::sleep(Duration::from_millis(200));
    assert!(
        (gantry.state()?.time - held).abs() < 1e-9,
        "a held path stays put"
    );
    gantry.resume()?;
    wait_motion(&client, "gantry", GroupMotion::Moving)?;
    gantry.set_feed(0.5)?;
    std::thread::sleep(Duration::from_millis(200));
    assert_eq!(gantry.state()?.feed_set, 0.5);
    gantry.cancel()?;
    let error = gantry
        .wait_done(Duration::from_secs(30))
        .expect_err("cancelled");
    assert!(
        matches!(&error, ClientError::GroupAborted(aborted) if aborted.reason == motion_client::ipc::GroupAbort::Cancelled),
        "{error:?}"
    );
    Ok(())
}

#[test]
fn real_group_claim_names_the_holder_to_others() -> Result {
    let server = RealServer::start()?;
    let holder = command(
        &server.name,
        &["group", "claim", "arm", "--duration", "20s"],
    )
    .stdin(Stdio::null())
    .stdout(Stdio::piped())
    .stderr(Stdio::piped())
    .spawn()?;
    poll_json(&server.name, &["status", "--json"], |status| {
        status["axes"].as_array().is_some_and(|axes| {
            axes.iter().any(|a| {
                a["name"] == "c"
                    && a["flags"]
                        .as_array()
                        .is_some_and(|f| f.contains(&"claimed".into()))
            })
        })
    })?;
    let output = run(
        &server.name,
        &["group", "move", "gantry", "x=10", "feeder=0", "lift=10"],
    )?;
    assert_fails(&output, 4, "axis `x` is claimed by client 0x");
    kill(Pid::from_raw(i32::try_from(holder.id())?), Signal::SIGINT)?;
    let released = finish(holder, DEADLINE)?;
    assert!(released.status.success(), "{released:?}");
    Ok(())
}

#[test]
fn real_ctrl_c_during_a_group_wait_stops_the_group() -> Result {
    let server = RealServer::start()?;
    let child = command(
        &server.name,
        &[
            "group",
            "move",
            "base",
            "wheel_left=3000",
            "wheel_right=3000",
            "--wait",
        ],
    )
    .stdin(Stdio::null())
    .stdout(Stdio::piped())
    .stderr(Stdio::piped())
    .spawn()?;
    let client = Client::<ipc::Service>::connect(&server.name)?;
    wait_motion(&client, "base", GroupMotion::Moving)?;
    kill(Pid::from_raw(i32::try_from(child.id())?), Signal::SIGINT)?;
    let output = finish(child, DEADLINE)?;
    assert_fails(&output, 130, "group base stopped");
    let state = client.group("base")?.state()?;
    assert_eq!(state.motion, GroupMotion::Aborted, "{state:?}");
    Ok(())
}

#[test]
fn real_trajectory_from_the_client_with_velocities() -> Result {
    let server = RealServer::start()?;
    let client = Client::<ipc::Service>::connect(&server.name)?;
    client.wait_ready(Duration::from_secs(10))?;
    let gantry = client.group("gantry")?;
    let mut path = Trajectory::new(3);
    // Relative to where the gantry is (lift: 12 mm/s, 100 mm/s² in config/sim.toml).
    let start: Vec<f64> = gantry
        .axis_handles()
        .iter()
        .map(|axis| axis.state().map(|state| state.position))
        .collect::<core::result::Result<_, _>>()?;
    let at =
        |offsets: [f64; 3]| -> Vec<f64> { start.iter().zip(offsets).map(|(s, o)| s + o).collect() };
    path.push_with_velocities(3.0, &at([20.0, 10.0, 20.0]), &[10.0, 5.0, 8.0])?
        .push_with_velocities(6.0, &at([40.0, 20.0, 40.0]), &[0.0, 0.0, 0.0])?;
    gantry.follow(&path)?;
    let outcome = gantry.wait_done(Duration::from_secs(40))?;
    assert_eq!(outcome.motion, GroupMotion::Done);
    assert!((outcome.duration - 6.0).abs() < 0.01, "{outcome:?}");
    Ok(())
}

/// Waits until group `group` shows `motion` in the frames.
fn wait_motion(client: &Client<ipc::Service>, group: &str, motion: GroupMotion) -> Result {
    let handle = client.group(group)?;
    let until = Instant::now() + DEADLINE;
    while handle.state()?.motion != motion {
        if Instant::now() > until {
            return Err(format!("{group} never {}", motion.name()).into());
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    Ok(())
}
