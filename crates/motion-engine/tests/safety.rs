//! Engine safety rules, stepped tick by tick with ideal boards and a fake clock.

mod support;

use motion_ipc::{AxisFlags, AxisMode, CommandKind, DeviceState, FaultCode, FrameFlags, Reason};
use support::*;

#[test]
fn deadman_stops_a_jogging_axis_that_is_not_refreshed() {
    let (engine, _) = two_link_engine();
    let mut h = Harness::new(engine);
    h.ticks(2);
    let reply = h.command(CLIENT_A, 0, CommandKind::Velocity, [10.0, 0.0, 0.0]);
    assert_eq!(reply.result(), Ok(()));
    h.ticks(100);
    assert!(
        h.axis(0).velocity > 9.9,
        "jogging at 10 mm/s: {:?}",
        h.axis(0)
    );
    // Refreshing the command keeps it alive past the timeout.
    h.command(CLIENT_A, 0, CommandKind::Velocity, [10.0, 0.0, 0.0]);
    h.ticks(200);
    assert_eq!(h.axis(0).mode().unwrap(), AxisMode::Velocity);
    // No refresh for command_timeout (250 ms): the axis ramps to a stop and holds.
    h.ticks(60);
    let state = h.axis(0);
    assert!(
        state.flags().contains(AxisFlags::DEADMAN_EXPIRED),
        "{state:?}"
    );
    h.ticks(100);
    let state = h.axis(0);
    assert_eq!(state.mode().unwrap(), AxisMode::Hold);
    assert_eq!(state.velocity, 0.0);
    assert!(!state.flags().contains(AxisFlags::MOVING));
}

#[test]
fn estop_latches_and_reset_does_not_resume_the_old_move() {
    let (engine, _) = two_link_engine();
    let mut h = Harness::new(engine);
    h.ticks(2);
    let reply = h.command(CLIENT_A, 0, CommandKind::RampPosition, [80.0, 0.0, 0.0]);
    assert_eq!(reply.result(), Ok(()));
    h.ticks(300);
    let moving_at = h.axis(0).position;
    assert!(moving_at > 1.0 && moving_at < 80.0);

    let reply = h.command(CLIENT_B, u32::MAX, CommandKind::EStop, [0.0; 3]);
    assert_eq!(reply.result(), Ok(()));
    assert!(h.frame.flags().contains(FrameFlags::ESTOP_LATCHED));
    // Nothing moves while latched; stop and reset are the only ways forward.
    let refused = h.command(CLIENT_A, 0, CommandKind::RampPosition, [10.0, 0.0, 0.0]);
    assert_eq!(refused.result(), Err(Reason::EstopLatched));
    let refused = h.command(CLIENT_A, 2, CommandKind::Velocity, [1.0, 0.0, 0.0]);
    assert_eq!(refused.result(), Err(Reason::EstopLatched));
    h.ticks(300);
    let stopped_at = h.axis(0).position;
    assert_eq!(h.axis(0).velocity, 0.0);
    assert!(h.axis(0).flags().contains(AxisFlags::ESTOPPED));

    assert_eq!(
        h.command(CLIENT_B, u32::MAX, CommandKind::Reset, [0.0; 3])
            .result(),
        Ok(())
    );
    assert!(!h.frame.flags().contains(FrameFlags::ESTOP_LATCHED));
    let state = h.axis(0);
    assert_eq!(
        state.target, stopped_at,
        "after reset the target is where the axis is"
    );
    h.ticks(300);
    assert_eq!(
        h.axis(0).position,
        stopped_at,
        "reset never resumes a stale setpoint"
    );
    assert!(!h.axis(0).flags().contains(AxisFlags::ESTOPPED));
}

