//! Axis groups on the fake clock: synchronized arrival, trajectories, replacement, hold,
//! resume, feed, cancel, path and goal tolerance, claims and dead clients.

mod support;

use motion_drivers::Follow;
use motion_ipc::{
    AxisMode, CommandKind, CommandRequest, FaultCode, GroupAbort, GroupMotion, Reason, Target,
};
use support::group_rig::{desired, group_command, line, motion, rig, run, run_out, trajectory};
use support::{CLIENT_A, CLIENT_B};

/// Velocity and acceleration of each axis's desired position never exceed its limits
/// (finite differences at the tick, a little slack for the discretisation).
fn assert_within_limits(seen: &[[f64; 4]], limits: [(f64, f64); 4]) {
    let dt = 1e-3;
    for axis in 0..4 {
        let (vmax, amax) = limits[axis];
        let mut previous_velocity = 0.0;
        for (tick, pair) in seen.windows(2).enumerate() {
            let velocity = (pair[1][axis] - pair[0][axis]) / dt;
            assert!(
                velocity.abs() <= vmax * (1.0 + 1e-6) + 1e-9,
                "axis {axis} tick {tick}: velocity {velocity} above {vmax}"
            );
            if tick > 0 {
                let accel = (velocity - previous_velocity) / dt;
                assert!(
                    accel.abs() <= amax * 1.02 + 1.0,
                    "axis {axis} tick {tick}: acceleration {accel} above {amax}"
                );
            }
            previous_velocity = velocity;
        }
    }
}

const LIMITS: [(f64, f64); 4] = [(50.0, 500.0), (50.0, 500.0), (50.0, 500.0), (20.0, 100.0)];

#[test]
fn a_line_starts_and_arrives_in_the_same_tick_on_every_axis() {
    let (mut h, _) = rig([Follow::Segments, Follow::Setpoints], 0.0);
    let reply = run(&mut h, CLIENT_A, line(7, &[10.0, -5.0, 3.0, 8.0]));
    assert_eq!(reply.result(), Ok(()), "{reply:?}");
    assert_eq!(motion(&h), GroupMotion::Moving);
    assert_eq!(h.frame.groups[0].path_id, 7);
    assert_eq!(h.frame.axes[0].mode().expect("mode"), AxisMode::Group);
    let seen = run_out(&mut h, 5000);
    assert_eq!(motion(&h), GroupMotion::Done, "{:?}", h.frame.groups[0]);
    let targets = [10.0, -5.0, 3.0, 8.0];
    let started: Vec<usize> = (0..4)
        .map(|axis| {
            seen.iter()
                .position(|d| d[axis] != seen[0][axis])
                .expect("moved")
        })
        .collect();
    let arrived: Vec<usize> = (0..4)
        .map(|axis| {
            seen.iter()
                .position(|d| (d[axis] - targets[axis]).abs() < 1e-9)
                .expect("arrived")
        })
        .collect();
    assert!(
        started.windows(2).all(|w| w[0] == w[1]),
        "started {started:?}"
    );
    assert!(
        arrived.windows(2).all(|w| w[0] == w[1]),
        "arrived {arrived:?}"
    );
    assert_within_limits(&seen, LIMITS);
    // w (20 units/s, 100 units/s²) sets the time: 8 units take 0.2 s to reach 20 units/s
    // and 2 units to do so, so 0.2 + 0.2 + 4/20 = 0.6 s.
    let duration = h.frame.groups[0].duration;
    assert!((duration - 0.6).abs() < 1e-6, "duration {duration}");
    for (axis, target) in h.frame.axes[..4].iter().zip(targets) {
        assert!((axis.position - target).abs() <= 0.05);
        assert_eq!(axis.mode().expect("mode"), AxisMode::Hold);
    }
}

