//! The engine driving a simulated US Digital QSB through a real `SimLink` at 230400 baud,
//! stepped with a fake clock: the QSB driver end to end.

mod support;

#[path = "engine_qsb/hold.rs"]
mod hold;
#[path = "engine_qsb/io.rs"]
mod io;
#[path = "engine_qsb/lag.rs"]
mod lag;
#[path = "engine_qsb/machine.rs"]
mod machine;
#[path = "engine_qsb/off.rs"]
mod off;
#[path = "engine_qsb/wire.rs"]
mod wire;

use core::time::Duration;
use std::sync::{Arc, Mutex};

use board_qsb::driver::{QsbDriver, QsbDriverConfig};
use board_qsb::sim::{EncoderMotion, QsbSim, QsbSimConfig, Variant};
use motion_engine::{AxisConfig, BusConfig, DeviceConfig, EngineConfig};
use motion_ipc::{AxisFlags, AxisMode, AxisState, CommandKind, FaultCode, Reason};
use motion_link::sim::{Direction, SimFaults, SimLink};
use qsb::{CommandType, Register, Request};
use support::rig::{Rig, Shared};

/// Axis units: 100 counts per mm; the -M has 10 encoder counts per step (2.5 quadrature
/// cycles per step in x4), so 10 steps per mm.
const COUNTS_PER_UNIT: f64 = 100.0;
const MAX_VELOCITY: f64 = 100.0; // mm/s = 1000 steps/s
const MAX_ACCEL: f64 = 1000.0; // mm/s² = 10000 steps/s²
/// One motor step: the resolution of a -M move.
const TOLERANCE: f64 = 0.1;

struct Qsb {
    rig: Rig,
    sim: Arc<Mutex<QsbSim>>,
    faults: SimFaults,
    /// Motor steps per axis unit.
    steps_per_unit: f64,
}

fn rig(variant: Variant, motion: EncoderMotion, command_timeout: Duration) -> Qsb {
    let sim = QsbSimConfig {
        variant,
        motion,
        ..QsbSimConfig::default()
    };
    let driver = QsbDriverConfig {
        variant,
        counts_per_step: 10.0,
        max_velocity: MAX_VELOCITY * COUNTS_PER_UNIT,
        max_accel: MAX_ACCEL * COUNTS_PER_UNIT,
        ..QsbDriverConfig::default()
    };
    rig_with(sim, driver, command_timeout)
}

/// The engine with one QSB axis (the constants above) on a simulated board `sim` driven by
/// a driver of `driver`.
fn rig_with(sim: QsbSimConfig, driver: QsbDriverConfig, command_timeout: Duration) -> Qsb {
    let (device, sim) = Shared::new(QsbSim::new(sim));
    // Behind USB: the host gets the board's bytes at the end of each 1 ms frame.
    let link = SimLink::stream("usb0", 230_400, device).with_host_frames(board_qsb::USB_FRAME);
    let faults = link.faults();
    let config = EngineConfig {
        name: "qsb".into(),
        tick_hz: 1000,
        command_timeout,
        links: vec![BusConfig {
            name: "usb0".into(),
            kind: motion_drivers::LinkKind::Stream,
        }],
        devices: vec![DeviceConfig {
            name: "feeder_qsb".into(),
            link: 0,
            address: 0,
        }],
        axes: vec![AxisConfig {
            name: "feeder".into(),
            unit: "mm".into(),
            device: 0,
            channel: 0,
            counts_per_unit: COUNTS_PER_UNIT,
            min: -1000.0,
            max: 1000.0,
            max_velocity: MAX_VELOCITY,
            max_accel: MAX_ACCEL,
            position_tolerance: TOLERANCE,
            ..AxisConfig::default()
        }],
        ..EngineConfig::default()
    };
    let steps_per_unit = COUNTS_PER_UNIT / driver.counts_per_step.abs();
    let driver = QsbDriver::new(driver);
    let mut rig = Rig::new(config, vec![Box::new(driver)], vec![Box::new(link)]);
    rig.log_wire = true;
    Qsb {
        rig,
        sim,
        faults,
        steps_per_unit,
    }
}

fn still() -> EncoderMotion {
    EncoderMotion {
        velocity: 0.0,
        amplitude: 0.0,
        frequency_hz: 0.0,
    }
}

fn flags(axis: &AxisState) -> AxisFlags {
    axis.flags()
}

