//! Engine + QuadQuad2Drv driver + simulated QuadQuad2Drv board on a real `SimLink` (SPI,
//! 500 kHz), stepped with a fake clock (what motiond's loop does, without sleeping).
//!
//! The counting global allocator (for the driver's zero-allocation test) counts on the
//! calling thread only, so the other tests of this binary do not disturb it.

mod support;

use core::time::Duration;
use std::sync::{Arc, Mutex};

use board_qq2drv::driver::{
    AxisLimits, ChannelConfig, FILLER, HomeInput, POLL_SLACK, Qq2drvDriver, Qq2drvDriverConfig,
    STATUS_MASK, STREAM_MASK,
};
use board_qq2drv::sim::{InputPin, InputSource, Qq2drvSim, Qq2drvSimConfig};
use motion_drivers::{Driver, Goal, LinkKind};
use motion_engine::{AxisConfig, BusConfig, DeviceConfig, EngineConfig};
use motion_ipc::{AxisFlags, AxisMode, CommandKind, FaultCode, Reason};
use motion_link::sim::{Direction, SimFaults, SimLink};
use qq2drv::{ControlMode, InputMode, Request, StreamDecoder};
use support::counting_alloc::{CountingAllocator, allocations};
use support::rig::{Rig, Shared, accepted, all_fresh, flag};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

/// SPI clock of the simulated link (the datasheet's recommended maximum).
const SPEED_HZ: u32 = 500_000;
/// Quadrature transitions per mm.
const COUNTS_PER_MM: f64 = 100.0;
const MAX_VELOCITY_MM: f64 = 30.0;
const MAX_ACCEL_MM: f64 = 300.0;
const TOLERANCE_MM: f64 = 0.05;
/// Where channel 2's end-stop switch sits (transitions from power-up), actuated at and
/// beyond it, pulling the pin low.
const SWITCH_AT: f64 = 600.0;
/// The counter value the board writes on the switch.
const HOME_COUNTS: i32 = 2_000;

type Board = Arc<Mutex<Qq2drvSim>>;

fn axis(name: &str, channel: usize) -> AxisConfig {
    AxisConfig {
        name: name.into(),
        unit: "mm".into(),
        device: 0,
        channel,
        counts_per_unit: COUNTS_PER_MM,
        min: -100.0,
        max: 100.0,
        max_velocity: MAX_VELOCITY_MM,
        max_accel: MAX_ACCEL_MM,
        position_tolerance: TOLERANCE_MM,
        ..AxisConfig::default()
    }
}

fn driver_config() -> Qq2drvDriverConfig {
    let limits = AxisLimits {
        max_velocity: MAX_VELOCITY_MM * COUNTS_PER_MM,
        max_accel: MAX_ACCEL_MM * COUNTS_PER_MM,
    };
    let mut config = Qq2drvDriverConfig {
        speed_hz: SPEED_HZ,
        ..Qq2drvDriverConfig::default()
    };
    for channel in &mut config.channels {
        channel.limits = limits;
    }
    config.channels[1].home = Some(HomeInput {
        mode: InputMode::Edge,
        active_high: false,
        positive_end: true,
        position: HOME_COUNTS,
        spacing: 0,
    });
    config.channels[2] = ChannelConfig {
        enabled: false,
        ..ChannelConfig::default()
    };
    config.channels[3] = ChannelConfig {
        enabled: false,
        ..ChannelConfig::default()
    };
    config
}

fn sim() -> Qq2drvSim {
    let mut config = Qq2drvSimConfig {
        seed: 11,
        spi_clock_hz: SPEED_HZ,
        ..Qq2drvSimConfig::default()
    };
    config.inputs[1] = InputPin {
        source: InputSource::EndStop {
            position: SWITCH_AT,
            positive_end: true,
        },
        actuated_high: false,
    };
    Qq2drvSim::new(config)
}

