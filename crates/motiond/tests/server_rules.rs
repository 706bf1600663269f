//! Issue 30's rules, from other processes' point of view (this test's iceoryx2 nodes against
//! a motiond child process):
//! - a reset ends no claim: after client B's reset, client A still holds its axis and B's
//!   move is refused;
//! - a link that opens late: its boards are starting, never "link is down", until it first
//!   opened; a move sent the moment the server first answers succeeds or is refused as
//!   starting;
//! - values: a digital output takes 0 or 1, nothing else.

mod support;

use core::time::Duration;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use board_qq2drv::sim::{Qq2drvSim, Qq2drvSimConfig};
use board_qsb::sim::{QsbSim, QsbSimConfig};
use board_tmcpack::sim::{TmcpackSim, TmcpackSimConfig};
use motion_ipc::{
    AxisFlags, ClientId, CommandKind, CommandRequest, DeviceState, MotionFrame, Reason, SignalFlags,
};
use nix::sys::signal::Signal;
use support::pty_board::PtyBoard;
use support::socket_board::SocketBoard;
use support::*;

/// A simulated SPI_motor stepper, axis `a` (index 0).
fn sim_config(name: &str) -> std::path::PathBuf {
    stepper_config(name, "liveness_check_ms = 50")
}

fn online(frame: &MotionFrame) -> bool {
    (0..frame.device_count as usize).all(|d| frame.device_state(d) == DeviceState::Online)
        && frame
            .axes()
            .iter()
            .all(|a| !a.flags().contains(AxisFlags::STALE))
}

#[test]
fn after_another_client_s_reset_the_claim_holds_and_the_other_s_move_is_refused() {
    let name = unique_name("rstclaim");
    let mut server = Server::start(&sim_config(&name));
    let mut a = RawClient::connect(&name, Duration::from_secs(10));
    let mut b = RawClient::connect(&name, Duration::from_secs(10));
    let (frame, up) = a.wait_frame(Duration::from_secs(10), online);
    assert!(up, "{:?}", frame.axes());
    assert_eq!(a.command(0, CommandKind::Claim, [0.0; 3]).result(), Ok(()));
    assert_eq!(
        b.command(0, CommandKind::RampPosition, [100.0, 0.0, 0.0])
            .result(),
        Err(Reason::ClaimedByOther)
    );
    // Nothing is latched: B's reset is accepted and clears nothing of A's.
    assert_eq!(
        b.command(CommandRequest::ALL_AXES, CommandKind::Reset, [0.0; 3])
            .result(),
        Ok(())
    );
    assert_eq!(
        b.command(0, CommandKind::RampPosition, [100.0, 0.0, 0.0])
            .result(),
        Err(Reason::ClaimedByOther),
        "a reset hands no axis over"
    );
    let (frame, held) = a.wait_frame(Duration::from_secs(1), |f| f.axes()[0].claimed_by == a.id());
    assert!(held, "{:?}", frame.axes()[0]);
    // A's move goes on through B's reset.
    assert_eq!(
        a.command(0, CommandKind::RampPosition, [2000.0, 0.0, 0.0])
            .result(),
        Ok(())
    );
    let reset = b.command(CommandRequest::ALL_AXES, CommandKind::Reset, [0.0; 3]);
    assert_eq!(reset.result(), Ok(()));
    // The frame of the reset's tick or later: the move still runs to its target, A's.
    let (frame, seen) = a.wait_frame(Duration::from_secs(2), |f| f.tick >= reset.tick_applied);
    assert!(seen, "tick {} never published", reset.tick_applied);
    let axis = frame.axes()[0];
    assert_eq!(
        axis.mode(),
        Ok(motion_ipc::AxisMode::RampPosition),
        "{axis:?}"
    );
    assert_eq!(axis.target, 2000.0, "{axis:?}");
    assert_eq!(axis.claimed_by, a.id());
    // A's release is what frees the axis.
    assert_eq!(
        a.command(0, CommandKind::Release, [0.0; 3]).result(),
        Ok(())
    );
    assert_eq!(
        b.command(0, CommandKind::RampPosition, [0.0, 0.0, 0.0])
            .result(),
        Ok(())
    );
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}

