//! Board I/O as named signals, from another process: motiond drives boards this test serves
//! (a QSB-M on a pseudo-terminal, a QuadQuad2Drv on an SPI socket); the test changes their
//! inputs and reads their outputs.
//! - an input change shows in the frame within the board's refresh budget;
//! - a set-output reaches the board's output (the command decoded with the protocol crate);
//! - an e-stop puts an output into its safe state.

mod support;

use core::time::Duration;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use board_qq2drv::sim::{Qq2drvSim, Qq2drvSimConfig};
use board_qsb::sim::{QsbSim, QsbSimConfig};
use motion_ipc::{
    ClientId, CommandKind, CommandReply, CommandRequest, DeviceState, FrameFlags, MotionFrame,
    SignalFlags,
};
use nix::sys::signal::Signal;
use support::pty_board::PtyBoard;
use support::socket_board::SocketBoard;
use support::*;

fn online(frame: &MotionFrame) -> bool {
    (0..frame.device_count as usize).all(|d| frame.device_state(d) == DeviceState::Online)
        && frame
            .signals()
            .iter()
            .all(|s| !s.flags().contains(SignalFlags::STALE))
}

/// Sends a request about signal `signal`.
fn signal_command(
    client: &mut RawClient,
    signal: u32,
    kind: CommandKind,
    value: f64,
) -> CommandReply {
    let request =
        CommandRequest::for_signal(ClientId::NONE, 0, signal, kind).with_values([value, 0.0, 0.0]);
    let pending = client.commands.send_copy(request).expect("send");
    let end = Instant::now() + Duration::from_secs(2);
    while Instant::now() < end {
        if let Ok(Some(reply)) = pending.receive() {
            return *reply;
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    panic!("no reply");
}

/// The DIG I/O values (`W01…`) the server wrote since `since`.
fn dig_io_writes(served: &PtyBoard, since: Duration) -> Vec<u32> {
    let mut decoder = qsb::CommandDecoder::new();
    served
        .received
        .lock()
        .expect("log")
        .iter()
        .filter(|(at, _)| *at >= since)
        .filter_map(|(_, byte)| decoder.push(*byte))
        .filter_map(Result::ok)
        .filter(|line| line.ty == qsb::CommandType::Write && line.register == 0x01)
        .filter_map(|line| line.data)
        .collect()
}

#[test]
fn qsb_inputs_show_outputs_reach_the_board_and_an_e_stop_makes_them_safe() {
    let name = unique_name("qsbio");
    let epoch = Instant::now();
    let board = Arc::new(Mutex::new(QsbSim::new(QsbSimConfig::default())));
    let tty = std::env::temp_dir().join(format!("{name}.tty"));
    let served = PtyBoard::start(&tty, Arc::clone(&board), epoch, 230_400);
    let config = qsb_io_config(
        &name,
        &tty,
        r#"[[signal]]
name = "lamp"
device = "io_board"
pin = "io0"
kind = "digital-out"
safe = false

[[signal]]
name = "door_closed"
device = "io_board"
pin = "io3"
kind = "digital-in"
invert = true
"#,
    );
    let mut server = Server::start(&config);
    let mut client = RawClient::connect(&name, Duration::from_secs(10));
    let (frame, ready) = client.wait_frame(Duration::from_secs(10), online);
    assert!(ready, "{:?}", frame.signals());
    assert_eq!(frame.signal_count, 2);
    // The input: nothing pulls io3 low (pull-up), so the inverted `door_closed` is 0.
    assert_eq!(frame.signals[1].value, 0.0);
    let before = client.frame();
    board
        .lock()
        .expect("board")
        .set_digital_inputs(epoch.elapsed(), 0b0111);
    let (frame, seen) = client.wait_frame(Duration::from_secs(2), |f| f.signals[1].value == 1.0);
    assert!(seen, "{:?}", frame.signals[1]);
    // Within the refresh budget (4 stream periods of 1.95 ms + the wire + 5 ms host latency).
    let ticks = frame.tick - before.tick;
    assert!(ticks <= 25, "the switch showed {ticks} ticks later");

    // The output: off (pulled low), then on (released high), each decoded on the wire as a
    // DIG I/O write.
    let since = epoch.elapsed();
    let reply = signal_command(&mut client, 0, CommandKind::SetOutput, 0.0);
    assert_eq!(reply.result(), Ok(()));
    let (frame, off) = client.wait_frame(Duration::from_secs(2), |f| {
        f.signals[0].value == 0.0 && !f.signals[0].flags().contains(SignalFlags::PENDING)
    });
    assert!(off, "{:?}", frame.signals[0]);
    let writes = dig_io_writes(&served, since);
    assert!(
        writes.iter().any(|v| v & 1 == 0),
        "DIG I/O written: {writes:?}"
    );
    let (outputs, latch) = board.lock().expect("board").digital_outputs();
    assert_eq!(
        (outputs & 1, latch & 1),
        (1, 0),
        "io0 is an output, pulled low"
    );
    let since = epoch.elapsed();
    let reply = signal_command(&mut client, 0, CommandKind::SetOutput, 1.0);
    assert_eq!(reply.result(), Ok(()));
    let (frame, on) = client.wait_frame(Duration::from_secs(2), |f| {
        f.signals[0].value == 1.0 && !f.signals[0].flags().contains(SignalFlags::PENDING)
    });
    assert!(on, "{:?}", frame.signals[0]);
    let writes = dig_io_writes(&served, since);
    assert!(
        writes.iter().any(|v| v & 1 == 1),
        "DIG I/O written: {writes:?}"
    );
    let (outputs, latch) = board.lock().expect("board").digital_outputs();
    assert_eq!(
        (outputs & 1, latch & 1),
        (1, 1),
        "io0 is an output, released high"
    );

    // E-stop: the lamp goes to its safe state (off).
    let estop = client.command(CommandRequest::ALL_AXES, CommandKind::EStop, [0.0; 3]);
    assert_eq!(estop.result(), Ok(()));
    let (frame, safe) = client.wait_frame(Duration::from_secs(2), |f| {
        f.flags().contains(FrameFlags::ESTOP_LATCHED)
            && f.signals[0].flags().contains(SignalFlags::SAFE_STATE)
            && f.signals[0].value == 0.0
    });
    assert!(safe, "{:?}", frame.signals[0]);
    assert_eq!(
        board.lock().expect("board").digital_outputs().1 & 1,
        0,
        "pulled low"
    );
    let refused = signal_command(&mut client, 0, CommandKind::SetOutput, 1.0);
    assert_eq!(refused.result(), Err(motion_ipc::Reason::EstopLatched));
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}

#[test]
fn qq2drv_in_pins_show_in_the_frame() {
    let name = unique_name("qq2io");
    let board = Arc::new(Mutex::new(Qq2drvSim::new(Qq2drvSimConfig::default())));
    let socket = std::env::temp_dir().join(format!("{name}.sock"));
    let _served = SocketBoard::start(&socket, Arc::clone(&board), Instant::now());
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

[[signal]]
name = "end_stop"
device = "drive"
pin = "in2"
kind = "digital-in"
"#,
            socket.display()
        ),
    );
    let mut server = Server::start(&config);
    let client = RawClient::connect(&name, Duration::from_secs(10));
    let (frame, ready) = client.wait_frame(Duration::from_secs(10), online);
    assert!(ready, "{:?}", frame.signals());
    let initial = frame.signals[0].value;
    let before = client.frame();
    // Drive the IN pin to the other level (the board reports Input Active after its
    // polarity: an unconfigured pin is active low).
    let level_high = initial == 1.0;
    board
        .lock()
        .expect("board")
        .force_input_level(1, Some(level_high));
    let (frame, seen) =
        client.wait_frame(Duration::from_secs(2), |f| f.signals[0].value != initial);
    assert!(seen, "{:?}", frame.signals[0]);
    let ticks = frame.tick - before.tick;
    assert!(ticks <= 25, "the pin showed {ticks} ticks later");
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}