fn rig_with(driver: Qq2drvDriver, model: Qq2drvSim) -> (Rig, Board, SimFaults) {
    let (wire, board) = Shared::new(model);
    let link = SimLink::spi("spi0", SPEED_HZ, wire);
    let faults = link.faults();
    let config = EngineConfig {
        name: "qq2drv".into(),
        tick_hz: 1000,
        command_timeout: Duration::from_millis(250),
        links: vec![BusConfig {
            name: "spi0".into(),
            kind: LinkKind::Spi,
        }],
        devices: vec![DeviceConfig {
            name: "quad".into(),
            link: 0,
            address: 0,
        }],
        axes: vec![axis("x", 0), axis("y", 1)],
        ..EngineConfig::default()
    };
    let rig = Rig::new(config, vec![Box::new(driver)], vec![Box::new(link)]);
    (rig, board, faults)
}

fn rig() -> (Rig, Board, SimFaults) {
    rig_with(Qq2drvDriver::new(driver_config()), sim())
}

fn wait_online(rig: &mut Rig) {
    assert!(
        rig.run_until(Duration::from_millis(100), |frame| all_fresh(frame, 2)),
        "the board starts within 100 ms"
    );
}

fn rejected(rig: &mut Rig, axis: u32, kind: CommandKind, values: [f64; 3]) -> Reason {
    rig.command(axis, kind, values)
        .result()
        .expect_err("refused")
}

/// Ticks until axis `index` arrives at `target_mm`, checking the simulated motor every
/// tick: never faster than `max_velocity` (plus 5 % for the PID following the board's
/// profile) and never more than the tolerance past the target.
fn move_and_check(rig: &mut Rig, board: &Board, index: usize, target_mm: f64, max_mm_s: f64) {
    let from = board.lock().unwrap().counter(index).unwrap();
    let target = target_mm * COUNTS_PER_MM;
    let direction = (target - f64::from(from)).signum();
    let end = rig.now + Duration::from_secs(3);
    let mut fastest: f64 = 0.0;
    while rig.now < end {
        rig.tick();
        let sim = board.lock().unwrap();
        let speed = sim.true_velocity(index).unwrap().abs();
        fastest = fastest.max(speed);
        assert!(
            speed <= max_mm_s * COUNTS_PER_MM * 1.05,
            "{speed} transitions/s over the limit"
        );
        let counter = f64::from(sim.counter(index).unwrap());
        assert!(
            (counter - target) * direction <= TOLERANCE_MM * COUNTS_PER_MM,
            "overshoot: {counter} for {target}"
        );
        drop(sim);
        if flag(rig, index, AxisFlags::ARRIVED) {
            break;
        }
    }
    assert!(
        flag(rig, index, AxisFlags::ARRIVED),
        "arrived at {target_mm}"
    );
    assert!((rig.axis(index).position - target_mm).abs() <= TOLERANCE_MM);
    let counter = f64::from(board.lock().unwrap().counter(index).unwrap());
    assert!((counter - target).abs() <= TOLERANCE_MM * COUNTS_PER_MM);
    let distance = (target - f64::from(from)).abs();
    let peak = (max_mm_s * COUNTS_PER_MM).min((distance * MAX_ACCEL_MM * COUNTS_PER_MM).sqrt());
    assert!(
        fastest > 0.3 * peak,
        "it moved at speed: {fastest} of {peak}"
    );
}

#[test]
fn the_board_starts_streams_and_reports_its_version() {
    let (mut rig, board, _) = rig();
    wait_online(&mut rig);
    let status = rig.engine.driver(0).unwrap().status();
    assert!(status.online);
    assert_eq!(status.firmware(), "fw 0.1 protocol 0");
    let sim = board.lock().unwrap();
    let masks = sim.data_masks();
    assert_eq!(&masks[..2], &[STREAM_MASK; 2]);
    assert_eq!(masks[2].0, 0, "channels without an axis are not streamed");
    assert_eq!(sim.stream_period(), 24, "24 × 40.96 µs ≤ the 1 ms tick");
    assert_eq!(sim.stats().rejected, 0);
    drop(sim);
    // Data keeps flowing, refreshed every few ticks.
    rig.run(200);
    let stats = board.lock().unwrap().stats();
    assert!(stats.stream_packets > 150, "{stats:?}");
    assert!(all_fresh(&rig.frame, 2));
    let tick = rig.engine.tick();
    assert!(tick - rig.axis(0).last_refresh_tick <= 3);
}

