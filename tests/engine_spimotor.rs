//! Engine + SPI_motor driver + simulated SPI_motor boards on real `SimLink`s, stepped with a
//! fake clock (what motiond's loop does, without sleeping).
//!
//! The counting global allocator (for the driver's zero-allocation test) counts on the
//! calling thread only, so the other tests of this binary do not disturb it.

mod support;

use core::time::Duration;
use std::sync::{Arc, Mutex};

use board_spimotor::driver::{AxisLimits, SpimotorDrive, SpimotorDriver, SpimotorDriverConfig};
use board_spimotor::sim::{Bridge, Drive, SpimotorSim, SpimotorSimConfig};
use motion_drivers::{Driver, LinkKind};
use motion_engine::{AxisConfig, BusConfig, DeviceConfig, EngineConfig};
use motion_ipc::{AxisFlags, AxisMode, CommandKind, FaultCode, Reason};
use motion_link::Link;
use motion_link::sim::{SimFaults, SimLink, SpiBus};
use spimotor::{Address, Direction, Motor, Request, Transaction};
use support::counting_alloc::{CountingAllocator, allocations};
use support::rig::{Rig, Shared, accepted, all_fresh, flag, fresh};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

/// SPI clock of the simulated bus.
const SPEED_HZ: u32 = 1_000_000;
/// Stepper axis: 100 full steps per mm.
const STEPS_PER_MM: f64 = 100.0;
const MAX_VELOCITY_MM: f64 = 20.0;
const MAX_ACCEL_MM: f64 = 200.0;
/// The board's slowest step rate (delay 25.5 ms): its start/stop rate.
const SLOWEST_RATE: f64 = 10_000.0 / 255.0;

type Board = Arc<Mutex<SpimotorSim>>;

fn stepper_axis(name: &str, device: usize) -> AxisConfig {
    AxisConfig {
        name: name.into(),
        unit: "mm".into(),
        device,
        channel: 0,
        counts_per_unit: STEPS_PER_MM,
        min: -100.0,
        max: 100.0,
        max_velocity: MAX_VELOCITY_MM,
        max_accel: MAX_ACCEL_MM,
        position_tolerance: 0.01,
        ..AxisConfig::default()
    }
}

fn brushed_axis(name: &str, device: usize, channel: usize) -> AxisConfig {
    AxisConfig {
        name: name.into(),
        unit: "rev".into(),
        device,
        channel,
        counts_per_unit: 1.0,
        min: -1e6,
        max: 1e6,
        max_velocity: 100.0,
        max_accel: 1_000.0,
        position_tolerance: 0.1,
        ..AxisConfig::default()
    }
}

fn driver_config(address: u8, drive: SpimotorDrive) -> SpimotorDriverConfig {
    SpimotorDriverConfig {
        address: Address::new(address).expect("even address"),
        drive,
        speed_hz: SPEED_HZ,
        limits: [AxisLimits {
            max_velocity: MAX_VELOCITY_MM * STEPS_PER_MM,
            max_accel: MAX_ACCEL_MM * STEPS_PER_MM,
        }; 2],
        ..SpimotorDriverConfig::default()
    }
}

fn sim(address: u8, drive: Drive) -> SpimotorSim {
    SpimotorSim::new(SpimotorSimConfig {
        address,
        drive,
        seed: 7,
        ..SpimotorSimConfig::default()
    })
}

fn engine_config(devices: Vec<DeviceConfig>, axes: Vec<AxisConfig>) -> EngineConfig {
    EngineConfig {
        name: "spimotor".into(),
        tick_hz: 1000,
        command_timeout: Duration::from_millis(250),
        links: vec![BusConfig {
            name: "spi0".into(),
            kind: LinkKind::Spi,
        }],
        devices,
        axes,
        ..EngineConfig::default()
    }
}

fn device(name: &str, address: u8) -> DeviceConfig {
    DeviceConfig {
        name: name.into(),
        link: 0,
        address: u32::from(address),
    }
}