#[test]
fn a_trajectory_with_velocities_is_followed_to_its_end() {
    let (mut h, _) = rig([Follow::Setpoints, Follow::Setpoints], 0.5);
    let points = [
        (0.5, [5.0, 0.0, 0.0, 2.0]),
        (1.0, [10.0, 5.0, -5.0, 4.0]),
        (1.5, [10.0, 10.0, -10.0, 4.0]),
    ];
    let velocities = [[10.0, 5.0, -5.0, 4.0], [5.0, 10.0, -10.0, 2.0], [0.0; 4]];
    let reply = run(&mut h, CLIENT_A, trajectory(1, &points, Some(&velocities)));
    assert_eq!(reply.result(), Ok(()), "{reply:?}");
    let mut visited = Vec::new();
    let mut seen = vec![desired(&h)];
    for _ in 0..4000 {
        h.tick();
        seen.push(desired(&h));
        visited.push(h.frame.groups[0].point);
        if !motion(&h).active() {
            break;
        }
    }
    assert_eq!(motion(&h), GroupMotion::Done, "{:?}", h.frame.groups[0]);
    assert!(
        visited.contains(&1) && visited.contains(&2),
        "points {visited:?}"
    );
    // At each point's time the path is at the point.
    for (time, positions) in &points {
        let tick = (time * 1000.0).round() as usize;
        for axis in 0..4 {
            assert!(
                (seen[tick][axis] - positions[axis]).abs() < 0.05,
                "t {time} axis {axis}"
            );
        }
    }
    assert_within_limits(&seen, LIMITS);
}

#[test]
fn a_refused_trajectory_names_its_point_and_axis_and_changes_nothing() {
    let (mut h, _) = rig([Follow::Setpoints, Follow::Setpoints], 0.0);
    // w may do 20 units/s: 10 units in 0.1 s between points 1 and 2 is far beyond.
    let points = [
        (0.5, [0.0, 0.0, 0.0, 1.0]),
        (1.0, [0.0, 0.0, 0.0, 2.0]),
        (1.1, [0.0, 0.0, 0.0, 12.0]),
    ];
    let reply = run(&mut h, CLIENT_A, trajectory(3, &points, None));
    assert!(
        matches!(
            reply.result(),
            Err(Reason::VelocityLimit | Reason::AccelLimit)
        ),
        "{reply:?}"
    );
    assert_eq!(reply.at_axis, 3, "{reply:?}");
    assert!(reply.at_point <= 2, "{reply:?}");
    assert!(reply.value.abs() > reply.limit, "{reply:?}");
    assert_eq!(motion(&h), GroupMotion::Idle);
    // Times that go back, an axis beyond its soft limit.
    let back = [(0.5, [0.0; 4]), (0.4, [1.0; 4])];
    let reply = run(&mut h, CLIENT_A, trajectory(4, &back, None));
    assert_eq!(
        (reply.result(), reply.at_point),
        (Err(Reason::PathTimes), 1)
    );
    let far = [(2.0, [0.0, 150.0, 0.0, 0.0])];
    let reply = run(&mut h, CLIENT_A, trajectory(5, &far, None));
    assert_eq!(reply.result(), Err(Reason::OutOfRange));
    assert_eq!((reply.at_point, reply.at_axis, reply.limit), (0, 1, 100.0));
    // No path of that id from this client; and a path only its publisher may run.
    let reply = group_command(&mut h, CLIENT_A, CommandKind::Run, 99.0);
    assert_eq!(reply.result(), Err(Reason::NoPath));
    h.port.paths.push((CLIENT_B, line(8, &[1.0; 4])));
    let reply = group_command(&mut h, CLIENT_A, CommandKind::Run, 8.0);
    assert_eq!(reply.result(), Err(Reason::NoPath));
    let mut wrong = line(9, &[1.0; 4]);
    wrong.axis_count = 3;
    let reply = run(&mut h, CLIENT_A, wrong);
    assert_eq!(reply.result(), Err(Reason::PathLayout));
    assert_eq!(motion(&h), GroupMotion::Idle);
}