#[test]
fn claims_are_exclusive_and_die_with_their_client() {
    let (engine, _) = two_link_engine();
    let mut h = Harness::new(engine);
    h.ticks(1);
    assert_eq!(
        h.command(CLIENT_A, 1, CommandKind::Claim, [0.0; 3])
            .result(),
        Ok(())
    );
    assert!(h.axis(1).flags().contains(AxisFlags::CLAIMED));
    assert_eq!(h.axis(1).claimed_by, CLIENT_A);
    let refused = h.command(CLIENT_B, 1, CommandKind::Velocity, [5.0, 0.0, 0.0]);
    assert_eq!(refused.result(), Err(Reason::ClaimedByOther));
    assert_eq!(
        h.command(CLIENT_B, 1, CommandKind::Claim, [0.0; 3])
            .result(),
        Err(Reason::ClaimedByOther)
    );
    assert_eq!(
        h.command(CLIENT_B, 1, CommandKind::Release, [0.0; 3])
            .result(),
        Err(Reason::NotClaimed)
    );
    // The owner commands; anyone may stop.
    assert_eq!(
        h.command(CLIENT_A, 1, CommandKind::Velocity, [5.0, 0.0, 0.0])
            .result(),
        Ok(())
    );
    h.ticks(50);
    assert_eq!(
        h.command(CLIENT_B, 1, CommandKind::Stop, [0.0; 3]).result(),
        Ok(())
    );
    assert_eq!(
        h.command(CLIENT_A, 1, CommandKind::Velocity, [5.0, 0.0, 0.0])
            .result(),
        Ok(())
    );
    h.ticks(50);
    // The owner dies: claim released, its jog stopped.
    h.engine.client_dead(CLIENT_A);
    h.ticks(200);
    let state = h.axis(1);
    assert!(!state.flags().contains(AxisFlags::CLAIMED));
    assert_eq!(state.velocity, 0.0);
    assert_eq!(state.mode().unwrap(), AxisMode::Hold);
    assert_eq!(
        h.command(CLIENT_B, 1, CommandKind::Claim, [0.0; 3])
            .result(),
        Ok(())
    );
}

#[test]
fn a_request_a_client_sent_just_before_it_died_starts_nothing() {
    // Campaign 1 of docs/RELIABILITY.md: a client SIGKILLed right after it renewed its
    // jog leaves that renewal queued; the server finds the client dead first, then reads
    // the renewal. It must not restart the jog (nobody would renew or stop it but the
    // deadman); a stop it sent still counts.
    let (engine, _) = two_link_engine();
    let mut h = Harness::new(engine);
    h.ticks(1);
    assert_eq!(
        h.command(CLIENT_A, 1, CommandKind::Velocity, [5.0, 0.0, 0.0])
            .result(),
        Ok(())
    );
    h.ticks(50);
    h.engine.client_dead(CLIENT_A);
    let late = h.command(CLIENT_A, 1, CommandKind::Velocity, [5.0, 0.0, 0.0]);
    assert_eq!(late.result(), Err(Reason::IdentityMismatch));
    let late = h.command(CLIENT_A, 0, CommandKind::Position, [1.0, 0.0, 0.0]);
    assert_eq!(late.result(), Err(Reason::IdentityMismatch));
    h.ticks(200);
    let state = h.axis(1);
    assert_eq!(state.velocity, 0.0);
    assert_eq!(state.mode().unwrap(), AxisMode::Hold);
    assert_eq!(
        h.command(CLIENT_A, 1, CommandKind::Stop, [0.0; 3]).result(),
        Ok(())
    );
    // Another client is not affected.
    assert_eq!(
        h.command(CLIENT_B, 1, CommandKind::Velocity, [5.0, 0.0, 0.0])
            .result(),
        Ok(())
    );
}