/// Fresh, not faulted, and on an online board (its start-up stop acknowledged).
fn healthy(axis: &AxisState) -> bool {
    !flags(axis).contains(AxisFlags::STALE)
        && !flags(axis).contains(AxisFlags::FAULT)
        && axis.device_state() == Ok(motion_ipc::DeviceState::Online)
}

impl Qsb {
    fn m() -> Self {
        let mut qsb = rig(Variant::M, still(), Duration::from_millis(250));
        qsb.start();
        qsb
    }

    fn start(&mut self) {
        assert!(
            self.rig
                .run_until(Duration::from_millis(200), |frame| healthy(&frame.axes[0])),
            "the QSB starts and streams"
        );
    }

    fn axis(&self) -> AxisState {
        self.rig.axis(0)
    }

    fn command(&mut self, kind: CommandKind, values: [f64; 3]) -> Reason {
        let reply = self.rig.command(0, kind, values);
        Reason::ALL
            .into_iter()
            .find(|reason| *reason as u32 == reply.reason)
            .expect("a known reason")
    }

    /// Runs until `done`, checking every tick that the stepper keeps within the axis
    /// limits (the board's 16-step increments round them down).
    fn run_within_limits(&mut self, limit: Duration, mut done: impl FnMut(&AxisState) -> bool) {
        let end = self.rig.now + limit;
        while self.rig.now < end {
            self.rig.tick();
            let (velocity, acceleration) = {
                let sim = self.sim.lock().expect("sim");
                (sim.motor_velocity(), sim.motor_acceleration())
            };
            // Rounding of the simulator's exact phase arithmetic aside.
            let margin = 1.0 + 1e-6;
            assert!(
                velocity.abs() <= MAX_VELOCITY * self.steps_per_unit * margin,
                "v {velocity} steps/s"
            );
            assert!(
                acceleration.abs() <= MAX_ACCEL * self.steps_per_unit * margin,
                "a {acceleration} steps/s²"
            );
            if done(&self.rig.axis(0)) {
                return;
            }
        }
        panic!("not done within {limit:?}: {:?}", self.axis());
    }

    fn sim_counter(&self) -> i32 {
        self.sim.lock().expect("sim").counter() as i32
    }
}

#[test]
fn start_up_reports_the_board_and_streams_the_counter() {
    let qsb = Qsb::m();
    let driver = qsb.rig.engine.driver(0).expect("driver");
    let status = driver.status();
    assert!(status.online);
    assert_eq!(status.firmware(), "QSB-M SN 00001 fw 13");
    assert_eq!(status.fault, None);
    let sim = qsb.sim.lock().expect("sim");
    assert!(sim.md_status().enabled, "COMMAND 2 enabled the drive");
    assert_eq!(sim.stats().errors + sim.stats().unsupported, 0);
}

#[test]
fn move_to_a_position_and_arrive_within_the_limits() {
    let mut qsb = Qsb::m();
    assert_eq!(
        qsb.command(CommandKind::Position, [20.0, 0.0, 0.0]),
        Reason::Accepted
    );
    qsb.run_within_limits(Duration::from_secs(2), |axis| {
        flags(axis).contains(AxisFlags::ARRIVED)
    });
    let axis = qsb.axis();
    assert!((axis.position - 20.0).abs() <= TOLERANCE, "{axis:?}");
    assert_eq!(axis.raw_counts, i64::from(qsb.sim_counter()));
    assert!(!flags(&axis).contains(AxisFlags::MOVING));
    // A ramp back with its own, lower limits: 20 mm/s = 200 steps/s (→ 192).
    let reply = qsb.command(CommandKind::RampPosition, [-5.0, 20.0, 200.0]);
    assert_eq!(reply, Reason::Accepted);
    let mut fastest: f64 = 0.0;
    let sim = Arc::clone(&qsb.sim);
    qsb.run_within_limits(Duration::from_secs(3), |axis| {
        fastest = fastest.max(sim.lock().expect("sim").motor_velocity().abs());
        flags(axis).contains(AxisFlags::ARRIVED)
    });
    assert!(
        fastest <= 192.0 && fastest > 150.0,
        "cruise {fastest} steps/s"
    );
    assert!((qsb.axis().position + 5.0).abs() <= TOLERANCE);
}

