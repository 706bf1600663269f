//! The deadman's bound per board (docs/ARCHITECTURE.md "The deadman's bound per board"),
//! held by the real motiond on the default config (`config/sim.toml`, the four boards on
//! simulated links with their wire times): a client jogs one axis of a board, stops renewing
//! the jog without a stop (it stays alive: only the deadman can end the jog), and the frames
//! must show the axis at rest — in `Hold`, at the engine's standstill speed — within
//!
//! ```text
//! lease + one bus exchange + |v| / max_accel + the board's refresh + margin
//! ```
//!
//! after the tick that applied the last renewal, every term computed from the config the
//! server runs (`deadman/bound.rs`) the way the document derives it, and `|v|` the fastest
//! speed the axis had between that tick and the stop: the frames' speed, or the speed its
//! ramp had reached when the lease ran out if faster (a jog sent once and never renewed
//! expires while still accelerating, and a board's frames lag its real speed — issue 40's
//! `conveyor`). Times are the server's own: the frames' tick deadlines, so the test
//! process's scheduling does not count.

mod support;

#[path = "deadman/bound.rs"]
mod bound;

use core::time::Duration;
use std::path::PathBuf;

use motion_config::ServerConfig;
use motion_ipc::{AxisFlags, AxisMode, CommandKind, DeviceState, MotionFrame};
use nix::sys::signal::Signal;
use support::*;

use bound::{Board, Bound, MARGIN};

static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// The default config, under a name of this test.
fn sim_config(test: &str) -> (String, PathBuf, ServerConfig) {
    let source = include_str!("../../../config/sim.toml");
    let name = unique_name(test);
    let text = source.replacen("name = \"demo\"", &format!("name = \"{name}\""), 1);
    let path = write_config(&name, &text);
    let config = ServerConfig::load(&path).expect("config/sim.toml is valid");
    (name, path, config)
}

fn axis_index(config: &ServerConfig, name: &str) -> usize {
    config
        .axes
        .iter()
        .position(|axis| axis.name == name)
        .unwrap_or_else(|| panic!("axis {name} in config/sim.toml"))
}

/// Every frame published since the last call (the subscriber keeps up to its buffer).
fn drain(client: &RawClient) -> Vec<MotionFrame> {
    let mut frames = Vec::new();
    while let Ok(Some(sample)) = client.frames.receive() {
        frames.push(*sample);
    }
    frames
}

/// What one deadman stop took, in server time.
#[derive(Debug)]
struct Stop {
    /// From the renewal's tick to the tick that set the stop.
    to_goal: Duration,
    /// From the renewal's tick to the stop's first byte written (the link's stamp).
    to_wire: Duration,
    /// From the renewal's tick to the first frame at rest.
    to_rest: Duration,
    /// The fastest speed the frames showed from the renewal to the rest (units/s).
    speed: f64,
    /// The latest a frame of that span was published after its tick's deadline: how late
    /// the server's tick ran (a loaded machine), for the failure message.
    late: Duration,
    /// The ticks (from the renewal's) at which the axis's data were refreshed after the stop
    /// was set.
    refreshed: Vec<u64>,
}

/// How a deadman test jogs.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Jog {
    /// Renewed every `lease / 4` until the frames show it at speed, then once more.
    AtSpeed,
    /// Sent once from rest and never renewed: the lease runs out while the axis still
    /// accelerates.
    Once,
}

