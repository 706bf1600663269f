//! The engine driving a QSB-M configured as a machine: encoder counts per step, stops from
//! the measured velocity within their bound, stops the driver did not expect, and homing
//! with a direction, a travel limit and an offset.

use core::time::Duration;

use board_qsb::driver::QsbDriverConfig;
use board_qsb::sim::QsbSimConfig;
use motion_ipc::{AxisFlags, AxisMode, CommandKind, FaultCode, Reason};
use motion_link::sim::StreamDevice;
use qsb::{QsbCommand, Request, Write};

use super::{COUNTS_PER_UNIT, MAX_ACCEL, MAX_VELOCITY, Qsb, TOLERANCE, flags, healthy, rig_with};

/// The wire latency a stop may add to |v| / decel: the MD ACCEL and COMMAND 4 lines and
/// their answers at 230400 baud (2 × (13 + 21) bytes ≈ 3 ms with the processing time), and
/// the tick that sends them.
const STOP_LATENCY: Duration = Duration::from_millis(5);

/// The acceleration the board stops with, steps/s²: the axis's, at 10 counts per step.
fn stop_accel(counts_per_step: f64) -> f64 {
    MAX_ACCEL * COUNTS_PER_UNIT / counts_per_step.abs()
}

/// A -M whose encoder counts `counts_per_step` per motor step, told so (or not).
fn m_with(sim_counts_per_step: f64, driver: QsbDriverConfig) -> Qsb {
    let sim = QsbSimConfig::default().with_counts_per_step(sim_counts_per_step);
    let mut qsb = rig_with(sim, driver, Duration::from_millis(250));
    qsb.start();
    qsb
}

fn driver(counts_per_step: f64) -> QsbDriverConfig {
    QsbDriverConfig {
        counts_per_step,
        max_velocity: MAX_VELOCITY * COUNTS_PER_UNIT,
        max_accel: MAX_ACCEL * COUNTS_PER_UNIT,
        ..QsbDriverConfig::default()
    }
}

/// The writes on the wire since message `from`, decoded with the protocol crate.
fn writes_since(qsb: &Qsb, from: usize) -> Vec<Write> {
    qsb.rig.wire_log(0)[from..]
        .iter()
        .filter_map(|(_, bytes)| {
            let line = bytes.strip_suffix(b"\r\n")?;
            match Request::decode(line).expect("a command of the command list") {
                Request::Write(write) => Some(write),
                _ => None,
            }
        })
        .collect()
}

fn moves(writes: &[Write]) -> usize {
    writes
        .iter()
        .filter(|w| **w == Write::Command(QsbCommand::MotorMove))
        .count()
}

#[test]
fn four_counts_per_step_move_in_one_move_and_at_most_one_correction() {
    let mut qsb = m_with(4.0, driver(4.0));
    for target in [20.0, -7.5, 3.33] {
        let from = qsb.rig.wire_log(0).len();
        let reply = qsb.command(CommandKind::Position, [target, 0.0, 0.0]);
        assert_eq!(reply, Reason::Accepted);
        qsb.run_within_limits(Duration::from_secs(3), |axis| {
            flags(axis).contains(AxisFlags::ARRIVED)
        });
        let axis = qsb.axis();
        assert!((axis.position - target).abs() <= TOLERANCE, "{axis:?}");
        assert_eq!(axis.raw_counts, i64::from(qsb.sim_counter()));
        let writes = writes_since(&qsb, from);
        let count = moves(&writes);
        assert!(
            (1..=2).contains(&count),
            "{count} moves to {target}: {writes:?}"
        );
        // "MD MOVE STEPS": 4 counts per step, so 2000 counts are 500 steps.
        if target == 20.0 {
            assert!(writes.contains(&Write::MoveSteps(500)), "{writes:?}");
        }
    }
    // The sim's encoder: 4 counts per motor step, as configured.
    let sim = qsb.sim.lock().expect("sim");
    let counts = f64::from(sim.counter() as i32);
    assert!((counts - 4.0 * sim.motor_position()).abs() <= 1.0);
}

#[test]
fn the_deadman_stop_ends_within_v_over_max_accel_and_the_wire_latency() {
    let mut qsb = m_with(10.0, driver(10.0));
    // 80 mm/s = 800 steps/s.
    let reply = qsb.command(CommandKind::Velocity, [80.0, 0.0, 0.0]);
    assert_eq!(reply, Reason::Accepted);
    let mut fired = None;
    let end = qsb.rig.now + Duration::from_secs(1);
    while qsb.rig.now < end {
        qsb.rig.tick();
        let sim = qsb.sim.lock().expect("sim");
        let velocity = sim.motor_velocity();
        drop(sim);
        match fired {
            None if flags(&qsb.axis()).contains(AxisFlags::DEADMAN_EXPIRED) => {
                // The tick that fired it sent the stop; the motor ran at `velocity`.
                fired = Some((qsb.rig.now - qsb.rig.period, velocity));
            }
            Some((at, v)) if velocity == 0.0 => {
                let took = qsb.rig.now - at;
                let bound = Duration::from_secs_f64(v.abs() / stop_accel(10.0)) + STOP_LATENCY;
                assert!(v > 700.0, "it ran at {v} steps/s");
                assert!(took <= bound, "stopped after {took:?}, bound {bound:?}");
                return;
            }
            _ => {}
        }
    }
    panic!("no deadman stop: {fired:?} {:?}", qsb.axis());
}