/// A SIXpack on a serial link at `tty`: axis `six0` (channel 0).
fn tmcpack_config(name: &str, tty: &std::path::Path) -> std::path::PathBuf {
    tmcpack_config_on(
        name,
        &format!(
            "type = \"serial\"\npath = \"{}\"\nbaud = 19200",
            tty.display()
        ),
    )
}

/// A SIXpack at address 1 on the link `rs485` (its keys after the name: `link_keys`): axis
/// `six0` (channel 0) at 640 µsteps/mm, 10 mm/s, 50 mm/s².
fn tmcpack_config_on(name: &str, link_keys: &str) -> std::path::PathBuf {
    write_config(
        name,
        &format!(
            r#"[server]
name = "{name}"

[[link]]
name = "rs485"
{link_keys}

[[device]]
name = "pack"
link = "rs485"
model = "tmcpack"
address = 1

[[axis]]
name = "six0"
device = "pack"
channel = 0
unit = "mm"
counts_per_unit = 640.0
min = -1000.0
max = 1000.0
max_velocity = 10.0
max_accel = 50.0
"#
        ),
    )
}

#[test]
fn a_move_on_a_pty_link_that_opens_late_is_refused_as_starting_never_link_down_then_works() {
    let name = unique_name("latelink");
    let tty = std::env::temp_dir().join(format!("{name}.tty"));
    let _ = std::fs::remove_file(&tty);
    let server = Server::start(&tmcpack_config(&name, &tty));
    late_link(&name, server, "pack", || {
        let pack = Arc::new(Mutex::new(TmcpackSim::new(TmcpackSimConfig::default())));
        Box::new(PtyBoard::start(&tty, pack, Instant::now(), 19_200))
    });
    let _ = std::fs::remove_file(&tty);
}

/// The same on an SPI socket whose peer (a QuadQuad2Drv) starts listening late.
#[test]
fn a_move_on_an_spi_socket_that_opens_late_is_refused_as_starting_then_works() {
    let name = unique_name("latesock");
    let socket = std::env::temp_dir().join(format!("{name}.sock"));
    let _ = std::fs::remove_file(&socket);
    let config = write_config(
        &name,
        &format!(
            r#"[server]
name = "{name}"

[[link]]
name = "spi"
type = "spi-socket"
path = "{}"

[[device]]
name = "drive"
link = "spi"
model = "qq2drv"

[[axis]]
name = "wheel"
device = "drive"
channel = 0
unit = "deg"
counts_per_unit = 10.0
min = -1000.0
max = 1000.0
max_velocity = 100.0
max_accel = 1000.0
"#,
            socket.display()
        ),
    );
    let server = Server::start(&config);
    late_link(&name, server, "drive", || {
        let board = Arc::new(Mutex::new(Qq2drvSim::new(Qq2drvSimConfig::default())));
        Box::new(SocketBoard::start(&socket, board, Instant::now()))
    });
    let _ = std::fs::remove_file(&socket);
}

