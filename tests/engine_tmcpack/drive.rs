//! The pack's drive functions beyond the ramp through engine + driver + simulated pack on
//! the fake clock: the `$45` power-down mode keeping a reference over a power outage
//! (manual 8.6), and the `$24` PI controller following a position target changed on the fly
//! (manual 8.4).

use super::*;
use board_tmcpack::{PositionMode, PowerDownMode};
use motion_ipc::DeviceState;

/// One SIXpack at address 1, axes x (motor 0) and y (motor 1), the driver config changed
/// by `change`.
fn rig_with(change: impl FnOnce(&mut TmcpackDriverConfig)) -> (Rig, Pack) {
    let (_, board) = Shared::new(pack(1, Variant::SixPack));
    let rig = rig_on(&board, change);
    (rig, board)
}

/// A rig with a fresh engine and driver on the simulated pack `board`.
fn rig_on(board: &Pack, change: impl FnOnce(&mut TmcpackDriverConfig)) -> Rig {
    let wire = Box::new(Shared(Arc::clone(board)));
    let link = SimLink::stream_with("rs485", BAUD, Duplex::Half, wire);
    let config = engine_config(
        vec![device("pack", 1)],
        vec![axis("x", 0, 0), axis("y", 0, 1)],
    );
    let mut channels = [None; 6];
    for slot in channels.iter_mut().take(2) {
        *slot = Some(TmcpackChannel {
            max_velocity: MAX_VELOCITY_MM * COUNTS,
            max_accel: MAX_ACCEL_MM * COUNTS,
            ..TmcpackChannel::default()
        });
    }
    let mut driver_config = TmcpackDriverConfig {
        address: 1,
        baud: BAUD,
        channels,
        ..TmcpackDriverConfig::default()
    };
    change(&mut driver_config);
    let driver = TmcpackDriver::new(driver_config);
    Rig::new(config, vec![Box::new(driver)], vec![Box::new(link)])
}

/// Homes x at its switch, then moves it to 20 mm.
fn home_and_move(rig: &mut Rig, board: &Pack) {
    wait_online(rig, 2);
    accepted(rig, 0, CommandKind::Home, [10.0, 0.0, 0.0]);
    assert!(
        rig.run_until(Duration::from_secs(10), |frame| {
            frame.axes[0].mode == AxisMode::Hold as u8
                && frame.axes[0].flags & AxisFlags::HOMED.0 != 0
        }),
        "homed within 10 s"
    );
    accepted(rig, 0, CommandKind::Position, [20.0, 0.0, 0.0]);
    move_and_check(
        rig,
        board,
        0,
        0,
        20.0,
        MAX_VELOCITY_MM,
        Duration::from_secs(3),
    );
    rig.run(100);
}

/// `power_down = "restore"`: the pack's supply fails with x at 20 mm and y never
/// referenced, while the server runs on (a UPS, another supply); the pack saved the
/// positions at the undervoltage, boots a second later, and the driver loads them (`$45`
/// bit 0). x is referenced again at 20 mm without a search and a move lands where it says;
/// y, never referenced, is not. The description says `PD loaded`.
#[test]
fn a_restored_position_keeps_the_reference_over_a_power_outage() {
    let (mut rig, board) = rig_with(|c| c.power_down = PowerDownMode::Restore);
    home_and_move(&mut rig, &board);
    let status = rig.engine.driver(0).expect("device 0").status();
    assert_eq!(status.firmware(), "SIXpack V1.4.9 #1001 PD armed");
    let physical = motor(&board, 0).physical;
    board.lock().unwrap().power_outage(rig.now);
    assert_eq!(
        board.lock().unwrap().saved_positions().map(|p| p[0]),
        Some(2000)
    );
    // The pack is deaf for its boot: the driver loses it, and finds it again rebooted.
    assert!(
        rig.run_until(Duration::from_secs(2), |frame| {
            frame.device_state(0) != DeviceState::Online
        }),
        "the pack went away"
    );
    assert!(
        rig.run_until(Duration::from_secs(5), |frame| {
            frame.device_state(0) == DeviceState::Online
                && frame.axes[0].flags & AxisFlags::HOMED.0 != 0
        }),
        "referenced again after the boot"
    );
    rig.run(200);
    assert!((rig.axis(0).position - 20.0).abs() < 1e-9);
    assert!(flag(&rig, 0, AxisFlags::HOMED));
    assert!(!flag(&rig, 1, AxisFlags::HOMED), "y had no reference");
    let status = rig.engine.driver(0).expect("device 0").status();
    assert_eq!(status.firmware(), "SIXpack V1.4.9 #1001 PD loaded");
    assert_eq!(status.resets, 1);
    // The EEPROM's positions were invalidated after the load.
    assert_eq!(board.lock().unwrap().saved_positions(), None);
    // The register and the rotor agree: 5 mm more is 500 µsteps of the rotor.
    accepted(&mut rig, 0, CommandKind::Position, [25.0, 0.0, 0.0]);
    move_and_check(
        &mut rig,
        &board,
        0,
        0,
        25.0,
        MAX_VELOCITY_MM,
        Duration::from_secs(3),
    );
    assert_eq!(motor(&board, 0).physical - physical, 500);
}