/// One stepper board at 0x90 (the driver may be told another address).
fn stepper_rig(driver_address: u8) -> (Rig, Board, SimFaults) {
    let (wire, board) = Shared::new(sim(0x90, Drive::Stepper));
    let link = SimLink::spi("spi0", SPEED_HZ, wire);
    let faults = link.faults();
    let driver = SpimotorDriver::new(driver_config(driver_address, SpimotorDrive::Stepper));
    let config = engine_config(
        vec![device("motor", driver_address)],
        vec![stepper_axis("x", 0)],
    );
    let rig = Rig::new(config, vec![Box::new(driver)], vec![Box::new(link)]);
    (rig, board, faults)
}

fn brushed_rig() -> (Rig, Board) {
    let (rig, board, _) = brushed_rig_with_faults();
    (rig, board)
}

fn brushed_rig_with_faults() -> (Rig, Board, SimFaults) {
    let (wire, board) = Shared::new(sim(0x90, Drive::Brushed));
    let link = SimLink::spi("spi0", SPEED_HZ, wire);
    let faults = link.faults();
    let driver = SpimotorDriver::new(driver_config(0x90, SpimotorDrive::Brushed));
    let config = engine_config(
        vec![device("wheels", 0x90)],
        vec![brushed_axis("left", 0, 0), brushed_axis("right", 0, 1)],
    );
    let rig = Rig::new(config, vec![Box::new(driver)], vec![Box::new(link)]);
    (rig, board, faults)
}

fn wait_online(rig: &mut Rig, axes: usize) {
    assert!(
        rig.run_until(Duration::from_millis(200), |frame| {
            all_fresh(frame, axes)
        }),
        "the boards start within 200 ms"
    );
}

fn rejected(rig: &mut Rig, axis: u32, kind: CommandKind, values: [f64; 3]) -> Reason {
    let reply = rig.command(axis, kind, values);
    reply.result().expect_err("refused")
}

/// Ticks until the stepper axis arrives, checking the limits on the simulated motor every
/// tick: never faster than `max_velocity`, never faster than a ramp from its start/stop
/// rate at `max_accel` allows (speeding up and braking), never past `target` (steps).
fn move_and_check(rig: &mut Rig, board: &Board, target_mm: f64, limit: Duration) {
    let start = rig.now;
    let from = board.lock().unwrap().rotor_steps();
    let target = (target_mm * STEPS_PER_MM).round() as i64;
    let max_rate = MAX_VELOCITY_MM * STEPS_PER_MM;
    let accel = MAX_ACCEL_MM * STEPS_PER_MM;
    let end = rig.now + limit;
    while rig.now < end {
        rig.tick();
        let sim = board.lock().unwrap();
        let rate = sim.velocity(0).unwrap().abs();
        let elapsed = (rig.now - start).as_secs_f64();
        assert!(rate <= max_rate + 1e-6, "{rate} steps/s over the limit");
        assert!(
            rate <= SLOWEST_RATE + accel * elapsed + 1e-6,
            "{rate} steps/s after {elapsed} s: faster than the ramp"
        );
        let rotor = sim.rotor_steps();
        // Braking: never faster than the curve from which it can stop at the target
        // (give or take the one step in progress).
        let brake = (2.0 * accel * ((target - rotor).abs() + 1) as f64).sqrt();
        assert!(
            rate <= brake + SLOWEST_RATE,
            "{rate} steps/s {} steps before the target: cannot brake in time",
            target - rotor
        );
        assert!(
            (rotor - from).signum() * (target - rotor).signum() >= 0,
            "overshoot: rotor {rotor}, target {target}"
        );
        drop(sim);
        if flag(rig, 0, AxisFlags::ARRIVED) {
            break;
        }
    }
    assert!(flag(rig, 0, AxisFlags::ARRIVED), "arrived within {limit:?}");
    assert!((rig.axis(0).position - target_mm).abs() <= 0.01);
    assert_eq!(board.lock().unwrap().rotor_steps(), target);
}

