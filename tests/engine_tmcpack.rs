//! Engine + Trinamic SIXpack/QUADpack driver + simulated packs on a simulated RS-485 pair
//! (half duplex, 19200 baud), stepped with a fake clock.
//!
//! The counting global allocator (for the driver's zero-allocation test) counts on the
//! calling thread only, so the other tests of this binary do not disturb it.

mod support;

#[path = "engine_tmcpack/can.rs"]
mod can;
#[path = "engine_tmcpack/deadman.rs"]
mod deadman;
#[path = "engine_tmcpack/drive.rs"]
mod drive;
#[path = "engine_tmcpack/io.rs"]
mod io;
#[path = "engine_tmcpack/lag.rs"]
mod lag;
#[path = "engine_tmcpack/off.rs"]
mod off;
#[path = "engine_tmcpack/silence.rs"]
mod silence;
#[path = "engine_tmcpack/stops.rs"]
mod stops;
#[path = "engine_tmcpack/wire.rs"]
mod wire;

use core::time::Duration;
use std::sync::{Arc, Mutex};

use board_tmcpack::driver::{TmcpackChannel, TmcpackDriver, TmcpackDriverConfig};
use board_tmcpack::sim::{TmcpackSim, TmcpackSimConfig};
use motion_drivers::{DeviceFault, Driver, LinkKind};
use motion_engine::{AxisConfig, BusConfig, DeviceConfig, EngineConfig};
use motion_ipc::{AxisFlags, AxisMode, CommandKind, FaultCode, Reason};
use motion_link::sim::{Duplex, SimFaults, SimLink, StreamBus};
use support::counting_alloc::{CountingAllocator, allocations};
use support::rig::{Rig, Shared, accepted, all_fresh, flag, fresh};
use tmcpack::convert::byte_time;
use tmcpack::{Action, Request, RequestFrame, Variant};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

const BAUD: u32 = 19_200;
/// Microsteps per mm.
const COUNTS: f64 = 100.0;
const MAX_VELOCITY_MM: f64 = 50.0;
const MAX_ACCEL_MM: f64 = 250.0;

type Pack = Arc<Mutex<TmcpackSim>>;

fn axis(name: &str, device: usize, channel: usize) -> AxisConfig {
    AxisConfig {
        name: name.into(),
        unit: "mm".into(),
        device,
        channel,
        counts_per_unit: COUNTS,
        min: -100.0,
        max: 100.0,
        max_velocity: MAX_VELOCITY_MM,
        max_accel: MAX_ACCEL_MM,
        position_tolerance: 0.01,
        ..AxisConfig::default()
    }
}

fn driver(address: u8, variant: Variant, motors: &[usize], bus_motors: u8) -> TmcpackDriver {
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
        variant,
        baud: BAUD,
        bus_motors,
        channels,
        ..TmcpackDriverConfig::default()
    })
}

fn pack(address: u8, variant: Variant) -> TmcpackSim {
    TmcpackSim::new(TmcpackSimConfig {
        address,
        variant,
        ..TmcpackSimConfig::default()
    })
}

