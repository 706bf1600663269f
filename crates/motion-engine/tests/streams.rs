//! Streamed setpoints on the fake clock: who may stream, when a setpoint applies (at most
//! once, in order, late and early ones counted), limits clamped or aborting, staleness.

mod support;

use core::time::Duration;

use motion_drivers::{Follow, LinkKind};
use motion_engine::{BusConfig, DeviceConfig, Engine, EngineConfig, GroupConfig, StreamLimit};
use motion_ipc::{
    AxisMode, ClientId, CommandKind, GroupAbort, GroupMotion, Reason, Setpoint, StreamFlags,
    StreamMode, StreamState,
};
use support::group_rig::group_command;
use support::{ALL_GOALS, CLIENT_A, CLIENT_B, Harness, IdealBoard, axis};

/// One SPI link, one ideal board with two axes (`left`, `right`: ±100 units, 50 units/s,
/// 500 units/s²), one group `base` of both.
fn rig(limit: StreamLimit, follow: Follow) -> Harness {
    let group = GroupConfig {
        name: "base".into(),
        axes: vec![0, 1],
        path_tolerance: vec![0.0; 2],
        goal_tolerance: vec![0.05; 2],
        stream_limit: limit,
        stream_timeout: 20,
        stream_buffer: 3,
        ..GroupConfig::default()
    };
    let config = EngineConfig {
        name: "streams".into(),
        links: vec![BusConfig {
            name: "spi".into(),
            kind: LinkKind::Spi,
        }],
        devices: vec![DeviceConfig {
            name: "drive".into(),
            link: 0,
            address: 0,
        }],
        axes: vec![axis("left", 0, 0), axis("right", 0, 1)],
        groups: vec![group],
        ..EngineConfig::default()
    };
    let (board, control) = IdealBoard::boxed(2, &ALL_GOALS);
    control.lock().expect("control").follow = follow;
    let mut h = Harness::new(Engine::new(config, vec![board]).expect("valid"));
    h.ticks(3);
    h
}

/// Claims the group for `CLIENT_A` and starts a stream of `mode`.
fn start(h: &mut Harness, mode: StreamMode) {
    assert_eq!(
        group_command(h, CLIENT_A, CommandKind::Claim, 0.0).result(),
        Ok(())
    );
    let reply = group_command(h, CLIENT_A, CommandKind::Stream, f64::from(mode as u32));
    assert_eq!(reply.result(), Ok(()), "{reply:?}");
    assert_eq!(h.frame.groups[0].stream(), Ok(StreamState::Streaming));
}

fn setpoint(mode: StreamMode, sequence: u64, for_tick: u64, values: [f64; 2]) -> Setpoint {
    let mut setpoint = Setpoint {
        sequence,
        for_tick,
        mode: mode as u32,
        ..Setpoint::EMPTY
    };
    setpoint.values[..2].copy_from_slice(&values);
    setpoint
}

/// The tick the next `step` runs.
fn next_tick(h: &Harness) -> u64 {
    h.frame.tick + 1
}

