//! The boards the campaigns serve themselves (a QSB-M and a Trinamic SIXpack on ptys, an
//! SPI_motor stepper on an SPI socket), their config sections, and what their wires carried,
//! decoded with the protocol crates.

use core::time::Duration;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use board_qsb::sim::{QsbSim, QsbSimConfig};
use board_spimotor::sim::{SpimotorSim, SpimotorSimConfig};
use motion_testkit::pty_board::{PtyBoard, PtyOptions};
use motion_testkit::socket_board::SocketBoard;

use crate::harness::Harness;

/// `[server]` of a generated config.
pub fn server_section(name: &str, extra: &str) -> String {
    format!("[server]\nname = \"{name}\"\ntick_hz = 1000\ncommand_timeout_ms = 250\n{extra}\n")
}

/// The QSB-M's axis: 100 counts/mm, 10 counts a step, so 10 steps/mm.
pub const QSB_STEPS_PER_MM: f64 = 10.0;
/// The QSB axis's limits (mm), max velocity (mm/s) and acceleration (mm/s²).
pub const QSB_LIMITS: (f64, f64, f64, f64) = (-1000.0, 1000.0, 100.0, 1000.0);

/// The QSB-M's baud rate (its link's `baud`).
pub const QSB_BAUD: u32 = 230_400;

/// A QSB-M (`feeder_qsb`, axis `feeder`) on the serial link `usb` at `tty`.
pub fn qsb_section(tty: &Path) -> String {
    let (min, max, velocity, accel) = QSB_LIMITS;
    format!(
        r#"
[[link]]
name = "usb"
type = "serial"
path = "{}"
baud = {QSB_BAUD}

[[device]]
name = "feeder_qsb"
link = "usb"
model = "qsb"

[[axis]]
name = "feeder"
device = "feeder_qsb"
channel = 0
unit = "mm"
counts_per_unit = 100.0
min = {min:?}
max = {max:?}
max_velocity = {velocity:?}
max_accel = {accel:?}
"#,
        tty.display()
    )
}

/// The stepper's limits (steps), max velocity (steps/s) and acceleration (steps/s²).
pub const FOCUS_LIMITS: (f64, f64, f64, f64) = (-5000.0, 5000.0, 500.0, 5000.0);

/// An SPI_motor stepper (`focus_drv`, axis `focus`, 1 count a step) on the SPI socket link
/// `spi` at `socket`.
pub fn spimotor_section(socket: &Path) -> String {
    let (min, max, velocity, accel) = FOCUS_LIMITS;
    format!(
        r#"
[[link]]
name = "spi"
type = "spi-socket"
path = "{}"

[[device]]
name = "focus_drv"
link = "spi"
model = "spimotor"

[[axis]]
name = "focus"
device = "focus_drv"
channel = 0
unit = "step"
counts_per_unit = 1.0
min = {min:?}
max = {max:?}
max_velocity = {velocity:?}
max_accel = {accel:?}
"#,
        socket.display()
    )
}

/// A SIXpack at address 1 (`pack`, axis `x` on motor 0) on the serial link `rs485` at `tty`.
pub fn tmcpack_section(tty: &Path) -> String {
    format!(
        r#"
[[link]]
name = "rs485"
type = "serial"
path = "{}"
baud = 19200

[[device]]
name = "pack"
link = "rs485"
model = "tmcpack"
address = 1

[[axis]]
name = "x"
device = "pack"
channel = 0
unit = "mm"
counts_per_unit = 640.0
min = -1000.0
max = 1000.0
max_velocity = 10.0
max_accel = 50.0
"#,
        tty.display()
    )
}

/// A fresh simulated QSB-M, as its defaults make it.
pub fn new_qsb() -> Arc<Mutex<QsbSim>> {
    Arc::new(Mutex::new(QsbSim::new(QsbSimConfig::default())))
}

/// A fresh simulated SPI_motor stepper, as its defaults make it.
pub fn new_stepper() -> Arc<Mutex<SpimotorSim>> {
    Arc::new(Mutex::new(SpimotorSim::new(SpimotorSimConfig::default())))
}

/// Serves `qsb` on a pty at `tty` at the QSB's baud rate.
pub fn serve_qsb(
    tty: &Path,
    qsb: &Arc<Mutex<QsbSim>>,
    epoch: Instant,
    options: PtyOptions,
) -> anyhow::Result<PtyBoard> {
    Ok(PtyBoard::try_start(
        tty,
        Arc::clone(qsb),
        epoch,
        QSB_BAUD,
        options,
    )?)
}

