//! Drives off and the shutdown stop through engine + driver + simulated pack: `off` cuts the
//! motor's coil current (manual 8.2 `$15` current control: the moving level I3 set to 0 %,
//! standstill I0 too) and the next goal energises it again; a shutdown stops a motor the
//! engine never commanded (another program left it rotating behind the driver's back).

use super::*;

#[test]
fn off_cuts_the_coil_current_until_the_next_goal() {
    let (mut rig, board, _) = single(1);
    wait_online(&mut rig, 2);
    rig.run(100);
    assert!(
        motor(&board, 0).coil_current_amps > 0.0,
        "held energised after start-up"
    );
    rig.log_wire = true;
    accepted(&mut rig, 0, CommandKind::Off, [0.0; 3]);
    assert!(
        rig.run_until(Duration::from_secs(1), |frame| {
            frame.axes[0].mode == AxisMode::Off as u8
        }),
        "the axis reports off"
    );
    rig.run(200);
    let view = motor(&board, 0);
    let sent: Vec<Request> = rig
        .wire_log(0)
        .iter()
        .filter_map(|(_, bytes)| RequestFrame::decode(bytes).ok())
        .map(|frame| frame.request)
        .filter(|r| {
            !matches!(
                r,
                Request::QueryPosition { .. }
                    | Request::QueryVelocity { .. }
                    | Request::QueryActions { .. }
                    | Request::ReadInput { .. }
            )
        })
        .collect();
    assert_eq!(
        view.coil_current_amps, 0.0,
        "de-energised: {view:?} after {sent:?}"
    );
    assert!(
        motor(&board, 1).coil_current_amps > 0.0,
        "the other motor stays energised"
    );
    accepted(&mut rig, 0, CommandKind::RampPosition, [1.0, 0.0, 0.0]);
    rig.run(300);
    assert!(
        motor(&board, 0).coil_current_amps > 0.0,
        "the next goal energises the motor again"
    );
}

#[test]
fn a_shutdown_stops_a_motor_the_engine_never_commanded() {
    // Supervision off on y, so the engine keeps believing it idle (with it on, the
    // following-error rule stops the motor long before the shutdown).
    let (wire, board) = Shared::new(pack(1, Variant::SixPack));
    let link = SimLink::stream_with("rs485", BAUD, Duplex::Half, wire);
    let unsupervised = AxisConfig {
        following_error: 0.0,
        overspeed_factor: 0.0,
        ..axis("y", 0, 1)
    };
    let config = engine_config(vec![device("pack", 1)], vec![axis("x", 0, 0), unsupervised]);
    let driver = driver(1, Variant::SixPack, &[0, 1], 0);
    let mut rig = Rig::new(config, vec![Box::new(driver)], vec![Box::new(link)]);
    wait_online(&mut rig, 2);
    rig.run(100);
    // Behind the engine's back (it believes motor 1 idle): another program on the pair
    // makes it rotate at 300.
    board.lock().unwrap().act_behind_the_back(
        rig.now,
        Request::Rotate {
            motor: 1,
            velocity: 300,
        },
    );
    rig.run(200);
    assert!(motor(&board, 1).microstep_hz.abs() > 1000.0, "rotating");
    rig.engine.begin_shutdown();
    let end = rig.now + Duration::from_secs(2);
    while !rig.engine.all_at_rest() && rig.now < end {
        rig.tick();
    }
    assert!(
        rig.engine.all_at_rest(),
        "the pack acknowledged the stops within 2 s"
    );
    rig.run(300);
    let view = motor(&board, 1);
    assert_eq!(view.microstep_hz, 0.0, "stopped: {view:?}");
    assert_eq!(view.action, Action::Inactive);
}
