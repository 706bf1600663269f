//! A QSB counter mode end to end, from another process: motiond reads a simulated QSB-D
//! on a pseudo-terminal in x1, modulo-n (DTR 499) with the index resetting the count,
//! as a wheel in degrees. The frames show the angle wrapping within one revolution at a
//! steady velocity, the board's count is the encoder's phase once the index has
//! synchronised it, and the mode's registers were written on the wire.

mod support;

use core::time::Duration;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use board_qsb::sim::{EncoderMotion, QsbSim, QsbSimConfig, Variant};
use motion_ipc::{DeviceState, MotionFrame};
use nix::sys::signal::Signal;
use support::pty_board::PtyBoard;
use support::*;

/// Quadrature cycles per second the wheel turns: 2000 counts/s in x1, 1440 °/s, four
/// revolutions a second.
const CYCLES_PER_S: f64 = 2000.0;

/// The wheel's velocity, °/s.
const DEG_PER_S: f64 = 1440.0;

/// Counts per degree of a 500-cycle encoder counted x1.
const COUNTS_PER_DEG: f64 = 500.0 / 360.0;

fn online(frame: &MotionFrame) -> bool {
    frame.device_state(0) == DeviceState::Online && frame.axes()[0].velocity > 100.0
}

/// The MDR0 and DTR values (`W03…`, `W08…`) the server wrote.
fn counter_writes(served: &PtyBoard) -> Vec<(u8, u32)> {
    let mut decoder = qsb::CommandDecoder::new();
    served
        .received
        .lock()
        .expect("log")
        .iter()
        .filter_map(|(_, byte)| decoder.push(*byte))
        .filter_map(Result::ok)
        .filter(|line| line.ty == qsb::CommandType::Write)
        .filter(|line| matches!(line.register, 0x03 | 0x08))
        .filter_map(|line| Some((line.register, line.data?)))
        .collect()
}

#[test]
fn a_modulo_n_wheel_wraps_in_the_frames_and_its_index_synchronises_the_count() {
    let name = unique_name("qsbmod");
    let epoch = Instant::now();
    let board = Arc::new(Mutex::new(QsbSim::new(QsbSimConfig {
        variant: Variant::D,
        motion: EncoderMotion {
            velocity: CYCLES_PER_S,
            amplitude: 0.0,
            frequency_hz: 0.0,
        },
        ..QsbSimConfig::default()
    })));
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
name = "wheel_qsb"
link = "usb"
model = "qsb"
variant = "qsb-d"
count_mode = "x1"
count_range = "modulo-n"
count_limit = 499
index_action = "reset"

[[axis]]
name = "wheel"
device = "wheel_qsb"
channel = 0
unit = "deg"
counts_per_unit = {COUNTS_PER_DEG:?}
min = 0.0
max = 360.0
max_velocity = 2000.0
max_accel = 20000.0
following_error = 0.0
"#,
            tty.display()
        ),
    );
    let mut server = Server::start(&config);
    let client = RawClient::connect(&name, Duration::from_secs(10));
    let (frame, ready) = client.wait_frame(Duration::from_secs(10), online);
    assert!(ready, "{:?}", frame.axes()[0]);
    // DTR 499 before MDR0 0x6D (sync index, index resets CNTR, modulo-n, x1).
    let writes = counter_writes(&served);
    let dtr = writes.iter().position(|w| *w == (0x08, 499));
    let mdr0 = writes.iter().position(|w| *w == (0x03, 0x6D));
    assert!(
        matches!((dtr, mdr0), (Some(d), Some(m)) if d < m),
        "{writes:?}"
    );

    // The first index re-synchronises the count (the first counts after power-up were
    // counted x4 by the factory mode): a jump the line-noise guard shows a few samples
    // late, with the velocity measured anew. Half a second is two revolutions.
    std::thread::sleep(Duration::from_millis(500));
    // Three seconds of frames: twelve revolutions.
    let end = Instant::now() + Duration::from_secs(3);
    let mut last: Option<MotionFrame> = None;
    let mut wraps = 0;
    let mut frames = 0;
    while Instant::now() < end {
        let frame = client.frame();
        if last.as_ref().is_some_and(|l| l.tick == frame.tick) {
            std::thread::sleep(Duration::from_millis(1));
            continue;
        }
        frames += 1;
        let axis = frame.axes()[0];
        assert!(
            (0.0..360.0).contains(&axis.position),
            "within one revolution: {axis:?}"
        );
        assert_eq!(axis.fault, 0, "{axis:?}");
        // Through every wrap (the velocity is measured over 8 samples: ±1 count of 31).
        assert!(
            (axis.velocity - DEG_PER_S).abs() < DEG_PER_S * 0.05,
            "steady velocity: {axis:?}"
        );
        if let Some(before) = &last
            && axis.position < before.axes()[0].position - 180.0
        {
            wraps += 1;
        }
        last = Some(frame);
    }
    assert!(frames > 100, "{frames} frames");
    assert!(wraps >= 10, "{wraps} wraps in 3 s at 4 revolutions/s");

    // The index reset the count at a revolution: the count is the encoder's phase (the
    // first counts, before the driver set x1, were counted x4 by the factory mode).
    {
        let sim = board.lock().expect("board");
        let phase = sim.encoder_position().rem_euclid(500.0).floor();
        let count = f64::from(sim.counter());
        let off = (count - phase).rem_euclid(500.0);
        assert!(off <= 1.0 || off >= 499.0, "count {count}, phase {phase}");
    }
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}