#[test]
fn the_board_starts_and_reports_its_identification() {
    let (mut rig, board, _) = stepper_rig(0x90);
    wait_online(&mut rig, 1);
    let driver = rig.engine.driver(0).expect("device 0");
    let status = driver.status();
    assert!(status.online);
    assert_eq!(status.firmware(), "spi_motor sn 00000001");
    let sim = board.lock().unwrap();
    // The engine's start-up stop leaves the stepper at rest, at the board's slowest step
    // delay (the driver's resting delay).
    assert_eq!(
        sim.step_delay().tenths_ms(),
        255,
        "at rest after the start-up stop"
    );
    assert_eq!(sim.stepper_intensity(), 0x20);
    assert_eq!(sim.coils(), spimotor::Coils::Two);
    assert_eq!(sim.stats().malformed, 0);
}

#[test]
fn a_move_arrives_within_the_axis_limits() {
    let (mut rig, board, _) = stepper_rig(0x90);
    wait_online(&mut rig, 1);
    accepted(&mut rig, 0, CommandKind::Position, [5.0, 0.0, 0.0]);
    move_and_check(&mut rig, &board, 5.0, Duration::from_secs(2));
    // And back, along a slower profile of the client's own.
    accepted(&mut rig, 0, CommandKind::RampPosition, [-2.5, 5.0, 50.0]);
    let start = rig.now;
    let mut fastest: f64 = 0.0;
    while !flag(&rig, 0, AxisFlags::ARRIVED) && rig.now < start + Duration::from_secs(4) {
        rig.tick();
        let rate = board.lock().unwrap().velocity(0).unwrap().abs();
        assert!(rate <= 500.0 + 1e-6, "ramp velocity 5 mm/s = 500 steps/s");
        fastest = fastest.max(rate);
    }
    assert!(flag(&rig, 0, AxisFlags::ARRIVED));
    assert_eq!(board.lock().unwrap().rotor_steps(), -250);
    assert!(
        fastest >= 450.0,
        "it did cruise near 500 steps/s: {fastest}"
    );
    assert_eq!(rig.axis(0).mode, AxisMode::RampPosition as u8);
}

#[test]
fn velocity_then_stop() {
    let (mut rig, board, _) = stepper_rig(0x90);
    wait_online(&mut rig, 1);
    for _ in 0..3 {
        // Refreshed before the 250 ms deadman.
        accepted(&mut rig, 0, CommandKind::Velocity, [-10.0, 0.0, 0.0]);
        rig.run(199);
    }
    let rate = board.lock().unwrap().velocity(0).unwrap();
    assert_eq!(
        rate, -1_000.0,
        "10 mm/s = 1000 steps/s = a step every 1.0 ms"
    );
    assert!((rig.axis(0).velocity + 10.0).abs() < 1e-9);
    assert!(flag(&rig, 0, AxisFlags::MOVING));
    let at_stop = board.lock().unwrap().rotor_steps();
    accepted(&mut rig, 0, CommandKind::Stop, [0.0; 3]);
    assert!(rig.run_until(Duration::from_millis(500), |frame| {
        frame.axes[0].mode == AxisMode::Hold as u8
    }));
    rig.run(20);
    let sim = board.lock().unwrap();
    assert!(!sim.is_moving());
    // 1000 steps/s braked at 20 000 steps/s²: 25 steps, plus a poll period of travel.
    let travelled = (sim.rotor_steps() - at_stop).abs();
    assert!(travelled <= 35, "stopped within {travelled} steps");
    assert!((rig.axis(0).position * STEPS_PER_MM - sim.rotor_steps() as f64).abs() < 1e-9);
}

