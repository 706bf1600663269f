//! Campaign 1, dead clients: a motion-client program jogging the QSB-M's axis (served by
//! this process on a pty) is SIGKILLed — or SIGSTOPped, a hung client — at a random moment;
//! the time from the signal to the first byte of the stop command (`W164`) at the board is
//! measured from the board's own log, and the motor must stand still after it.
//!
//! Expected bounds (`command_timeout_ms` 250, `liveness_check_ms` 100, the guard renewing
//! every 250 / 3 = 83 ms): a SIGKILLed client's node is found dead by the next liveness
//! check and its goals voided — at most 100 ms + 1 tick + the line; a SIGSTOPped client
//! stays alive, so only the deadman stops it: 250 ms after its last renewal, which was 0 to
//! 83 ms before the signal, so 167–250 ms + 1 tick + the line. The deadman also bounds the
//! SIGKILL case should the liveness check be late.

use core::time::Duration;
use std::io::Read as _;
use std::process::{Child, Command, Stdio};
use std::sync::Mutex;
use std::time::Instant;

use anyhow::{Context, bail};
use board_qsb::sim::QsbSim;
use motion_ipc::{AxisFlags, AxisMode, CommandKind, DeviceState, MotionFrame};
use motion_sim::rng::SimRng;
use motion_testkit::RawClient;
use motion_testkit::pty_board::{PtyBoard, PtyOptions};
use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;

use crate::boards::{is_qsb_stop, new_qsb, qsb_lines, qsb_section, serve_qsb, server_section};
use crate::harness::{Harness, Samples};
use crate::report::Row;

const DEADMAN_MS: f64 = 250.0;
const LIVENESS_MS: f64 = 100.0;
const JOG: f64 = 20.0;

/// Whether the axis is ready for goals.
pub fn online(frame: &MotionFrame, axis: usize) -> bool {
    frame.axes().get(axis).is_some_and(|a| {
        a.device_state() == Ok(DeviceState::Online) && !a.flags().contains(AxisFlags::STALE)
    })
}

struct Outcome {
    latency_ms: Option<f64>,
    left_moving: bool,
}

/// Runs the campaign.
pub fn run(h: &Harness) -> anyhow::Result<Row> {
    let count = if h.quick { 8 } else { 1000 };
    let mut row = Row::new("1 dead clients");
    row.runs = format!("{count} × SIGKILL, {count} × SIGSTOP of a jogging client");
    let name = h.name("dead");
    let epoch = Instant::now();
    let board = new_qsb();
    let tty = h.path(&format!("{name}.tty"));
    let served = serve_qsb(&tty, &board, epoch, PtyOptions::default())?;
    let config = h.write(
        &format!("{name}.toml"),
        &format!(
            "{}{}",
            server_section(&name, "liveness_check_ms = 100"),
            qsb_section(&tty)
        ),
    )?;
    let mut server = h.server(&config)?;
    let mut watcher = RawClient::try_connect(&name, Duration::from_secs(10))?;
    match watcher.try_wait_frame(Duration::from_secs(10), |f| online(f, 0)) {
        Some((_, true)) => {}
        _ => bail!("the QSB axis is not online after 10 s"),
    }
    let mut rng = SimRng::new(h.seed ^ 0xD1E5);
    let mut failures: Vec<String> = Vec::new();
    let mut board_resets = 0u32;
    let mut fault_codes: std::collections::BTreeMap<String, u32> = Default::default();
    for signal in [Signal::SIGKILL, Signal::SIGSTOP] {
        let mut latency = Samples::default();
        let mut left_moving = 0u32;
        let mut no_stop = 0u32;
        let mut not_started = 0u32;
        for i in 0..count {
            let velocity = if i % 2 == 0 { JOG } else { -JOG };
            let outcome = one_kill(
                h, &name, &watcher, &served, &board, epoch, signal, velocity, &mut rng,
            );
            match outcome {
                Ok(outcome) => {
                    match outcome.latency_ms {
                        Some(ms) => latency.push(ms),
                        None => no_stop += 1,
                    }
                    left_moving += u32::from(outcome.left_moving);
                }
                // The jog never ran (the signal was not sent): nothing to stop.
                Err(e) => {
                    if failures.len() < 5 {
                        failures.push(format!("{signal:?} #{i}: {e:#}"));
                    }
                    not_started += 1;
                }
            }
            // A fault latched meanwhile (the board's or the axis's) would refuse every
            // later jog: reset it, and count it.
            let faulted = watcher.try_wait_frame(Duration::from_millis(200), |f| {
                let a = f.axes()[0];
                a.fault != 0 || a.device_state() == Ok(DeviceState::Faulted)
            });
            if let Some((frame, true)) = faulted {
                board_resets += 1;
                let a = frame.axes()[0];
                *fault_codes
                    .entry(format!("{:?}/{:?}", a.fault(), a.device_state()))
                    .or_insert(0u32) += 1;
                let _ = watcher.try_command(0, CommandKind::Reset, [0.0; 3]);
                let _ = watcher.try_wait_frame(Duration::from_secs(3), |f| online(f, 0));
            }
            if !server.is_running() {
                bail!("motiond died during the {signal:?} runs (#{i})");
            }
        }
        let label = if signal == Signal::SIGKILL {
            "SIGKILL"
        } else {
            "SIGSTOP"
        };
        row.figure(
            &format!("{label} → stop on the wire"),
            latency.p50_p99_max(1.0, "ms"),
        );
        row.check(
            &format!("{label}: 0 axes left moving"),
            left_moving == 0,
            format!("{left_moving} of {count} runs left the motor moving"),
        );
        row.check(
            &format!("{label}: a stop reached the wire every time"),
            no_stop == 0,
            format!(
                "{no_stop} of {} jogs signalled without a stop command within 3 s",
                count - not_started
            ),
        );
        row.figure(
            &format!("{label}: jogs that never started (no signal sent)"),
            format!("{not_started} of {count}"),
        );
        // The bound (see the module docs): timing, so a target, never a failure.
        let bound = if signal == Signal::SIGKILL {
            LIVENESS_MS + 5.0
        } else {
            DEADMAN_MS + 5.0
        };
        row.target(
            &format!("{label} max ÷ {bound:.0} ms bound"),
            latency.max(),
            bound,
            1.0,
        );
    }
    row.figure(
        "faults latched between runs (reset)",
        format!("{board_resets} (axis fault/device state: {fault_codes:?})"),
    );
    for failure in failures {
        row.note(failure);
    }
    let alive = server.is_running();
    row.check("server alive", alive, if alive { "yes" } else { "no" });
    let code = server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10));
    drop(watcher);
    drop(served);
    h.check_clean_exit(&mut row, code);
    row.note(format!(
        "bounds: SIGKILL ≤ liveness_check_ms {LIVENESS_MS} ms + 1 tick (the dead node's goals are voided), \
         SIGSTOP ≤ command_timeout_ms {DEADMAN_MS} ms after the last renewal (the deadman); \
         the kill lands uniformly within 0–250 ms after the jog started"
    ));
    Ok(row)
}