#[test]
fn bad_values_are_refused_and_nothing_reaches_the_wire() {
    let (engine, controls) = two_link_engine();
    let mut h = Harness::new(engine);
    h.ticks(2);
    // The start-up stop of every channel went out; nothing else may follow.
    for control in &controls {
        let mut control = control.lock().unwrap();
        assert_eq!(control.wire.len(), 2, "one start-up stop per channel");
        control.wire.clear();
    }
    let cases = [
        (
            CommandKind::Velocity,
            [f64::NAN, 0.0, 0.0],
            Reason::NotFinite,
        ),
        (
            CommandKind::Velocity,
            [f64::INFINITY, 0.0, 0.0],
            Reason::NotFinite,
        ),
        (
            CommandKind::RampPosition,
            [10.0, f64::NEG_INFINITY, 0.0],
            Reason::NotFinite,
        ),
        (CommandKind::Position, [100.5, 0.0, 0.0], Reason::OutOfRange),
        (
            CommandKind::RampPosition,
            [-100.5, 0.0, 0.0],
            Reason::OutOfRange,
        ),
        (
            CommandKind::Velocity,
            [50.1, 0.0, 0.0],
            Reason::VelocityLimit,
        ),
        (
            CommandKind::RampVelocity,
            [5.0, 501.0, 0.0],
            Reason::AccelLimit,
        ),
        (
            CommandKind::RampVelocity,
            [5.0, -1.0, 0.0],
            Reason::AccelLimit,
        ),
        (
            CommandKind::RampPosition,
            [5.0, -1.0, 0.0],
            Reason::VelocityLimit,
        ),
        (CommandKind::Power, [1.5, 0.0, 0.0], Reason::PowerLimit),
        (
            CommandKind::SetPosition,
            [1e9, 0.0, 0.0],
            Reason::OutOfRange,
        ),
    ];
    for (kind, values, reason) in cases {
        let reply = h.command(CLIENT_A, 0, kind, values);
        assert_eq!(reply.result(), Err(reason), "{kind:?} {values:?}");
    }
    let unknown = h.command(CLIENT_A, 99, CommandKind::Velocity, [1.0, 0.0, 0.0]);
    assert_eq!(unknown.result(), Err(Reason::UnknownAxis));
    let mut garbled = motion_ipc::CommandRequest::new(CLIENT_A, 1000, 0, CommandKind::Velocity);
    garbled.kind = 77;
    h.port.requests.push_back(garbled);
    garbled.kind = CommandKind::Velocity as u32;
    garbled.schema_version = 99;
    h.port.requests.push_back(garbled);
    h.tick();
    let reasons: Vec<_> = h.port.replies.drain(..).map(|r| r.result()).collect();
    assert_eq!(
        reasons,
        vec![Err(Reason::UnknownKind), Err(Reason::SchemaMismatch)]
    );
    h.ticks(10);
    for control in &controls {
        assert!(
            control.lock().unwrap().wire.is_empty(),
            "a refused command reached the wire"
        );
    }
    assert_eq!(h.axis(0).mode().unwrap(), AxisMode::Hold);
}

#[test]
fn unsupported_goals_are_refused_with_a_reason() {
    use motion_drivers::{GoalKind, LinkKind};
    use motion_engine::{BusConfig, DeviceConfig, Engine, EngineConfig};
    let (board, _) = IdealBoard::boxed(1, &[GoalKind::Off, GoalKind::Stop, GoalKind::Power]);
    let config = EngineConfig {
        name: "caps".into(),
        tick_hz: 1000,
        command_timeout: core::time::Duration::from_millis(250),
        links: vec![BusConfig {
            name: "spi".into(),
            kind: LinkKind::Spi,
        }],
        devices: vec![DeviceConfig {
            name: "brushed".into(),
            link: 0,
            address: 0x90,
        }],
        axes: vec![axis("a", 0, 0)],
        ..EngineConfig::default()
    };
    let mut h = Harness::new(Engine::new(config, vec![board]).unwrap());
    h.tick();
    for kind in [
        CommandKind::Position,
        CommandKind::Velocity,
        CommandKind::Home,
        CommandKind::SetPosition,
    ] {
        assert_eq!(
            h.command(CLIENT_A, 0, kind, [1.0, 0.0, 0.0]).result(),
            Err(Reason::Unsupported)
        );
    }
    assert_eq!(
        h.command(CLIENT_A, 0, CommandKind::Power, [0.5, 0.0, 0.0])
            .result(),
        Ok(())
    );
}