#[test]
fn the_deadman_stops_a_jog() {
    let (mut rig, board, _) = stepper_rig(0x90);
    wait_online(&mut rig, 1);
    accepted(&mut rig, 0, CommandKind::Velocity, [5.0, 0.0, 0.0]);
    rig.run(400);
    assert!(flag(&rig, 0, AxisFlags::DEADMAN_EXPIRED));
    assert!(!board.lock().unwrap().is_moving());
}

#[test]
fn set_position_redefines_here_without_moving() {
    let (mut rig, board, _) = stepper_rig(0x90);
    wait_online(&mut rig, 1);
    accepted(&mut rig, 0, CommandKind::Position, [1.0, 0.0, 0.0]);
    move_and_check(&mut rig, &board, 1.0, Duration::from_secs(1));
    accepted(&mut rig, 0, CommandKind::SetPosition, [12.5, 0.0, 0.0]);
    rig.run(10);
    let sim = board.lock().unwrap();
    assert_eq!(sim.rotor_steps(), 100, "the rotor did not move");
    assert_eq!(sim.current_position(), 1_250);
    assert_eq!(sim.target_position(), 1_250);
    assert!(!sim.is_moving());
    drop(sim);
    assert_eq!(rig.axis(0).position, 12.5);
    assert!(flag(&rig, 0, AxisFlags::HOMED));
    // Moves are relative to the new origin.
    accepted(&mut rig, 0, CommandKind::Position, [12.0, 0.0, 0.0]);
    assert!(rig.run_until(Duration::from_secs(1), |frame| {
        frame.axes[0].flags & AxisFlags::ARRIVED.0 != 0
    }));
    assert_eq!(board.lock().unwrap().rotor_steps(), 50);
}

#[test]
fn goals_the_stepper_cannot_do_are_refused() {
    let (mut rig, _, _) = stepper_rig(0x90);
    wait_online(&mut rig, 1);
    let home = rejected(&mut rig, 0, CommandKind::Home, [0.0; 3]);
    assert_eq!(home, Reason::Unsupported);
    let power = rejected(&mut rig, 0, CommandKind::Power, [0.5, 0.0, 0.0]);
    assert_eq!(power, Reason::Unsupported);
    // 0.2 mm/s = 20 steps/s: slower than the board's slowest step rate.
    let slow = rejected(&mut rig, 0, CommandKind::Velocity, [0.2, 0.0, 0.0]);
    assert_eq!(slow, Reason::VelocityLimit);
}

#[test]
fn bytes_on_the_wire_decode_with_the_protocol_crate() {
    let (mut rig, board, _) = stepper_rig(0x90);
    rig.log_wire = true;
    wait_online(&mut rig, 1);
    accepted(&mut rig, 0, CommandKind::Position, [3.0, 0.0, 0.0]);
    move_and_check(&mut rig, &board, 3.0, Duration::from_secs(2));
    accepted(&mut rig, 0, CommandKind::SetPosition, [0.0, 0.0, 0.0]);
    rig.run(10);
    let log = rig.wire_log(0);
    assert!(log.len() > 100);
    let mut targets = Vec::new();
    for (_, mosi) in log {
        let transaction = Transaction::decode(mosi).expect("valid transaction");
        assert_eq!(transaction.address, Address::DEFAULT);
        let mut again = [0u8; 64];
        let len = transaction.encode(&mut again).expect("encodes");
        assert_eq!(
            &again[..len],
            &mosi[..],
            "the protocol crate's own encoding"
        );
        if let Request::Write(spimotor::Write::TargetPosition(target)) = transaction.request {
            targets.push(target);
        }
    }
    assert_eq!(targets, [300, 0], "the move and the set-position");
    assert_eq!(board.lock().unwrap().stats().malformed, 0);
}

