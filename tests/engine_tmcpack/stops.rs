//! Stops through the engine: from the measured velocity, of a motor left running before
//! the driver started, of a motor the driver believes idle; a failed reference search.

use motion_link::sim::StreamDevice;

use super::*;

/// The longest a stop can wait for the wire and the pack, at 19200 baud with the 2 ms
/// switch-over the driver programs: a query that was just sent when the stop came (request,
/// switch-over, answer, the pack's hold after it: 2 words + 2 switch-overs, the bus allows
/// no second request before that), one engine tick, the `$25` word itself, and two 2 ms
/// cycles of the pack (the word is acted on at the pack's next cycle; its ramp stops once
/// below vstart, rounded up to a cycle). The `$14` that makes amax exactly the requested
/// deceleration goes after the `$25` (see the driver), so it adds nothing.
fn command_latency() -> Duration {
    let word = byte_time(BAUD) * 9;
    let switchover = Duration::from_millis(2);
    let cycle = Duration::from_millis(2);
    2 * word + 2 * switchover + Duration::from_millis(1) + word + 2 * cycle
}

/// Task: the deadman stops a jog within |v_measured| / max_accel + the command latency.
#[test]
fn the_deadman_stops_a_jog_within_the_deceleration_time_of_its_measured_speed() {
    let (mut rig, board, _) = single(1);
    wait_online(&mut rig, 2);
    accepted(&mut rig, 0, CommandKind::Velocity, [40.0, 0.0, 0.0]);
    let fired = loop {
        rig.tick();
        if flag(&rig, 0, AxisFlags::DEADMAN_EXPIRED) {
            break rig.now - rig.period;
        }
        assert!(rig.now < Duration::from_secs(5), "the deadman fires");
    };
    let measured = rig.axis(0).velocity;
    assert!(
        (measured - 40.0).abs() < 2.0,
        "the driver measured the jog: {measured} mm/s"
    );
    assert!(motor(&board, 0).microstep_hz > 3900.0, "still running");
    let still = loop {
        rig.tick();
        if motor(&board, 0).microstep_hz == 0.0 {
            break rig.now - rig.period;
        }
        assert!(rig.now < fired + Duration::from_secs(2), "it stops");
    };
    let bound = Duration::from_secs_f64(measured.abs() / MAX_ACCEL_MM) + command_latency();
    assert!(
        still - fired <= bound,
        "stopped {:?} after the deadman fired; bound {bound:?}",
        still - fired
    );
    rig.run(300);
    assert_eq!(motor(&board, 0).action, Action::Inactive);
    assert_eq!(rig.axis(0).mode, AxisMode::Hold as u8);
}

/// Task: a motor that was already rotating before the driver started (a previous server
/// left it so) is stopped; the driver stops it before `$12` ("change only with stopped
/// motors!") reaches the pack.
#[test]
fn a_motor_left_running_before_the_driver_started_is_stopped() {
    let (wire, board) = Shared::new(pack(1, Variant::SixPack));
    {
        let mut sim = board.lock().unwrap();
        let word = RequestFrame::new(
            1,
            Request::Rotate {
                motor: 0,
                velocity: 300,
            },
        )
        .to_word()
        .expect("valid");
        sim.receive(Duration::from_millis(5), &word);
        sim.advance(Duration::from_millis(400));
        assert_eq!(sim.motor(0).expect("motor 0").action, Action::Rotation);
    }
    let link = SimLink::stream_with("rs485", BAUD, Duplex::Half, wire);
    let config = engine_config(
        vec![device("pack", 1)],
        vec![axis("x", 0, 0), axis("y", 0, 1)],
    );
    let driver = driver(1, Variant::SixPack, &[0, 1], 0);
    let mut rig = Rig::new(config, vec![Box::new(driver)], vec![Box::new(link)]);
    rig.now = Duration::from_millis(500);
    rig.log_wire = true;
    assert!(
        motor(&board, 0).microstep_hz > 1000.0,
        "running at the start"
    );
    wait_online(&mut rig, 2);
    assert_eq!(
        motor(&board, 0).microstep_hz,
        0.0,
        "at rest by the time the pack is configured"
    );
    accepted(&mut rig, 0, CommandKind::Stop, [0.0; 3]);
    rig.run(500);
    let view = motor(&board, 0);
    assert_eq!(view.microstep_hz, 0.0);
    assert_eq!(view.action, Action::Inactive, "the rotation was ended");
    let requests: Vec<Request> = rig
        .wire_log(0)
        .iter()
        .map(|(_, bytes)| RequestFrame::decode(bytes).expect("a valid word").request)
        .collect();
    let stop = requests.iter().position(|r| {
        *r == Request::Rotate {
            motor: 0,
            velocity: 0,
        }
    });
    let clkdiv = requests
        .iter()
        .position(|r| matches!(r, Request::VelocitySetting { .. }));
    assert!(stop.is_some() && stop < clkdiv, "{requests:?}");
    let stats = board.lock().unwrap().stats();
    assert_eq!(stats.invalid, 0);
    assert_eq!(stats.replaced_replies, 0);
    assert_eq!(stats.interlaced, 0, "manual 7.1: never interlaced");
}