#[test]
fn tmcpack_inputs_show_outputs_reach_the_pack_and_an_e_stop_makes_them_safe() {
    use board_tmcpack::sim::{TmcpackSim, TmcpackSimConfig};
    let name = unique_name("tmcio");
    let epoch = Instant::now();
    let pack = Arc::new(Mutex::new(TmcpackSim::new(TmcpackSimConfig::default())));
    let tty = std::env::temp_dir().join(format!("{name}.tty"));
    let served = PtyBoard::start(&tty, Arc::clone(&pack), epoch, 19_200);
    let config = write_config(
        &name,
        &format!(
            r#"[server]
name = "{name}"

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

[[signal]]
name = "beacon"
device = "pack"
pin = "ttlout1"
kind = "digital-out"
safe = false

[[signal]]
name = "pressure"
device = "pack"
pin = "analog6"
kind = "analog-in"
scale = 0.01
unit = "bar"
"#,
            tty.display()
        ),
    );
    let mut server = Server::start(&config);
    let mut client = RawClient::connect(&name, Duration::from_secs(10));
    let (frame, ready) = client.wait_frame(Duration::from_secs(15), online);
    assert!(ready, "{:?}", frame.signals());
    // The analogue input: the external input moves to 500 counts = 5.00 bar.
    let before = client.frame();
    pack.lock().expect("pack").set_analog(6, 500);
    let (frame, seen) = client.wait_frame(Duration::from_secs(3), |f| {
        (f.signals[1].value - 5.0).abs() < 0.011
    });
    assert!(seen, "{:?}", frame.signals[1]);
    let budget_ticks = 1000; // the pack's refresh budget, in 1 ms ticks, is well below a second
    assert!(
        frame.tick - before.tick < budget_ticks,
        "{} ticks",
        frame.tick - before.tick
    );
    // The output: on, decoded on the wire as `$32` with TTLOUT1 set, seen on the pack.
    let since = epoch.elapsed();
    let reply = signal_command(&mut client, 0, CommandKind::SetOutput, 1.0);
    assert_eq!(reply.result(), Ok(()));
    let (frame, on) = client.wait_frame(Duration::from_secs(3), |f| {
        f.signals[0].value == 1.0 && !f.signals[0].flags().contains(SignalFlags::PENDING)
    });
    assert!(on, "{:?}", frame.signals[0]);
    // The driver shows the level once the `$32` is on the wire; the pack applies it a few
    // milliseconds later, when its nine bytes have arrived at 19200 baud.
    let end = Instant::now() + Duration::from_secs(2);
    while !pack.lock().expect("pack").ttlout1() && Instant::now() < end {
        std::thread::sleep(Duration::from_millis(5));
    }
    assert!(
        pack.lock().expect("pack").ttlout1(),
        "TTLOUT1 high on the pack"
    );
    let words: Vec<u8> = served
        .received
        .lock()
        .expect("log")
        .iter()
        .filter(|(at, _)| *at >= since)
        .map(|(_, byte)| *byte)
        .collect();
    // The log may begin inside a frame: try every offset (the checksum rejects false starts).
    let outputs = words
        .windows(9)
        .filter_map(|word| tmcpack::RequestFrame::decode(word).ok())
        .any(|frame| {
            matches!(
                frame.request,
                tmcpack::Request::Outputs { ttlout1: true, .. }
            )
        });
    assert!(outputs, "a $32 with TTLOUT1 set went out");
    // E-stop: the beacon goes to its safe state (off).
    let estop = client.command(CommandRequest::ALL_AXES, CommandKind::EStop, [0.0; 3]);
    assert_eq!(estop.result(), Ok(()));
    let (frame, safe) = client.wait_frame(Duration::from_secs(3), |f| {
        f.signals[0].flags().contains(SignalFlags::SAFE_STATE) && f.signals[0].value == 0.0
    });
    assert!(safe, "{:?}", frame.signals[0]);
    let end = Instant::now() + Duration::from_secs(2);
    while pack.lock().expect("pack").ttlout1() && Instant::now() < end {
        std::thread::sleep(Duration::from_millis(10));
    }
    assert!(
        !pack.lock().expect("pack").ttlout1(),
        "TTLOUT1 low on the pack"
    );
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}