#[allow(clippy::too_many_arguments)]
fn one_kill(
    h: &Harness,
    name: &str,
    watcher: &RawClient,
    served: &PtyBoard,
    board: &Mutex<QsbSim>,
    epoch: Instant,
    signal: Signal,
    velocity: f64,
    rng: &mut SimRng,
) -> anyhow::Result<Outcome> {
    let _ = h;
    let mut child = spawn_jogger(name, velocity)?;
    let result = (|| {
        let jogging = watcher.try_wait_frame(Duration::from_secs(10), |f| {
            let a = f.axes()[0];
            matches!(a.mode(), Ok(AxisMode::Velocity | AxisMode::RampVelocity))
                && a.flags().contains(AxisFlags::MOVING)
        });
        if !matches!(jogging, Some((_, true))) {
            let mut err = String::new();
            if let Ok(Some(status)) = child.try_wait() {
                if let Some(mut out) = child.stderr.take() {
                    let _ = out.read_to_string(&mut err);
                }
                bail!("the jogger exited ({status}): {}", err.trim());
            }
            bail!(
                "the jog did not start within 10 s: {:?}",
                jogging.map(|(f, _)| f.axes()[0])
            );
        }
        std::thread::sleep(Duration::from_micros(rng.range_f64(0.0, 250_000.0) as u64));
        let _ = served.take_received();
        let killed_at = epoch.elapsed();
        kill(Pid::from_raw(child.id() as i32), signal).context("signal the jogger")?;
        let mut received = Vec::new();
        let end = Instant::now() + Duration::from_secs(3);
        let mut latency_ms = None;
        while Instant::now() < end {
            received.extend(served.take_received());
            if let Some(stop) = qsb_lines(&received)
                .iter()
                .find(|l| l.at >= killed_at && is_qsb_stop(&l.line))
            {
                latency_ms = Some((stop.at - killed_at).as_secs_f64() * 1e3);
                break;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        // The motor must come to rest (it decelerates at max_accel from 20 mm/s: 20 ms).
        let end = Instant::now() + Duration::from_secs(2);
        let mut left_moving = true;
        while Instant::now() < end {
            if board
                .lock()
                .map(|b| b.motor_velocity() == 0.0)
                .unwrap_or(false)
            {
                left_moving = false;
                break;
            }
            std::thread::sleep(Duration::from_millis(5));
        }
        Ok(Outcome {
            latency_ms,
            left_moving,
        })
    })();
    let _ = child.kill();
    let _ = child.wait();
    // Held again before the next run.
    let _ = watcher.try_wait_frame(Duration::from_secs(3), |f| {
        let a = f.axes()[0];
        a.mode() == Ok(AxisMode::Hold) && !a.flags().contains(AxisFlags::MOVING)
    });
    result
}

fn spawn_jogger(name: &str, velocity: f64) -> anyhow::Result<Child> {
    Command::new(std::env::current_exe()?)
        .args(["jogger", "--server", name, "--axis", "feeder", "--velocity"])
        .arg(format!("{velocity}"))
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .context("start the jogger")
}