#[test]
fn a_garbage_burst_is_survived_without_losing_the_position() {
    let (mut rig, board, faults) = stepper_rig(0x90);
    wait_online(&mut rig, 1);
    accepted(&mut rig, 0, CommandKind::Position, [2.0, 0.0, 0.0]);
    move_and_check(&mut rig, &board, 2.0, Duration::from_secs(1));
    // 200 bytes of MISO (about 13 polls of 15 bytes): below the driver's PROTOCOL_LIMIT of
    // 20 disagreeing polls in a row, which would raise a protocol fault.
    faults.inject_noise(200);
    for _ in 0..100 {
        rig.tick();
        assert_eq!(rig.axis(0).position, 2.0, "garbage never reaches the axis");
        assert!(!flag(&rig, 0, AxisFlags::FAULT));
    }
    rig.run(50);
    assert!(fresh(&rig, 0));
    let driver = rig.engine.driver(0).unwrap();
    assert!(driver.status().bad_replies > 0);
    assert_eq!(driver.status().resets, 0);
    // Still drivable.
    accepted(&mut rig, 0, CommandKind::Position, [0.5, 0.0, 0.0]);
    move_and_check(&mut rig, &board, 0.5, Duration::from_secs(1));
}

#[test]
fn unplug_and_replug_fault_the_axis_then_it_needs_a_new_command() {
    let (mut rig, board, faults) = stepper_rig(0x90);
    wait_online(&mut rig, 1);
    accepted(&mut rig, 0, CommandKind::Position, [1.0, 0.0, 0.0]);
    rig.run(20);
    faults.unplug();
    rig.run(300);
    assert!(rig.link_is_down(0));
    assert!(flag(&rig, 0, AxisFlags::STALE));
    assert!(flag(&rig, 0, AxisFlags::FAULT));
    assert_eq!(rig.axis(0).fault, FaultCode::LinkDown as u16);
    let reason = rejected(&mut rig, 0, CommandKind::Position, [0.0, 0.0, 0.0]);
    assert_eq!(reason, Reason::LinkDown);
    faults.replug();
    assert!(rig.run_until(Duration::from_secs(1), |frame| {
        frame.axes[0].flags & (AxisFlags::STALE.0 | AxisFlags::FAULT.0) == 0
    }));
    // The board kept its position; the axis holds and needs a new command.
    let axis = rig.axis(0);
    assert_ne!(axis.mode, AxisMode::Position as u8);
    assert!(!board.lock().unwrap().is_moving());
    let here = board.lock().unwrap().rotor_steps();
    assert!((axis.position * STEPS_PER_MM - here as f64).abs() < 1e-9);
    accepted(&mut rig, 0, CommandKind::Position, [-1.0, 0.0, 0.0]);
    move_and_check(&mut rig, &board, -1.0, Duration::from_secs(2));
}

#[test]
fn a_board_that_does_not_answer_is_faulted() {
    // The driver looks for a board at 0x92; the only board on the bus is at 0x90.
    let (mut rig, board, _) = stepper_rig(0x92);
    assert!(rig.run_until(Duration::from_secs(1), |frame| {
        frame.axes[0].fault == FaultCode::BoardNotResponding as u16
    }));
    assert!(flag(&rig, 0, AxisFlags::STALE));
    let driver = rig.engine.driver(0).unwrap();
    assert!(!driver.status().online);
    let reason = rejected(&mut rig, 0, CommandKind::Position, [1.0, 0.0, 0.0]);
    assert_eq!(
        reason,
        Reason::DeviceOffline,
        "a board that does not answer is offline"
    );
    assert_eq!(board.lock().unwrap().stats().addressed, 0);
}

