//! Stops through engine + driver + simulator: planned from the velocity the board measures
//! (a saturated motor, a motor left running by another program), always on the wire, and
//! a home search stopped midway.

use super::*;

/// Every request the driver wrote on the wire from the `from`-th logged transaction on.
fn logged_requests(rig: &Rig, from: usize) -> Vec<(Duration, Vec<u8>)> {
    let mut out = Vec::new();
    for (at, mosi) in &rig.wire_log(0)[from..] {
        if mosi.iter().all(|b| *b == FILLER) {
            continue;
        }
        let mut rest = &mosi[..];
        while !rest.is_empty() {
            let len = usize::from(rest[1]);
            Request::parse(&rest[..len]).expect("a valid request");
            out.push((*at, rest[..len].to_vec()));
            rest = &rest[len..];
        }
    }
    out
}

/// The ids and single-entry values of `requests` for `channel` (0-based).
fn requests_for(requests: &[(Duration, Vec<u8>)], channel: usize) -> Vec<Request<'_>> {
    requests
        .iter()
        .map(|(_, bytes)| Request::parse(bytes).expect("valid"))
        .filter(|request| {
            let mask = match request {
                Request::SetControlMode(e) => e.iter().next().map(|e| e.channels),
                Request::SetAccelerationLimit(e) => e.iter().next().map(|e| e.channels),
                Request::VelocityRamp(e) => e.iter().next().map(|e| e.channels),
                Request::SetPositionTarget(e) => e.iter().next().map(|e| e.channels),
                Request::SetInputMode(e) => e.iter().next().map(|e| e.channels),
                _ => None,
            };
            mask.is_some_and(|m| m.contains(channel))
        })
        .collect()
}

/// How a stop went, watched tick by tick on the simulated board.
struct StopTrace {
    /// Highest |velocity setpoint| of the board's loop after the stop was set.
    peak_setpoint: f64,
    /// When the setpoint reached 0 (and stayed).
    setpoint_zero: Option<Duration>,
    /// When the shaft first stood still once the setpoint was 0 (the hold that follows may
    /// then creep back the few transitions the motor coasted).
    still: Option<Duration>,
}

/// Standstill of the simulated shaft, transitions/s.
const STILL: f64 = 5.0;

/// Ticks for `span`, recording the board's setpoint and the shaft of `channel`.
fn trace_stop(rig: &mut Rig, board: &Board, channel: usize, span: Duration) -> StopTrace {
    let start = rig.now;
    let mut trace = StopTrace {
        peak_setpoint: 0.0,
        setpoint_zero: None,
        still: None,
    };
    while rig.now - start < span {
        rig.tick();
        let sim = board.lock().unwrap();
        let elapsed = rig.now - start;
        let mode = sim.control_mode(channel).unwrap();
        let setpoint = if mode == ControlMode::VelocityPid {
            sim.velocity_setpoint(channel).unwrap().abs()
        } else {
            0.0
        };
        trace.peak_setpoint = trace.peak_setpoint.max(setpoint);
        if setpoint == 0.0 {
            trace.setpoint_zero.get_or_insert(elapsed);
        } else {
            trace.setpoint_zero = None;
        }
        let still = sim.true_velocity(channel).unwrap().abs() <= STILL;
        if still && trace.setpoint_zero.is_some() {
            trace.still.get_or_insert(elapsed);
        }
    }
    trace
}

/// The bound on a stop's setpoint: the ramp from the measured velocity at max_accel, plus
/// the latency on the wire and in the board: one tick to send the setpoint reset, two to
/// read its answer, the 2 ms loop period the driver waits, one tick for the ramp and one
/// loop period for the board to start it.
fn setpoint_bound(measured: f64) -> Duration {
    let ramp = measured.abs() / (MAX_ACCEL_MM * COUNTS_PER_MM);
    Duration::from_secs_f64(ramp) + Duration::from_millis(8)
}

/// The shaft follows the setpoint with the board's loop and the simulated motor's own
/// 20 ms mechanical time constant (its friction dead band leaves the last transitions/s to
/// coast): five time constants.
const MOTOR_SETTLE: Duration = Duration::from_millis(100);

