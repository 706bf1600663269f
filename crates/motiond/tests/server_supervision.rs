//! Supervision from outside: motiond drives boards that this test serves (a QSB-M on a
//! pseudo-terminal, an SPI_motor stepper on an SPI socket) and disturbs behind the server's
//! back, as a slipping motor or another program would.
//! - an axis driven away from its hold faults `FollowingError` within 100 ticks, and a stop
//!   reaches the board;
//! - a stepper left running before the server starts is stopped by the start-up stop;
//! - SIGTERM stops an axis the server never commanded while its motor runs.

mod support;

use core::time::Duration;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use board_qsb::sim::{QsbSim, QsbSimConfig};
use board_spimotor::sim::{SpimotorSim, SpimotorSimConfig};
use motion_ipc::{AxisFlags, FaultCode};
use motion_link::sim::SpiDevice;
use motion_link::sim::StreamDevice;
use nix::sys::signal::Signal;
use spimotor::{Address, StepDelay, Transaction, Write};
use support::pty_board::PtyBoard;
use support::socket_board::SocketBoard;
use support::*;

type Board = Arc<Mutex<SpimotorSim>>;

fn config(name: &str, socket: &std::path::Path, supervision: &str) -> std::path::PathBuf {
    write_config(
        name,
        &format!(
            r#"[server]
name = "{name}"
tick_hz = 1000
command_timeout_ms = 250

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
min = -1000000.0
max = 1000000.0
max_velocity = 2000.0
max_accel = 20000.0
{supervision}
"#,
            socket.display()
        ),
    )
}

/// Writes into the board as another program on the bus would (SPI writes have no answer).
fn poke(board: &Board, now: Duration, writes: &[Write]) {
    for write in writes {
        let mut mosi = [0u8; 16];
        let n = Transaction::write(Address::DEFAULT, *write)
            .encode(&mut mosi)
            .expect("encodes");
        let mut miso = [0u8; 16];
        board
            .lock()
            .expect("board")
            .transfer(now, &mosi[..n], &mut miso[..n]);
    }
}

/// Sets the stepper running towards a far target at 2500 steps/s (before a server
/// started).
fn run_away_fast(board: &Board, now: Duration) {
    poke(
        board,
        now,
        &[
            Write::StepDelay(StepDelay::from_tenths_ms(4)),
            Write::TargetPosition(900_000),
        ],
    );
}