/// Axis 0's device (named `device`) is on a link that is not there yet: from the moment the
/// server first answers it is starting, a move is refused as starting (never link down, never
/// offline, no fault) and the operator is told why; once `plug_in` serves the board the same
/// move is taken, having been refused only as starting.
fn late_link(
    name: &str,
    mut server: Server,
    device: &str,
    plug_in: impl FnOnce() -> Box<dyn std::any::Any>,
) {
    let mut client = RawClient::connect(name, Duration::from_secs(10));
    let first = client.command(0, CommandKind::RampPosition, [1.0, 0.0, 0.0]);
    assert_eq!(
        first.result(),
        Err(Reason::DeviceStarting),
        "no board on the link yet"
    );
    // For a while (several of the I/O thread's opening attempts): starting, not down.
    let until = Instant::now() + Duration::from_millis(600);
    while Instant::now() < until {
        let frame = client.frame();
        assert_eq!(
            frame.device_state(0),
            DeviceState::Starting,
            "tick {}",
            frame.tick
        );
        let axis = frame.axes()[0];
        assert!(!axis.flags().contains(AxisFlags::FAULT), "{axis:?}");
        let refused = client.command(0, CommandKind::Velocity, [1.0, 0.0, 0.0]);
        assert_eq!(refused.result(), Err(Reason::DeviceStarting));
        std::thread::sleep(Duration::from_millis(50));
    }
    assert!(
        server.wait_for_log("not open yet", Duration::from_secs(5)),
        "the operator is told why: {}",
        server.log_text()
    );
    // The board appears: the link opens, the board starts, the move is taken.
    let _board = plug_in();
    let mut answers = Vec::new();
    let end = Instant::now() + Duration::from_secs(15);
    let mut accepted = false;
    while Instant::now() < end && !accepted {
        let reply = client.command(0, CommandKind::RampPosition, [1.0, 0.0, 0.0]);
        match reply.result() {
            Ok(()) => accepted = true,
            Err(reason) => answers.push(reason),
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(accepted, "never accepted: {answers:?}");
    assert!(
        answers.iter().all(|r| *r == Reason::DeviceStarting),
        "refused otherwise than as starting: {answers:?}"
    );
    let log = server.log_text();
    assert!(
        !log.contains(&format!("`{device}` is not answering")),
        "{log}"
    );
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}

/// A move sent the moment the server first answers, with the board's tty there from the
/// start: accepted or refused as starting, never "link is down".
#[test]
fn a_move_sent_as_soon_as_the_server_answers_is_taken_or_refused_as_starting() {
    let name = unique_name("firstmove");
    let tty = std::env::temp_dir().join(format!("{name}.tty"));
    let epoch = Instant::now();
    let pack = Arc::new(Mutex::new(TmcpackSim::new(TmcpackSimConfig::default())));
    let _board = PtyBoard::start(&tty, Arc::clone(&pack), epoch, 19_200);
    let mut server = Server::start(&tmcpack_config(&name, &tty));
    let mut client = RawClient::connect(&name, Duration::from_secs(10));
    let mut answers = Vec::new();
    let end = Instant::now() + Duration::from_secs(15);
    loop {
        let reason = client
            .command(0, CommandKind::RampPosition, [1.0, 0.0, 0.0])
            .result();
        answers.push(reason);
        if reason.is_ok() || Instant::now() > end {
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    assert_eq!(answers.last(), Some(&Ok(())), "{answers:?}");
    assert!(
        answers
            .iter()
            .all(|r| *r == Ok(()) || *r == Err(Reason::DeviceStarting)),
        "{answers:?}"
    );
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}

/// Sends a `SetOutput` of `value` to signal `signal`.
fn set_output(client: &RawClient, signal: u32, value: f64) -> Result<(), Reason> {
    let request = CommandRequest::for_signal(ClientId::NONE, 0, signal, CommandKind::SetOutput)
        .with_values([value, 0.0, 0.0]);
    client
        .request(request, Duration::from_secs(2))
        .expect("a reply")
        .result()
}

#[test]
fn a_digital_output_takes_0_or_1_and_nothing_else() {
    let name = unique_name("outval");
    let epoch = Instant::now();
    let board = Arc::new(Mutex::new(QsbSim::new(QsbSimConfig::default())));
    let tty = std::env::temp_dir().join(format!("{name}.tty"));
    let _served = PtyBoard::start(&tty, Arc::clone(&board), epoch, 230_400);
    let config = qsb_io_config(
        &name,
        &tty,
        r#"[[signal]]
name = "lamp"
device = "io_board"
pin = "io0"
kind = "digital-out"
"#,
    );
    let mut server = Server::start(&config);
    let client = RawClient::connect(&name, Duration::from_secs(10));
    let (frame, ready) = client.wait_frame(Duration::from_secs(10), |f| {
        f.device_state(0) == DeviceState::Online
            && !f.signals()[0].flags().contains(SignalFlags::STALE)
    });
    assert!(ready, "{:?}", frame.signals());
    assert_eq!(set_output(&client, 0, 1.0), Ok(()));
    let (frame, on) = client.wait_frame(Duration::from_secs(2), |f| {
        f.signals()[0].value == 1.0 && !f.signals()[0].flags().contains(SignalFlags::PENDING)
    });
    assert!(on, "{:?}", frame.signals()[0]);
    for value in [0.5, 2.0, -1.0, 5e-324] {
        assert_eq!(
            set_output(&client, 0, value),
            Err(Reason::OutOfRange),
            "{value:e}"
        );
    }
    // Nothing of that changed the output.
    std::thread::sleep(Duration::from_millis(50));
    assert_eq!(client.frame().signals()[0].value, 1.0);
    assert_eq!(set_output(&client, 0, 0.0), Ok(()));
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}

/// A simulated SIXpack, axis `six0` at 640 µsteps/mm and 10 mm/s (6400 µsteps/s). The
/// manual ("Instruction Set"): f = f_clk / (clkdiv + 1) · v / 2^(14 + div), "clkdiv is the
/// same for all motors (range 0..31)", v up to 511; so the pack runs at clkdiv 31 and div 1
/// (the largest div at which v = 511 still reaches 6400 µsteps/s): one velocity unit is
/// 20 MHz / 32 / 2^15 = 19.07 µsteps/s (0.0298 mm/s), one amax unit 500/64 of that per
/// second ("1/64 amax is accumulated with 500Hz"). Slower rates are refused, never rounded
/// up to the pack's step.
#[test]
fn rates_below_the_pack_s_smallest_step_are_refused_and_at_it_taken() {
    let name = unique_name("floor");
    let config = tmcpack_config_on(&name, r#"type = "sim""#);
    let mut server = Server::start(&config);
    let mut client = RawClient::connect(&name, Duration::from_secs(10));
    let (frame, up) = client.wait_frame(Duration::from_secs(10), online);
    assert!(up, "{:?}", frame.axes());
    let unit = 20e6 / 32.0 / 32768.0 / 640.0;
    let amax = unit * 500.0 / 64.0;
    for (kind, values, reason) in [
        (
            CommandKind::RampPosition,
            [10.0, 0.0, 5e-324],
            Reason::AccelLimit,
        ),
        (
            CommandKind::RampVelocity,
            [1.0, 0.9 * amax, 0.0],
            Reason::AccelLimit,
        ),
        (
            CommandKind::RampVelocity,
            [0.9 * unit, 0.0, 0.0],
            Reason::VelocityLimit,
        ),
        (
            CommandKind::RampPosition,
            [10.0, 0.9 * unit, 0.0],
            Reason::VelocityLimit,
        ),
        (
            CommandKind::Velocity,
            [5e-324, 0.0, 0.0],
            Reason::VelocityLimit,
        ),
    ] {
        assert_eq!(
            client.command(0, kind, values).result(),
            Err(reason),
            "{kind:?} {values:?}"
        );
        assert_eq!(
            client.frame().axes()[0].mode(),
            Ok(motion_ipc::AxisMode::Hold)
        );
    }
    assert_eq!(
        client
            .command(
                0,
                CommandKind::RampPosition,
                [0.5, 1.001 * unit, 1.001 * amax]
            )
            .result(),
        Ok(())
    );
    assert_eq!(
        client.command(0, CommandKind::Stop, [0.0; 3]).result(),
        Ok(())
    );
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}
