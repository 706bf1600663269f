//! Drives off and the shutdown stop through engine + driver + simulator: with
//! `enable_output`, `off` quits the motor and releases the external driver's enable line
//! (the simulated drive ignores steps then), and the next goal enables it first; without
//! it `off` is refused as unsupported; a shutdown stops a motor the engine never
//! commanded.

use core::time::Duration;

use board_qsb::driver::{EnableOutput, QsbDriverConfig};
use board_qsb::sim::{DriveEnable, QsbSimConfig};
use motion_ipc::{AxisMode, CommandKind, Reason};
use motion_link::sim::StreamDevice;

use super::{COUNTS_PER_UNIT, MAX_ACCEL, MAX_VELOCITY, Qsb, rig_with};

fn driver(enable: Option<EnableOutput>) -> QsbDriverConfig {
    QsbDriverConfig {
        counts_per_step: 10.0,
        max_velocity: MAX_VELOCITY * COUNTS_PER_UNIT,
        max_accel: MAX_ACCEL * COUNTS_PER_UNIT,
        enable,
        ..QsbDriverConfig::default()
    }
}

fn with_enable_line() -> Qsb {
    let sim = QsbSimConfig {
        drive_enable: Some(DriveEnable {
            bit: 3,
            active_high: false,
        }),
        ..QsbSimConfig::default()
    };
    let enable = EnableOutput {
        bit: 3,
        active_high: false,
    };
    let mut qsb = rig_with(sim, driver(Some(enable)), Duration::from_millis(250));
    qsb.start();
    qsb
}

#[test]
fn off_releases_the_drive_enable_line_until_the_next_goal() {
    let mut qsb = with_enable_line();
    assert!(qsb.sim.lock().expect("sim").drive_energised());
    assert_eq!(qsb.command(CommandKind::Off, [0.0; 3]), Reason::Accepted);
    qsb.rig.run(20);
    assert!(
        !qsb.sim.lock().expect("sim").drive_energised(),
        "de-energised"
    );
    assert_eq!(qsb.axis().mode, AxisMode::Off as u8);
    assert_eq!(
        qsb.command(CommandKind::RampPosition, [2.0, 0.0, 0.0]),
        Reason::Accepted
    );
    qsb.rig.run(20);
    assert!(
        qsb.sim.lock().expect("sim").drive_energised(),
        "enabled first"
    );
}

#[test]
fn off_without_an_enable_line_is_unsupported() {
    let mut qsb = rig_with(
        QsbSimConfig::default(),
        driver(None),
        Duration::from_millis(250),
    );
    qsb.start();
    assert_eq!(qsb.command(CommandKind::Off, [0.0; 3]), Reason::Unsupported);
    assert_ne!(qsb.axis().mode, AxisMode::Off as u8);
}

#[test]
fn a_shutdown_stops_a_motor_the_engine_never_commanded() {
    let mut qsb = rig_with(
        QsbSimConfig::default(),
        driver(None),
        Duration::from_millis(250),
    );
    qsb.start();
    let now = qsb.rig.now;
    // Another program makes the motor jog at 800 steps/s (supervision is off in this rig).
    qsb.sim
        .lock()
        .expect("sim")
        .receive(now, b"W12320\r\nW169\r\n");
    qsb.rig.run(100);
    assert!(qsb.sim.lock().expect("sim").motor_velocity().abs() > 700.0);
    assert_eq!(qsb.axis().mode, AxisMode::Hold as u8, "never commanded");
    qsb.rig.engine.begin_shutdown();
    let end = qsb.rig.now + Duration::from_secs(2);
    while !qsb.rig.engine.all_at_rest() && qsb.rig.now < end {
        qsb.rig.tick();
    }
    assert!(qsb.rig.engine.all_at_rest(), "acknowledged within 2 s");
    qsb.rig.run(50);
    assert_eq!(
        qsb.sim.lock().expect("sim").motor_velocity(),
        0.0,
        "stopped"
    );
}