#[test]
fn a_move_arrives_within_the_axis_limits() {
    let (mut rig, board, _) = rig();
    wait_online(&mut rig);
    accepted(&mut rig, 0, CommandKind::Position, [8.0, 0.0, 0.0]);
    move_and_check(&mut rig, &board, 0, 8.0, MAX_VELOCITY_MM);
    assert_eq!(
        board.lock().unwrap().control_mode(0),
        Some(ControlMode::PositionPid)
    );
    // Back along the client's own slower profile (packet 34).
    accepted(&mut rig, 0, CommandKind::RampPosition, [-2.0, 10.0, 100.0]);
    move_and_check(&mut rig, &board, 0, -2.0, 10.0);
    assert_eq!(rig.axis(0).mode, AxisMode::RampPosition as u8);
    // Start-up, two goals, their polls: every packet read out before the next request.
    assert_eq!(board.lock().unwrap().stats().interlaced, 0);
}

#[test]
fn velocity_then_stop() {
    let (mut rig, board, _) = rig();
    wait_online(&mut rig);
    accepted(&mut rig, 0, CommandKind::Velocity, [-10.0, 0.0, 0.0]);
    rig.run(200);
    accepted(&mut rig, 0, CommandKind::Velocity, [-10.0, 0.0, 0.0]);
    rig.run(100);
    let true_velocity = board.lock().unwrap().true_velocity(0).unwrap();
    assert!(
        (true_velocity + 1_000.0).abs() < 60.0,
        "10 mm/s = 1000 transitions/s: {true_velocity}"
    );
    assert!((rig.axis(0).velocity + 10.0).abs() < 0.6);
    assert!(flag(&rig, 0, AxisFlags::MOVING));
    let at_stop = board.lock().unwrap().true_position(0).unwrap();
    accepted(&mut rig, 0, CommandKind::Stop, [0.0; 3]);
    assert!(rig.run_until(Duration::from_millis(800), |frame| {
        frame.axes[0].mode == AxisMode::Hold as u8
    }));
    rig.run(100);
    let sim = board.lock().unwrap();
    assert_eq!(sim.control_mode(0), Some(ControlMode::PositionPid), "holds");
    assert!(sim.true_velocity(0).unwrap().abs() < 5.0);
    // 1000 transitions/s braked at 30 000 /s²: ~17 transitions, plus the loop's lag.
    let travelled = (sim.true_position(0).unwrap() - at_stop).abs();
    assert!(travelled < 60.0, "stopped within {travelled} transitions");
    assert!(!flag(&rig, 0, AxisFlags::MOVING));
}

#[test]
fn the_deadman_stops_a_jog() {
    let (mut rig, board, _) = rig();
    wait_online(&mut rig);
    accepted(&mut rig, 1, CommandKind::Velocity, [5.0, 0.0, 0.0]);
    assert!(rig.run_until(Duration::from_secs(1), |frame| {
        frame.axes[1].flags & AxisFlags::DEADMAN_EXPIRED.0 != 0
    }));
    assert!(rig.run_until(Duration::from_millis(500), |frame| {
        frame.axes[1].mode == AxisMode::Hold as u8
    }));
    rig.run(200);
    let v = board.lock().unwrap().true_velocity(1).unwrap();
    assert!(v.abs() < 5.0, "{v} {:?}", rig.axis(1));
}