/// Jogs axis `index` at `fraction` of its velocity limit as `how` says, then lets the
/// deadman end it.
fn deadman_stop(
    client: &mut RawClient,
    config: &ServerConfig,
    index: usize,
    fraction: f64,
    how: Jog,
) -> Stop {
    let axis = &config.axes[index];
    let lease = config.server.command_timeout;
    let period_ns = 1_000_000_000 / u64::from(config.server.tick_hz);
    let jog = axis.max_velocity * fraction;
    let axis_no = u32::try_from(index).expect("axis index");
    let started = std::time::Instant::now();
    let renewal = loop {
        if how == Jog::Once {
            let reply = client.command(axis_no, CommandKind::Velocity, [jog, 0.0, 0.0]);
            assert_eq!(reply.result(), Ok(()), "jog of {}: {reply:?}", axis.name);
            break reply.tick_applied;
        }
        let reply = client.command(axis_no, CommandKind::Velocity, [jog, 0.0, 0.0]);
        assert_eq!(
            reply.result(),
            Ok(()),
            "jog of {}: {reply:?} {:?}",
            axis.name,
            client.frame().axes()[index]
        );
        std::thread::sleep(lease / 4);
        let frame = client.frame();
        let state = frame.axes()[index];
        if (state.velocity - jog).abs() <= jog.abs() * 0.05
            && state.mode() == Ok(AxisMode::Velocity)
        {
            // One renewal more, at speed: the deadman runs from this one.
            let reply = client.command(axis_no, CommandKind::Velocity, [jog, 0.0, 0.0]);
            assert_eq!(reply.result(), Ok(()), "jog of {}", axis.name);
            break reply.tick_applied;
        }
        assert!(
            started.elapsed() < Duration::from_secs(10),
            "{} never reached {jog} {}/s: {state:?}",
            axis.name,
            axis.unit
        );
    };
    let _ = drain(client);
    let mut speed: f64 = 0.0;
    let mut goal = None;
    let mut wire_ns = None;
    let mut rest = None;
    let waited = std::time::Instant::now();
    let mut last = None;
    let mut late = Duration::ZERO;
    let mut refreshed = Vec::new();
    while rest.is_none() {
        assert!(
            waited.elapsed() < Duration::from_secs(10),
            "{} never came to rest after the deadman: {last:?}",
            axis.name
        );
        for frame in drain(client) {
            last = Some((frame.tick, frame.axes()[index], frame.wire[index]));
            if frame.tick < renewal {
                continue;
            }
            let state = frame.axes()[index];
            let renewed_ns = frame.time_ns - (frame.tick - renewal) * period_ns;
            speed = speed.max(state.velocity.abs());
            late = late.max(Duration::from_nanos(
                frame.publish_ns.saturating_sub(frame.time_ns),
            ));
            if !state.flags().contains(AxisFlags::DEADMAN_EXPIRED) {
                continue;
            }
            let at = state.last_refresh_tick.saturating_sub(renewal);
            if refreshed.last() != Some(&at) {
                refreshed.push(at);
            }
            let wire = frame.wire[index];
            if goal.is_none() {
                goal = Some(Duration::from_nanos((wire.goal_tick - renewal) * period_ns));
            }
            if wire_ns.is_none() && wire.written() {
                wire_ns = Some(Duration::from_nanos(
                    wire.wire_ns.saturating_sub(renewed_ns),
                ));
            }
            let still = state.velocity.abs() <= axis.max_velocity * 1e-3;
            if rest.is_none() && still && state.mode() == Ok(AxisMode::Hold) {
                rest = Some(Duration::from_nanos(frame.time_ns - renewed_ns));
            }
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    // The speed its ramp had reached when the lease ran out (lease + the tick that saw
    // it), were the frames behind it: from rest at max_accel, never beyond the jog.
    if how == Jog::Once {
        let expiry = (lease + Duration::from_nanos(period_ns)).as_secs_f64();
        speed = speed.max((axis.max_accel * expiry).min(jog.abs()));
    }
    Stop {
        to_goal: goal.expect("the deadman set a stop"),
        to_wire: wire_ns.expect("the stop was written"),
        to_rest: rest.expect("at rest"),
        speed,
        late,
        refreshed,
    }
}

/// Starts the default robot, waits until `axis` reports in, and holds it to its board's
/// bound at each of `fractions` of its velocity limit (a quarter and four fifths: the
/// deceleration term small, then large; a sign keeps the axis inside its soft limits).
fn holds_its_bound(test: &str, axis: &str, fractions: &[f64]) {
    holds_its_bound_jogged(test, axis, fractions, Jog::AtSpeed);
}

/// [`holds_its_bound`] with jogs sent as `how` says.
fn holds_its_bound_jogged(test: &str, axis: &str, fractions: &[f64], how: Jog) {
    // One server at a time: four robots at 1 kHz on a loaded 2-core machine would measure
    // each other.
    let _one = ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let (name, _path, config) = sim_config(test);
    let index = axis_index(&config, axis);
    let mut server = Server::start(&_path);
    let mut client = RawClient::connect(&name, Duration::from_secs(10));
    let device = config.axes[index].device;
    let (frame, online) = client.wait_frame(Duration::from_secs(20), |f| {
        f.devices[device] == DeviceState::Online as u8
            && !f.axes()[index].flags().contains(AxisFlags::STALE)
            && f.axes()[index].mode() == Ok(AxisMode::Hold)
    });
    assert!(
        online,
        "{axis} online and holding: {:?}",
        frame.axes()[index]
    );
    let board = Board::of(&config, index);
    for &fraction in fractions {
        let mut attempts = 0;
        let (stop, bound) = loop {
            attempts += 1;
            let stop = deadman_stop(&mut client, &config, index, fraction, how);
            // At rest before the next jog.
            let _ = client.wait_frame(Duration::from_secs(5), |f| {
                f.axes()[index].mode() == Ok(AxisMode::Hold)
            });
            let bound = Bound::new(&config, index, board, stop.speed);
            eprintln!(
                "{axis} ({board:?}) at {fraction} of its limit: measured {:.2} {}/s; stop set \
                 after {:?}, on the wire after {:?}, at rest after {:?}; bound {bound}; the \
                 server's tick ran up to {:?} late",
                stop.speed,
                config.axes[index].unit,
                stop.to_goal,
                stop.to_wire,
                stop.to_rest,
                stop.late
            );
            // The server itself says it was stalled longer than the margin (a host stall
            // on a loaded machine): that stop measured the machine, not the code. Measured
            // again, at most twice; a machine that stalls every time fails the test.
            if stop.late <= MARGIN || attempts == 3 {
                break (stop, bound);
            }
        };
        assert!(
            stop.to_goal <= bound.lease + bound.margin,
            "{axis}: the deadman fired {:?} after the renewal, lease {:?}",
            stop.to_goal,
            bound.lease
        );
        assert!(
            stop.to_wire <= bound.lease + bound.exchange + bound.margin,
            "{axis}: the stop reached the wire {:?} after the renewal; bound {bound}",
            stop.to_wire
        );
        assert!(
            stop.to_rest <= bound.total(),
            "{axis}: at rest {:?} after the renewal; bound {bound}; the server's tick ran up \
             to {:?} late; the axis was refreshed at renewal + {:?} ticks (stop set at {:?})",
            stop.to_rest,
            stop.late,
            stop.refreshed,
            stop.to_goal
        );
    }
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}

#[test]
fn a_sixpack_axis_on_the_shared_rs485_bus_stops_within_its_bound() {
    holds_its_bound("dm_tmcpack", "x", &[0.25, 0.8]);
}

/// Issue 40: a jog of the QUADpack's `conveyor` sent once and never renewed expires while
/// the pack still accelerates, faster than its frames show; the bound takes the ramp's
/// speed at expiry (before, the frames' speed gave 577–607 ms, and the stop took 663–676).
#[test]
fn a_quadpack_jog_sent_once_stops_within_its_bound_from_its_ramp_speed() {
    holds_its_bound_jogged("dm_conveyor", "conveyor", &[0.8, -0.8], Jog::Once);
}

#[test]
fn a_quadquad2drv_axis_stops_within_its_bound() {
    holds_its_bound("dm_qq2drv", "turret", &[0.25, -0.8]);
}

#[test]
fn an_spi_motor_stepper_stops_within_its_bound() {
    holds_its_bound("dm_spimotor", "focus", &[0.25, 0.8]);
}

#[test]
fn a_qsb_m_stepper_stops_within_its_bound() {
    holds_its_bound("dm_qsb", "feeder", &[0.25, 0.8]);
}