#[test]
fn positions_whose_spline_is_too_fast_are_blended_at_the_points_and_run_to_done() {
    // w (20 units/s, 100 units/s²) at 16 units/s from rest: the exact spline through its
    // points peaks above 20 units/s. Blended: straight segments with parabolic blends, the
    // start from rest within 175 ms, w's turn at point 2 (16 → 8 units/s) in 80 ms, passed
    // at 8·0.08/8 = 0.08 from it; x passes point 2 at 10·0.08/8 = 0.1.
    let points = [
        (0.0, [0.0, 0.0, 0.0, 0.0]),
        (1.0, [10.0, 0.0, 0.0, 16.0]),
        (2.0, [20.0, 0.0, 0.0, 32.0]),
        (3.0, [20.0, 0.0, 0.0, 40.0]),
        (4.0, [10.0, 0.0, 0.0, 40.0]),
    ];
    // With no path tolerance it cannot be blended: refused at point 1, where the blend
    // would pass it (distance and tolerance in the reply).
    let (mut h, _) = rig([Follow::Setpoints, Follow::Setpoints], 0.0);
    let reply = run(&mut h, CLIENT_A, trajectory(1, &points, None));
    assert_eq!(reply.result(), Err(Reason::BlendTolerance), "{reply:?}");
    assert_eq!((reply.at_point, reply.at_axis), (1, 0), "{reply:?}");
    assert!(reply.value > reply.limit, "{reply:?}");
    assert_eq!(motion(&h), GroupMotion::Idle);

    let tolerance = 0.5;
    let (mut h, _) = rig([Follow::Setpoints, Follow::Setpoints], tolerance);
    let reply = run(&mut h, CLIENT_A, trajectory(2, &points, None));
    assert_eq!(reply.result(), Ok(()), "{reply:?}");
    let mut seen = vec![desired(&h)];
    seen.extend(run_out(&mut h, 6000));
    assert_eq!(motion(&h), GroupMotion::Done, "{:?}", h.frame.groups[0]);
    assert_within_limits(&seen, LIMITS);
    // Every point passed at its time within the tolerance (and a tick's travel); the turns
    // not exactly: blended.
    for (time, positions) in &points {
        let tick = (time * 1000.0).round() as usize;
        for axis in 0..4 {
            let distance = (seen[tick][axis] - positions[axis]).abs();
            assert!(
                distance <= tolerance + 0.05,
                "t {time} axis {axis}: {distance}"
            );
        }
    }
    assert!(
        (seen[2000][3] - 32.0).abs() > 0.04,
        "w at point 2: {}",
        seen[2000][3]
    );
    assert!(
        (seen[2000][0] - 20.0).abs() > 0.05,
        "x at point 2: {}",
        seen[2000][0]
    );
    // The end: exactly the last point.
    let last = points[points.len() - 1].1;
    assert_eq!(desired(&h), last);
    for (axis, target) in h.frame.axes[..4].iter().zip(last) {
        assert!((axis.position - target).abs() <= 0.05);
    }
}

#[test]
fn a_new_path_replaces_the_running_one_without_a_step() {
    let (mut h, _) = rig([Follow::Setpoints, Follow::Setpoints], 0.0);
    assert_eq!(
        run(&mut h, CLIENT_A, line(1, &[20.0, 20.0, 20.0, 10.0])).result(),
        Ok(())
    );
    let mut seen = vec![desired(&h)];
    for _ in 0..250 {
        h.tick();
        seen.push(desired(&h));
    }
    assert_eq!(motion(&h), GroupMotion::Moving);
    // Mid-flight, back towards the start; then a trajectory replaces that.
    h.port
        .paths
        .push((CLIENT_A, line(2, &[-10.0, 0.0, 5.0, -5.0])));
    h.sequence += 1;
    let mut request =
        CommandRequest::new(CLIENT_A, h.sequence, 0, CommandKind::Run).with_values([2.0, 0.0, 0.0]);
    request.target = Target::Group as u32;
    h.port.requests.push_back(request);
    h.tick();
    seen.push(desired(&h));
    assert_eq!(h.port.replies.pop().expect("reply").result(), Ok(()));
    for _ in 0..300 {
        h.tick();
        seen.push(desired(&h));
    }
    let points = [(1.5, [0.0, 0.0, 0.0, 0.0])];
    h.port.paths.push((CLIENT_A, trajectory(3, &points, None)));
    h.sequence += 1;
    let mut request =
        CommandRequest::new(CLIENT_A, h.sequence, 0, CommandKind::Run).with_values([3.0, 0.0, 0.0]);
    request.target = Target::Group as u32;
    h.port.requests.push_back(request);
    let rest = run_out(&mut h, 10_000);
    seen.extend(rest);

    assert_eq!(h.port.replies.pop().expect("reply").result(), Ok(()));
    assert_eq!(motion(&h), GroupMotion::Done, "{:?}", h.frame.groups[0]);
    assert_within_limits(&seen, LIMITS);
}