#[test]
fn the_deadman_stops_a_saturated_motor_from_its_real_velocity() {
    // Channel 1's power is limited to 15 % of full scale: commanded at 30 mm/s (3000
    // transitions/s) it really runs at about 780.
    let mut config = driver_config();
    config.channels[0].power_limit = 1_229;
    let (mut rig, board, _) = rig_with(Qq2drvDriver::new(config), sim());
    wait_online(&mut rig);
    accepted(&mut rig, 0, CommandKind::Velocity, [30.0, 0.0, 0.0]);
    assert!(rig.run_until(Duration::from_secs(1), |frame| {
        frame.axes[0].flags & AxisFlags::DEADMAN_EXPIRED.0 != 0
    }));
    let measured = rig.axis(0).velocity * COUNTS_PER_MM;
    let true_velocity = board.lock().unwrap().true_velocity(0).unwrap();
    assert!(
        (600.0..900.0).contains(&true_velocity) && (600.0..900.0).contains(&measured),
        "saturated: {true_velocity} / {measured} of 3000"
    );
    // The deadman fired in the tick just run: its stop is on the wire.
    let trace = trace_stop(&mut rig, &board, 0, Duration::from_millis(400));
    // The board's setpoint never went back above what the motor really did (the old
    // driver ramped it down from the commanded 3000, keeping the motor at full power).
    assert!(
        trace.peak_setpoint <= measured.abs() * 1.1 + 10.0,
        "setpoint {} from a measured {measured}",
        trace.peak_setpoint
    );
    let bound = setpoint_bound(measured);
    let zero = trace.setpoint_zero.expect("the setpoint reached 0");
    assert!(zero <= bound, "setpoint 0 after {zero:?}, bound {bound:?}");
    let still = trace.still.expect("the shaft stopped");
    assert!(
        still <= bound + MOTOR_SETTLE,
        "standstill after {still:?}, bound {:?}",
        bound + MOTOR_SETTLE
    );
    assert_eq!(rig.axis(0).mode, AxisMode::Hold as u8);
    assert_eq!(
        board.lock().unwrap().control_mode(0),
        Some(ControlMode::PositionPid)
    );
}