#[test]
fn setpoints_apply_in_their_tick_at_most_once_and_in_order() {
    let mut h = rig(StreamLimit::Abort, Follow::Setpoints);
    start(&mut h, StreamMode::Position);
    let base = next_tick(&h);
    // One for this tick, one for the next, one two ahead: each applies in its own tick.
    for (sequence, ahead, value) in [(1, 0, 0.0001), (2, 1, 0.0002), (3, 2, 0.0003)] {
        let sp = setpoint(
            StreamMode::Position,
            sequence,
            base + ahead,
            [value, -value],
        );
        // The shell's receive stamp: the frame carries the applied one's.
        h.engine
            .handle_setpoint_at(CLIENT_A, &sp, 1_000_000 + sequence);
    }
    for (ahead, value) in [(0, 0.0001), (1, 0.0002), (2, 0.0003)] {
        h.tick();
        let state = h.frame.groups[0];
        assert_eq!(h.frame.tick, base + ahead);
        assert_eq!(state.last_applied_tick, base + ahead, "{state:?}");
        assert_eq!(state.last_received_ns, 1_000_001 + ahead, "{state:?}");
        assert!(state.stream_flags().contains(StreamFlags::APPLIED));
        assert!((h.frame.axes[0].desired_position - value).abs() < 1e-12);
        assert!((h.frame.axes[1].desired_position + value).abs() < 1e-12);
        assert_eq!(h.frame.axes[0].mode(), Ok(AxisMode::Group));
    }
    assert_eq!(h.frame.groups[0].applied, 3);
    // A sequence not above the last applied one is late, never applied twice.
    let now = next_tick(&h);
    h.engine.handle_setpoint(
        CLIENT_A,
        &setpoint(StreamMode::Position, 3, now, [0.5, 0.5]),
    );
    h.tick();
    let state = h.frame.groups[0];
    assert_eq!((state.applied, state.late), (3, 1), "{state:?}");
    assert!((h.frame.axes[0].desired_position - 0.0003).abs() < 1e-12);
    // Two due in one tick (the first a tick late): each applies on its own time, the
    // first now, the second in the next tick — the stream runs a tick behind from then on
    // (`stream_delay`), nothing is skipped.
    let now = next_tick(&h);
    h.engine.handle_setpoint(
        CLIENT_A,
        &setpoint(StreamMode::Position, 4, now - 1, [0.0004, 0.0]),
    );
    h.engine.handle_setpoint(
        CLIENT_A,
        &setpoint(StreamMode::Position, 5, now, [0.0005, 0.0]),
    );
    h.tick();
    let state = h.frame.groups[0];
    assert_eq!(
        (
            state.applied,
            state.late,
            state.last_sequence,
            state.stream_delay
        ),
        (4, 1, 4, 1),
        "{state:?}"
    );
    assert!((h.frame.axes[0].desired_position - 0.0004).abs() < 1e-12);
    h.tick();
    let state = h.frame.groups[0];
    assert_eq!(
        (
            state.applied,
            state.late,
            state.last_sequence,
            state.stream_delay
        ),
        (5, 1, 5, 1),
        "{state:?}"
    );
    assert_eq!(state.last_applied_tick, now + 1);
    assert!((h.frame.axes[0].desired_position - 0.0005).abs() < 1e-12);
    // Two for the same tick: the newer sequence applies, the other is late.
    let now = next_tick(&h);
    for (sequence, value) in [(6, 0.00061), (7, 0.0006)] {
        h.engine.handle_setpoint(
            CLIENT_A,
            &setpoint(StreamMode::Position, sequence, now - 1, [value, 0.0]),
        );
    }
    h.tick();
    let state = h.frame.groups[0];
    assert_eq!(
        (state.applied, state.late, state.last_sequence),
        (6, 2, 7),
        "{state:?}"
    );
    assert!((h.frame.axes[0].desired_position - 0.0006).abs() < 1e-12);
    // More than stream_buffer (3) ticks behind: late, never applied; the next on time is.
    let now = next_tick(&h);
    h.engine.handle_setpoint(
        CLIENT_A,
        &setpoint(StreamMode::Position, 8, now - 5, [0.0007, 0.0]),
    );
    h.engine.handle_setpoint(
        CLIENT_A,
        &setpoint(StreamMode::Position, 9, now - 1, [0.0007, 0.0]),
    );
    h.tick();
    let state = h.frame.groups[0];
    assert_eq!(
        (state.applied, state.late, state.last_sequence),
        (7, 3, 9),
        "{state:?}"
    );
    // Too far ahead: early, dropped.
    let now = next_tick(&h);
    h.engine.handle_setpoint(
        CLIENT_A,
        &setpoint(StreamMode::Position, 6, now + 4, [0.06, 0.0]),
    );
    h.tick();
    assert_eq!(h.frame.groups[0].early, 1);
}

