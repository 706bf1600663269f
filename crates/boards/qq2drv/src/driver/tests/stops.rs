//! Stops planned from the measured velocity, and `Off`.

use super::*;

#[test]
fn stop_resets_the_setpoint_to_the_measured_velocity_then_ramps_and_holds() {
    let (mut driver, mut now) = running();
    // The channel was asked for 3000 transitions/s but really runs at 900 (saturated).
    let mosi = acked(
        &mut driver,
        now,
        0,
        Goal::Velocity {
            velocity: 3_000.0,
            accel: 30_000.0,
        },
    );
    assert_eq!(requests(&mosi).len(), 2);
    now += 4 * MS;
    driver.handle_rx(now, &ours_stream([100, 0, 0], [900, 0, 0], [0; 3]));
    let mosi = goal_packets(&mut driver, now, 0, Goal::Stop { decel: 20_000.0 });
    // First transaction: Off, Velocity PID (the loop starts afresh), acceleration limit
    // lifted (packet 28: "A value of zero disables acceleration limiting") and the
    // velocity target = the measured 900 with no ramp (packet 36: "Set to 0 to ignore").
    let r = requests(&mosi);
    assert_eq!(r.len(), 4);
    match (&r[0], &r[1], &r[2], &r[3]) {
        (
            Request::SetControlMode(off),
            Request::SetControlMode(velocity),
            Request::SetAccelerationLimit(limit),
            Request::VelocityRamp(ramp),
        ) => {
            assert_eq!(one(off).mode, ControlMode::Off);
            assert_eq!(one(velocity).mode, ControlMode::VelocityPid);
            assert_eq!(one(limit).limit, 0);
            assert_eq!((one(ramp).velocity, one(ramp).acceleration), (900, 0));
        }
        other => panic!("{other:?}"),
    }
    assert!(driver.channel(0).moving);
    now += MS;
    driver.handle_rx(now, &acks(&mosi, 0));
    // Not before one board loop period (2 ms) after the answers.
    assert!(
        drain(&mut driver, now + MS)
            .iter()
            .all(|t| t.iter().all(|b| *b == FILLER))
    );
    now += LOOP_PERIOD;
    let sent = drain(&mut driver, now);
    let r = requests(&sent[0]);
    match r.as_slice() {
        [Request::VelocityRamp(ramp)] => {
            assert_eq!(
                (one(ramp).velocity, one(ramp).acceleration),
                (0, 20_000 << 12)
            );
        }
        other => panic!("{other:?}"),
    }
    driver.handle_rx(now + MS, &acks(&sent[0], 0));
    assert!(driver.goals_pending(), "the hold is still to come");
    // 900 / 20 000 = 45 ms of ramp; the channel reports standstill at 60.
    now += 60 * MS;
    driver.handle_rx(now, &ours_stream([150, 0, 0], [0, 0, 0], [0; 3]));
    let sent = drain(&mut driver, now);
    let r = requests(&sent[0]);
    // The hold restores the acceleration limit (30 000 shl 12) first.
    match r.as_slice() {
        [
            Request::SetAccelerationLimit(limit),
            Request::SetControlMode(mode),
            Request::SetPositionTarget(target),
        ] => {
            assert_eq!(one(limit).limit, 30_000 << 12);
            assert_eq!(one(mode).mode, ControlMode::PositionPid);
            assert_eq!(one(target).position, 150);
        }
        other => panic!("{other:?}"),
    }
    driver.handle_rx(now + MS, &acks(&sent[0], 0));
    let state = driver.channel(0);
    assert!(!state.moving);
    assert!(state.arrived);
    assert!(!driver.goals_pending());
    // The next goal has nothing to restore.
    let mosi = acked(&mut driver, later(&mut now), 0, Goal::Off);
    assert_eq!(requests(&mosi).len(), 1);
}

#[test]
fn a_stop_is_always_sent_even_on_an_idle_channel() {
    let (mut driver, now) = running();
    // Nothing was ever commanded on channel 3 (index 2); it stands still: a hold where
    // it is, at once.
    let mosi = goal_packets(&mut driver, now, 2, Goal::Stop { decel: 10_000.0 });
    match requests(&mosi).as_slice() {
        [
            Request::SetControlMode(mode),
            Request::SetPositionTarget(target),
        ] => {
            assert_eq!(one(mode).mode, ControlMode::PositionPid);
            assert_eq!(one(target).position, 30);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_stop_waits_for_data_measured_after_a_restart() {
    let (mut driver, mut now) = running();
    driver.link_down(now);
    now += 10 * MS;
    driver.link_up(now);
    let probe = drain(&mut driver, now);
    assert!(probe[0].starts_with(&[2, 4, 1, 249]));
    now += MS;
    let masks = driver.stream_masks();
    driver.handle_rx(now, &probe_answers(masks, STREAM_CONFIG, 24));
    let sent = drain(&mut driver, now);
    now += MS;
    driver.handle_rx(now, &acks(&sent[0], 0));
    now += 4 * MS;
    driver
        .set_goal(now, 0, Goal::Stop { decel: 10_000.0 })
        .unwrap();
    assert_eq!(
        driver.wants_transmit(now),
        Some(Priority::Poll),
        "no data yet"
    );
    driver.handle_rx(now, &ours_stream([70, 0, 0], [-600, 0, 0], [0; 3]));
    let sent = drain(&mut driver, now);
    match requests(&sent[0]).as_slice() {
        [_, _, _, Request::VelocityRamp(ramp)] => assert_eq!(one(ramp).velocity, -600),
        other => panic!("{other:?}"),
    }
}

#[test]
fn off_de_energises_and_the_next_goal_sets_its_mode_again() {
    let (mut driver, mut now) = running();
    let mosi = acked(&mut driver, later(&mut now), 0, Goal::Off);
    match requests(&mosi).as_slice() {
        // Packet 16 mode 0x00: "Motor output will be set to zero / off".
        [Request::SetControlMode(mode)] => assert_eq!(one(mode).mode, ControlMode::Off),
        other => panic!("{other:?}"),
    }
    let mosi = acked(
        &mut driver,
        later(&mut now),
        0,
        Goal::Velocity {
            velocity: 100.0,
            accel: 1_000.0,
        },
    );
    match requests(&mosi).as_slice() {
        [Request::SetControlMode(mode), Request::VelocityRamp(_)] => {
            assert_eq!(one(mode).mode, ControlMode::VelocityPid);
        }
        other => panic!("{other:?}"),
    }
}