#[test]
fn a_power_cycled_board_is_reported_reset() {
    let (mut rig, board, _) = stepper_rig(0x90);
    wait_online(&mut rig, 1);
    accepted(&mut rig, 0, CommandKind::Position, [1.5, 0.0, 0.0]);
    move_and_check(&mut rig, &board, 1.5, Duration::from_secs(1));
    let now = rig.now;
    board.lock().unwrap().power_cycle(now);
    assert!(rig.run_until(Duration::from_millis(100), |frame| {
        frame.axes[0].fault == FaultCode::BoardReset as u16
    }));
    assert!(rig.run_until(Duration::from_millis(200), |frame| {
        frame.axes[0].flags & (AxisFlags::STALE.0 | AxisFlags::FAULT.0) == 0
    }));
    assert_eq!(
        rig.axis(0).position,
        0.0,
        "the board's counter restarted at 0"
    );
    assert!(!flag(&rig, 0, AxisFlags::HOMED));
    assert_eq!(rig.engine.driver(0).unwrap().status().resets, 1);
    assert_eq!(
        board.lock().unwrap().coils(),
        spimotor::Coils::Two,
        "configured again (the board powers on with one coil)"
    );
}

#[test]
fn brushed_power_spins_and_stops_each_motor() {
    let (mut rig, board) = brushed_rig();
    wait_online(&mut rig, 2);
    accepted(&mut rig, 0, CommandKind::Power, [0.5, 0.0, 0.0]);
    accepted(&mut rig, 1, CommandKind::Power, [-0.3, 0.0, 0.0]);
    rig.run(100);
    {
        let sim = board.lock().unwrap();
        assert_eq!(
            sim.bridge(Motor::A),
            Bridge::Spin {
                direction: Direction::A,
                intensity: 128
            }
        );
        assert_eq!(
            sim.bridge(Motor::B),
            Bridge::Spin {
                direction: Direction::B,
                intensity: 77
            }
        );
        assert!(sim.motor_velocity(Motor::A) > 40.0);
        assert!(sim.motor_velocity(Motor::B) < -20.0);
    }
    assert!(flag(&rig, 0, AxisFlags::MOVING) && flag(&rig, 1, AxisFlags::MOVING));
    assert_eq!(rig.axis(0).position, 0.0, "no encoder: nothing measured");
    accepted(&mut rig, 0, CommandKind::Stop, [0.0; 3]);
    rig.run(5);
    assert_eq!(board.lock().unwrap().bridge(Motor::A), Bridge::Stopped);
    assert_eq!(rig.axis(0).mode, AxisMode::Hold as u8);
    // Motor B's power expires with the deadman.
    rig.run(300);
    assert_eq!(board.lock().unwrap().bridge(Motor::B), Bridge::Stopped);
    assert!(flag(&rig, 1, AxisFlags::DEADMAN_EXPIRED));
    for kind in [
        CommandKind::Position,
        CommandKind::Velocity,
        CommandKind::Home,
        CommandKind::SetPosition,
    ] {
        assert_eq!(
            rejected(&mut rig, 0, kind, [1.0, 0.0, 0.0]),
            Reason::Unsupported,
            "{kind:?}"
        );
    }
    assert!(fresh(&rig, 0) && fresh(&rig, 1));
}

#[test]
fn a_replugged_brushed_board_is_stopped_by_its_start_up() {
    let (mut rig, board, faults) = brushed_rig_with_faults();
    wait_online(&mut rig, 2);
    accepted(&mut rig, 0, CommandKind::Power, [0.8, 0.0, 0.0]);
    rig.run(20);
    faults.unplug();
    rig.run(150);
    assert_eq!(rig.axis(0).fault, FaultCode::LinkDown as u16);
    assert!(flag(&rig, 0, AxisFlags::STALE) && flag(&rig, 1, AxisFlags::STALE));
    // The board itself knows nothing of the link: motor A still spins.
    assert_ne!(board.lock().unwrap().bridge(Motor::A), Bridge::Stopped);
    faults.replug();
    assert!(rig.run_until(Duration::from_secs(1), |frame| {
        (0..2).all(|i| frame.axes[i].flags & (AxisFlags::STALE.0 | AxisFlags::FAULT.0) == 0)
    }));
    assert_eq!(board.lock().unwrap().bridge(Motor::A), Bridge::Stopped);
    assert!(!flag(&rig, 0, AxisFlags::MOVING));
    assert_ne!(
        rig.axis(0).mode,
        AxisMode::Power as u8,
        "needs a new command"
    );
    accepted(&mut rig, 0, CommandKind::Power, [-0.2, 0.0, 0.0]);
    rig.run(3);
    assert_eq!(
        board.lock().unwrap().bridge(Motor::A),
        Bridge::Spin {
            direction: Direction::B,
            intensity: 51
        }
    );
}