#[test]
fn only_the_claimant_streams_and_others_are_counted_not_heard() {
    let mut h = rig(StreamLimit::Abort, Follow::Setpoints);
    // Without the group's claim there is no stream.
    let reply = group_command(&mut h, CLIENT_A, CommandKind::Stream, 1.0);
    assert_eq!(reply.result(), Err(Reason::NotClaimed));
    start(&mut h, StreamMode::Position);
    let reply = group_command(&mut h, CLIENT_B, CommandKind::Stream, 1.0);
    assert_eq!(reply.result(), Err(Reason::ClaimedByOther));
    let now = next_tick(&h);
    h.engine.handle_setpoint(
        CLIENT_B,
        &setpoint(StreamMode::Position, 1, now, [5.0, 5.0]),
    );
    h.engine.handle_setpoint(
        ClientId::NONE,
        &setpoint(StreamMode::Position, 2, now, [5.0, 5.0]),
    );
    h.engine.handle_setpoint(
        CLIENT_A,
        &setpoint(StreamMode::Velocity, 3, now, [5.0, 5.0]),
    );
    let mut bad = setpoint(StreamMode::Position, 4, now, [f64::NAN, 0.0]);
    h.engine.handle_setpoint(CLIENT_A, &bad);
    bad.values[0] = 0.0001;
    h.engine.handle_setpoint(CLIENT_A, &bad);
    h.tick();
    let state = h.frame.groups[0];
    assert_eq!((state.refused, state.applied), (4, 1), "{state:?}");
    assert_eq!(state.stream(), Ok(StreamState::Streaming));
    assert_eq!(state.owner, CLIENT_A);
    assert!((h.frame.axes[0].desired_position - 0.0001).abs() < 1e-12);
    // The claimant's single-axis commands are refused while the group streams; a stop is
    // not.
    let reply = h.command(CLIENT_A, 0, CommandKind::Position, [1.0, 0.0, 0.0]);
    assert_eq!(reply.result(), Err(Reason::GroupBusy));
}

#[test]
fn a_step_beyond_a_limit_is_clamped_and_counted_or_aborts() {
    let mut h = rig(StreamLimit::Clamp, Follow::Setpoints);
    start(&mut h, StreamMode::Position);
    // 1 unit in one tick is 1000 units/s: clamped to what max_accel allows from rest.
    let now = next_tick(&h);
    h.engine.handle_setpoint(
        CLIENT_A,
        &setpoint(StreamMode::Position, 1, now, [1.0, 0.0]),
    );
    h.tick();
    let state = h.frame.groups[0];
    assert_eq!(state.clamped, 1);
    assert!(state.stream_flags().contains(StreamFlags::CLAMPED));
    let first = h.frame.axes[0].desired_position;
    // From rest at 500 units/s² for 1 ms: 0.5 units/s, 0.0005 units.
    assert!((first - 0.0005).abs() < 1e-12, "{first}");
    assert_eq!(state.stream(), Ok(StreamState::Streaming));
    // Beyond the soft limit: clamped to it (and to the rates on the way).
    let now = next_tick(&h);
    h.engine.handle_setpoint(
        CLIENT_A,
        &setpoint(StreamMode::Position, 2, now, [0.0, 500.0]),
    );
    h.tick();
    assert_eq!(h.frame.groups[0].clamped, 2);

    let mut h = rig(StreamLimit::Abort, Follow::Setpoints);
    start(&mut h, StreamMode::Position);
    let now = next_tick(&h);
    h.engine.handle_setpoint(
        CLIENT_A,
        &setpoint(StreamMode::Position, 1, now, [0.0, 1.0]),
    );
    h.tick();
    let state = h.frame.groups[0];
    assert_eq!(state.motion(), Ok(GroupMotion::Aborted));
    assert_eq!(state.abort(), Ok(GroupAbort::StreamLimit));
    assert_eq!(state.stream(), Ok(StreamState::Aborted));
    assert_eq!(state.abort_axis(), Some(1));
    assert!(state.abort_value > state.abort_limit, "{state:?}");
    for axis in 0..2 {
        let mode = h.frame.axes[axis].mode().expect("mode");
        assert!(
            matches!(mode, AxisMode::Stopping | AxisMode::Hold),
            "{mode:?}"
        );
    }
    // A new stream starts only with a new start.
    let now = next_tick(&h);
    h.engine.handle_setpoint(
        CLIENT_A,
        &setpoint(StreamMode::Position, 2, now, [0.0, 0.0]),
    );
    h.tick();
    assert_eq!(h.frame.groups[0].refused, 1);
    let reply = group_command(&mut h, CLIENT_A, CommandKind::Stream, 1.0);
    assert_eq!(reply.result(), Ok(()));
}