fn engine_config(devices: Vec<DeviceConfig>, axes: Vec<AxisConfig>) -> EngineConfig {
    EngineConfig {
        name: "tmcpack".into(),
        tick_hz: 1000,
        command_timeout: Duration::from_millis(250),
        links: vec![BusConfig {
            name: "rs485".into(),
            kind: LinkKind::Stream,
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

/// One SIXpack at address 1 with axes on motors 0 and 1; the driver may be told another
/// address.
fn single(driver_address: u8) -> (Rig, Pack, SimFaults) {
    let (wire, board) = Shared::new(pack(1, Variant::SixPack));
    let link = SimLink::stream_with("rs485", BAUD, Duplex::Half, wire);
    let faults = link.faults();
    let config = engine_config(
        vec![device("pack", driver_address)],
        vec![axis("x", 0, 0), axis("y", 0, 1)],
    );
    let driver = driver(driver_address, Variant::SixPack, &[0, 1], 0);
    let rig = Rig::new(config, vec![Box::new(driver)], vec![Box::new(link)]);
    (rig, board, faults)
}

fn wait_online(rig: &mut Rig, axes: usize) {
    assert!(
        rig.run_until(Duration::from_secs(2), |frame| { all_fresh(frame, axes) }),
        "the packs start within 2 s"
    );
}

fn motor(board: &Pack, motor: u8) -> board_tmcpack::sim::MotorView {
    board.lock().unwrap().motor(motor).expect("motor exists")
}

/// Ticks until axis `index` (motor `m` of `board`) arrives at `target_mm`, checking on the
/// simulated motor every tick that it never runs faster than `max_mm_s`.
fn move_and_check(
    rig: &mut Rig,
    board: &Pack,
    index: usize,
    m: u8,
    target_mm: f64,
    max_mm_s: f64,
    limit: Duration,
) {
    let end = rig.now + limit;
    let mut fastest: f64 = 0.0;
    while rig.now < end {
        rig.tick();
        let hz = motor(board, m).microstep_hz.abs();
        assert!(
            hz <= max_mm_s * COUNTS + 1e-6,
            "{hz} µsteps/s over the {max_mm_s} mm/s limit"
        );
        fastest = fastest.max(hz);
        if flag(rig, index, AxisFlags::ARRIVED) {
            break;
        }
    }
    assert!(
        flag(rig, index, AxisFlags::ARRIVED),
        "arrived within {limit:?}"
    );
    assert!((rig.axis(index).position - target_mm).abs() <= 0.01);
    let view = motor(board, m);
    assert_eq!(f64::from(view.position), (target_mm * COUNTS).round());
    assert_eq!(view.action, Action::Inactive);
    assert!(fastest > 0.0, "it moved");
}

#[test]
fn the_pack_starts_reports_its_firmware_and_gets_configured() {
    let (mut rig, board, _) = single(1);
    wait_online(&mut rig, 2);
    let status = rig.engine.driver(0).expect("device 0").status();
    assert!(status.online);
    assert_eq!(status.firmware(), "SIXpack V1.4.9 s/n 1001");
    let sim = board.lock().unwrap();
    assert_eq!(
        sim.switchover(),
        Duration::from_millis(2),
        "$40 delay 1 unit"
    );
    assert_eq!(sim.baud_rate(), BAUD, "the baud rate is left alone");
    let stats = sim.stats();
    assert_eq!(stats.invalid, 0);
    assert_eq!(
        stats.lost_bytes, 0,
        "nothing sent while the pack drove the pair"
    );
    assert_eq!(stats.replaced_replies, 0, "never two requests in flight");
    assert_eq!(stats.interlaced, 0, "manual 7.1: never interlaced");
}

#[test]
fn a_move_arrives_within_the_axis_limits() {
    let (mut rig, board, _) = single(1);
    wait_online(&mut rig, 2);
    accepted(&mut rig, 0, CommandKind::Position, [20.0, 0.0, 0.0]);
    move_and_check(
        &mut rig,
        &board,
        0,
        0,
        20.0,
        MAX_VELOCITY_MM,
        Duration::from_secs(3),
    );
    // And back along a slower profile of the client's own.
    accepted(&mut rig, 0, CommandKind::RampPosition, [-5.0, 10.0, 100.0]);
    move_and_check(&mut rig, &board, 0, 0, -5.0, 10.0, Duration::from_secs(5));
    assert_eq!(rig.axis(0).mode, AxisMode::RampPosition as u8);
    // The other axis did not move.
    assert_eq!(motor(&board, 1).physical, 0);
}

#[test]
fn velocity_then_stop_decelerates_and_holds() {
    let (mut rig, board, _) = single(1);
    wait_online(&mut rig, 2);
    for _ in 0..3 {
        // Refreshed before the 250 ms deadman.
        accepted(&mut rig, 1, CommandKind::Velocity, [-20.0, 0.0, 0.0]);
        rig.run(199);
    }
    let view = motor(&board, 1);
    assert_eq!(view.action, Action::Rotation);
    assert!(
        (view.microstep_hz + 2000.0).abs() < 2000.0 * 0.01,
        "20 mm/s = 2000 µsteps/s: {}",
        view.microstep_hz
    );
    assert!((rig.axis(1).velocity + 20.0).abs() < 2.0);
    assert!(flag(&rig, 1, AxisFlags::MOVING));
    let at_stop = view.physical;
    accepted(&mut rig, 1, CommandKind::Stop, [0.0; 3]);
    assert!(rig.run_until(Duration::from_secs(1), |frame| {
        frame.axes[1].mode == AxisMode::Hold as u8
    }));
    rig.run(50);
    let view = motor(&board, 1);
    assert_eq!(view.microstep_hz, 0.0);
    assert_eq!(view.action, Action::Inactive, "the rotation was ended");
    // 2000 µsteps/s braked at 25 000 µsteps/s²: 80 µsteps, plus wire latency.
    let travelled = (view.physical - at_stop).abs();
    assert!(travelled <= 200, "stopped within {travelled} µsteps");
    assert!((rig.axis(1).position * COUNTS - f64::from(view.position)).abs() < 1e-9);
}

#[test]
fn the_deadman_stops_a_jog() {
    let (mut rig, board, _) = single(1);
    wait_online(&mut rig, 2);
    accepted(&mut rig, 0, CommandKind::Velocity, [5.0, 0.0, 0.0]);
    rig.run(800);
    assert!(flag(&rig, 0, AxisFlags::DEADMAN_EXPIRED));
    assert_eq!(motor(&board, 0).microstep_hz, 0.0);
}

#[test]
fn home_finds_the_reference_switch_and_zeroes_there() {
    let (mut rig, board, _) = single(1);
    wait_online(&mut rig, 2);
    accepted(&mut rig, 0, CommandKind::Home, [10.0, 0.0, 0.0]);
    assert!(
        rig.run_until(Duration::from_secs(10), |frame| {
            frame.axes[0].mode == AxisMode::Hold as u8
                && frame.axes[0].flags & AxisFlags::HOMED.0 != 0
        }),
        "homed within 10 s"
    );
    let view = motor(&board, 0);
    assert_eq!(view.action, Action::Inactive);
    assert_eq!(view.position, 0, "stopped at the new zero point");
    // The default simulated switch starts at physical microstep 3200.
    assert!((3200..3240).contains(&view.physical), "{}", view.physical);
    rig.run(200);
    assert_eq!(rig.axis(0).position, 0.0);
    assert!(flag(&rig, 0, AxisFlags::HOMED));
}

#[test]
fn set_position_redefines_here_without_moving() {
    let (mut rig, board, _) = single(1);
    wait_online(&mut rig, 2);
    accepted(&mut rig, 0, CommandKind::Position, [1.0, 0.0, 0.0]);
    move_and_check(
        &mut rig,
        &board,
        0,
        0,
        1.0,
        MAX_VELOCITY_MM,
        Duration::from_secs(2),
    );
    accepted(&mut rig, 0, CommandKind::SetPosition, [12.5, 0.0, 0.0]);
    assert!(rig.run_until(Duration::from_millis(500), |frame| {
        frame.axes[0].position == 12.5
    }));
    let view = motor(&board, 0);
    assert_eq!(view.physical, 100, "the rotor did not move");
    assert_eq!(view.position, 1250);
    assert!(flag(&rig, 0, AxisFlags::HOMED));
    accepted(&mut rig, 0, CommandKind::Position, [12.0, 0.0, 0.0]);
    move_and_check(
        &mut rig,
        &board,
        0,
        0,
        12.0,
        MAX_VELOCITY_MM,
        Duration::from_secs(2),
    );
    assert_eq!(motor(&board, 0).physical, 50);
}

#[test]
fn goals_a_stepper_pack_cannot_do_are_refused() {
    let (mut rig, _, _) = single(1);
    wait_online(&mut rig, 2);
    let power = rig.command(0, CommandKind::Power, [0.5, 0.0, 0.0]);
    assert_eq!(power.result(), Err(Reason::Unsupported));
}

#[test]
fn bytes_on_the_wire_decode_with_the_protocol_crate() {
    let (mut rig, board, _) = single(1);
    rig.log_wire = true;
    wait_online(&mut rig, 2);
    accepted(&mut rig, 0, CommandKind::Position, [3.0, 0.0, 0.0]);
    move_and_check(
        &mut rig,
        &board,
        0,
        0,
        3.0,
        MAX_VELOCITY_MM,
        Duration::from_secs(2),
    );
    let log = rig.wire_log(0);
    let mut starts = Vec::new();
    for (_, bytes) in log {
        let frame = RequestFrame::decode(bytes).expect("a valid 9-byte word");
        assert_eq!(frame.address, 1);
        assert_eq!(frame.to_word().expect("encodes")[..], bytes[..]);
        if let Some(reply_to) = frame.request.reply_to() {
            assert_eq!(reply_to, 0xFE);
        }
        if let Request::StartRamp { motor, target } = frame.request {
            starts.push((motor, target));
        }
    }
    // The engine's start-up stop of both motors (a ramp to where each stands), then the move.
    assert_eq!(starts, [(0, 0), (1, 0), (0, 300)]);
    assert_eq!(board.lock().unwrap().stats().invalid, 0);
}

#[test]
fn a_garbage_burst_is_survived_without_losing_the_position() {
    let (mut rig, board, faults) = single(1);
    wait_online(&mut rig, 2);
    accepted(&mut rig, 0, CommandKind::Position, [2.0, 0.0, 0.0]);
    move_and_check(
        &mut rig,
        &board,
        0,
        0,
        2.0,
        MAX_VELOCITY_MM,
        Duration::from_secs(2),
    );
    faults.inject_noise(100);
    for _ in 0..300 {
        rig.tick();
        assert_eq!(rig.axis(0).position, 2.0, "garbage never reaches the axis");
    }
    rig.run(300);
    assert!(fresh(&rig, 0));
    let status = rig.engine.driver(0).unwrap().status();
    assert!(status.bad_replies > 0);
    assert_eq!(status.resets, 0);
    accepted(&mut rig, 0, CommandKind::Position, [0.5, 0.0, 0.0]);
    move_and_check(
        &mut rig,
        &board,
        0,
        0,
        0.5,
        MAX_VELOCITY_MM,
        Duration::from_secs(2),
    );
}

#[test]
fn unplug_and_replug_fault_the_axes_then_they_need_a_new_command() {
    let (mut rig, board, faults) = single(1);
    wait_online(&mut rig, 2);
    accepted(&mut rig, 0, CommandKind::Position, [1.0, 0.0, 0.0]);
    rig.run(20);
    faults.unplug();
    rig.run(600);
    assert!(rig.link_is_down(0));
    assert!(flag(&rig, 0, AxisFlags::STALE));
    assert!(flag(&rig, 0, AxisFlags::FAULT));
    assert_eq!(rig.axis(0).fault, FaultCode::LinkDown as u16);
    let reason = rig.command(0, CommandKind::Position, [0.0, 0.0, 0.0]);
    assert_eq!(reason.result(), Err(Reason::LinkDown));
    faults.replug();
    wait_online(&mut rig, 2);
    assert_ne!(
        rig.axis(0).mode,
        AxisMode::Position as u8,
        "the goal was voided"
    );
    accepted(&mut rig, 0, CommandKind::Position, [-1.0, 0.0, 0.0]);
    move_and_check(
        &mut rig,
        &board,
        0,
        0,
        -1.0,
        MAX_VELOCITY_MM,
        Duration::from_secs(2),
    );
}

#[test]
fn a_pack_that_does_not_answer_is_a_fault() {
    // The driver talks to address 3; the pack on the pair is 1.
    let (mut rig, board, _) = single(3);
    rig.run(1000);
    assert!(flag(&rig, 0, AxisFlags::FAULT));
    assert!(flag(&rig, 0, AxisFlags::STALE));
    assert_eq!(rig.axis(0).fault, FaultCode::BoardNotResponding as u16);
    let status = rig.engine.driver(0).unwrap().status();
    assert!(!status.online);
    assert_eq!(status.fault, Some(DeviceFault::NotResponding));
    assert!(status.timeouts >= 3);
    assert_eq!(board.lock().unwrap().stats().executed, 0);
}

#[test]
fn a_power_cycled_pack_is_detected_and_configured_again() {
    let (mut rig, board, _) = single(1);
    wait_online(&mut rig, 2);
    board.lock().unwrap().power_cycle(rig.now);
    assert!(rig.run_until(Duration::from_secs(3), |frame| {
        frame.axes[0].flags & AxisFlags::FAULT.0 != 0
    }));
    wait_online(&mut rig, 2);
    let status = rig.engine.driver(0).unwrap().status();
    assert!(status.online);
    assert_eq!(status.resets, 1);
    assert_eq!(board.lock().unwrap().switchover(), Duration::from_millis(2));
    accepted(&mut rig, 0, CommandKind::Position, [1.0, 0.0, 0.0]);
    move_and_check(
        &mut rig,
        &board,
        0,
        0,
        1.0,
        MAX_VELOCITY_MM,
        Duration::from_secs(2),
    );
}

/// Manual 7.1 "Interlacing of Requests": two packs on one 19200-baud pair, commands and
/// polls interleaved, never a second request before the first is answered and the pack has
/// released the line.
#[test]
fn two_packs_on_one_bus_never_have_two_requests_in_flight() {
    let (six, six_board) = Shared::new(pack(1, Variant::SixPack));
    let (quad, quad_board) = Shared::new(pack(2, Variant::QuadPack));
    let bus = StreamBus::new().with(six).with(quad);
    let (wire, bus) = Shared::new(bus);
    let link = SimLink::stream_with("rs485", BAUD, Duplex::Half, wire);
    let config = engine_config(
        vec![device("six", 1), device("quad", 2)],
        vec![axis("x", 0, 0), axis("y", 0, 1), axis("g", 1, 0)],
    );
    let drivers: Vec<Box<dyn Driver>> = vec![
        Box::new(driver(1, Variant::SixPack, &[0, 1], 3)),
        Box::new(driver(2, Variant::QuadPack, &[0], 3)),
    ];
    let mut rig = Rig::new(config, drivers, vec![Box::new(link)]);
    rig.log_wire = true;
    wait_online(&mut rig, 3);
    accepted(&mut rig, 0, CommandKind::Position, [10.0, 0.0, 0.0]);
    accepted(&mut rig, 2, CommandKind::Position, [-7.5, 0.0, 0.0]);
    accepted(&mut rig, 1, CommandKind::Velocity, [15.0, 0.0, 0.0]);
    rig.run(150);
    accepted(&mut rig, 1, CommandKind::Stop, [0.0; 3]);
    assert!(rig.run_until(Duration::from_secs(4), |frame| {
        frame.axes[0].flags & AxisFlags::ARRIVED.0 != 0
            && frame.axes[2].flags & AxisFlags::ARRIVED.0 != 0
            && frame.axes[1].mode == AxisMode::Hold as u8
    }));
    rig.run(200);
    assert_eq!(motor(&six_board, 0).position, 1000);
    assert_eq!(motor(&quad_board, 0).position, -750);
    assert_eq!(motor(&six_board, 1).action, Action::Inactive);

    // On the wire: a query's next word comes only after request, switch-over, answer and
    // the pack's hold; any word only after the previous one is on the wire.
    let word = byte_time(BAUD) * 9;
    let switchover = Duration::from_millis(2);
    let log = rig.wire_log(0);
    let mut addresses = [0usize; 3];
    let mut polls = [0usize; 3];
    let mut commands = 0;
    for pair in log.windows(2) {
        let (t0, first) = (&pair[0].0, &pair[0].1);
        let t1 = pair[1].0;
        let frame = RequestFrame::decode(first).expect("a valid word");
        let gap = t1 - *t0;
        assert!(gap >= word, "{gap:?} after {frame:?}");
        if frame.request.reply_to().is_some() {
            assert!(
                gap >= 2 * word + 2 * switchover,
                "{gap:?} after the query {frame:?}"
            );
        }
        addresses[usize::from(frame.address)] += 1;
        match frame.request {
            Request::QueryPosition { .. } => polls[usize::from(frame.address)] += 1,
            Request::SetTarget { .. } | Request::StartRamp { .. } | Request::Rotate { .. } => {
                commands += 1;
            }
            _ => {}
        }
    }
    assert!(addresses[1] > 20 && addresses[2] > 20, "{addresses:?}");
    assert!(polls[1] > 10 && polls[2] > 10, "{polls:?}");
    assert!(commands >= 6);
    for board in [&six_board, &quad_board] {
        let stats = board.lock().unwrap().stats();
        assert_eq!(
            stats.lost_bytes, 0,
            "nothing sent while a pack drove the pair"
        );
        assert_eq!(stats.replaced_replies, 0, "never two requests in flight");
        assert_eq!(stats.interlaced, 0, "manual 7.1: never interlaced");
        assert_eq!(stats.invalid, 0);
        assert!(stats.foreign > 0, "each pack heard the other's traffic");
    }
    assert_eq!(bus.lock().unwrap().collisions(), 0);
}

#[test]
fn the_driver_allocates_nothing_after_construction() {
    use motion_drivers::Goal;
    use motion_link::Link;

    let variant = Variant::SixPack;
    let inputs = io::io_config(variant, &["ref0", "analog6", "analog7"], &["ttlout1"]);
    let mut driver = io::driver_with_io(1, variant, &[0, 1], 0, inputs);
    let (ref0, ttlout1) = (io::pin(variant, "ref0"), io::pin(variant, "ttlout1"));
    let mut link = SimLink::stream_with(
        "rs485",
        BAUD,
        Duplex::Half,
        Box::new(pack(1, Variant::SixPack)),
    );
    let faults = link.faults();
    let mut buf = [0u8; 256];
    let mut rx = [0u8; 256];
    let mut in_driver = 0;
    let mut online = false;
    // Another pack's late answer, as a link bus hands it over.
    let other = [motion_drivers::LateAnswer::new(
        &[0xFE, 0x20, 1],
        Duration::from_secs(3600),
    )];
    let period = Duration::from_millis(1);
    for tick in 0..10_000u32 {
        let now = period * tick;
        // Answers held 150 ms (late answers, probes), and once 900 ms (a not-answering
        // verdict with its evidence, then the start-up again).
        match tick {
            2_500 | 7_000 => faults.set_reply_delay(Duration::from_millis(150)),
            5_000 => faults.set_reply_delay(Duration::from_millis(900)),
            2_650 | 5_900 | 7_150 => faults.set_reply_delay(Duration::ZERO),
            _ => {}
        }
        let goal = match tick % 2_500 {
            400 => Some(Goal::Position { counts: 400.0 }),
            900 => Some(Goal::Velocity {
                velocity: -800.0,
                accel: 10_000.0,
            }),
            1_200 => Some(Goal::Stop { decel: 20_000.0 }),
            1_600 => Some(Goal::Home { velocity: 1000.0 }),
            2_000 => Some(Goal::SetPosition { counts: 0.0 }),
            2_200 => Some(Goal::Off),
            _ => None,
        };
        let len = link.read(now, &mut rx).expect("sim link");
        let before = allocations();
        driver.handle_late_answers(&other);
        let _ = driver.late_answers();
        driver.handle_rx(now, &rx[..len]);
        driver.handle_timeout(now);
        if let Some(goal) = goal {
            let _ = driver.set_goal(now, 0, goal);
        }
        if tick % 700 == 0 {
            let _ = driver.set_output(now, ttlout1, tick % 1400 == 0);
        }
        let transmit = driver.poll_transmit(now, &mut buf);
        let _ = driver.channel(0);
        let _ = driver.read_pin(ref0);
        online |= driver.status().online;
        in_driver += allocations() - before;
        if let Some(transmit) = transmit {
            link.write(now, &buf[..transmit.len]).expect("sim link");
        }
    }
    assert!(online);
    assert_eq!(in_driver, 0, "allocations inside the driver");
    let status = driver.status();
    assert!(driver.late_replies() > 0, "late answers were handled");
    assert!(status.verdicts >= 1, "a verdict was formatted");
}

/// The sim.toml bus: a SIXpack and a QUADpack, ten motors polled on one 19200-baud pair.
/// With moves going on, no axis ever goes stale: the refresh budget fits a real bus.
#[test]
fn ten_motors_on_one_bus_stay_fresh_within_the_refresh_budget() {
    let (six, six_board) = Shared::new(pack(1, Variant::SixPack));
    let (quad, quad_board) = Shared::new(pack(2, Variant::QuadPack));
    let (wire, bus) = Shared::new(StreamBus::new().with(six).with(quad));
    let link = SimLink::stream_with("rs485", BAUD, Duplex::Half, wire);
    let mut axes: Vec<AxisConfig> = (0..6).map(|m| axis(&format!("six{m}"), 0, m)).collect();
    axes.extend((0..4).map(|m| axis(&format!("quad{m}"), 1, m)));
    let config = engine_config(vec![device("six", 1), device("quad", 2)], axes);
    let drivers: Vec<Box<dyn Driver>> = vec![
        Box::new(driver(1, Variant::SixPack, &[0, 1, 2, 3, 4, 5], 10)),
        Box::new(driver(2, Variant::QuadPack, &[0, 1, 2, 3], 10)),
    ];
    let mut rig = Rig::new(config, drivers, vec![Box::new(link)]);
    wait_online(&mut rig, 10);
    let budget = rig.engine.driver(0).unwrap().refresh_budget();
    assert!(budget < Duration::from_millis(500), "{budget:?}");
    for index in 0..10u32 {
        let target = f64::from(index) - 4.5;
        accepted(&mut rig, index, CommandKind::Position, [target, 0.0, 0.0]);
    }
    let end = rig.now + Duration::from_secs(3);
    while rig.now < end {
        rig.tick();
        for index in 0..10 {
            assert!(
                fresh(&rig, index),
                "axis {index} stale at {:?}: {:?}",
                rig.now,
                rig.axis(index)
            );
        }
    }
    for index in 0..10usize {
        assert!(flag(&rig, index, AxisFlags::ARRIVED), "axis {index}");
    }
    assert_eq!(motor(&six_board, 5).position, 50);
    assert_eq!(motor(&quad_board, 3).position, 450);
    assert_eq!(bus.lock().unwrap().collisions(), 0);
}

#[test]
fn a_lost_answer_or_a_torn_request_costs_one_timeout_and_no_state() {
    use motion_link::sim::Direction;

    let (mut rig, board, faults) = single(1);
    wait_online(&mut rig, 2);
    accepted(&mut rig, 0, CommandKind::Position, [1.5, 0.0, 0.0]);
    move_and_check(
        &mut rig,
        &board,
        0,
        0,
        1.5,
        MAX_VELOCITY_MM,
        Duration::from_secs(2),
    );
    // Half an answer lost, then half a request: the pack's packet timeout and the driver's
    // silence after a timeout resynchronise both sides.
    faults.drop_next(Direction::ToHost, 4);
    rig.run(100);
    faults.drop_next(Direction::ToDevice, 5);
    rig.run(300);
    let status = rig.engine.driver(0).unwrap().status();
    assert!(status.online);
    assert_eq!(status.timeouts, 2);
    assert_eq!(status.resets, 0);
    assert!(fresh(&rig, 0) && fresh(&rig, 1));
    assert_eq!(rig.axis(0).position, 1.5);
    assert_eq!(board.lock().unwrap().stats().invalid, 0);
    accepted(&mut rig, 0, CommandKind::Position, [0.0, 0.0, 0.0]);
    move_and_check(
        &mut rig,
        &board,
        0,
        0,
        0.0,
        MAX_VELOCITY_MM,
        Duration::from_secs(2),
    );
}
