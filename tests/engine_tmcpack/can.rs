//! The same driver on a CAN bus (manual 6.2): the simulated pack on a simulated CAN link
//! (`SimCanLink`, 250 kbit/s by default), stepped with the fake clock. Only the framing and
//! the timing differ from the RS-485 pair; the goals, the polls and the answers are the
//! same, and so is where a move ends.

use super::*;
use motion_link::sim::{CanBus, SimCanLink};

const BITRATE: u32 = 250_000;

/// The driver of `single`'s pack, on a CAN link at `bitrate`.
fn can_driver(address: u8, motors: &[usize], bitrate: u32) -> TmcpackDriver {
    let mut channels = [None; 6];
    for &motor in motors {
        channels[motor] = Some(TmcpackChannel {
            max_velocity: MAX_VELOCITY_MM * COUNTS,
            max_accel: MAX_ACCEL_MM * COUNTS,
            ..TmcpackChannel::default()
        });
    }
    TmcpackDriver::new(TmcpackDriverConfig {
        address,
        variant: Variant::SixPack,
        channels,
        can_bitrate: Some(bitrate),
        ..TmcpackDriverConfig::default()
    })
}

/// One SIXpack at address 1 with axes on motors 0 and 1, on a simulated CAN bus.
fn single_can(bitrate: u32) -> (Rig, Pack, SimFaults) {
    let (wire, board) = Shared::new(pack(1, Variant::SixPack));
    let link = SimCanLink::new("can", bitrate, wire);
    let faults = link.faults();
    let config = engine_config(
        vec![device("pack", 1)],
        vec![axis("x", 0, 0), axis("y", 0, 1)],
    );
    let driver = can_driver(1, &[0, 1], bitrate);
    let rig = Rig::new(config, vec![Box::new(driver)], vec![Box::new(link)]);
    (rig, board, faults)
}

#[test]
fn over_can_the_pack_starts_takes_its_configuration_and_moves() {
    let (mut rig, board, _) = single_can(BITRATE);
    wait_online(&mut rig, 2);
    let status = rig.engine.driver(0).expect("device 0").status();
    assert_eq!(status.firmware(), "SIXpack V1.4.9 s/n 1001");
    {
        let sim = board.lock().unwrap();
        assert!(sim.can_active(), "CAN took over from RS-232 / RS-485");
        let can = sim.can_stats();
        assert!(can.executed > 20, "{can:?}");
        assert_eq!(
            can.overflowed, 0,
            "no command lost to a full cache: {can:?}"
        );
        assert_eq!(can.invalid, 0, "{can:?}");
        assert_eq!(can.unanswerable, 0, "{can:?}");
        // The driver lets at most half the cache fill.
        assert!(can.deepest <= 8, "{can:?}");
        assert_eq!(sim.stats().executed, 0, "nothing came over the serial side");
        // $40 and $41 set up the serial line: not sent on CAN, so the pack keeps its
        // factory switch-over.
        assert_eq!(sim.switchover(), Duration::from_millis(6));
    }
    accepted(&mut rig, 0, CommandKind::RampPosition, [20.0, 0.0, 0.0]);
    move_and_check(
        &mut rig,
        &board,
        0,
        0,
        20.0,
        MAX_VELOCITY_MM,
        Duration::from_secs(3),
    );
    let can = board.lock().unwrap().can_stats();
    assert_eq!(can.overflowed, 0, "{can:?}");
}

/// The same move on the RS-485 pair at 19200 baud and on CAN at 250 kbit/s ends at the
/// same microstep; CAN refreshes the axes several times as often (no switch-over, 0.44 ms
/// frames and 2 ms processing instead of 4.7 ms words and 2 ms turn-arounds).
#[test]
fn the_same_move_over_serial_and_over_can_ends_alike_and_can_polls_faster() {
    let (mut serial, serial_board, _) = single(1);
    let (mut can, can_board, _) = single_can(BITRATE);
    wait_online(&mut serial, 2);
    wait_online(&mut can, 2);
    let polls = |board: &Pack| -> u64 {
        let sim = board.lock().unwrap();
        sim.stats().executed + sim.can_stats().executed
    };
    let (serial_before, can_before) = (polls(&serial_board), polls(&can_board));
    serial.run(1000);
    can.run(1000);
    let serial_rate = polls(&serial_board) - serial_before;
    let can_rate = polls(&can_board) - can_before;
    assert!(
        can_rate >= 2 * serial_rate,
        "requests in one second: CAN {can_rate}, serial {serial_rate}"
    );
    for (rig, board) in [(&mut serial, &serial_board), (&mut can, &can_board)] {
        accepted(rig, 1, CommandKind::RampPosition, [-12.5, 0.0, 0.0]);
        move_and_check(
            rig,
            board,
            1,
            1,
            -12.5,
            MAX_VELOCITY_MM,
            Duration::from_secs(3),
        );
    }
    assert_eq!(
        motor(&serial_board, 1).position,
        motor(&can_board, 1).position
    );
}