#[test]
fn a_motor_jogging_before_start_up_or_behind_the_drivers_back_is_stopped() {
    // A motor left jogging by a previous server: the start-up stops it.
    let sim = QsbSimConfig::default();
    let mut board = board_qsb::sim::QsbSim::new(sim.clone());
    board.receive(Duration::ZERO, b"W162\r\nW12320\r\nW169\r\n"); // 800 steps/s
    assert!(board.md_status().jogging);
    let mut qsb = super::rig_with(sim, driver(10.0), Duration::from_millis(250));
    *qsb.sim.lock().expect("sim") = board;
    qsb.start();
    let writes = writes_since(&qsb, 0);
    let stop = writes
        .iter()
        .position(|w| *w == Write::Command(QsbCommand::MotorStop))
        .expect("the start-up stop");
    assert_eq!(
        writes[stop - 1],
        Write::Accel(10_000),
        "at the axis's acceleration"
    );
    qsb.rig.run(150);
    assert_eq!(qsb.sim.lock().expect("sim").motor_velocity(), 0.0);
    // Now someone else makes it jog, behind the driver's back; a Stop reaches it.
    let now = qsb.rig.now;
    qsb.sim
        .lock()
        .expect("sim")
        .receive(now, b"W12FFFFFCE0\r\nW169\r\n"); // -800 steps/s
    qsb.rig.run(100);
    let v = qsb.sim.lock().expect("sim").motor_velocity();
    assert!(v < -700.0, "{v}");
    assert_eq!(qsb.command(CommandKind::Stop, [0.0; 3]), Reason::Accepted);
    let at = qsb.rig.now - qsb.rig.period;
    let bound = Duration::from_secs_f64(v.abs() / stop_accel(10.0)) + STOP_LATENCY;
    let sim = std::sync::Arc::clone(&qsb.sim);
    let done = qsb
        .rig
        .run_until(bound, |_| sim.lock().expect("sim").motor_velocity() == 0.0);
    assert!(done, "not stopped within {bound:?} of {at:?}");
}

#[test]
fn a_stop_on_an_idle_motor_still_goes_on_the_wire() {
    let mut qsb = m_with(10.0, driver(10.0));
    let reply = qsb.command(CommandKind::Position, [2.0, 0.0, 0.0]);
    assert_eq!(reply, Reason::Accepted);
    qsb.run_within_limits(Duration::from_secs(2), |axis| {
        flags(axis).contains(AxisFlags::ARRIVED)
    });
    qsb.rig.run(20);
    assert_eq!(qsb.sim.lock().expect("sim").motor_velocity(), 0.0);
    let from = qsb.rig.wire_log(0).len();
    assert_eq!(qsb.command(CommandKind::Stop, [0.0; 3]), Reason::Accepted);
    qsb.rig.run(5);
    let writes = writes_since(&qsb, from);
    assert!(
        writes.contains(&Write::Command(QsbCommand::MotorStop)),
        "{writes:?}"
    );
}

#[test]
fn a_search_without_an_index_within_its_travel_faults_home_failed_and_stops() {
    // An encoder whose index is far away (one per 100000 cycles = 400000 counts); the
    // search may travel 20 mm = 2000 counts.
    let sim = QsbSimConfig {
        cycles_per_rev: 100_000,
        ..QsbSimConfig::default()
    };
    let driver = QsbDriverConfig {
        home_max_travel: 2000.0,
        ..driver(10.0)
    };
    let mut qsb = rig_with(sim, driver, Duration::from_millis(250));
    qsb.start();
    let start = qsb.sim_counter();
    assert_eq!(qsb.command(CommandKind::Home, [0.0; 3]), Reason::Accepted);
    assert_eq!(qsb.axis().mode(), Ok(AxisMode::Homing));
    let mut faulted = false;
    let done = qsb.rig.run_until(Duration::from_secs(3), |frame| {
        faulted |= frame.axes[0].fault() == Ok(FaultCode::HomeFailed);
        faulted && frame.axes[0].mode() == Ok(AxisMode::Hold) && healthy(&frame.axes[0])
    });
    assert!(faulted, "HomeFailed was reported: {:?}", qsb.axis());
    assert!(done, "the axis left Homing and holds: {:?}", qsb.axis());
    let axis = qsb.axis();
    assert!(!flags(&axis).contains(AxisFlags::HOMED));
    assert_eq!(qsb.sim.lock().expect("sim").motor_velocity(), 0.0);
    // It searched towards negative counts (the default direction), no farther than its
    // travel limit and the stop (25 mm/s at 1000 mm/s² is 0.31 mm) with a sample of slack.
    let travel = f64::from(start - qsb.sim_counter());
    assert!(travel > 2000.0 && travel < 2100.0, "travel {travel} counts");
}

#[test]
fn a_positive_search_loads_the_home_offset_at_the_index() {
    // Index every 500 cycles = 2000 counts; searching up from 0 finds the one at 2000
    // and the counter becomes the offset, 2.5 mm = 250 counts.
    let driver = QsbDriverConfig {
        home_positive: true,
        home_position: 250,
        ..driver(10.0)
    };
    let mut qsb = m_with(10.0, driver);
    assert_eq!(qsb.command(CommandKind::Home, [0.0; 3]), Reason::Accepted);
    qsb.run_within_limits(Duration::from_secs(3), |axis| {
        axis.mode() == Ok(AxisMode::Hold)
    });
    let axis = qsb.axis();
    assert!(flags(&axis).contains(AxisFlags::HOMED), "{axis:?}");
    // Stopped just past the index: 2.5 mm and the stopping distance (0.3 mm).
    assert!(axis.position >= 2.5 && axis.position < 3.0, "{axis:?}");
    let sim = qsb.sim.lock().expect("sim");
    let true_counts = sim.encoder_position() * 4.0;
    let offset = true_counts - f64::from(sim.counter() as i32);
    assert!(
        (offset - 1750.0).abs() <= 2.0,
        "index at 2000 is 250: {offset}"
    );
}