#[test]
fn velocity_then_stop() {
    let mut qsb = rig(Variant::M, still(), Duration::ZERO);
    qsb.start();
    assert_eq!(
        qsb.command(CommandKind::Velocity, [-30.0, 0.0, 0.0]),
        Reason::Accepted
    );
    qsb.rig.run(400);
    let axis = qsb.axis();
    // 300 steps/s rounds down to 288: 28.8 mm/s.
    assert!((axis.velocity + 28.8).abs() < 0.5, "{axis:?}");
    assert!(flags(&axis).contains(AxisFlags::MOVING));
    assert_eq!(axis.mode().expect("mode"), AxisMode::Velocity);
    assert_eq!(qsb.command(CommandKind::Stop, [0.0; 3]), Reason::Accepted);
    qsb.run_within_limits(Duration::from_millis(300), |axis| {
        axis.mode() == Ok(AxisMode::Hold)
    });
    let axis = qsb.axis();
    assert_eq!(axis.velocity, 0.0);
    assert_eq!(qsb.sim.lock().expect("sim").motor_velocity(), 0.0);
    assert_eq!(axis.raw_counts, i64::from(qsb.sim_counter()));
}

#[test]
fn home_on_the_index_then_set_position() {
    let mut qsb = Qsb::m();
    assert_eq!(
        qsb.command(CommandKind::Position, [3.0, 0.0, 0.0]),
        Reason::Accepted
    );
    qsb.run_within_limits(Duration::from_secs(1), |axis| {
        flags(axis).contains(AxisFlags::ARRIVED)
    });
    assert!(!flags(&qsb.axis()).contains(AxisFlags::HOMED));
    assert_eq!(qsb.command(CommandKind::Home, [0.0; 3]), Reason::Accepted);
    qsb.run_within_limits(Duration::from_secs(3), |axis| {
        axis.mode() == Ok(AxisMode::Hold)
    });
    let axis = qsb.axis();
    assert!(flags(&axis).contains(AxisFlags::HOMED));
    // Searching down from 3 mm, the index at 0 reset the counter; the motor stopped just
    // past it (25 mm/s at 1000 mm/s² is 0.3 mm).
    assert!(axis.position <= 0.0 && axis.position > -0.5, "{axis:?}");
    assert_eq!(axis.raw_counts, i64::from(qsb.sim_counter()));
    // The counter is referenced to the index: the true encoder position (x4) at 0 is
    // count 0, within the index's quarter cycle (one count) and one count of
    // quantisation.
    let sim = qsb.sim.lock().expect("sim");
    let offset = sim.encoder_position() * 4.0 - f64::from(sim.counter() as i32);
    assert!(offset.abs() <= 2.0, "offset {offset}");
    drop(sim);
    assert_eq!(
        qsb.command(CommandKind::SetPosition, [7.5, 0.0, 0.0]),
        Reason::Accepted
    );
    qsb.rig.run(20);
    assert!((qsb.axis().position - 7.5).abs() < 1e-9);
    assert_eq!(qsb.sim_counter(), 750);
    // Positions go on from there.
    assert_eq!(
        qsb.command(CommandKind::Position, [8.0, 0.0, 0.0]),
        Reason::Accepted
    );
    qsb.run_within_limits(Duration::from_secs(1), |axis| {
        flags(axis).contains(AxisFlags::ARRIVED)
    });
    assert!((qsb.axis().position - 8.0).abs() <= TOLERANCE);
}

#[test]
fn every_byte_on_the_wire_is_a_command_line_of_the_codec() {
    let mut qsb = Qsb::m();
    qsb.command(CommandKind::Position, [1.0, 0.0, 0.0]);
    qsb.rig.run(300);
    qsb.command(CommandKind::Velocity, [10.0, 0.0, 0.0]);
    qsb.rig.run(50);
    qsb.command(CommandKind::Home, [0.0; 3]);
    qsb.rig.run(500);
    qsb.command(CommandKind::SetPosition, [0.0; 3]);
    qsb.rig.run(50);
    let log = qsb.rig.wire_log(0);
    assert!(log.len() > 20);
    let mut streams = Vec::new();
    for (_, bytes) in log {
        let line = bytes.strip_suffix(b"\r\n").expect("CR LF end of command");
        let request = Request::decode(line).expect("a command of the command list");
        request
            .check(qsb::ProductType::M)
            .expect("available on the -M");
        if request.command_type() == CommandType::Stream {
            streams.push(request.register());
        }
    }
    assert!(streams.contains(&Register::ReadEncoder));
    assert!(streams.contains(&Register::MdStatus));
    let sim = qsb.sim.lock().expect("sim");
    assert_eq!(sim.stats().errors + sim.stats().unsupported, 0, "no e or x");
    assert_eq!(sim.stats().interlaced, 0, "one command at a time");
}