#[test]
fn hold_comes_to_rest_on_the_path_and_resume_ends_at_the_same_targets() {
    let (mut h, _) = rig([Follow::Segments, Follow::Setpoints], 0.0);
    let targets = [30.0, -20.0, 10.0, 8.0];
    assert_eq!(run(&mut h, CLIENT_A, line(1, &targets)).result(), Ok(()));
    let mut seen = vec![desired(&h)];
    for _ in 0..300 {
        h.tick();
        seen.push(desired(&h));
    }
    assert_eq!(
        group_command(&mut h, CLIENT_A, CommandKind::Hold, 0.0).result(),
        Ok(())
    );
    seen.push(desired(&h));
    assert_eq!(motion(&h), GroupMotion::Holding);
    for _ in 0..2000 {
        h.tick();
        seen.push(desired(&h));
        if motion(&h) == GroupMotion::Held {
            break;
        }
    }
    assert_eq!(motion(&h), GroupMotion::Held);
    assert_eq!(h.frame.groups[0].feed, 0.0);
    let held = desired(&h);
    for _ in 0..100 {
        h.tick();
        seen.push(desired(&h));
    }
    assert_eq!(desired(&h), held, "a held group stays where it stopped");
    // Still on the line from the start to the targets.
    let fraction = held[0] / targets[0];
    for axis in 0..4 {
        assert!(
            (held[axis] - targets[axis] * fraction).abs() < 1e-6,
            "axis {axis} left the line"
        );
    }
    assert_eq!(
        group_command(&mut h, CLIENT_A, CommandKind::Resume, 0.0).result(),
        Ok(())
    );
    seen.push(desired(&h));
    seen.extend(run_out(&mut h, 10_000));
    assert_eq!(motion(&h), GroupMotion::Done, "{:?}", h.frame.groups[0]);
    for (axis, target) in h.frame.axes[..4].iter().zip(targets) {
        assert!((axis.desired_position - target).abs() < 1e-9);
    }
    assert_within_limits(&seen, LIMITS);
}

#[test]
fn feed_override_scales_time_and_cancel_ends_along_the_path() {
    let (mut h, _) = rig([Follow::Setpoints, Follow::Setpoints], 0.0);
    assert_eq!(
        group_command(&mut h, CLIENT_A, CommandKind::Feed, 0.5).result(),
        Ok(())
    );
    assert_eq!(
        group_command(&mut h, CLIENT_A, CommandKind::Feed, 1.6).result(),
        Err(Reason::OutOfRange)
    );
    assert_eq!(
        run(&mut h, CLIENT_A, line(1, &[10.0, 10.0, 10.0, 4.0])).result(),
        Ok(())
    );
    h.ticks(200);
    let state = h.frame.groups[0];
    assert!(
        (state.feed - 0.5).abs() < 1e-9 && state.feed_set == 0.5,
        "{state:?}"
    );
    assert!(
        (state.time - 0.1).abs() < 0.002,
        "half the time at half the feed: {state:?}"
    );
    assert_eq!(
        group_command(&mut h, CLIENT_A, CommandKind::Cancel, 0.0).result(),
        Ok(())
    );
    let seen = run_out(&mut h, 5000);
    assert_eq!(motion(&h), GroupMotion::Aborted);
    assert_eq!(h.frame.groups[0].abort(), Ok(GroupAbort::Cancelled));
    let last = seen.last().copied().expect("seen");
    assert!(
        last[0] < 10.0 && last[0] > 0.0,
        "stopped short of the end: {last:?}"
    );
    assert_eq!(
        group_command(&mut h, CLIENT_A, CommandKind::Hold, 0.0).result(),
        Err(Reason::NotMoving)
    );
}