#[test]
fn power_drives_the_motor_open_loop() {
    let (mut rig, board, _) = rig();
    wait_online(&mut rig);
    accepted(&mut rig, 0, CommandKind::Power, [0.25, 0.0, 0.0]);
    rig.run(100);
    let sim = board.lock().unwrap();
    assert_eq!(sim.control_mode(0), Some(ControlMode::Power));
    assert_eq!(sim.motor_power(0), Some(2_048), "round(0.25 × 8191)");
    assert!(sim.true_velocity(0).unwrap() > 1_000.0);
    drop(sim);
    assert!(rig.axis(0).velocity > 10.0);
    accepted(&mut rig, 0, CommandKind::Power, [0.0, 0.0, 0.0]);
    rig.run(5);
    assert_eq!(board.lock().unwrap().motor_power(0), Some(0));
}

#[test]
fn home_finds_the_end_stop_and_sets_the_counter() {
    let (mut rig, board, _) = rig();
    wait_online(&mut rig);
    assert!(!flag(&rig, 1, AxisFlags::HOMED));
    accepted(&mut rig, 1, CommandKind::Home, [10.0, 0.0, 0.0]);
    assert!(rig.run_until(Duration::from_secs(3), |frame| {
        frame.axes[1].mode == AxisMode::Hold as u8
    }));
    rig.run(50);
    assert!(flag(&rig, 1, AxisFlags::HOMED));
    let sim = board.lock().unwrap();
    let shaft = sim.true_position(1).unwrap();
    let counter = f64::from(sim.counter(1).unwrap());
    // The counter was written on the switch: it now reads HOME_COUNTS there.
    let offset = counter - (shaft - SWITCH_AT) - f64::from(HOME_COUNTS);
    assert!(offset.abs() <= 4.0, "counter {counter} shaft {shaft}");
    assert!(
        shaft - SWITCH_AT < 80.0,
        "stopped just past the switch: {shaft}"
    );
    assert_eq!(sim.control_mode(1), Some(ControlMode::PositionPid));
    drop(sim);
    assert!((rig.axis(1).position * COUNTS_PER_MM - counter).abs() <= 4.0);
    // From beyond the switch (EDGE needs an inactive → active transition): it backs off
    // first, then finds the switch again.
    board.lock().unwrap().displace_shaft(1, 300.0);
    rig.run(20);
    assert!(flag(&rig, 1, AxisFlags::AT_LIMIT), "the switch is pressed");
    accepted(&mut rig, 1, CommandKind::Home, [10.0, 0.0, 0.0]);
    assert!(rig.run_until(Duration::from_secs(3), |frame| {
        frame.axes[1].mode == AxisMode::Hold as u8
    }));
    let sim = board.lock().unwrap();
    let shaft = sim.true_position(1).unwrap();
    let counter = f64::from(sim.counter(1).unwrap());
    let offset = counter - (shaft - SWITCH_AT) - f64::from(HOME_COUNTS);
    assert!(offset.abs() <= 4.0, "counter {counter} shaft {shaft}");
    assert!((shaft - SWITCH_AT).abs() < 80.0, "near the switch: {shaft}");
    drop(sim);
    // Channel 1 has no home input.
    let reason = rejected(&mut rig, 0, CommandKind::Home, [5.0, 0.0, 0.0]);
    assert_eq!(reason, Reason::Unsupported);
}

#[test]
fn set_position_redefines_here_without_moving() {
    let (mut rig, board, _) = rig();
    wait_online(&mut rig);
    accepted(&mut rig, 0, CommandKind::Position, [3.0, 0.0, 0.0]);
    move_and_check(&mut rig, &board, 0, 3.0, MAX_VELOCITY_MM);
    let shaft = board.lock().unwrap().true_position(0).unwrap();
    accepted(&mut rig, 0, CommandKind::SetPosition, [50.0, 0.0, 0.0]);
    rig.run(100);
    let sim = board.lock().unwrap();
    assert!((f64::from(sim.counter(0).unwrap()) - 5_000.0).abs() <= 3.0);
    assert!(
        (sim.true_position(0).unwrap() - shaft).abs() < 5.0,
        "no motion"
    );
    drop(sim);
    assert!((rig.axis(0).position - 50.0).abs() <= TOLERANCE_MM);
    assert!(flag(&rig, 0, AxisFlags::HOMED));
    accepted(&mut rig, 0, CommandKind::Position, [49.0, 0.0, 0.0]);
    move_and_check(&mut rig, &board, 0, 49.0, MAX_VELOCITY_MM);
}