/// The server itself went down with the supply and starts afresh after the pack's boot:
/// the positions are loaded (x shows 20 mm), but no reference of before is known to it —
/// the pack saves positions, not references — so x is not referenced.
#[test]
fn a_server_started_after_the_outage_gets_the_positions_but_no_reference() {
    let (mut rig, board) = rig_with(|c| c.power_down = PowerDownMode::Restore);
    home_and_move(&mut rig, &board);
    board.lock().unwrap().power_outage(rig.now);
    let then = rig.now + Duration::from_secs(2);
    drop(rig);
    let mut rig = rig_on(&board, |c| c.power_down = PowerDownMode::Restore);
    rig.now = then;
    wait_online(&mut rig, 2);
    rig.run(200);
    assert!((rig.axis(0).position - 20.0).abs() < 1e-9);
    assert!(!flag(&rig, 0, AxisFlags::HOMED));
    let status = rig.engine.driver(0).expect("device 0").status();
    assert_eq!(status.firmware(), "SIXpack V1.4.9 #1001 PD loaded");
}

/// Without the key (today's behaviour) the same outage leaves x without its reference, at
/// position 0 of the rebooted pack.
#[test]
fn without_power_down_an_outage_loses_the_reference() {
    let (mut rig, board) = rig_with(|_| {});
    home_and_move(&mut rig, &board);
    board.lock().unwrap().power_outage(rig.now);
    assert_eq!(board.lock().unwrap().saved_positions(), None);
    assert!(rig.run_until(Duration::from_secs(2), |frame| {
        frame.device_state(0) != DeviceState::Online
    }));
    assert!(rig.run_until(Duration::from_secs(5), |frame| {
        frame.device_state(0) == DeviceState::Online
            && frame.axes[0].flags & AxisFlags::STALE.0 == 0
    }));
    rig.run(200);
    assert!(!flag(&rig, 0, AxisFlags::HOMED));
    assert_eq!(rig.axis(0).position, 0.0);
}

/// `position_mode = "pi"` on y: a position command is the PI controller's target (`$24`);
/// a new target while y runs towards the first is taken on the fly — y never stops between
/// them — and y arrives and holds there with the PI controller.
#[test]
fn the_pi_controller_follows_a_target_changed_on_the_fly() {
    let (mut rig, board) = rig_with(|c| {
        if let Some(Some(y)) = c.channels.get_mut(1) {
            y.position_mode = PositionMode::Pi;
        }
    });
    wait_online(&mut rig, 2);
    accepted(&mut rig, 1, CommandKind::Position, [30.0, 0.0, 0.0]);
    rig.run(300);
    let first = motor(&board, 1);
    assert_eq!(first.action, Action::PiController);
    assert!(first.microstep_hz > 0.0 && first.position > 0, "{first:?}");
    accepted(&mut rig, 1, CommandKind::Position, [40.0, 0.0, 0.0]);
    let mut slowest = f64::MAX;
    let end = rig.now + Duration::from_secs(10);
    while rig.now < end && motor(&board, 1).position < 3000 {
        rig.tick();
        slowest = slowest.min(motor(&board, 1).microstep_hz);
    }
    assert!(slowest > 0.0, "no stop between the two targets");
    assert!(
        rig.run_until(Duration::from_secs(10), |frame| {
            frame.axes[1].flags & AxisFlags::ARRIVED.0 != 0
        }),
        "arrived at 40 mm: {:?}",
        motor(&board, 1)
    );
    assert!((rig.axis(1).position - 40.0).abs() <= 0.01);
    assert!(
        !flag(&rig, 1, AxisFlags::MOVING),
        "holding counts as at rest"
    );
    assert_eq!(motor(&board, 1).action, Action::PiController);
    // Never faster than the axis limit.
    assert!(motor(&board, 1).microstep_hz.abs() <= MAX_VELOCITY_MM * COUNTS);
    // A stop leaves the PI controller.
    accepted(&mut rig, 1, CommandKind::Stop, [0.0; 3]);
    rig.run(500);
    assert_eq!(motor(&board, 1).action, Action::Inactive);
}