#[test]
fn a_garbage_burst_is_survived() {
    let mut qsb = Qsb::m();
    assert_eq!(
        qsb.command(CommandKind::Position, [10.0, 0.0, 0.0]),
        Reason::Accepted
    );
    qsb.rig.run(30);
    qsb.faults.inject_noise(300);
    qsb.rig.run(20);
    qsb.faults.inject_garbage(b"s0E0000r14x!e0\n\r\x00w16");
    qsb.run_within_limits(Duration::from_secs(2), |axis| {
        flags(axis).contains(AxisFlags::ARRIVED)
    });
    let axis = qsb.axis();
    assert!((axis.position - 10.0).abs() <= TOLERANCE, "{axis:?}");
    let status = qsb.rig.engine.driver(0).expect("driver").status();
    assert!(status.online);
    assert!(status.bad_replies > 0, "the garbage was seen");
    assert!(healthy(&axis));
}

#[test]
fn unplug_and_replug_fault_the_axis_then_it_needs_a_new_command() {
    let mut qsb = Qsb::m();
    assert_eq!(
        qsb.command(CommandKind::Velocity, [20.0, 0.0, 0.0]),
        Reason::Accepted
    );
    qsb.rig.run(100);
    qsb.faults.unplug();
    qsb.rig.run(50);
    let axis = qsb.axis();
    assert!(flags(&axis).contains(AxisFlags::STALE));
    assert_eq!(axis.fault().expect("fault"), FaultCode::LinkDown);
    assert_ne!(axis.mode(), Ok(AxisMode::Velocity), "the goal was voided");
    assert_eq!(
        qsb.command(CommandKind::Position, [0.0; 3]),
        Reason::LinkDown
    );
    qsb.faults.replug();
    assert!(
        qsb.rig
            .run_until(Duration::from_millis(500), |frame| healthy(&frame.axes[0])),
        "back after replug: {:?}",
        qsb.axis()
    );
    // The start-up stopped the motor the lost link could not stop.
    qsb.rig.run(300);
    assert_eq!(qsb.sim.lock().expect("sim").motor_velocity(), 0.0);
    let axis = qsb.axis();
    assert!(healthy(&axis));
    assert_ne!(axis.mode(), Ok(AxisMode::Velocity));
    assert_eq!(axis.raw_counts, i64::from(qsb.sim_counter()));
    // A new command works.
    assert_eq!(
        qsb.command(CommandKind::Position, [1.0, 0.0, 0.0]),
        Reason::Accepted
    );
    qsb.run_within_limits(Duration::from_secs(2), |axis| {
        flags(axis).contains(AxisFlags::ARRIVED)
    });
}

#[test]
fn a_board_that_stops_answering_is_not_responding_then_comes_back() {
    let mut qsb = Qsb::m();
    qsb.faults.set_drop_probability(Direction::ToHost, 1.0);
    // Stale after its refresh budget; not answering once its probe went `silence_ms`
    // (500 ms) without a word.
    qsb.rig.run(20);
    assert!(flags(&qsb.axis()).contains(AxisFlags::STALE));
    assert_eq!(qsb.axis().fault, 0, "silence is not a verdict yet");
    qsb.rig.run(600);
    let axis = qsb.axis();
    assert!(flags(&axis).contains(AxisFlags::STALE));
    assert_eq!(axis.fault().expect("fault"), FaultCode::BoardNotResponding);
    let status = qsb.rig.engine.driver(0).expect("driver").status();
    assert!(!status.online);
    assert!(status.timeouts >= 1);
    let verdict = status.verdict.expect("the evidence");
    assert!(
        verdict.evidence.as_str().starts_with("`R0D` written at ")
            && verdict
                .evidence
                .as_str()
                .ends_with("ms of silence (silence_ms 500)"),
        "{}",
        verdict.evidence.as_str()
    );
    assert_eq!(
        qsb.command(CommandKind::Position, [1.0, 0.0, 0.0]),
        Reason::DeviceOffline,
        "a board that stopped answering is offline"
    );
    qsb.faults.set_drop_probability(Direction::ToHost, 0.0);
    // The start-up tried again 100 ms after the verdict, while the answers were still
    // lost: its COMMAND 1 stopped the stream, so that answer is waited for through
    // another silence (it may be held up on the host) before the next try.
    assert!(
        qsb.rig
            .run_until(Duration::from_millis(1200), |frame| healthy(&frame.axes[0])),
        "{:?}",
        qsb.axis()
    );
    let status = qsb.rig.engine.driver(0).expect("driver").status();
    assert_eq!(status.verdicts, 1, "one verdict while it stayed silent");
    assert_eq!(
        qsb.command(CommandKind::Position, [1.0, 0.0, 0.0]),
        Reason::Accepted
    );
    qsb.run_within_limits(Duration::from_secs(2), |axis| {
        flags(axis).contains(AxisFlags::ARRIVED)
    });
}