#[test]
fn bytes_on_the_wire_decode_with_the_protocol_crate() {
    let (mut rig, board, _) = rig();
    rig.log_wire = true;
    wait_online(&mut rig);
    accepted(&mut rig, 0, CommandKind::Position, [2.0, 0.0, 0.0]);
    move_and_check(&mut rig, &board, 0, 2.0, MAX_VELOCITY_MM);
    accepted(&mut rig, 1, CommandKind::Velocity, [4.0, 0.0, 0.0]);
    rig.run(100);
    accepted(&mut rig, 1, CommandKind::Stop, [0.0; 3]);
    rig.run(200);
    let log = rig.wire_log(0);
    assert!(log.len() > 100);
    let mut ids = Vec::new();
    let mut polls = 0;
    for (_, mosi) in log {
        if mosi.iter().all(|b| *b == FILLER) {
            // Two streamed channels: 4 + 2 (timing) + 2 × 9 = 24 bytes, plus the slack.
            assert_eq!(mosi.len(), 24 + POLL_SLACK);
            polls += 1;
            continue;
        }
        // A request transaction: whole packets back to back, nothing else.
        let mut rest = &mosi[..];
        while !rest.is_empty() {
            let len = usize::from(rest[1]);
            let request = Request::parse(&rest[..len]).expect("a valid request");
            let mut again = [0u8; 256];
            let n = request.encode(&mut again).expect("encodes");
            assert_eq!(&again[..n], &rest[..len], "the protocol crate's encoding");
            ids.push(request.id().as_u8());
            rest = &rest[len..];
        }
    }
    assert!(polls > 100);
    // Start-up: probe 1, 7, 9, 5; configure 12, 6, 8, 24, 26, 28, 30, 32, 14, 4; the
    // engine's start-up stop of both channels at rest (straight to the hold: 16, 20 each);
    // then the goals: position (16, 20), velocity (16, 36), and the stop: setpoint reset
    // (16 Off, 16 Velocity PID, 28 ← 0, 36 measured), ramp (36), hold (28 restored, 16, 20).
    assert_eq!(
        &ids[..14],
        &[1, 7, 9, 5, 12, 6, 8, 24, 26, 28, 30, 32, 14, 4]
    );
    assert_eq!(&ids[14..18], &[16, 20, 16, 20]);
    assert_eq!(
        &ids[18..],
        &[16, 20, 16, 36, 16, 16, 28, 36, 36, 28, 16, 20]
    );
    let sim = board.lock().unwrap();
    assert_eq!(sim.stats().bad_packets, 0);
    assert_eq!(sim.stats().rejected, 0);
    // Every MISO byte decoded too: nothing the driver could not parse.
    let driver = rig.engine.driver(0).unwrap();
    assert_eq!(driver.status().bad_replies, 0);
    let mut decoder = StreamDecoder::new();
    decoder.push(&[FILLER; 8]);
    assert!(decoder.next_packet().is_none());
}