#[test]
fn an_axis_driven_off_the_path_aborts_the_group_and_stops_every_axis() {
    let (mut h, controls) = rig([Follow::Segments, Follow::Setpoints], 0.5);
    assert_eq!(
        run(&mut h, CLIENT_A, line(1, &[40.0, 40.0, 40.0, 10.0])).result(),
        Ok(())
    );
    h.ticks(50);
    // y's motor slips: 20 units/s on its own.
    controls[0].lock().expect("control").drift[1] = 2000.0;
    for _ in 0..2000 {
        h.tick();
        if !motion(&h).active() {
            break;
        }
    }
    let state = h.frame.groups[0];
    assert_eq!(motion(&h), GroupMotion::Aborted);
    assert_eq!(state.abort(), Ok(GroupAbort::PathTolerance));
    assert_eq!(state.abort_axis(), Some(1));
    assert!(
        state.abort_value > 0.5 && state.abort_limit == 0.5,
        "{state:?}"
    );
    for axis in 0..4 {
        let mode = h.frame.axes[axis].mode().expect("mode");
        assert!(
            matches!(mode, AxisMode::Stopping | AxisMode::Hold),
            "axis {axis}: {mode:?}"
        );
    }
}

#[test]
fn a_board_that_cannot_reach_the_end_faults_goal_tolerance() {
    let (mut h, controls) = rig([Follow::Segments, Follow::Setpoints], 0.0);
    assert_eq!(
        run(&mut h, CLIENT_A, line(1, &[5.0, 5.0, 5.0, 5.0])).result(),
        Ok(())
    );
    // x creeps backwards: it never settles within 0.05 of its goal.
    controls[0].lock().expect("control").drift[0] = -50.0;
    run_out(&mut h, 5000);
    let state = h.frame.groups[0];
    assert_eq!(
        state.abort(),
        Ok(GroupAbort::GoalTolerance),
        "{state:?} {:?}",
        h.frame.axes[0]
    );

    assert_eq!(state.abort_axis(), Some(0));
    assert_eq!(h.frame.axes[0].fault(), Ok(FaultCode::GoalTolerance));
}

#[test]
fn group_claims_are_all_or_none_and_name_the_holder() {
    let (mut h, _) = rig([Follow::Setpoints, Follow::Setpoints], 0.0);
    assert_eq!(
        h.command(CLIENT_B, 2, CommandKind::Claim, [0.0; 3])
            .result(),
        Ok(())
    );
    let reply = group_command(&mut h, CLIENT_A, CommandKind::Claim, 0.0);
    assert_eq!(reply.result(), Err(Reason::ClaimedByOther));
    assert_eq!((reply.at_axis, reply.holder), (2, CLIENT_B));
    for axis in [0, 1, 3] {
        assert!(h.frame.axes[axis].claimed_by.is_none(), "none claimed");
    }
    let reply = run(&mut h, CLIENT_A, line(1, &[1.0; 4]));
    assert_eq!(
        (reply.result(), reply.at_axis),
        (Err(Reason::ClaimedByOther), 2)
    );
    assert_eq!(
        h.command(CLIENT_B, 2, CommandKind::Release, [0.0; 3])
            .result(),
        Ok(())
    );
    assert_eq!(
        group_command(&mut h, CLIENT_A, CommandKind::Claim, 0.0).result(),
        Ok(())
    );
    assert!((0..4).all(|axis| h.frame.axes[axis].claimed_by == CLIENT_A));
    assert_eq!(h.frame.groups[0].owner, CLIENT_A);
    // Another client can neither move the group nor one of its axes.
    let reply = run(&mut h, CLIENT_B, line(2, &[1.0; 4]));
    assert_eq!(reply.result(), Err(Reason::ClaimedByOther));
    assert_eq!(run(&mut h, CLIENT_A, line(3, &[2.0; 4])).result(), Ok(()));
    let reply = h.command(CLIENT_A, 0, CommandKind::Position, [5.0, 0.0, 0.0]);
    assert_eq!(
        reply.result(),
        Err(Reason::GroupBusy),
        "its own group moves it"
    );
    assert_eq!(
        group_command(&mut h, CLIENT_A, CommandKind::Release, 0.0).result(),
        Ok(())
    );
    assert_eq!(
        group_command(&mut h, CLIENT_B, CommandKind::Release, 0.0).result(),
        Err(Reason::NotClaimed)
    );
}

