//! Lines a board runs itself (`Driver::lead_line`), on the fake clock: handed over from
//! rest board by board, started on every board in one tick with the path, paused and
//! resumed by the boards that can, and followed with goals by the engine once the line
//! is not the board's any more (a feed change, a board that drifts, one too slow to
//! prepare).

mod support;

use motion_drivers::{Follow, GoalKind};
use motion_ipc::{CommandKind, GroupMotion};
use support::CLIENT_A;
use support::group_rig::{desired, group_command, line, motion, rig, run, run_out, trajectory};

const TARGETS: [f64; 4] = [40.0, -20.0, 30.0, 16.0];

/// The goals the engine sent to a board's channels (its wire) from `from` on.
fn goals_since(control: &support::BoardControl, from: usize) -> usize {
    control.wire.len().saturating_sub(from)
}

#[test]
fn a_line_from_rest_is_handed_to_the_boards_and_starts_on_all_of_them_in_one_tick() {
    let (mut h, controls) = rig([Follow::Segments, Follow::Segments], 1.0);
    {
        let mut slow = controls[0].lock().expect("control");
        slow.leads = true;
        slow.prepare_steps = 30;
        let mut quick = controls[1].lock().expect("control");
        quick.leads = true;
        quick.prepare_steps = 3;
    }
    let start = desired(&h);
    let wire_before: Vec<usize> = controls
        .iter()
        .map(|c| c.lock().expect("control").wire.len())
        .collect();
    assert!(run(&mut h, CLIENT_A, line(1, &TARGETS)).result().is_ok());
    // Each board was handed its two axes' legs: the same time law for every leg (velocity
    // and acceleration in proportion to the distance), within each axis's limits.
    let mut legs = Vec::new();
    for (board, control) in controls.iter().enumerate() {
        let control = control.lock().expect("control");
        assert_eq!(control.lines.len(), 1, "board {board}");
        for leg in &control.lines[0] {
            legs.push((board * 2 + leg.channel, *leg));
        }
    }
    assert_eq!(legs.len(), 4);
    let (_, first) = legs[0];
    let rate = first.velocity / (first.counts - start[0] * 100.0).abs();
    let accel = first.accel / (first.counts - start[0] * 100.0).abs();
    for (axis, leg) in &legs {
        let distance = (TARGETS[*axis] - start[*axis]) * 100.0;
        assert_eq!(leg.counts, TARGETS[*axis] * 100.0);
        assert!((leg.velocity / distance.abs() - rate).abs() < 1e-9 * rate);
        assert!((leg.accel / distance.abs() - accel).abs() < 1e-9 * accel);
        let (vmax, amax) = if *axis == 3 {
            (20.0, 100.0)
        } else {
            (50.0, 500.0)
        };
        assert!(leg.velocity <= vmax * 100.0 * (1.0 + 1e-9));
        assert!(leg.accel <= amax * 100.0 * (1.0 + 1e-9));
    }
    // The path waits at its start while the slow board prepares.
    for _ in 0..20 {
        h.tick();
        assert_eq!(desired(&h), start);
        assert_eq!(h.frame.groups[0].time, 0.0);
        assert!(controls[1].lock().expect("control").starts.is_empty());
    }
    let seen = run_out(&mut h, 5000);
    assert_eq!(motion(&h), GroupMotion::Done, "{:?}", h.frame.groups[0]);
    let starts: Vec<_> = controls
        .iter()
        .map(|c| c.lock().expect("control").starts.clone())
        .collect();
    assert_eq!(starts[0].len(), 1);
    assert_eq!(starts[0], starts[1], "both boards start in the same tick");
    // Every desired position arrives in the same tick, and the boards got no goal while
    // they ran the line.
    let arrivals: Vec<usize> = (0..4)
        .map(|axis| {
            seen.iter()
                .position(|d| d[axis] == TARGETS[axis])
                .expect("arrives")
        })
        .collect();
    assert!(
        arrivals.iter().all(|&tick| tick == arrivals[0]),
        "{arrivals:?}"
    );
    for (board, control) in controls.iter().enumerate() {
        let control = control.lock().expect("control");
        assert_eq!(
            goals_since(&control, wire_before[board]),
            0,
            "board {board}"
        );
    }
    for (axis, target) in TARGETS.iter().enumerate() {
        assert!((h.axis(axis).position - target).abs() <= 0.05);
    }
}

#[test]
fn a_hold_pauses_the_boards_that_can_and_the_others_are_followed_with_goals() {
    let (mut h, controls) = rig([Follow::Segments, Follow::Setpoints], 1.0);
    for (board, control) in controls.iter().enumerate() {
        let mut control = control.lock().expect("control");
        control.leads = true;
        control.pauses = board == 0;
    }
    assert!(run(&mut h, CLIENT_A, line(1, &TARGETS)).result().is_ok());
    h.ticks(150);
    let wire: Vec<usize> = controls
        .iter()
        .map(|c| c.lock().expect("control").wire.len())
        .collect();
    assert!(
        group_command(&mut h, CLIENT_A, CommandKind::Hold, 0.0)
            .result()
            .is_ok()
    );
    for _ in 0..2000 {
        h.tick();
        if motion(&h) == GroupMotion::Held {
            break;
        }
    }
    assert_eq!(motion(&h), GroupMotion::Held);
    {
        let paused = controls[0].lock().expect("control");
        assert_eq!(paused.paused, 2, "x and y paused by their board");
        assert_eq!(goals_since(&paused, wire[0]), 0);
        let followed = controls[1].lock().expect("control");
        assert_eq!(followed.paused, 0);
        assert!(
            goals_since(&followed, wire[1]) > 0,
            "z and w held with goals"
        );
    }
    let held = desired(&h);
    h.ticks(100);
    assert_eq!(desired(&h), held);
    assert!(
        group_command(&mut h, CLIENT_A, CommandKind::Resume, 0.0)
            .result()
            .is_ok()
    );
    run_out(&mut h, 5000);
    assert_eq!(motion(&h), GroupMotion::Done, "{:?}", h.frame.groups[0]);
    assert_eq!(controls[0].lock().expect("control").resumed, 2);
    for (axis, target) in TARGETS.iter().enumerate() {
        assert!((h.axis(axis).position - target).abs() <= 0.05);
    }
}