#[test]
fn a_garbage_burst_is_survived() {
    let (mut rig, board, faults) = rig();
    wait_online(&mut rig);
    accepted(&mut rig, 0, CommandKind::Position, [2.0, 0.0, 0.0]);
    move_and_check(&mut rig, &board, 0, 2.0, MAX_VELOCITY_MM);
    // A short burst costs a packet or two and nothing else.
    faults.inject_noise(60);
    for _ in 0..50 {
        rig.tick();
        assert!((rig.axis(0).position - 2.0).abs() <= TOLERANCE_MM);
    }
    assert!(all_fresh(&rig.frame, 2));
    // A long one (≈ 60 ms of MISO) makes the axes stale, keeping their state; shorter
    // than `silence_ms` (500 ms) without a valid packet, it is no verdict: the axes are
    // not faulted, their goals stay.
    faults.inject_noise(3_000);
    assert!(rig.run_until(Duration::from_millis(200), |frame| {
        frame.axes[0].flags & AxisFlags::STALE.0 != 0
    }));
    assert!(
        (rig.axis(0).position - 2.0).abs() <= TOLERANCE_MM,
        "last state kept"
    );
    assert_eq!(rig.axis(0).fault, 0);
    assert!(rig.run_until(Duration::from_secs(1), |frame| all_fresh(frame, 2)));
    assert_eq!(rig.axis(0).mode, AxisMode::Position as u8, "the goal stays");
    let status = rig.engine.driver(0).unwrap().status();
    assert!(status.online);
    assert_eq!(status.resets, 0, "garbage is not a reset");
    assert_eq!(status.verdicts, 0, "{:?}", status.verdict);
    accepted(&mut rig, 0, CommandKind::Position, [-1.0, 0.0, 0.0]);
    move_and_check(&mut rig, &board, 0, -1.0, MAX_VELOCITY_MM);
}

#[test]
fn unplug_and_replug_fault_the_axes_then_they_need_a_new_command() {
    let (mut rig, board, faults) = rig();
    wait_online(&mut rig);
    accepted(&mut rig, 1, CommandKind::Velocity, [5.0, 0.0, 0.0]);
    rig.run(50);
    faults.unplug();
    rig.run(300);
    assert!(rig.link_is_down(0));
    for axis in 0..2 {
        assert!(flag(&rig, axis, AxisFlags::STALE));
        assert_eq!(rig.axis(axis).fault, FaultCode::LinkDown as u16);
    }
    assert_eq!(
        rejected(&mut rig, 0, CommandKind::Position, [0.0; 3]),
        Reason::LinkDown
    );
    faults.replug();
    assert!(rig.run_until(Duration::from_secs(1), |frame| all_fresh(frame, 2)));
    // The jog that was running when the link died is stopped once the board is back.
    rig.run(300);
    assert!(board.lock().unwrap().true_velocity(1).unwrap().abs() < 5.0);
    assert_ne!(rig.axis(1).mode, AxisMode::Velocity as u8);
    accepted(&mut rig, 0, CommandKind::Position, [1.0, 0.0, 0.0]);
    move_and_check(&mut rig, &board, 0, 1.0, MAX_VELOCITY_MM);
}

#[test]
fn a_reset_board_is_reported_and_configured_again() {
    let (mut rig, board, _) = rig();
    wait_online(&mut rig);
    accepted(&mut rig, 0, CommandKind::Position, [1.0, 0.0, 0.0]);
    move_and_check(&mut rig, &board, 0, 1.0, MAX_VELOCITY_MM);
    board.lock().unwrap().reset();
    assert!(rig.run_until(Duration::from_millis(100), |frame| {
        frame.axes[0].fault == FaultCode::BoardReset as u16
    }));
    assert!(rig.run_until(Duration::from_millis(200), |frame| all_fresh(frame, 2)));
    assert_eq!(rig.engine.driver(0).unwrap().status().resets, 1);
    let sim = board.lock().unwrap();
    assert_eq!(sim.stream_period(), 24, "configured again");
    assert_eq!(sim.data_masks()[0], STREAM_MASK);
    drop(sim);
    // The counter restarted at 0 with the shaft where it was.
    assert!(rig.axis(0).position.abs() <= TOLERANCE_MM);
    accepted(&mut rig, 0, CommandKind::Position, [1.0, 0.0, 0.0]);
    move_and_check(&mut rig, &board, 0, 1.0, MAX_VELOCITY_MM);
}

