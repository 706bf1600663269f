//! Drives off and the shutdown stop through engine + driver + simulator: `off` sets a
//! stepper's drive intensity to 0 (port 0x10) and the next goal writes it back first; a
//! brushed motor is stopped (its stop port); a shutdown stops a stepper on its way.

use super::*;

#[test]
fn off_leaves_the_stepper_without_current_until_the_next_goal() {
    let (mut rig, board, _) = stepper_rig(0x90);
    wait_online(&mut rig, 1);
    assert_eq!(board.lock().unwrap().stepper_intensity(), 0x20, "held");
    accepted(&mut rig, 0, CommandKind::Off, [0.0; 3]);
    rig.run(20);
    assert_eq!(board.lock().unwrap().stepper_intensity(), 0, "de-energised");
    assert_eq!(rig.axis(0).mode, AxisMode::Off as u8);
    accepted(&mut rig, 0, CommandKind::RampPosition, [1.0, 0.0, 0.0]);
    rig.run(20);
    assert_eq!(
        board.lock().unwrap().stepper_intensity(),
        0x20,
        "driven again"
    );
}

#[test]
fn off_stops_a_brushed_motor() {
    let (mut rig, board) = brushed_rig();
    wait_online(&mut rig, 2);
    accepted(&mut rig, 0, CommandKind::Power, [0.5, 0.0, 0.0]);
    rig.run(20);
    assert!(
        board.lock().unwrap().velocity(0).unwrap().abs() > 0.0,
        "spinning"
    );
    accepted(&mut rig, 0, CommandKind::Off, [0.0; 3]);
    rig.run(20);
    let sim = board.lock().unwrap();
    assert_eq!(
        sim.motor_settled_velocity(spimotor::Motor::A),
        0.0,
        "no power on the bridge"
    );
    assert!(
        sim.motor_velocity(spimotor::Motor::A).abs() < 20.0,
        "coasting down"
    );
    assert_eq!(rig.axis(0).mode, AxisMode::Off as u8);
}

#[test]
fn a_shutdown_stops_a_stepper_on_its_way() {
    // (The driver itself puts back a target another program writes behind its back: a
    // stepper cannot run away from it for long, so this board's shutdown case is a move.)
    let (mut rig, board, _) = stepper_rig(0x90);
    wait_online(&mut rig, 1);
    accepted(&mut rig, 0, CommandKind::RampPosition, [90.0, 0.0, 0.0]);
    rig.run(50);
    assert!(board.lock().unwrap().is_moving());
    rig.engine.begin_shutdown();
    let end = rig.now + Duration::from_secs(2);
    while !rig.engine.all_at_rest() && rig.now < end {
        rig.tick();
    }
    assert!(rig.engine.all_at_rest(), "acknowledged within 2 s");
    rig.run(50);
    assert!(!board.lock().unwrap().is_moving(), "stopped");
}