/// Task: a Stop of a motor the driver believes idle still goes on the wire, with an amax
/// no gentler than the requested deceleration (8.3 $14: amax/64 per 2 ms).
#[test]
fn a_stop_of_a_motor_the_driver_believes_idle_goes_on_the_wire() {
    let (mut rig, board, _) = single(1);
    wait_online(&mut rig, 2);
    accepted(&mut rig, 0, CommandKind::Position, [1.0, 0.0, 0.0]);
    move_and_check(
        &mut rig,
        &board,
        0,
        0,
        1.0,
        MAX_VELOCITY_MM,
        Duration::from_secs(2),
    );
    rig.run(100);
    assert!(!flag(&rig, 0, AxisFlags::MOVING));
    rig.log_wire = true;
    let sent_from = rig.now;
    accepted(&mut rig, 0, CommandKind::Stop, [0.0; 3]);
    rig.run(100);
    let after: Vec<Request> = rig
        .wire_log(0)
        .iter()
        .filter(|(at, _)| *at >= sent_from)
        .map(|(_, bytes)| RequestFrame::decode(bytes).expect("a valid word").request)
        .collect();
    assert!(
        after.contains(&Request::Rotate {
            motor: 0,
            velocity: 0
        }),
        "{after:?}"
    );
    let amax = after.iter().find_map(|r| match r {
        Request::VelocityAcceleration { motor: 0, amax, .. } => Some(*amax),
        _ => None,
    });
    let (clkdiv, div, _, _) = rig_settings(&rig, 0);
    let clock = tmcpack::StepClock::new(clkdiv, div).expect("valid clock");
    let requested = MAX_ACCEL_MM * COUNTS;
    if let Some(amax) = amax {
        let rate = clock
            .accel_hz_per_s(amax, tmcpack::AmaxDivisor::By64)
            .expect("valid amax");
        assert!(rate >= requested, "{rate} < {requested}");
        let below = clock
            .accel_hz_per_s(amax - 1, tmcpack::AmaxDivisor::By64)
            .expect("valid amax");
        assert!(below < requested, "the closest amax at or above");
    }
    assert_eq!(motor(&board, 0).action, Action::Inactive);
    assert_eq!(motor(&board, 0).physical, 100, "nothing moved");
}

/// The clock settings the driver of device 0 wrote for `motor`.
fn rig_settings(_rig: &Rig, motor: usize) -> (u8, u8, u16, u16) {
    driver(1, Variant::SixPack, &[0, 1], 0).board_settings()[motor].expect("configured")
}

/// Manual 8.4 $22: "if no switch is seen during 125% of the drive limit-range, the whole
/// procedure repeats": the driver reports HomeFailed, the engine maps it and stops.
#[test]
fn a_reference_search_without_a_switch_fails_with_home_failed() {
    let (mut rig, board, _) = single(1);
    board.lock().unwrap().set_ref_switch(0, None);
    wait_online(&mut rig, 2);
    accepted(&mut rig, 0, CommandKind::Home, [40.0, 0.0, 0.0]);
    assert!(
        rig.run_until(Duration::from_secs(10), |frame| {
            frame.axes[0].fault == FaultCode::HomeFailed as u16
        }),
        "HomeFailed within 10 s"
    );
    assert!(!flag(&rig, 0, AxisFlags::HOMED));
    rig.run(1000);
    let view = motor(&board, 0);
    assert_eq!(view.microstep_hz, 0.0, "the search was stopped");
    assert!(!view.action.is_referencing());
}