#[test]
fn two_boards_share_one_bus_by_address() {
    let (stepper_wire, stepper) = Shared::new(sim(0x90, Drive::Stepper));
    let (brushed_wire, brushed) = Shared::new(sim(0x92, Drive::Brushed));
    let bus = SpiBus::new().with(stepper_wire).with(brushed_wire);
    let link = SimLink::spi("spi0", SPEED_HZ, Box::new(bus));
    let drivers: Vec<Box<dyn Driver>> = vec![
        Box::new(SpimotorDriver::new(driver_config(
            0x90,
            SpimotorDrive::Stepper,
        ))),
        Box::new(SpimotorDriver::new(driver_config(
            0x92,
            SpimotorDrive::Brushed,
        ))),
    ];
    let config = engine_config(
        vec![device("stepper", 0x90), device("wheels", 0x92)],
        vec![stepper_axis("x", 0), brushed_axis("left", 1, 0)],
    );
    let mut rig = Rig::new(config, drivers, vec![Box::new(link) as Box<dyn Link>]);
    wait_online(&mut rig, 2);
    accepted(&mut rig, 1, CommandKind::Power, [1.0, 0.0, 0.0]);
    rig.run(5);
    assert_eq!(
        brushed.lock().unwrap().bridge(Motor::A),
        Bridge::Spin {
            direction: Direction::A,
            intensity: 255
        }
    );
    accepted(&mut rig, 0, CommandKind::Position, [4.0, 0.0, 0.0]);
    move_and_check(&mut rig, &stepper, 4.0, Duration::from_secs(2));
    assert_eq!(stepper.lock().unwrap().bridge(Motor::A), Bridge::Stopped);
    assert!(fresh(&rig, 0) && fresh(&rig, 1));
    for index in 0..2 {
        assert_eq!(rig.engine.driver(index).unwrap().status().bad_replies, 0);
    }
    assert_eq!(stepper.lock().unwrap().stats().malformed, 0);
    assert_eq!(brushed.lock().unwrap().stats().malformed, 0);
}

#[test]
fn the_driver_allocates_nothing_after_construction() {
    use motion_drivers::Goal;
    use motion_link::sim::SpiDevice;

    let mut driver = SpimotorDriver::new(driver_config(0x90, SpimotorDrive::Stepper));
    let mut board = sim(0x90, Drive::Stepper);
    let mut mosi = [0u8; 256];
    let mut miso = [0u8; 256];
    let mut in_driver = 0;
    let period = Duration::from_millis(1);
    for tick in 0..10_000u32 {
        let now = period * tick;
        let goal = match tick % 2_000 {
            100 => Some(Goal::Position { counts: 400.0 }),
            700 => Some(Goal::Velocity {
                velocity: -800.0,
                accel: 10_000.0,
            }),
            1_000 => Some(Goal::Stop { decel: 20_000.0 }),
            1_300 => Some(Goal::SetPosition { counts: 0.0 }),
            1_500 => Some(Goal::Off),
            _ => None,
        };
        let before = allocations();
        driver.handle_timeout(now);
        if let Some(goal) = goal {
            let _ = driver.set_goal(now, 0, goal);
        }
        in_driver += allocations() - before;
        loop {
            let before = allocations();
            let transmit = driver.poll_transmit(now, &mut mosi);
            in_driver += allocations() - before;
            let Some(transmit) = transmit else { break };
            let len = transmit.len;
            miso[..len].fill(0xFF);
            board.transfer(now, &mosi[..len], &mut miso[..len]);
            let before = allocations();
            driver.handle_rx(now + Duration::from_micros(100), &miso[..len]);
            let _ = driver.channel(0);
            let _ = driver.status();
            in_driver += allocations() - before;
        }
    }
    assert!(driver.status().online);
    assert_eq!(driver.status().bad_replies, 0);
    assert_eq!(in_driver, 0, "allocations inside the driver");
}