/// A QSB-M on a pty and an SPI_motor stepper on an SPI socket, served by this process for a
/// campaign's server (`<name>.tty` and `<name>.sock` in the harness's directory).
pub struct QsbAndStepper {
    /// The simulated QSB-M.
    pub qsb: Arc<Mutex<QsbSim>>,
    /// The simulated stepper.
    pub stepper: Arc<Mutex<SpimotorSim>>,
    /// The pty serving the QSB-M (what the server sent it).
    pub qsb_board: PtyBoard,
    /// The socket serving the stepper (what the server sent it).
    pub stepper_board: SocketBoard,
    /// The QSB-M's pty.
    pub tty: PathBuf,
    /// The stepper's socket.
    pub socket: PathBuf,
}

impl QsbAndStepper {
    /// Fresh boards served for the campaign instance `name`, their model time from `epoch`.
    pub fn serve(h: &Harness, name: &str, epoch: Instant) -> anyhow::Result<Self> {
        let qsb = new_qsb();
        let stepper = new_stepper();
        let tty = h.path(&format!("{name}.tty"));
        let socket = h.path(&format!("{name}.sock"));
        let qsb_board = serve_qsb(&tty, &qsb, epoch, PtyOptions::default())?;
        let stepper_board = SocketBoard::try_start(&socket, Arc::clone(&stepper), epoch)?;
        Ok(Self {
            qsb,
            stepper,
            qsb_board,
            stepper_board,
            tty,
            socket,
        })
    }

    /// The config of both boards: [`qsb_section`] then [`spimotor_section`].
    pub fn sections(&self) -> String {
        format!(
            "{}{}",
            qsb_section(&self.tty),
            spimotor_section(&self.socket)
        )
    }
}

/// A QSB command line the server sent, with the model time of its first byte.
#[derive(Debug, Clone, Copy)]
pub struct QsbLine {
    /// When its first byte reached the board.
    pub at: Duration,
    /// The decoded line.
    pub line: qsb::CommandLine,
}

/// Splits received bytes into command lines (a line cut by the start of the log is
/// dropped: it does not decode).
pub fn qsb_lines(bytes: &[(Duration, u8)]) -> Vec<QsbLine> {
    let mut lines = Vec::new();
    let mut current: Vec<u8> = Vec::new();
    let mut start = Duration::ZERO;
    for &(at, byte) in bytes {
        if byte == b'\r' || byte == b'\n' {
            if !current.is_empty()
                && let Ok(line) = qsb::CommandLine::decode(&current)
            {
                lines.push(QsbLine { at: start, line });
            }
            current.clear();
            continue;
        }
        if current.is_empty() {
            start = at;
        }
        if current.len() < 64 {
            current.push(byte);
        }
    }
    lines
}

/// Whether `line` stops the motor: COMMAND 4 (stop with MD ACCEL, `W164`: how the QSB
/// driver stops), 5 (quit) or 0 (stop everything).
pub fn is_qsb_stop(line: &qsb::CommandLine) -> bool {
    line.ty == qsb::CommandType::Write
        && line.register == 0x16
        && matches!(line.data, Some(0 | 4 | 5))
}

/// Whether `line` starts motion: COMMAND 7, 8 or 9 (resume, move, jog).
pub fn is_qsb_motion(line: &qsb::CommandLine) -> bool {
    line.ty == qsb::CommandType::Write && line.register == 0x16 && matches!(line.data, Some(7..=9))
}

/// A QSB write outside the axis's limits: a jog or step rate above max_velocity, an
/// acceleration above max_accel (in steps, one step of rounding allowed).
pub fn qsb_out_of_limits(line: &qsb::CommandLine) -> Option<String> {
    if line.ty != qsb::CommandType::Write {
        return None;
    }
    let data = line.data?;
    let (_, _, velocity, accel) = QSB_LIMITS;
    let max_rate = velocity * QSB_STEPS_PER_MM + 1.0;
    let max_accel = accel * QSB_STEPS_PER_MM + 1.0;
    let (what, value, limit) = match line.register {
        0x12 => (
            "jog rate",
            f64::from((data as i32).unsigned_abs()),
            max_rate,
        ),
        0x0F => ("step rate", f64::from(data), max_rate),
        0x10 => ("acceleration", f64::from(data), max_accel),
        _ => return None,
    };
    (value > limit).then(|| format!("QSB {what} {value} steps/s > {limit}"))
}

/// Targets this far out are velocity runs, not positions (half the driver's run distance
/// of 2^30 steps).
pub const RUN_TARGET: u32 = 1 << 29;

/// Steps past a limit the stepper may travel while the engine stops a velocity run at the
/// limit: 20 ms at max_velocity (the position it judges by is one poll old).
pub const FOCUS_SLACK: f64 = FOCUS_LIMITS.2 * 0.02;

