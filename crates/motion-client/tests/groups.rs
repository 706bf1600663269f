//! Axis groups against the fake server (`FakeConfig::with_groups`: `xy` = x y, `all` = x y
//! a): lines, trajectories, refusals naming point and axis, claims, feed hold, aborts.

use core::time::Duration;

use iceoryx2::prelude::local;
use motion_client::ipc::{GroupAbort, GroupMotion, MAX_PATH_POINTS, PathKind, Reason};
use motion_client::testing::{FakeConfig, FakeServer, unique_name};
use motion_client::{Client, ClientError, Trajectory, TrajectoryError};

type Result<T = ()> = core::result::Result<T, Box<dyn std::error::Error>>;

const WAIT: Duration = Duration::from_secs(10);

fn start(prefix: &str) -> Result<(FakeServer, Client<local::Service>)> {
    let server =
        FakeServer::start::<local::Service>(FakeConfig::demo(&unique_name(prefix)).with_groups())?;
    let client = Client::<local::Service>::connect(server.name())?;
    Ok((server, client))
}

fn positions(client: &Client<local::Service>, axes: &[usize]) -> Result<Vec<f64>> {
    let frame = client.latest()?;
    Ok(axes.iter().map(|&a| frame.axes()[a].position).collect())
}

#[test]
fn a_group_is_found_by_name_and_an_unknown_name_lists_the_groups() -> Result {
    let (_server, client) = start("group-names")?;
    let all = client.group("all")?;
    assert_eq!((all.index(), all.name()), (1, "all".to_owned()));
    assert_eq!(all.axes(), ["x", "y", "a"]);
    assert_eq!(all.info().goal_tolerance[..3], [0.05; 3]);
    assert_eq!(client.groups().len(), 2);
    let error = client.group("arm").expect_err("no such group");
    assert!(
        matches!(&error, ClientError::UnknownGroup { name, known } if name == "arm" && known == &["xy", "all"]),
        "{error:?}"
    );
    assert!(error.to_string().contains("its groups: xy, all"), "{error}");
    Ok(())
}

#[test]
fn a_line_moves_every_axis_together_and_ends_done() -> Result {
    let (_server, client) = start("group-line")?;
    let xy = client.group("xy")?;
    let run = xy.move_to(&[10.0, -20.0])?;
    assert_eq!(run.path_id, 1);
    let outcome = xy.wait_done(WAIT)?;
    assert_eq!(outcome.motion, GroupMotion::Done);
    assert_eq!(outcome.path_id, run.path_id);
    assert!(outcome.duration > 0.0);
    let reached = positions(&client, &[0, 1])?;
    assert!((reached[0] - 10.0).abs() < 1e-9 && (reached[1] + 20.0).abs() < 1e-9);
    let state = xy.state()?;
    assert_eq!(
        (state.motion, state.kind),
        (GroupMotion::Done, PathKind::Line)
    );
    assert_eq!(state.abort, GroupAbort::None);
    // A second path gets the next id; scales are passed on.
    let again = xy.move_to_scaled(&[0.0, 0.0], 0.5, 0.5)?;
    assert_eq!(again.path_id, 2);
    xy.wait_done(WAIT)?;
    Ok(())
}

#[test]
fn a_trajectory_is_followed_to_its_last_point() -> Result {
    let (_server, client) = start("group-follow")?;
    let all = client.group("all")?;
    let mut path = Trajectory::new(3);
    path.push(0.2, &[1.0, 2.0, 3.0])?
        .push(0.4, &[4.0, 5.0, 6.0])?
        .push(0.5, &[4.5, 5.5, 6.5])?;
    let mut moved = 0;
    all.follow(&path)?;
    let outcome = all.wait_done_observing(WAIT, |frame| {
        if frame.groups()[1].motion == GroupMotion::Moving as u8 {
            moved += 1;
        }
    })?;
    assert!((outcome.duration - 0.5).abs() < 1e-9, "{outcome:?}");
    assert!(moved > 10, "frames seen while moving: {moved}");
    assert_eq!(positions(&client, &[0, 1, 2])?, [4.5, 5.5, 6.5]);
    assert_eq!(all.state()?.kind, PathKind::Trajectory);
    Ok(())
}