#[test]
fn a_stream_that_goes_quiet_stops_from_the_measured_speed() {
    for follow in [Follow::Setpoints, Follow::Segments, Follow::Velocity] {
        let mut h = rig(StreamLimit::Abort, follow);
        start(&mut h, StreamMode::Velocity);
        // Accelerate to 20 units/s within max_accel (0.5 units/s per tick).
        let mut velocity = 0.0;
        for sequence in 1..=60 {
            velocity = (velocity + 0.4_f64).min(20.0);
            let now = next_tick(&h);
            let sp = setpoint(StreamMode::Velocity, sequence, now, [velocity, -velocity]);
            h.engine.handle_setpoint(CLIENT_A, &sp);
            h.tick();
        }
        let state = h.frame.groups[0];
        assert_eq!(
            (state.applied, state.clamped),
            (60, 0),
            "{follow:?} {state:?}"
        );
        assert!(h.frame.axes[0].desired_velocity > 19.0);
        // Then nothing: after stream_timeout ticks the group stops.
        let mut stale_at = None;
        for tick in 0..100 {
            h.tick();
            if h.frame.groups[0].stream() == Ok(StreamState::Stale) {
                stale_at = Some(tick);
                break;
            }
        }
        let stale_at = stale_at.expect("the stream went stale");
        assert!((18..=20).contains(&stale_at), "{follow:?}: {stale_at}");
        let state = h.frame.groups[0];
        assert_eq!(state.abort(), Ok(GroupAbort::StreamStale));
        assert_eq!(h.frame.axes[0].mode(), Ok(AxisMode::Stopping), "{follow:?}");
        // It comes to rest within the deceleration time (|v| / max_accel), and holds.
        for _ in 0..200 {
            h.tick();
        }
        assert_eq!(h.frame.axes[0].mode(), Ok(AxisMode::Hold), "{follow:?}");
        assert_eq!(h.frame.axes[0].velocity, 0.0);
    }
}

/// Issue 40: a claimant sending a setpoint that can never apply (its last sequence again,
/// or one far behind) every tick does not keep the stream alive: it goes stale after
/// `stream_timeout` ticks and the group stops.
#[test]
fn setpoints_that_can_never_apply_do_not_keep_a_stream_alive() {
    let mut h = rig(StreamLimit::Abort, Follow::Setpoints);
    start(&mut h, StreamMode::Velocity);
    let now = next_tick(&h);
    h.engine.handle_setpoint(
        CLIENT_A,
        &setpoint(StreamMode::Velocity, 1, now, [0.4, -0.4]),
    );
    h.tick();
    assert_eq!(h.frame.groups[0].applied, 1);
    let mut stale_at = None;
    for tick in 0..100_u64 {
        let now = next_tick(&h);
        // The applied sequence again, and a new sequence for a tick long gone.
        h.engine.handle_setpoint(
            CLIENT_A,
            &setpoint(StreamMode::Velocity, 1, now, [0.4, -0.4]),
        );
        h.engine.handle_setpoint(
            CLIENT_A,
            &setpoint(
                StreamMode::Velocity,
                1000 + tick,
                now.saturating_sub(10),
                [0.4, -0.4],
            ),
        );
        h.tick();
        if h.frame.groups[0].stream() == Ok(StreamState::Stale) {
            stale_at = Some(tick);
            break;
        }
    }
    let stale_at = stale_at.expect("the stream went stale");
    assert!((18..=20).contains(&stale_at), "{stale_at}");
    let state = h.frame.groups[0];
    assert_eq!(state.abort(), Ok(GroupAbort::StreamStale), "{state:?}");
    assert_eq!(state.applied, 1, "{state:?}");
    assert!(state.late >= 2 * stale_at, "{state:?}");
}

#[test]
fn cancel_ends_a_stream_and_a_velocity_stream_keeps_its_last_velocity_meanwhile() {
    let mut h = rig(StreamLimit::Abort, Follow::Setpoints);
    start(&mut h, StreamMode::Velocity);
    let now = next_tick(&h);
    h.engine.handle_setpoint(
        CLIENT_A,
        &setpoint(StreamMode::Velocity, 1, now, [0.4, 0.0]),
    );
    for _ in 0..10 {
        h.tick();
    }
    // 1 tick applied, then 9 more at the same velocity: 10 ticks × 0.4 units/s.
    let position = h.frame.axes[0].desired_position;
    assert!((position - 0.004).abs() < 1e-9, "{position}");
    assert_eq!(
        group_command(&mut h, CLIENT_A, CommandKind::Cancel, 0.0).result(),
        Ok(())
    );
    let state = h.frame.groups[0];
    assert_eq!(state.stream(), Ok(StreamState::Idle));
    assert_eq!(state.motion(), Ok(GroupMotion::Done));
    assert_eq!(
        group_command(&mut h, CLIENT_A, CommandKind::Stream, 7.0).result(),
        Err(Reason::OutOfRange)
    );
    let _ = Duration::ZERO;
}