#[test]
fn a_board_that_does_not_answer_is_faulted() {
    let (mut rig, _board, faults) = rig();
    // Nobody drives MISO: every byte reads 0xFF.
    faults.set_drop_probability(Direction::ToHost, 1.0);
    assert!(rig.run_until(Duration::from_secs(1), |frame| {
        frame.axes[0].fault == FaultCode::BoardNotResponding as u16
    }));
    assert!(flag(&rig, 0, AxisFlags::STALE));
    let status = rig.engine.driver(0).unwrap().status();
    assert!(!status.online);
    assert!(status.timeouts > 0);
    assert_eq!(
        rejected(&mut rig, 0, CommandKind::Position, [1.0, 0.0, 0.0]),
        Reason::DeviceOffline,
        "a board that stopped answering is offline"
    );
    // It answers again: the axes come back.
    faults.set_drop_probability(Direction::ToHost, 0.0);
    assert!(rig.run_until(Duration::from_secs(1), |frame| all_fresh(frame, 2)));
}

#[test]
fn a_board_that_dies_while_running_is_faulted() {
    let (mut rig, _board, faults) = rig();
    wait_online(&mut rig);
    faults.set_drop_probability(Direction::ToHost, 1.0);
    let start = rig.now;
    // Stale after its refresh budget, not answering after `silence_ms` without a valid
    // packet (a floating MISO reads 0xFF), with the evidence.
    assert!(rig.run_until(Duration::from_millis(100), |frame| {
        frame.axes[0].flags & AxisFlags::STALE.0 != 0
    }));
    assert_eq!(rig.axis(0).fault, 0);
    assert!(rig.run_until(Duration::from_millis(700), |frame| {
        frame.axes[0].fault == FaultCode::BoardNotResponding as u16
    }));
    let silence = motion_drivers::DEFAULT_SILENCE;
    assert!(rig.now - start >= silence);
    assert!(rig.now - start <= silence + Duration::from_millis(5));
    let status = rig.engine.driver(0).unwrap().status();
    let evidence = status.verdict.expect("verdict").evidence;
    assert!(
        evidence
            .as_str()
            .starts_with("no valid packet on MISO since "),
        "{}",
        evidence.as_str()
    );
}

/// The driver straight on the simulated board (no link, no engine), one transaction at a
/// time; `garbage` corrupts MISO bytes. Returns the allocations made inside the driver.
fn drive_directly(
    driver: &mut Qq2drvDriver,
    board: &mut Qq2drvSim,
    ticks: u32,
    mut goal_at: impl FnMut(u32) -> Option<(usize, Goal)>,
    mut garbage: impl FnMut(u32, &mut [u8]),
) -> u64 {
    use motion_link::sim::SpiDevice;

    let mut mosi = [0u8; 256];
    let mut miso = [0u8; 256];
    let mut in_driver = 0;
    let period = Duration::from_millis(1);
    for tick in 0..ticks {
        let now = period * tick;
        let goal = goal_at(tick);
        let before = allocations();
        driver.handle_timeout(now);
        if let Some((channel, goal)) = goal {
            let _ = driver.set_goal(now, channel, goal);
        }
        in_driver += allocations() - before;
        loop {
            let before = allocations();
            let transmit = driver.poll_transmit(now, &mut mosi);
            in_driver += allocations() - before;
            let Some(transmit) = transmit else { break };
            let len = transmit.len;
            board.transfer(now, &mosi[..len], &mut miso[..len]);
            garbage(tick, &mut miso[..len]);
            let before = allocations();
            driver.handle_rx(now + Duration::from_micros(100), &miso[..len]);
            for channel in 0..4 {
                let _ = driver.channel(channel);
            }
            let _ = driver.status();
            let _ = driver.poll_timeout();
            in_driver += allocations() - before;
        }
    }
    in_driver
}