#[test]
fn a_feed_change_hands_the_line_back_to_the_engine() {
    let (mut h, controls) = rig([Follow::Segments, Follow::Setpoints], 1.0);
    controls[0].lock().expect("control").leads = true;
    assert!(run(&mut h, CLIENT_A, line(1, &TARGETS)).result().is_ok());
    h.ticks(100);
    let wire = controls[0].lock().expect("control").wire.len();
    assert!(
        group_command(&mut h, CLIENT_A, CommandKind::Feed, 0.5)
            .result()
            .is_ok()
    );
    h.ticks(50);
    let control = controls[0].lock().expect("control");
    assert!(goals_since(&control, wire) > 0);
    assert_eq!(control.wire[wire].1, GoalKind::RampPosition as u8);
    drop(control);
    run_out(&mut h, 10_000);
    assert_eq!(motion(&h), GroupMotion::Done, "{:?}", h.frame.groups[0]);
}

/// A board that runs the line off the path (its own rates are not exactly the path's) is
/// followed with goals once it is half its path tolerance away, and the group still ends
/// done, not aborted.
#[test]
fn a_board_drifting_off_the_line_is_followed_with_goals() {
    let (mut h, controls) = rig([Follow::Segments, Follow::Segments], 1.0);
    for control in &controls {
        control.lock().expect("control").leads = true;
    }
    assert!(run(&mut h, CLIENT_A, line(1, &TARGETS)).result().is_ok());
    h.ticks(5);
    let wire: Vec<usize> = controls
        .iter()
        .map(|c| c.lock().expect("control").wire.len())
        .collect();
    // x slips 1 mm/s behind: half its 1 mm tolerance after about half a second.
    controls[0].lock().expect("control").drift[0] = -100.0;
    let mut deviation: f64 = 0.0;
    for _ in 0..10_000 {
        h.tick();
        let x = h.axis(0);
        deviation = deviation.max((x.desired_position - x.position).abs());
        if goals_since(&controls[0].lock().expect("control"), wire[0]) > 0 {
            break;
        }
    }
    assert!(
        goals_since(&controls[0].lock().expect("control"), wire[0]) > 0,
        "x's board is followed with goals"
    );
    assert!(deviation > 0.5 && deviation < 0.6, "{deviation}");
    controls[0].lock().expect("control").drift[0] = 0.0;
    // z and w keep their board's line.
    assert_eq!(
        goals_since(&controls[1].lock().expect("control"), wire[1]),
        0
    );
    run_out(&mut h, 10_000);
    assert_eq!(motion(&h), GroupMotion::Done, "{:?}", h.frame.groups[0]);
}

#[test]
fn a_board_too_slow_to_prepare_is_followed_with_goals_after_half_a_second() {
    let (mut h, controls) = rig([Follow::Segments, Follow::Setpoints], 1.0);
    {
        let mut control = controls[0].lock().expect("control");
        control.leads = true;
        control.prepare_steps = 100_000;
    }
    let start = desired(&h);
    assert!(run(&mut h, CLIENT_A, line(1, &TARGETS)).result().is_ok());
    h.ticks(490);
    assert_eq!(desired(&h), start, "the path waits for the boards");
    h.ticks(20);
    assert_ne!(desired(&h), start, "then starts without the board's line");
    assert!(controls[0].lock().expect("control").starts.is_empty());
    run_out(&mut h, 10_000);
    assert_eq!(motion(&h), GroupMotion::Done, "{:?}", h.frame.groups[0]);
}

/// Only a line from rest is handed over: not a line replacing a moving path, not a
/// trajectory.
#[test]
fn only_a_line_from_rest_is_handed_over() {
    let (mut h, controls) = rig([Follow::Segments, Follow::Setpoints], 1.0);
    controls[0].lock().expect("control").leads = true;
    let points = [(0.5, [2.0, 1.0, 1.0, 1.0]), (1.0, [3.0, 2.0, 2.0, 1.0])];
    assert!(
        run(&mut h, CLIENT_A, trajectory(1, &points, None))
            .result()
            .is_ok()
    );
    h.ticks(100);
    assert!(run(&mut h, CLIENT_A, line(2, &TARGETS)).result().is_ok());
    run_out(&mut h, 10_000);
    assert_eq!(motion(&h), GroupMotion::Done, "{:?}", h.frame.groups[0]);
    assert!(controls[0].lock().expect("control").lines.is_empty());
}