/// Two packs on one CAN bus (addresses 1 and 2, identifiers $008 and $010): each driver
/// takes the answers for its own query only, and both move at once.
#[test]
fn two_packs_share_a_can_bus() {
    let (wire1, board1) = Shared::new(pack(1, Variant::SixPack));
    let (wire2, board2) = Shared::new(pack(2, Variant::QuadPack));
    let bus = CanBus::new().with(wire1).with(wire2);
    let link = SimCanLink::new("can", 500_000, Box::new(bus));
    let config = engine_config(
        vec![device("a", 1), device("b", 2)],
        vec![axis("x", 0, 0), axis("z", 1, 3)],
    );
    let drivers: Vec<Box<dyn Driver>> = vec![
        Box::new(can_driver(1, &[0], 500_000)),
        Box::new(TmcpackDriver::new(TmcpackDriverConfig {
            address: 2,
            variant: Variant::QuadPack,
            channels: {
                let mut channels = [None; 6];
                channels[3] = Some(TmcpackChannel {
                    max_velocity: MAX_VELOCITY_MM * COUNTS,
                    max_accel: MAX_ACCEL_MM * COUNTS,
                    ..TmcpackChannel::default()
                });
                channels
            },
            can_bitrate: Some(500_000),
            ..TmcpackDriverConfig::default()
        })),
    ];
    let mut rig = Rig::new(config, drivers, vec![Box::new(link)]);
    wait_online(&mut rig, 2);
    accepted(&mut rig, 0, CommandKind::RampPosition, [5.0, 0.0, 0.0]);
    accepted(&mut rig, 1, CommandKind::RampPosition, [-5.0, 0.0, 0.0]);
    let end = rig.now + Duration::from_secs(3);
    let both = |rig: &Rig| flag(rig, 0, AxisFlags::ARRIVED) && flag(rig, 1, AxisFlags::ARRIVED);
    while rig.now < end && !both(&rig) {
        rig.tick();
    }
    assert!(
        both(&rig),
        "both arrived: {:?} {:?}",
        rig.axis(0),
        rig.axis(1)
    );
    assert_eq!(motor(&board1, 0).position, 500);
    assert_eq!(motor(&board2, 3).position, -500);
    for board in [&board1, &board2] {
        let sim = board.lock().unwrap();
        let can = sim.can_stats();
        assert_eq!((can.overflowed, can.invalid), (0, 0), "{can:?}");
        // Each hears the other's requests and answers, and takes none of them.
        assert!(can.foreign > 0, "{can:?}");
    }
    for index in 0..2 {
        let status = rig.engine.driver(index).expect("device").status();
        assert_eq!(status.timeouts, 0, "device {index}: {status:?}");
    }
}

/// Unplugging the CAN bus takes the pack offline; plugged in again it comes back and is
/// configured anew.
#[test]
fn a_can_bus_unplugged_and_back_brings_the_pack_back() {
    let (mut rig, board, faults) = single_can(BITRATE);
    wait_online(&mut rig, 2);
    faults.unplug();
    assert!(
        rig.run_until(Duration::from_secs(2), |frame| !all_fresh(frame, 2)),
        "the axes go stale without the bus"
    );
    let executed = board.lock().unwrap().can_stats().executed;
    faults.replug();
    assert!(
        rig.run_until(Duration::from_secs(5), |frame| all_fresh(frame, 2)),
        "back within 5 s"
    );
    let can = board.lock().unwrap().can_stats();
    assert!(can.executed > executed + 20, "configured again: {can:?}");
    assert_eq!(can.overflowed, 0, "{can:?}");
}