#[test]
fn a_dead_client_a_stop_or_an_estop_stops_the_whole_group() {
    for event in ["dead", "stop", "estop"] {
        let (mut h, _) = rig([Follow::Segments, Follow::Setpoints], 0.0);
        assert_eq!(run(&mut h, CLIENT_A, line(1, &[40.0; 4])).result(), Ok(()));
        h.ticks(100);
        match event {
            "dead" => h.engine.client_dead(CLIENT_A),
            "stop" => {
                let reply = h.command(CLIENT_B, 3, CommandKind::Stop, [0.0; 3]);
                assert_eq!(reply.result(), Ok(()));
            }
            _ => h.engine.estop(),
        }
        h.tick();
        let expected = match event {
            "dead" => GroupAbort::ClientDead,
            "stop" => GroupAbort::Stopped,
            _ => GroupAbort::EStop,
        };
        assert_eq!(motion(&h), GroupMotion::Aborted, "{event}");
        assert_eq!(h.frame.groups[0].abort(), Ok(expected), "{event}");
        for axis in 0..4 {
            let mode = h.frame.axes[axis].mode().expect("mode");
            assert!(
                matches!(mode, AxisMode::Stopping | AxisMode::Hold),
                "{event} axis {axis}: {mode:?}"
            );
        }
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(16))]

    /// Random targets, random trajectories, a hold and a resume at random ticks, on boards
    /// that follow by setpoints and by segments: the desired positions never break a
    /// limit, the axes of a line arrive in the same tick, and every motion ends done at its
    /// targets.
    #[test]
    fn limits_hold_whatever_the_path(
        targets in proptest::array::uniform4(-90.0_f64..90.0),
        waypoints in proptest::collection::vec(proptest::array::uniform4(-50.0_f64..50.0), 1..5),
        hold_at in 1_usize..800,
        held_for in 0_usize..300,
        segments in proptest::bool::ANY,
    ) {
        let style = if segments { Follow::Segments } else { Follow::Setpoints };
        let (mut h, _) = rig([style, Follow::Setpoints], 0.0);
        let targets = [targets[0], targets[1], targets[2], targets[3].clamp(-90.0, 90.0)];
        assert_eq!(run(&mut h, CLIENT_A, line(1, &targets)).result(), Ok(()));
        let mut seen = vec![desired(&h)];
        for tick in 0..20_000 {
            if tick == hold_at {
                h.sequence += 1;
                let mut request = CommandRequest::new(CLIENT_A, h.sequence, 0, CommandKind::Hold);
                request.target = Target::Group as u32;
                h.port.requests.push_back(request);
            }
            if tick == hold_at + held_for + 1 {
                h.sequence += 1;
                let mut request = CommandRequest::new(CLIENT_A, h.sequence, 0, CommandKind::Resume);
                request.target = Target::Group as u32;
                h.port.requests.push_back(request);
            }
            h.tick();
            seen.push(desired(&h));
            if !motion(&h).active() && tick > hold_at + held_for + 1 {
                break;
            }
        }
        assert_eq!(motion(&h), GroupMotion::Done, "{:?}", h.frame.groups[0]);
        assert_within_limits(&seen, LIMITS);
        for (axis, target) in h.frame.axes[..4].iter().zip(targets) {
            assert!((axis.desired_position - target).abs() < 1e-9);
        }
        // A trajectory through the waypoints, timed generously (16 s to the first, 20 s
        // between: within every axis's limits for any two points), from where the line
        // ended.
        let points: Vec<(f64, [f64; 4])> = waypoints
            .iter()
            .enumerate()
            .map(|(index, point)| (16.0 + 20.0 * index as f64, *point))
            .collect();
        let reply = run(&mut h, CLIENT_A, trajectory(2, &points, None));
        assert_eq!(reply.result(), Ok(()), "{reply:?}");
        let seen = run_out(&mut h, 200_000);
        assert_eq!(motion(&h), GroupMotion::Done, "{:?}", h.frame.groups[0]);
        assert_within_limits(&seen, LIMITS);
    }
}