/// The stepper's true position (the board's step counter, which `SetPosition` writes) when
/// it is outside the axis's limits by more than [`FOCUS_SLACK`].
pub fn spimotor_position_outside(position: i32) -> Option<String> {
    let (min, max, _, _) = FOCUS_LIMITS;
    let position = f64::from(position);
    (position < min - FOCUS_SLACK || position > max + FOCUS_SLACK).then(|| {
        format!("SPI_motor stepper at {position} steps, outside {min}..{max} (± {FOCUS_SLACK})")
    })
}

/// An SPI_motor write outside the stepper axis's limits: a target outside min..max, a step
/// delay shorter than max_velocity allows.
pub fn spimotor_out_of_limits(mosi: &[u8]) -> Option<String> {
    let transaction = spimotor::Transaction::decode(mosi).ok()?;
    let spimotor::Request::Write(write) = transaction.request else {
        return None;
    };
    let (min, max, velocity, _) = FOCUS_LIMITS;
    match write {
        // A target 2^29 steps or more away is how the driver runs at a velocity (it steps
        // towards a target 2^30 from where the motor is, `RUN_DISTANCE`); the engine stops
        // that run before the soft limit, which the motor's true position shows
        // (`spimotor_position_outside`).
        spimotor::Write::TargetPosition(target) if target.unsigned_abs() >= RUN_TARGET => None,
        spimotor::Write::TargetPosition(target) => {
            let target = f64::from(target);
            (target < min || target > max)
                .then(|| format!("SPI_motor target {target} outside {min}..{max}"))
        }
        spimotor::Write::StepDelay(delay) => {
            // A step every `delay`: the rate must not exceed max_velocity (steps/s); the
            // board's 0.1 ms resolution is rounded up by the driver, never down. Delay 0 is
            // "stopped".
            let tenths = f64::from(delay.tenths_ms());
            let rate = if tenths == 0.0 { 0.0 } else { 1e4 / tenths };
            (rate > velocity).then(|| format!("SPI_motor step rate {rate} steps/s > {velocity}"))
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bytes(text: &[u8], from_ms: u64) -> Vec<(Duration, u8)> {
        text.iter()
            .enumerate()
            .map(|(i, b)| (Duration::from_millis(from_ms + i as u64), *b))
            .collect()
    }

    #[test]
    fn qsb_lines_keep_the_first_byte_time_and_drop_a_cut_line() {
        let mut log = bytes(b"169\r\nW164\r\nW12FFFFFF00\r\n", 10);
        log.extend(bytes(b"W12", 100));
        let lines = qsb_lines(&log);
        // "169" decodes as nothing valid (no command type); W164 at 15 ms; the jog rate.
        assert_eq!(lines.len(), 2, "{lines:?}");
        assert!(is_qsb_stop(&lines[0].line));
        assert_eq!(lines[0].at, Duration::from_millis(15));
        assert!(qsb_out_of_limits(&lines[1].line).is_none(), "-256 steps/s");
        let fast = qsb::CommandLine::decode(b"W12FFFFF000").expect("line");
        assert!(qsb_out_of_limits(&fast).is_some(), "-4096 steps/s > 1001");
    }

    #[test]
    fn spimotor_targets_outside_the_limits_are_found() {
        let mut mosi = [0u8; 16];
        let encode = |write, mosi: &mut [u8; 16]| {
            spimotor::Transaction::write(spimotor::Address::DEFAULT, write)
                .encode(mosi)
                .expect("encodes")
        };
        let n = encode(spimotor::Write::TargetPosition(4000), &mut mosi);
        assert!(spimotor_out_of_limits(&mosi[..n]).is_none());
        let n = encode(spimotor::Write::TargetPosition(-6000), &mut mosi);
        assert!(spimotor_out_of_limits(&mosi[..n]).is_some());
        // A velocity run's far target is no position.
        let n = encode(spimotor::Write::TargetPosition(-(1 << 30)), &mut mosi);
        assert!(spimotor_out_of_limits(&mosi[..n]).is_none());
        let n = encode(spimotor::Write::TargetPosition(1 << 28), &mut mosi);
        assert!(spimotor_out_of_limits(&mosi[..n]).is_some());
        assert!(spimotor_position_outside(5010).is_none());
        assert!(spimotor_position_outside(-5011).is_some());
        let n = encode(
            spimotor::Write::StepDelay(spimotor::StepDelay::from_tenths_ms(20)),
            &mut mosi,
        );
        assert!(spimotor_out_of_limits(&mosi[..n]).is_none(), "500 steps/s");
        let n = encode(
            spimotor::Write::StepDelay(spimotor::StepDelay::from_tenths_ms(19)),
            &mut mosi,
        );
        assert!(spimotor_out_of_limits(&mosi[..n]).is_some(), "526 steps/s");
    }
}