#[test]
fn a_refused_path_names_its_point_axis_and_figures() -> Result {
    let (_server, client) = start("group-refused")?;
    let xy = client.group("xy")?;
    let mut path = Trajectory::new(2);
    path.push(0.5, &[1.0, 1.0])?
        .push(1.0, &[2.0, 2.0])?
        .push(1.5, &[3.0, 250.0])?;
    let error = xy.follow(&path).expect_err("y's max is 100");
    let ClientError::GroupRefused(refusal) = &error else {
        panic!("not a group refusal: {error:?}");
    };
    assert_eq!(refusal.reason, Reason::OutOfRange);
    assert_eq!(refusal.point, Some(2));
    assert_eq!(refusal.axis.as_deref(), Some("y"));
    assert_eq!((refusal.value, refusal.limit), (Some(250.0), Some(100.0)));
    assert_eq!(error.reason(), Some(Reason::OutOfRange));
    let text = error.to_string();
    assert!(
        text.contains(
            "run on group xy refused at point 2, axis `y`: position 250.0000 mm, limit 100.0000 mm"
        ),
        "{text}"
    );
    // A point at time 0 must be where the group is.
    let mut jump = Trajectory::new(2);
    jump.push(0.0, &[50.0, 0.0])?.push(1.0, &[60.0, 0.0])?;
    let error = xy.follow(&jump).expect_err("x is at 0");
    assert_eq!(error.reason(), Some(Reason::PathStart), "{error}");
    // Wrong shapes never reach the server.
    let error = xy.move_to(&[1.0, 2.0, 3.0]).expect_err("xy has two axes");
    assert!(
        matches!(
            error,
            ClientError::Trajectory(TrajectoryError::GroupAxes {
                expected: 2,
                got: 3,
                ..
            })
        ),
        "{error:?}"
    );
    assert!(error.to_string().contains("(x, y)"), "{error}");
    let error = xy.follow(&Trajectory::new(2)).expect_err("no points");
    assert!(matches!(
        error,
        ClientError::Trajectory(TrajectoryError::Empty)
    ));
    Ok(())
}

#[test]
fn the_longest_trajectory_the_contract_holds_is_sent_and_run() -> Result {
    let (_server, client) = start("group-long")?;
    let xy = client.group("xy")?;
    let mut path = Trajectory::new(2);
    for point in 0..MAX_PATH_POINTS {
        let time = (point + 1) as f64 * 1e-3;
        path.push(time, &[point as f64 * 0.01, -(point as f64) * 0.01])?;
    }
    xy.follow(&path)?;
    xy.wait_done(WAIT)?;
    let end = positions(&client, &[0, 1])?;
    assert!(
        (end[0] - 10.23).abs() < 1e-9 && (end[1] + 10.23).abs() < 1e-9,
        "{end:?}"
    );
    Ok(())
}

#[test]
fn a_group_claim_is_all_or_none_and_names_the_holder() -> Result {
    let (server, first) = start("group-claim")?;
    let second = Client::<local::Service>::connect(server.name())?;
    let guard = first.group("xy")?.claim()?;
    let error = second
        .group("all")?
        .claim()
        .expect_err("x and y are held by the first client");
    let ClientError::GroupRefused(refusal) = &error else {
        panic!("not a group refusal: {error:?}");
    };
    assert_eq!(refusal.reason, Reason::ClaimedByOther);
    assert_eq!(refusal.axis.as_deref(), Some("x"));
    assert_eq!(refusal.holder, Some(first.id()));
    assert!(
        error
            .to_string()
            .contains(&format!("claimed by client {:#x}", first.id().as_u128())),
        "{error}"
    );
    // All or none: `a` was not claimed by the refused request.
    let a_claim = second.axis("a")?.claim_guard()?;
    drop(a_claim);
    let refused = second
        .group("xy")?
        .move_to(&[1.0, 1.0])
        .expect_err("claimed");
    assert_eq!(refused.reason(), Some(Reason::ClaimedByOther));
    drop(guard);
    let guard = second.group("all")?.claim()?;
    assert_eq!(guard.label(), "group all");
    second.group("all")?.move_to(&[1.0, 1.0, 1.0])?;
    second.group("all")?.wait_done(WAIT)?;
    Ok(())
}