fn wait_still(board: &Board, timeout: Duration) -> bool {
    let end = Instant::now() + timeout;
    while Instant::now() < end {
        if !board.lock().expect("board").is_moving() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    false
}

#[test]
fn a_stepper_left_running_before_the_server_starts_is_stopped_at_start_up() {
    let name = unique_name("leftover");
    let board: Board = Arc::new(Mutex::new(SpimotorSim::new(SpimotorSimConfig::default())));
    let socket = std::env::temp_dir().join(format!("{name}.sock"));
    let served = SocketBoard::start(&socket, Arc::clone(&board), Instant::now());
    run_away_fast(&board, served.now());
    std::thread::sleep(Duration::from_millis(50));
    board.lock().expect("board").advance(served.now());
    assert!(board.lock().expect("board").is_moving());
    let mut server = Server::start(&config(&name, &socket, ""));
    let client = RawClient::connect(&name, Duration::from_secs(10));
    let (frame, ready) = client.wait_frame(Duration::from_secs(10), axis0_online);
    assert!(ready, "{:?}", frame.axes()[0]);
    assert!(
        wait_still(&board, Duration::from_secs(2)),
        "the start-up stop stopped it"
    );
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}

type Qsb = Arc<Mutex<QsbSim>>;

/// A QSB-M served on a pty, its server, and a client waiting until the board is online.
fn qsb_setup(test: &str, supervision: &str) -> (Qsb, PtyBoard, Instant, Server, RawClient) {
    let name = unique_name(test);
    let epoch = Instant::now();
    let board: Qsb = Arc::new(Mutex::new(QsbSim::new(QsbSimConfig::default())));
    let tty = std::env::temp_dir().join(format!("{name}.tty"));
    let served = PtyBoard::start(&tty, Arc::clone(&board), epoch, 230_400);
    let config = write_config(
        &name,
        &format!(
            r#"[server]
name = "{name}"

[[link]]
name = "usb"
type = "serial"
path = "{}"
baud = 230400

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
min = -1000.0
max = 1000.0
max_velocity = 100.0
max_accel = 1000.0
{supervision}
"#,
            tty.display()
        ),
    );
    let server = Server::start(&config);
    let client = RawClient::connect(&name, Duration::from_secs(10));
    let (frame, ready) = client.wait_frame(Duration::from_secs(10), axis0_online);
    assert!(ready, "{:?}", frame.axes()[0]);
    (board, served, epoch, server, client)
}

/// The command lines the server sent the QSB after `since` (model time).
fn qsb_lines_since(served: &PtyBoard, since: Duration) -> Vec<qsb::CommandLine> {
    let mut decoder = qsb::CommandDecoder::new();
    served
        .received
        .lock()
        .expect("log")
        .iter()
        .filter(|(at, _)| *at >= since)
        .filter_map(|(_, byte)| decoder.push(*byte))
        .filter_map(Result::ok)
        .collect()
}

#[test]
fn an_axis_driven_away_from_its_hold_faults_within_100_ticks_and_is_stopped() {
    let (board, served, epoch, mut server, client) = qsb_setup("ferror", "following_error = 1.0");
    std::thread::sleep(Duration::from_millis(200));
    let before = client.frame();
    assert_eq!(
        before.axes()[0].fault(),
        Ok(FaultCode::None),
        "{:?}",
        before.axes()[0]
    );
    assert_eq!(before.axes()[0].mode(), Ok(motion_ipc::AxisMode::Hold));
    // The motor slips: the encoder turns 50 cycles (200 counts = 2 mm) without a step.
    let slipped_at = epoch.elapsed();
    board.lock().expect("board").nudge_encoder(slipped_at, 50.0);
    let (frame, faulted) = client.wait_frame(Duration::from_secs(2), |f| {
        f.axes()[0].fault() == Ok(FaultCode::FollowingError)
    });
    let axis = frame.axes()[0];
    assert!(faulted, "{axis:?}");
    // Server time, from the last frame before the slip to the faulted frame.
    let ticks = frame.tick - before.tick;
    assert!(ticks <= 100, "FollowingError {ticks} ticks after the slip");
    assert!((axis.fault_value - 2.0).abs() < 0.05, "{axis:?}");
    assert_eq!(axis.fault_limit, 1.0);
    // The stop (category hold) is on the wire: COMMAND 4, motor stop (`W164`).
    std::thread::sleep(Duration::from_millis(100));
    let lines = qsb_lines_since(&served, slipped_at);
    assert!(
        lines.iter().any(|line| line.ty == qsb::CommandType::Write
            && line.register == 0x16
            && line.data == Some(4)),
        "a stop after the slip: {lines:?}"
    );
    assert!(
        server.wait_for_log("following error: 2.0", Duration::from_secs(2)),
        "the fault is logged with its figures: {:#?}",
        server.log
    );
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}

#[test]
fn sigterm_stops_an_axis_the_server_never_commanded_while_its_motor_runs() {
    // Supervision off (with the warnings that say so): only the shutdown can stop it.
    let (board, _served, epoch, mut server, client) =
        qsb_setup("never", "following_error = 0.0\noverspeed_factor = 0.0");
    // Another program makes the motor jog at 800 steps/s (the line ends first, in case the
    // server was half way through one of its own).
    board
        .lock()
        .expect("board")
        .receive(epoch.elapsed(), b"\r\nW12320\r\nW169\r\n");
    let (frame, moving) = client.wait_frame(Duration::from_secs(2), |f| {
        f.axes()[0].flags().contains(AxisFlags::MOVING)
    });
    assert!(moving, "{:?}", frame.axes()[0]);
    assert_eq!(frame.axes()[0].fault(), Ok(FaultCode::None));
    assert_eq!(
        frame.axes()[0].mode(),
        Ok(motion_ipc::AxisMode::Hold),
        "never commanded"
    );
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
    assert!(
        server.log.iter().any(|l| l.contains("every axis stopped")),
        "{:#?}",
        server.log
    );
    assert!(
        server
            .log
            .iter()
            .any(|l| l.contains("following_error") && l.contains("0 turns off")),
        "warned at start: {:#?}",
        server.log
    );
    assert_eq!(
        board.lock().expect("board").motor_velocity(),
        0.0,
        "stopped by the shutdown"
    );
}
