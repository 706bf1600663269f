//! Drives off and the shutdown stop through engine + driver + simulator: `off` leaves the
//! channel in control mode Off (packet 16, mode 0) and the next goal drives it again; a
//! shutdown stops a motor the engine never commanded.

use super::*;

#[test]
fn off_leaves_the_channel_de_energised_until_the_next_goal() {
    let (mut rig, board, _) = rig();
    wait_online(&mut rig);
    assert_eq!(
        board.lock().unwrap().control_mode(0),
        Some(ControlMode::PositionPid),
        "held"
    );
    accepted(&mut rig, 0, CommandKind::Off, [0.0; 3]);
    rig.run(20);
    assert_eq!(
        board.lock().unwrap().control_mode(0),
        Some(ControlMode::Off)
    );
    assert_eq!(board.lock().unwrap().motor_power(0), Some(0));
    assert_eq!(rig.axis(0).mode, AxisMode::Off as u8);
    accepted(&mut rig, 0, CommandKind::RampPosition, [1.0, 0.0, 0.0]);
    rig.run(20);
    assert_ne!(
        board.lock().unwrap().control_mode(0),
        Some(ControlMode::Off)
    );
}

#[test]
fn a_shutdown_stops_a_motor_the_engine_never_commanded() {
    use qq2drv::{ChannelMask, ControlModeEntry, Entries, MotorPowerEntry};
    let (mut rig, board, _) = rig();
    wait_online(&mut rig);
    // Behind the engine's back (the engine believes it holds): Power mode at 30 %.
    let one = ChannelMask::single(1);
    stops::poke(
        &board,
        rig.now,
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
    rig.run(100);
    assert!(board.lock().unwrap().true_velocity(1).unwrap().abs() > 500.0);
    rig.engine.begin_shutdown();
    let end = rig.now + Duration::from_secs(2);
    while !rig.engine.all_at_rest() && rig.now < end {
        rig.tick();
    }
    assert!(
        rig.engine.all_at_rest(),
        "every board acknowledged its stop within 2 s"
    );
    rig.run(100);
    let sim = board.lock().unwrap();
    // At rest: below the board's velocity resolution (4 transitions/s), held in place.
    let velocity = sim.true_velocity(1).unwrap();
    assert!(velocity.abs() < 4.0, "stopped: {velocity}");
    assert_eq!(sim.control_mode(1), Some(ControlMode::PositionPid));
}