/// Writes raw requests into the simulated board at `now`, as another program would.
pub(super) fn poke(board: &Board, now: Duration, requests: &[Request<'_>]) {
    use motion_link::sim::SpiDevice;
    let mut mosi = [0u8; 256];
    let mut len = 0;
    for request in requests {
        len += request.encode(&mut mosi[len..]).expect("encodes");
    }
    let mut miso = [0u8; 256];
    board
        .lock()
        .unwrap()
        .transfer(now, &mosi[..len], &mut miso[..len]);
}

#[test]
fn a_motor_left_running_by_another_program_is_stopped_once_online() {
    use motion_link::sim::SpiDevice;
    use qq2drv::{ChannelMask, ControlModeEntry, Entries, MotorPowerEntry};
    let (mut rig, board, _) = rig();
    // Before the server starts, something left channel 1 in Power mode at 30 %.
    let one = ChannelMask::single(0);
    poke(
        &board,
        Duration::ZERO,
        &[
            Request::SetControlMode(Entries::new(&[ControlModeEntry {
                channels: one,
                mode: ControlMode::Power,
            }])),
            Request::SetMotorPower(Entries::new(&[MotorPowerEntry {
                channels: one,
                power: 2_457,
            }])),
        ],
    );
    board.lock().unwrap().advance(Duration::from_millis(200));
    rig.now = Duration::from_millis(200);
    assert!(board.lock().unwrap().true_velocity(0).unwrap() > 1_000.0);
    wait_online(&mut rig);
    assert!(flag(&rig, 0, AxisFlags::MOVING), "the driver sees it run");
    let measured = rig.axis(0).velocity * COUNTS_PER_MM;
    // No command: the engine's start-up stop (sent when the board came online) does it.
    let trace = trace_stop(&mut rig, &board, 0, Duration::from_millis(400));
    assert!(trace.peak_setpoint <= measured.abs() * 1.1 + 10.0);
    let bound = setpoint_bound(measured);
    let zero = trace.setpoint_zero.expect("the setpoint reached 0");
    assert!(zero <= bound, "setpoint 0 after {zero:?}, bound {bound:?}");
    let still = trace.still.expect("the shaft stopped");
    assert!(still <= bound + MOTOR_SETTLE, "standstill after {still:?}");
    assert_eq!(
        board.lock().unwrap().control_mode(0),
        Some(ControlMode::PositionPid),
        "held"
    );
}
#[test]
fn a_stop_on_a_channel_at_rest_still_goes_on_the_wire() {
    let (mut rig, board, _) = rig();
    rig.log_wire = true;
    wait_online(&mut rig);
    accepted(&mut rig, 0, CommandKind::Position, [1.0, 0.0, 0.0]);
    move_and_check(&mut rig, &board, 0, 1.0, MAX_VELOCITY_MM);
    rig.run(20);
    // The driver believes the channel at rest (arrived, standing): the stop still goes
    // out, as a hold where the channel is.
    let from = rig.wire_log(0).len();
    accepted(&mut rig, 0, CommandKind::Stop, [0.0; 3]);
    rig.run(10);
    let log = logged_requests(&rig, from);
    let requests = requests_for(&log, 0);
    let counter = board.lock().unwrap().counter(0).unwrap();
    match requests.as_slice() {
        [
            Request::SetControlMode(mode),
            Request::SetPositionTarget(target),
        ] => {
            assert_eq!(mode.iter().next().unwrap().mode, ControlMode::PositionPid);
            let at = target.iter().next().unwrap().position;
            assert!((at - counter).abs() <= 2, "held at {at}, counter {counter}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_home_search_stopped_midway_disarms_the_input_and_stops() {
    let (mut rig, board, _) = rig();
    wait_online(&mut rig);
    accepted(&mut rig, 1, CommandKind::Home, [10.0, 0.0, 0.0]);
    rig.run(150);
    {
        let sim = board.lock().unwrap();
        assert_eq!(
            sim.input_config(1).unwrap().0.mode(),
            InputMode::Edge,
            "armed"
        );
        let shaft = sim.true_position(1).unwrap();
        assert!(
            shaft > 50.0 && shaft < SWITCH_AT - 200.0,
            "on its way: {shaft}"
        );
    }
    // The engine's travel supervision (or a client) stops it before the switch.
    let measured = rig.axis(1).velocity * COUNTS_PER_MM;
    accepted(&mut rig, 1, CommandKind::Stop, [0.0; 3]);
    let trace = trace_stop(&mut rig, &board, 1, Duration::from_millis(300));
    let bound = setpoint_bound(measured);
    assert!(
        trace.setpoint_zero.is_some_and(|at| at <= bound),
        "{:?}",
        trace.setpoint_zero
    );
    assert!(trace.still.is_some_and(|at| at <= bound + MOTOR_SETTLE));
    let sim = board.lock().unwrap();
    assert_eq!(
        sim.input_config(1).unwrap().0.mode(),
        InputMode::Disabled,
        "the input is disarmed: the switch will not set the counter later"
    );
    assert!(sim.true_position(1).unwrap() < SWITCH_AT);
    drop(sim);
    assert!(!flag(&rig, 1, AxisFlags::HOMED));
    assert_ne!(rig.axis(1).mode, AxisMode::Homing as u8);
}

#[test]
fn home_with_two_end_stops_on_one_input_uses_the_spacing() {
    let mut config = driver_config();
    if let Some(home) = &mut config.channels[1].home {
        home.spacing = 100;
    }
    let mut model = Qq2drvSimConfig {
        seed: 11,
        spi_clock_hz: SPEED_HZ,
        ..Qq2drvSimConfig::default()
    };
    model.inputs[1] = InputPin {
        source: InputSource::TwoEndStops {
            negative: -SWITCH_AT,
            positive: SWITCH_AT,
        },
        actuated_high: false,
    };
    let (mut rig, board, _) = rig_with(Qq2drvDriver::new(config), Qq2drvSim::new(model));
    wait_online(&mut rig);
    assert_eq!(
        board.lock().unwrap().input_config(1).unwrap().1,
        100,
        "Spacing"
    );
    accepted(&mut rig, 1, CommandKind::Home, [10.0, 0.0, 0.0]);
    assert!(rig.run_until(Duration::from_secs(3), |frame| {
        frame.axes[1].mode == AxisMode::Hold as u8
    }));
    assert!(flag(&rig, 1, AxisFlags::HOMED));
    let sim = board.lock().unwrap();
    let shaft = sim.true_position(1).unwrap();
    let counter = f64::from(sim.counter(1).unwrap());
    // Found at the positive end (the search direction), where the counter was set.
    assert!((shaft - SWITCH_AT).abs() < 80.0, "{shaft}");
    let offset = counter - (shaft - SWITCH_AT) - f64::from(HOME_COUNTS);
    assert!(offset.abs() <= 4.0, "counter {counter} shaft {shaft}");
}
