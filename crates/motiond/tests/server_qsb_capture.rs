//! Capture, the trigger output and an axis's own hold end to end, from another process:
//! motiond drives a simulated QSB-M on a pseudo-terminal (the feeder of the simulated
//! robot: 100 counts/mm, 10 counts per step) with a probe on io3 (`capture_input`) and a
//! camera trigger on io0 pulsed when the count matches 20 mm (`trigger_on = ["match"]`,
//! `compare_position`). The frames show every pulse and every capture as an event with
//! its tick; a new compare position goes out as DTR; `Hold` and `Resume` of the axis go
//! out as COMMAND 6 and 7 and the move ends at its target.

mod support;

use core::time::Duration;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use board_qsb::sim::{QsbSim, QsbSimConfig, Variant};
use motion_ipc::{
    AxisFlags, AxisMode, CommandKind, CommandRequest, MotionFrame, Reason, SignalFlags, SignalKind,
};
use nix::sys::signal::Signal;
use support::pty_board::PtyBoard;
use support::*;

const PROBE: usize = 0;
const CAMERA: usize = 1;

/// The command lines the server wrote to the board, in order.
fn written(served: &PtyBoard) -> Vec<String> {
    let mut decoder = qsb::CommandDecoder::new();
    let mut lines = Vec::new();
    let mut line = Vec::new();
    for (_, byte) in served.received.lock().expect("log").iter() {
        line.push(*byte);
        if decoder.push(*byte).is_some() {
            lines.push(String::from_utf8_lossy(&line).trim().to_owned());
            line.clear();
        }
    }
    lines
}

fn arrived_at(target: f64) -> impl Fn(&MotionFrame) -> bool {
    move |frame| {
        let axis = frame.axes()[0];
        axis.flags().contains(AxisFlags::ARRIVED) && (axis.position - target).abs() < 0.05
    }
}