#[test]
fn a_dead_link_faults_only_its_axes_and_recovery_needs_a_new_command() {
    let (engine, _) = two_link_engine();
    let mut h = Harness::new(engine);
    h.ticks(2);
    h.command(CLIENT_A, 0, CommandKind::Velocity, [5.0, 0.0, 0.0]);
    h.command(CLIENT_A, 2, CommandKind::Velocity, [5.0, 0.0, 0.0]);
    h.ticks(20);
    let now = h.now;
    h.engine.link_down(0, now);
    h.ticks(50);
    for index in [0, 1] {
        let state = h.axis(index);
        assert!(state.flags().contains(AxisFlags::FAULT), "{state:?}");
        assert!(state.flags().contains(AxisFlags::STALE), "{state:?}");
        assert_eq!(state.fault().unwrap(), FaultCode::LinkDown);
    }
    for index in [2, 3] {
        let state = h.axis(index);
        assert!(!state.flags().contains(AxisFlags::STALE), "{state:?}");
        assert_eq!(state.last_refresh_tick, h.frame.tick);
    }
    let refused = h.command(CLIENT_A, 0, CommandKind::Velocity, [5.0, 0.0, 0.0]);
    assert_eq!(refused.result(), Err(Reason::LinkDown));

    let now = h.now;
    h.engine.link_up(0, now);
    h.ticks(5);
    let state = h.axis(0);
    assert!(!state.flags().contains(AxisFlags::FAULT), "{state:?}");
    assert!(!state.flags().contains(AxisFlags::STALE));
    assert_ne!(
        state.mode().unwrap(),
        AxisMode::Velocity,
        "the old goal is gone"
    );
    assert_eq!(state.velocity, 0.0);
    assert_eq!(
        h.command(CLIENT_A, 0, CommandKind::Velocity, [5.0, 0.0, 0.0])
            .result(),
        Ok(())
    );
}

#[test]
fn a_link_not_open_yet_is_starting_not_down_until_it_opens_and_down_after() {
    let (mut engine, _) = two_link_engine();
    engine.link_opening(0);
    let mut h = Harness::new(engine);
    h.ticks(50);
    // Its board is starting, nothing is sent to it, no axis faults; the other link runs.
    assert_eq!(h.engine.device_state(0), Some(DeviceState::Starting));
    assert_eq!(h.engine.device_state(1), Some(DeviceState::Online));
    for index in [0, 1] {
        let state = h.axis(index);
        assert!(!state.flags().contains(AxisFlags::FAULT), "{state:?}");
    }
    let now = h.now;
    // A failure before the first opening changes nothing: still starting, not down.
    h.engine.link_down(0, now);
    for kind in [CommandKind::Velocity, CommandKind::RampPosition] {
        let refused = h.command(CLIENT_A, 0, kind, [1.0, 0.0, 0.0]);
        assert_eq!(refused.result(), Err(Reason::DeviceStarting), "{kind:?}");
    }
    let mut buf = [0u8; 256];
    assert_eq!(
        h.engine.poll_link_transmit(0, h.now, &mut buf),
        None,
        "nothing goes to a link that never opened"
    );
    assert_eq!(
        h.command(CLIENT_A, 2, CommandKind::Velocity, [1.0, 0.0, 0.0])
            .result(),
        Ok(())
    );

    // It opens: the board starts, then takes goals.
    let now = h.now;
    h.engine.link_up(0, now);
    h.ticks(10);
    assert_eq!(h.engine.device_state(0), Some(DeviceState::Online));
    assert_eq!(
        h.command(CLIENT_A, 0, CommandKind::Velocity, [1.0, 0.0, 0.0])
            .result(),
        Ok(())
    );
    // Opened once, a failure is a link down.
    let now = h.now;
    h.engine.link_down(0, now);
    h.ticks(5);
    assert_eq!(h.engine.device_state(0), Some(DeviceState::Offline));
    let refused = h.command(CLIENT_A, 0, CommandKind::Velocity, [1.0, 0.0, 0.0]);
    assert_eq!(refused.result(), Err(Reason::LinkDown));
}

#[test]
fn a_silent_board_goes_stale_and_comes_back() {
    let (engine, controls) = two_link_engine();
    let mut h = Harness::new(engine);
    h.ticks(5);
    assert!(!h.axis(2).flags().contains(AxisFlags::STALE));
    controls[1].lock().unwrap().silent = true;
    h.ticks(30);
    assert!(h.axis(2).flags().contains(AxisFlags::STALE));
    assert!(!h.axis(0).flags().contains(AxisFlags::STALE));
    let stale_since = h.axis(2).last_refresh_tick;
    controls[1].lock().unwrap().silent = false;
    h.ticks(2);
    assert!(!h.axis(2).flags().contains(AxisFlags::STALE));
    assert!(h.axis(2).last_refresh_tick > stale_since);
}