#[test]
fn the_driver_allocates_nothing_after_construction() {
    let mut driver = Qq2drvDriver::new(driver_config());
    let mut board = sim();
    let in_driver = drive_directly(
        &mut driver,
        &mut board,
        10_000,
        |tick| match tick % 2_000 {
            100 => Some((0, Goal::Position { counts: 400.0 })),
            300 => Some((1, Goal::Home { velocity: 1_000.0 })),
            700 => Some((
                0,
                Goal::Velocity {
                    velocity: -800.0,
                    accel: 10_000.0,
                },
            )),
            1_000 => Some((0, Goal::Stop { decel: 20_000.0 })),
            1_200 => Some((0, Goal::Power { fraction: 0.1 })),
            1_300 => Some((0, Goal::SetPosition { counts: 0.0 })),
            1_400 => Some((
                1,
                Goal::RampPosition {
                    counts: 0.0,
                    velocity: 500.0,
                    accel: 5_000.0,
                },
            )),
            1_500 => Some((0, Goal::Off)),
            _ => None,
        },
        |_, _| {},
    );
    assert!(driver.status().online);
    assert_eq!(driver.status().bad_replies, 0);
    let packets = driver.stream_packets();
    assert!(packets > 8_000, "{packets} stream packets in 10 s");
    assert_eq!(in_driver, 0, "allocations inside the driver");
}

/// A small deterministic generator for the random-traffic test.
struct XorShift(u64);

impl XorShift {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    fn value(&mut self) -> f64 {
        match self.next() % 8 {
            0 => f64::NAN,
            1 => f64::INFINITY,
            2 => -1e12,
            3 => 0.0,
            _ => (self.next() % 20_001) as f64 - 10_000.0,
        }
    }
}

#[test]
fn random_goals_and_noise_never_break_the_driver() {
    let mut driver = Qq2drvDriver::new(driver_config());
    let mut board = sim();
    let mut rng = XorShift(0x5EED_1234);
    let mut goals = XorShift(0xC0FF_EE00);
    drive_directly(
        &mut driver,
        &mut board,
        6_000,
        |tick| {
            tick.is_multiple_of(37).then(|| {
                let channel = (goals.next() % 5) as usize;
                let (a, b, c) = (goals.value(), goals.value(), goals.value());
                let goal = match goals.next() % 8 {
                    0 => Goal::Off,
                    1 => Goal::Stop { decel: a },
                    2 => Goal::Power {
                        fraction: a / 10_000.0,
                    },
                    3 => Goal::Position { counts: a },
                    4 => Goal::Velocity {
                        velocity: a,
                        accel: b,
                    },
                    5 => Goal::RampPosition {
                        counts: a,
                        velocity: b,
                        accel: c,
                    },
                    6 => Goal::Home { velocity: a },
                    _ => Goal::SetPosition { counts: a },
                };
                (channel, goal)
            })
        },
        |tick, miso| {
            // Noise for the first 4 s, clean after.
            if tick < 4_000 && rng.next().is_multiple_of(5) {
                for byte in miso.iter_mut() {
                    if rng.next().is_multiple_of(7) {
                        *byte = rng.next() as u8;
                    }
                }
            }
        },
    );
    // Clean traffic for the last 2 s: the board is back and streaming.
    let status = driver.status();
    assert!(status.online, "{status:?}");
    assert_eq!(status.fault, None);
    assert!(status.bad_replies > 0, "the noise was seen");
    for channel in 0..2 {
        let state = driver.channel(channel);
        assert!(state.position.is_finite() && state.velocity.is_finite());
        assert!(state.refreshed_at.is_some());
    }
    assert_eq!(board.stats().bad_packets, 0, "MOSI stayed clean");
}

// Stops planned from the measured velocity, and homing that a stop interrupts.
#[path = "engine_qq2drv/stops.rs"]
mod stops;
// The IN pins and Status bits as signals.
#[path = "engine_qq2drv/hold.rs"]
mod hold;
#[path = "engine_qq2drv/io.rs"]
mod io;
#[path = "engine_qq2drv/lag.rs"]
mod lag;
#[path = "engine_qq2drv/off.rs"]
mod off;
#[path = "engine_qq2drv/readings.rs"]
mod readings;
#[path = "engine_qq2drv/wire.rs"]
mod wire;