#[test]
fn pulses_and_captures_are_events_in_the_frames_and_a_held_move_resumes() {
    let name = unique_name("qsbcap");
    let epoch = Instant::now();
    let board = Arc::new(Mutex::new(QsbSim::new(QsbSimConfig {
        variant: Variant::M,
        // 10 counts per step, x4: 2.5 quadrature cycles per step.
        cycles_per_step: 2.5,
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
name = "feeder_qsb"
link = "usb"
model = "qsb"
counts_per_step = 10.0
capture_input = 3
trigger_on = ["match"]
compare_position = 20.0

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

[[signal]]
name = "probe"
device = "feeder_qsb"
pin = "capture"
kind = "capture"

[[signal]]
name = "camera"
device = "feeder_qsb"
pin = "trigger"
kind = "trigger"
"#,
            tty.display()
        ),
    );
    let mut server = Server::start(&config);
    let mut client = RawClient::connect(&name, Duration::from_secs(10));
    let (frame, ready) = client.wait_frame(Duration::from_secs(10), |frame| {
        axis0_online(frame) && !frame.signals()[CAMERA].flags().contains(SignalFlags::STALE)
    });
    assert!(ready, "{:?} {:?}", frame.axes()[0], frame.signals());
    let camera = frame.signals()[CAMERA];
    assert_eq!(camera.kind, SignalKind::Trigger as u8);
    assert_eq!(
        (camera.value, camera.sequence),
        (20.0, 0),
        "20 mm, in the axis's unit"
    );
    assert_eq!(frame.signals()[PROBE].sequence, 0);
    let lines = written(&served);
    for line in ["W087D0", "W0420", "W021180", "S05", "S06"] {
        assert!(lines.iter().any(|l| l == line), "{line} in {lines:?}");
    }

    // Through 20 mm: one pulse on io0, one event in the frames.
    let reply = client.command(0, CommandKind::RampPosition, [40.0, 0.0, 0.0]);
    assert_eq!(reply.result(), Ok(()));
    let (frame, done) = client.wait_frame(Duration::from_secs(10), |frame| {
        arrived_at(40.0)(frame) && frame.signals()[CAMERA].sequence == 1
    });
    assert!(done, "{:?} {:?}", frame.axes()[0], frame.signals()[CAMERA]);
    assert_eq!(board.lock().expect("board").trigger_pulses(), 1);
    let camera = frame.signals()[CAMERA];
    assert!(camera.event_tick > reply.tick_applied, "{camera:?}");

    // A new compare position at run time: DTR 3000 (30 mm); back through it.
    let request =
        CommandRequest::for_signal(client.id(), 99, CAMERA as u32, CommandKind::SetOutput)
            .with_values([30.0, 0.0, 0.0]);
    let reply = client
        .request(request, Duration::from_secs(2))
        .expect("answered");
    assert_eq!(reply.result(), Ok(()));
    let (frame, set) = client.wait_frame(Duration::from_secs(5), |frame| {
        let camera = frame.signals()[CAMERA];
        camera.value == 30.0 && !camera.flags().contains(SignalFlags::PENDING)
    });
    assert!(set, "{:?}", frame.signals()[CAMERA]);
    assert!(written(&served).iter().any(|l| l == "W08BB8"));
    client.command(0, CommandKind::RampPosition, [10.0, 0.0, 0.0]);
    let (frame, done) = client.wait_frame(Duration::from_secs(10), |frame| {
        arrived_at(10.0)(frame) && frame.signals()[CAMERA].sequence == 2
    });
    assert!(done, "{:?} {:?}", frame.axes()[0], frame.signals()[CAMERA]);

    // The probe: a rising edge on io3 captures the count (10 mm = 1000 counts).
    let before = client.frame();
    {
        let mut sim = board.lock().expect("board");
        let now = epoch.elapsed();
        sim.set_digital_inputs(now, 0b0111);
        sim.set_digital_inputs(now + Duration::from_millis(5), 0b1111);
    }
    let (frame, captured) = client.wait_frame(Duration::from_secs(5), |frame| {
        frame.signals()[PROBE].sequence == 1
    });
    assert!(captured, "{:?}", frame.signals()[PROBE]);
    let probe = frame.signals()[PROBE];
    assert!((probe.value - 10.0).abs() < 0.05, "{probe:?}");
    assert!(probe.event_tick > before.tick);

    // Hold a slow move on its way: COMMAND 6, the axis comes to rest short of its target
    // and stays; Resume: COMMAND 7, and it arrives.
    client.command(0, CommandKind::RampPosition, [80.0, 20.0, 0.0]);
    std::thread::sleep(Duration::from_millis(700));
    let reply = client.command(0, CommandKind::Hold, [0.0; 3]);
    assert_eq!(reply.result(), Ok(()));
    let (frame, held) = client.wait_frame(Duration::from_secs(5), |frame| {
        let axis = frame.axes()[0];
        axis.mode() == Ok(AxisMode::Hold) && axis.flags().contains(AxisFlags::HELD)
    });
    assert!(held, "{:?}", frame.axes()[0]);
    let at = frame.axes()[0].position;
    assert!(at > 15.0 && at < 70.0, "held on its way: {at}");
    std::thread::sleep(Duration::from_millis(300));
    assert!(
        (client.frame().axes()[0].position - at).abs() < 0.05,
        "stays held"
    );
    let lines = written(&served);
    assert!(lines.iter().any(|l| l == "W166"), "COMMAND 6 in {lines:?}");
    assert_eq!(
        client.command(0, CommandKind::Hold, [0.0; 3]).result(),
        Ok(()),
        "held already"
    );
    assert_eq!(
        client.command(0, CommandKind::Resume, [0.0; 3]).result(),
        Ok(())
    );
    let (frame, done) = client.wait_frame(Duration::from_secs(10), arrived_at(80.0));
    assert!(done, "{:?}", frame.axes()[0]);
    assert!(written(&served).iter().any(|l| l == "W167"), "COMMAND 7");
    assert_eq!(
        client.command(0, CommandKind::Resume, [0.0; 3]).result(),
        Err(Reason::NotMoving)
    );
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}