/// A small deterministic generator for the random-goal test.
struct XorShift(u64);

impl XorShift {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    fn range(&mut self, low: f64, high: f64) -> f64 {
        low + (high - low) * (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[test]
fn random_goal_sequences_never_step_too_fast_nor_raise_false_faults() {
    use motion_drivers::Goal;
    use motion_link::sim::SpiDevice;

    let max_rate = MAX_VELOCITY_MM * STEPS_PER_MM;
    let accel = MAX_ACCEL_MM * STEPS_PER_MM;
    let mut mosi = [0u8; 256];
    let mut miso = [0u8; 256];
    for seed in 1..=12u64 {
        let mut rng = XorShift(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let mut driver = SpimotorDriver::new(driver_config(0x90, SpimotorDrive::Stepper));
        let mut board = sim(0x90, Drive::Stepper);
        let period = Duration::from_millis(1);
        for tick in 0..3_000u32 {
            let now = period * tick;
            driver.handle_timeout(now);
            if tick > 20 && rng.next().is_multiple_of(60) {
                let goal = match rng.next() % 6 {
                    0 => Goal::Position {
                        counts: rng.range(-3_000.0, 3_000.0).round(),
                    },
                    1 => Goal::RampPosition {
                        counts: rng.range(-3_000.0, 3_000.0).round(),
                        velocity: rng.range(SLOWEST_RATE, max_rate),
                        accel: rng.range(100.0, accel),
                    },
                    2 => Goal::Velocity {
                        velocity: rng.range(SLOWEST_RATE, max_rate)
                            * if rng.next().is_multiple_of(2) {
                                1.0
                            } else {
                                -1.0
                            },
                        accel: rng.range(100.0, accel),
                    },
                    3 => Goal::Stop {
                        decel: rng.range(100.0, accel),
                    },
                    4 => Goal::SetPosition {
                        counts: rng.range(-3_000.0, 3_000.0).round(),
                    },
                    _ => Goal::Off,
                };
                driver
                    .set_goal(now, 0, goal)
                    .expect("a goal within the limits");
            }
            while let Some(transmit) = driver.poll_transmit(now, &mut mosi) {
                let len = transmit.len;
                miso[..len].fill(0xFF);
                board.transfer(now, &mosi[..len], &mut miso[..len]);
                driver.handle_rx(now + Duration::from_micros(200), &miso[..len]);
            }
            board.advance(now + Duration::from_micros(999));
            let rate = board.velocity(0).unwrap().abs();
            assert!(rate <= max_rate + 1e-6, "seed {seed} tick {tick}: {rate}");
            let status = driver.status();
            assert_eq!(status.fault, None, "seed {seed} tick {tick}");
            assert_eq!(status.bad_replies, 0, "seed {seed} tick {tick}");
        }
        // The driver's idea of the position is the board's counter.
        driver.handle_timeout(Duration::from_secs(3));
        let state = driver.channel(0);
        assert!(state.refreshed_at.is_some());
        assert!((state.position - f64::from(board.current_position())).abs() <= 20.0);
    }
}

// Stops ramped down from the rate the board steps at.
#[path = "engine_spimotor/hold.rs"]
mod hold;
#[path = "engine_spimotor/lag.rs"]
mod lag;
#[path = "engine_spimotor/off.rs"]
mod off;
#[path = "engine_spimotor/stops.rs"]
mod stops;
#[path = "engine_spimotor/wire.rs"]
mod wire;