#[test]
fn velocity_goals_stop_before_the_soft_limit_and_are_refused_at_it() {
    let (engine, _) = two_link_engine();
    let mut h = Harness::new(engine);
    h.ticks(1);
    assert_eq!(
        h.command(CLIENT_A, 0, CommandKind::SetPosition, [90.0, 0.0, 0.0])
            .result(),
        Ok(())
    );
    h.tick();
    assert_eq!(
        h.command(CLIENT_A, 0, CommandKind::Velocity, [50.0, 0.0, 0.0])
            .result(),
        Ok(())
    );
    for _ in 0..400 {
        h.tick();
        assert!(h.axis(0).position <= 100.0 + 1e-9, "{:?}", h.axis(0));
    }
    let state = h.axis(0);
    assert_eq!(state.mode().unwrap(), AxisMode::Hold, "{state:?}");
    assert!(state.position > 99.9, "{state:?}");
    assert_eq!(h.engine.counters().limit_stops, 1);
    // Further into the limit: refused. Away from it: accepted.
    let refused = h.command(CLIENT_A, 0, CommandKind::Velocity, [50.0, 0.0, 0.0]);
    assert_eq!(refused.result(), Err(Reason::OutOfRange));
    let refused = h.command(CLIENT_A, 0, CommandKind::Power, [0.2, 0.0, 0.0]);
    assert_eq!(refused.result(), Err(Reason::OutOfRange));
    let away = h.command(CLIENT_A, 0, CommandKind::Velocity, [-5.0, 0.0, 0.0]);
    assert_eq!(away.result(), Ok(()));
}

#[test]
fn every_request_is_answered_once_and_a_flood_spills_into_the_next_tick() {
    let (engine, _) = two_link_engine();
    let mut h = Harness::new(engine);
    for sequence in 0..100u64 {
        let request = motion_ipc::CommandRequest::new(CLIENT_A, sequence, 0, CommandKind::Claim);
        h.port.requests.push_back(request);
    }
    h.tick();
    assert_eq!(h.port.replies.len(), motion_engine::MAX_COMMANDS_PER_STEP);
    assert!(h.port.replies.iter().all(|r| r.tick_applied == 0));
    h.tick();
    assert_eq!(h.port.replies.len(), 100);
    let sequences: Vec<u64> = h.port.replies.iter().map(|r| r.sequence).collect();
    assert_eq!(sequences, (0..100).collect::<Vec<_>>());
    assert_eq!(h.port.replies[99].tick_applied, 1);
}

#[test]
fn a_board_fault_stops_its_axis_until_cleared_then_needs_a_new_command() {
    let (engine, controls) = two_link_engine();
    let mut h = Harness::new(engine);
    h.ticks(2);
    h.command(CLIENT_A, 2, CommandKind::Velocity, [5.0, 0.0, 0.0]);
    h.ticks(10);
    controls[1].lock().unwrap().fault = Some(motion_drivers::DeviceFault::Overspeed);
    h.ticks(100);
    let state = h.axis(2);
    assert_eq!(state.fault().unwrap(), FaultCode::Overspeed);
    assert_eq!(state.velocity, 0.0);
    assert_eq!(
        h.command(CLIENT_A, 2, CommandKind::Velocity, [5.0, 0.0, 0.0])
            .result(),
        Err(Reason::AxisFaulted)
    );
    controls[1].lock().unwrap().fault = None;
    h.ticks(3);
    assert!(!h.axis(2).flags().contains(AxisFlags::FAULT));
    assert_eq!(h.axis(2).velocity, 0.0);
    assert_eq!(
        h.command(CLIENT_A, 2, CommandKind::Velocity, [5.0, 0.0, 0.0])
            .result(),
        Ok(())
    );
}