#[test]
fn a_board_reset_is_reported_and_the_board_set_up_again() {
    let mut qsb = Qsb::m();
    assert_eq!(
        qsb.command(CommandKind::SetPosition, [5.0, 0.0, 0.0]),
        Reason::Accepted
    );
    qsb.rig.run(20);
    assert!(flags(&qsb.axis()).contains(AxisFlags::HOMED));
    let now = qsb.rig.now;
    qsb.sim.lock().expect("sim").reset(now);
    let mut seen = false;
    let recovered = qsb.rig.run_until(Duration::from_millis(500), |frame| {
        seen |= frame.axes[0].fault() == Ok(FaultCode::BoardReset);
        seen && healthy(&frame.axes[0])
    });
    assert!(seen, "the reset was reported");
    assert!(recovered, "{:?}", qsb.axis());
    let status = qsb.rig.engine.driver(0).expect("driver").status();
    assert_eq!(status.resets, 1);
    // The counter restarted at 0 with the board.
    assert_eq!(qsb.axis().raw_counts, i64::from(qsb.sim_counter()));
    assert!(qsb.sim.lock().expect("sim").md_status().enabled);
}

#[test]
fn a_qsb_s_reads_its_encoder_and_sets_position_but_drives_nothing() {
    let motion = EncoderMotion {
        velocity: 500.0, // quadrature cycles/s = 2000 counts/s = 20 mm/s
        amplitude: 0.0,
        frequency_hz: 0.0,
    };
    let mut qsb = rig(Variant::S, motion, Duration::from_millis(250));
    qsb.start();
    let status = qsb.rig.engine.driver(0).expect("driver").status();
    assert_eq!(status.firmware(), "QSB-S SN 00001 fw 13");
    qsb.rig.run(200);
    let axis = qsb.axis();
    // One count of quantisation over the 8-sample (15.6 ms) window is 0.64 mm/s.
    assert!((axis.velocity - 20.0).abs() < 0.7, "{axis:?}");
    assert!(flags(&axis).contains(AxisFlags::MOVING));
    // The sample is at most a stream period, its wire time and a tick old: ≤ 4 ms at
    // 2000 counts/s.
    let lag = i64::from(qsb.sim_counter()) - axis.raw_counts;
    assert!((0..=8).contains(&lag), "{lag} counts behind");
    assert_eq!(
        qsb.command(CommandKind::Position, [1.0, 0.0, 0.0]),
        Reason::Unsupported
    );
    assert_eq!(
        qsb.command(CommandKind::Velocity, [1.0, 0.0, 0.0]),
        Reason::Unsupported
    );
    assert_eq!(
        qsb.command(CommandKind::Home, [0.0; 3]),
        Reason::Unsupported
    );
    assert_eq!(
        qsb.command(CommandKind::Power, [0.1, 0.0, 0.0]),
        Reason::Unsupported
    );
    assert_eq!(qsb.command(CommandKind::Stop, [0.0; 3]), Reason::Accepted);
    assert_eq!(
        qsb.command(CommandKind::SetPosition, [-3.0, 0.0, 0.0]),
        Reason::Accepted
    );
    qsb.rig.run(10);
    let axis = qsb.axis();
    assert!((axis.position + 3.0).abs() < 0.3, "{axis:?}");
    assert!(flags(&axis).contains(AxisFlags::HOMED));
    let sim = qsb.sim.lock().expect("sim");
    assert_eq!(sim.stats().errors + sim.stats().unsupported, 0, "no e or x");
}

#[test]
fn the_deadman_stops_a_jog_on_the_board() {
    let mut qsb = Qsb::m();
    assert_eq!(
        qsb.command(CommandKind::Velocity, [20.0, 0.0, 0.0]),
        Reason::Accepted
    );
    qsb.rig.run(200);
    assert!(qsb.sim.lock().expect("sim").motor_velocity() > 150.0);
    qsb.run_within_limits(Duration::from_millis(400), |axis| {
        axis.mode() == Ok(AxisMode::Hold)
    });
    let axis = qsb.axis();
    assert!(flags(&axis).contains(AxisFlags::DEADMAN_EXPIRED));
    assert_eq!(qsb.sim.lock().expect("sim").motor_velocity(), 0.0);
    assert!(!qsb.sim.lock().expect("sim").md_status().jogging);
}
