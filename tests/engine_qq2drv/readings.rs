//! The QuadQuad2Drv where its datasheet ("QuadQuad2Drv PCB Datasheet", interface protocol
//! v1) reads two ways (docs/ARCHITECTURE.md), engine + driver + simulated board on the
//! fake clock: packet 36's "Range: 0 - 100,000" for an I32 velocity, and packet 3 with
//! the Return Code its text names.

use core::time::Duration;

use qq2drv::ControlMode;
use qq2drv::limits::VelocityRampSign;

use crate::{
    Qq2drvDriver, Qq2drvSim, Qq2drvSimConfig, SPEED_HZ, accepted, driver_config, flag, rig_with,
    wait_online,
};
use motion_ipc::{AxisFlags, AxisMode, CommandKind, FaultCode};

fn board(velocity_ramp: VelocityRampSign, stream_return_code: bool) -> Qq2drvSim {
    Qq2drvSim::new(Qq2drvSimConfig {
        seed: 11,
        spi_clock_hz: SPEED_HZ,
        velocity_ramp,
        stream_return_code,
        ..Qq2drvSimConfig::default()
    })
}

fn driver(velocity_ramp: VelocityRampSign) -> Qq2drvDriver {
    let mut config = driver_config();
    for channel in &mut config.channels {
        channel.velocity_ramp = velocity_ramp;
    }
    Qq2drvDriver::new(config)
}

/// Packet 36 read as "Range: 0 - 100,000" (`velocity_ramp = "unsigned"`): a reverse jog
/// runs through packets 28 and 22 at the speed asked, the board refuses nothing, and the
/// stop brings it to rest and holds.
#[test]
fn a_reverse_jog_on_a_forward_only_packet_36_goes_through_packet_22() {
    let unsigned = VelocityRampSign::Unsigned;
    let (mut rig, board, _) = rig_with(driver(unsigned), board(unsigned, false));
    wait_online(&mut rig);
    accepted(&mut rig, 0, CommandKind::Velocity, [-10.0, 0.0, 0.0]);
    rig.run(200);
    accepted(&mut rig, 0, CommandKind::Velocity, [-10.0, 0.0, 0.0]);
    rig.run(100);
    let v = board.lock().unwrap().true_velocity(0).unwrap();
    assert!((v + 1_000.0).abs() < 60.0, "10 mm/s in reverse: {v}");
    // Forward goes through packet 36 as before.
    accepted(&mut rig, 1, CommandKind::Velocity, [5.0, 0.0, 0.0]);
    rig.run(200);
    let v = board.lock().unwrap().true_velocity(1).unwrap();
    assert!((v - 500.0).abs() < 40.0, "5 mm/s forward: {v}");
    accepted(&mut rig, 0, CommandKind::Stop, [0.0; 3]);
    assert!(rig.run_until(Duration::from_millis(800), |frame| {
        frame.axes[0].mode == AxisMode::Hold as u8
    }));
    rig.run(100);
    let sim = board.lock().unwrap();
    assert_eq!(sim.stats().rejected, 0, "every packet within its range");
    assert_eq!(sim.control_mode(0), Some(ControlMode::PositionPid), "holds");
    assert!(sim.true_velocity(0).unwrap().abs() < 5.0);
    drop(sim);
    assert!(!flag(&rig, 0, AxisFlags::FAULT));
}

/// The default reading (signed) against a board that range-checks packet 36 as forward
/// only: the board answers the reverse jog with a non-zero Return Code, and the axis
/// faults instead of moving. (A board that does not check could run forward: hence the
/// key.)
#[test]
fn a_signed_reverse_on_a_forward_only_board_is_refused_not_run() {
    let (mut rig, board, _) = rig_with(
        driver(VelocityRampSign::Signed),
        board(VelocityRampSign::Unsigned, false),
    );
    wait_online(&mut rig);
    accepted(&mut rig, 0, CommandKind::Velocity, [-10.0, 0.0, 0.0]);
    assert!(
        rig.run_until(Duration::from_millis(100), |frame| {
            frame.axes[0].fault == FaultCode::BoardError as u16
        }),
        "the axis reports the board's error"
    );
    rig.run(100);
    let sim = board.lock().unwrap();
    assert!(sim.stats().rejected > 0);
    assert!(sim.true_velocity(0).unwrap().abs() < 5.0, "not moving");
}

/// Packet 3 with a Return Code in front (its text's reading): the board streams, the axes
/// stay fresh and a move arrives, as with the table's form.
#[test]
fn a_board_that_streams_a_return_code_runs_as_one_that_does_not() {
    let signed = VelocityRampSign::Signed;
    let (mut rig, board, _) = rig_with(driver(signed), board(signed, true));
    wait_online(&mut rig);
    rig.run(200);
    assert!(board.lock().unwrap().stats().stream_packets > 150);
    accepted(&mut rig, 0, CommandKind::Position, [3.0, 0.0, 0.0]);
    assert!(rig.run_until(Duration::from_secs(2), |frame| {
        frame.axes[0].flags & AxisFlags::ARRIVED.0 != 0
    }));
    assert!((rig.axis(0).position - 3.0).abs() <= 0.05);
    assert_eq!(rig.engine.driver(0).unwrap().status().fault, None);
}