#[test]
fn hold_resume_feed_and_cancel_steer_a_running_path() -> Result {
    let (_server, client) = start("group-hold")?;
    let xy = client.group("xy")?;
    let idle = xy.hold().expect_err("nothing runs");
    assert_eq!(idle.reason(), Some(Reason::NotMoving));
    xy.move_to_scaled(&[90.0, 90.0], 0.1, 1.0)?; // 18 s at 5 mm/s
    xy.hold()?;
    let held = wait_motion(&client, GroupMotion::Held)?;
    let paused = xy.state()?.time;
    std::thread::sleep(Duration::from_millis(50));
    assert_eq!(xy.state()?.time, paused, "a held path stays put ({held})");
    xy.resume()?;
    wait_motion(&client, GroupMotion::Moving)?;
    xy.set_feed(0.5)?;
    let feed = xy.set_feed(2.0).expect_err("at most 150 %");
    assert_eq!(feed.reason(), Some(Reason::OutOfRange));
    std::thread::sleep(Duration::from_millis(20));
    assert_eq!(xy.state()?.feed_set, 0.5);
    let busy = client
        .axis("x")?
        .ramp_to(0.0, 0.0, 0.0)
        .expect_err("x follows xy");
    assert_eq!(busy.reason(), Some(Reason::GroupBusy));
    xy.cancel()?;
    let error = xy.wait_done(WAIT).expect_err("cancelled");
    let ClientError::GroupAborted(aborted) = &error else {
        panic!("not an abort: {error:?}");
    };
    assert_eq!(aborted.reason, GroupAbort::Cancelled);
    assert!(error.to_string().contains("aborted (cancelled)"), "{error}");
    Ok(())
}

#[test]
fn an_abort_names_the_axis_and_its_figures() -> Result {
    let (server, client) = start("group-abort")?;
    let all = client.group("all")?;
    all.move_to_scaled(&[50.0, 50.0, 50.0], 0.1, 1.0)?;
    server.abort_group(1, GroupAbort::PathTolerance, Some(1), 0.75, 0.5);
    let error = all.wait_done(WAIT).expect_err("aborted");
    let ClientError::GroupAborted(aborted) = &error else {
        panic!("not an abort: {error:?}");
    };
    assert_eq!(aborted.reason, GroupAbort::PathTolerance);
    assert_eq!(aborted.axis.as_deref(), Some("y"));
    assert_eq!((aborted.value, aborted.limit), (0.75, 0.5));
    assert!(
        error
            .to_string()
            .contains("axis `y` was 0.7500 mm from its path, tolerance 0.5000 mm"),
        "{error}"
    );
    let state = all.state()?;
    assert_eq!(
        (state.motion, state.abort_axis.as_deref()),
        (GroupMotion::Aborted, Some("y"))
    );
    // A stop of a member axis ends a new motion too.
    all.move_to_scaled(&[-50.0, -50.0, -50.0], 0.1, 1.0)?;
    client.axis("a")?.stop()?;
    let error = all.wait_done(WAIT).expect_err("stopped");
    assert!(
        matches!(&error, ClientError::GroupAborted(a) if a.reason == GroupAbort::Stopped),
        "{error:?}"
    );
    Ok(())
}

#[test]
fn a_wait_times_out_naming_the_group() -> Result {
    let (_server, client) = start("group-timeout")?;
    let xy = client.group("xy")?;
    xy.move_to_scaled(&[90.0, 90.0], 0.1, 1.0)?;
    let error = xy
        .wait_done(Duration::from_millis(100))
        .expect_err("18 s to go");
    assert!(
        matches!(&error, ClientError::GroupTimeout { group, motion: "moving", .. } if group == "xy"),
        "{error:?}"
    );
    xy.stop()?;
    Ok(())
}

/// Waits until group `xy` shows `motion`; returns the tick.
fn wait_motion(client: &Client<local::Service>, motion: GroupMotion) -> Result<u64> {
    let deadline = std::time::Instant::now() + WAIT;
    loop {
        let frame = client.next_frame(WAIT)?;
        if frame.groups()[0].motion == motion as u8 {
            return Ok(frame.tick);
        }
        if std::time::Instant::now() > deadline {
            return Err(format!("group never {}", motion.name()).into());
        }
    }
}
