//! The black box of a running motiond (docs/ARCHITECTURE.md "The black box"): a simulated
//! QSB-M on a pty driven through a move, a jog, an e-stop and a following-error fault; the
//! e-stop and the fault each save the ring, SIGUSR2 saves the whole run; `motiond --replay`
//! gives every frame again, and one byte changed in what the board said is found at the
//! tick it was said. And the default simulated robot with a ring of 2 s that wraps: its
//! save replays from the state snapshot in it.

mod support;

use core::time::Duration;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use board_qsb::sim::{QsbSim, QsbSimConfig};
use motion_blackbox::record::Kind;
use motion_blackbox::{BlackboxFile, Recording};
use motion_ipc::{CommandKind, CommandRequest, FaultCode};
use nix::sys::signal::Signal;
use support::pty_board::PtyBoard;
use support::*;

/// The path of the first "black box saved (reasons): PATH (N ticks)" log line whose
/// reasons include `why` (triggers within 300 ms make one save).
fn saved_path(server: &mut Server, why: &str) -> PathBuf {
    const NEEDLE: &str = "black box saved (";
    let found = |line: &String| {
        let rest = &line[line.find(NEEDLE)? + NEEDLE.len()..];
        let (reasons, rest) = rest.split_once("): ")?;
        reasons
            .split(", ")
            .any(|reason| reason == why)
            .then(|| PathBuf::from(rest.split(" (").next().unwrap_or(rest)))
    };
    let end = Instant::now() + Duration::from_secs(5);
    loop {
        if let Some(path) = server.log.iter().find_map(found) {
            return path;
        }
        assert!(Instant::now() < end, "no {why} save: {:#?}", server.log);
        std::thread::sleep(Duration::from_millis(50));
        server.drain_log();
    }
}

/// SIGUSR2 (save the ring), the file saved, then SIGTERM and a clean exit.
fn save_and_stop(server: &mut Server) -> PathBuf {
    nix::sys::signal::kill(
        nix::unistd::Pid::from_raw(server.pid() as i32),
        Signal::SIGUSR2,
    )
    .expect("SIGUSR2");
    let saved = saved_path(server, "sigusr2");
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
    saved
}

fn replay(file: &Path) -> (Option<i32>, String) {
    let output = Command::new(env!("CARGO_BIN_EXE_motiond"))
        .arg("--replay")
        .arg(file)
        .output()
        .expect("motiond --replay runs");
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    (output.status.code(), text)
}

/// Where the first data digit of each of the last `count` `w` lines of the run is, latest
/// first: the tick and the offset in that tick's records. "QSB Command List" 1.28, command response: "For write commands,
/// the returned Data value will be a copy of the data that was written."
///
/// The bytes of a line come in several `LinkRx` records (a pty hands over a few bytes at a
/// time), often across ticks, so the search runs over the received bytes put back together.
/// The driver takes a write as done only when the echo carries the data it wrote, so a
/// digit changed there leaves the write unanswered and the driver's next bytes differ; a
/// digit changed in a streamed encoder line may be held by the line-noise guard and leave
/// no trace in any frame. Several are changed: on a loaded machine an echo can come after
/// its reply window, and the driver drops it as late whatever its digits say.
fn last_write_echo_digits(ticks: &[Vec<u8>], count: usize) -> Vec<(usize, usize)> {
    let mut stream = Vec::new();
    let mut origin = Vec::new();
    for (tick, records) in ticks.iter().enumerate() {
        let mut at = 0;
        while at + 6 <= records.len() {
            let Some(len) = records
                .get(at + 2..at + 6)
                .and_then(|b| b.try_into().ok())
                .map(|b| u32::from_le_bytes(b) as usize)
            else {
                break;
            };
            if records[at] == Kind::LinkRx as u8 && len > 8 {
                let data = at + 6 + 8..at + 6 + len;
                let Some(bytes) = records.get(data.clone()) else {
                    break;
                };
                stream.extend_from_slice(bytes);
                origin.extend(data.map(|offset| (tick, offset)));
            }
            at += 6 + len;
        }
    }
    (0..stream.len())
        .rev()
        .filter_map(|start| {
            let line_start = start == 0 || matches!(stream[start - 1], b'!' | b'\r' | b'\n');
            if !(line_start && stream[start] == b'w') {
                return None;
            }
            // `w`, separator, two register digits, separator, eight data digits.
            let digits: Vec<usize> = (start + 1..stream.len())
                .take_while(|&i| stream[i] != b'!')
                .filter(|&i| stream[i].is_ascii_hexdigit())
                .collect();
            (digits.len() >= 10).then(|| origin[digits[2]])
        })
        .take(count)
        .collect()
}

#[test]
fn a_run_with_a_move_a_jog_an_estop_and_a_fault_replays_frame_for_frame() {
    let name = unique_name("blackbox");
    let epoch = Instant::now();
    let board = Arc::new(Mutex::new(QsbSim::new(QsbSimConfig::default())));
    let tty = std::env::temp_dir().join(format!("{name}.tty"));
    let _served = PtyBoard::start(&tty, Arc::clone(&board), epoch, 230_400);
    let dir = std::env::temp_dir().join(format!("{name}-blackbox"));
    let config = write_config(
        &name,
        &format!(
            r#"[server]
name = "{name}"
blackbox_seconds = 120
blackbox_dir = "{}"

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
following_error = 1.0
"#,
            dir.display(),
            tty.display()
        ),
    );
    let mut server = Server::start(&config);
    let mut client = RawClient::connect(&name, Duration::from_secs(10));
    let (frame, ready) = client.wait_frame(Duration::from_secs(10), axis0_online);
    assert!(ready, "{:?}", frame.axes()[0]);

    // A move, and its arrival.
    let reply = client.command(0, CommandKind::RampPosition, [5.0, 0.0, 0.0]);
    assert!(reply.result().is_ok(), "{reply:?}");
    let (frame, arrived) = client.wait_frame(Duration::from_secs(5), |f| {
        (f.axes()[0].position - 5.0).abs() < 0.05
    });
    assert!(arrived, "{:?}", frame.axes()[0]);
    // A jog, then a stop.
    let reply = client.command(0, CommandKind::Velocity, [10.0, 0.0, 0.0]);
    assert!(reply.result().is_ok(), "{reply:?}");
    std::thread::sleep(Duration::from_millis(300));
    let reply = client.command(0, CommandKind::Stop, [0.0; 3]);
    assert!(reply.result().is_ok(), "{reply:?}");
    std::thread::sleep(Duration::from_millis(300));
    // An e-stop saves the ring; a reset ends it.
    let reply = client.command(CommandRequest::ALL_AXES, CommandKind::EStop, [0.0; 3]);
    assert!(reply.result().is_ok(), "{reply:?}");
    let at_estop = saved_path(&mut server, "estop");
    let reply = client.command(CommandRequest::ALL_AXES, CommandKind::Reset, [0.0; 3]);
    assert!(reply.result().is_ok(), "{reply:?}");
    std::thread::sleep(Duration::from_millis(300));
    // The motor slips: a following-error fault saves the ring too.
    board
        .lock()
        .expect("board")
        .nudge_encoder(epoch.elapsed(), 50.0);
    let (frame, faulted) = client.wait_frame(Duration::from_secs(2), |f| {
        f.axes()[0].fault() == Ok(FaultCode::FollowingError)
    });
    assert!(faulted, "{:?}", frame.axes()[0]);
    let at_fault = saved_path(&mut server, "fault");
    // SIGUSR2 saves the whole run so far.
    let whole = save_and_stop(&mut server);

    for file in [&at_estop, &at_fault, &whole] {
        let (status, text) = replay(file);
        assert_eq!(status, Some(0), "{}: {text}", file.display());
        assert!(text.contains("frames identical"), "{text}");
    }
    let recording = motion_blackbox::read(&whole).expect("the file reads back");
    assert!(
        recording.ticks.len() > 1000,
        "{} ticks",
        recording.ticks.len()
    );
    let (_, text) = replay(&whole);
    assert!(
        text.contains(&format!("replayed {} ticks", recording.ticks.len())),
        "{text}"
    );

    // One digit of what the board said, changed, in a copy of the file: in the echoes of
    // the run's last writes.
    let echoes = last_write_echo_digits(&recording.ticks, 8);
    assert!(!echoes.is_empty(), "a write's echo");
    let mut changed = recording.clone();
    for &(index, at) in &echoes {
        // '0'..'9' and 'A'..'F' with the low bit flipped: still a digit, or not hex at all.
        changed.ticks[index][at] ^= 0x01;
    }
    let index = echoes.iter().map(|&(index, _)| index).min().unwrap_or(0);
    let copy = dir.join("changed.mcap");
    write_recording(&changed, &copy);
    let (status, text) = replay(&copy);
    assert_eq!(status, Some(1), "{text}");
    let tick: u64 = text
        .split("tick ")
        .nth(1)
        .and_then(|rest| rest.split(':').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("a tick in {text:?}"));
    assert!(
        tick + 1 >= index as u64,
        "diverged at tick {tick}, before the change (journal tick {index}): {text}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The simulated robot (`config/sim.toml`, all four boards) with a 2 s ring, moving for
/// 4 s: SIGUSR2 saves a ring that wrapped, and `motiond --replay` starts from the snapshot
/// of the engine's state in it (one every 0.5 s) and gives every later frame, byte and
/// reply again; one byte changed after the snapshot is found.
#[test]
fn a_ring_that_wrapped_replays_from_its_state_snapshot() {
    let name = unique_name("wrapped");
    let dir = std::env::temp_dir().join(format!("{name}-blackbox"));
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../config/sim.toml");
    let robot = std::fs::read_to_string(&path).expect("config/sim.toml");
    let text = robot.replacen(
        "[server]\nname = \"demo\"",
        &format!(
            "[server]\nname = \"{name}\"\nblackbox_seconds = 2\nblackbox_dir = \"{}\"",
            dir.display()
        ),
        1,
    );
    assert_ne!(
        text, robot,
        "config/sim.toml starts with [server] name = \"demo\""
    );
    let config_path = write_config(&name, &text);
    let config = motion_config::ServerConfig::load(&config_path).expect("valid");
    let axes = config.axes.len();
    let mut server = Server::start(&config_path);
    let mut client = RawClient::connect(&name, Duration::from_secs(10));
    let (frame, ready) = client.wait_frame(Duration::from_secs(15), |f| {
        f.axes()[..axes]
            .iter()
            .all(|a| a.device_state() == Ok(motion_ipc::DeviceState::Online))
    });
    assert!(ready, "every board online: {:?}", frame.axes());
    // Every axis that can, on its way to the middle of its range; then 4 s of it.
    let mut moving = 0;
    for (index, axis) in config.axes.iter().enumerate() {
        let target = (axis.min + axis.max) / 2.0;
        let reply = client.command(index as u32, CommandKind::RampPosition, [target, 0.0, 0.0]);
        moving += usize::from(reply.result().is_ok());
    }
    assert!(moving >= 4, "{moving} axes took a move");
    std::thread::sleep(Duration::from_secs(4));
    let saved = save_and_stop(&mut server);

    let recording = motion_blackbox::read(&saved).expect("the file reads back");
    assert!(recording.dropped() > 0, "the ring wrapped");
    let (status, text) = replay(&saved);
    assert_eq!(status, Some(0), "{text}");
    assert!(
        text.contains("from the state snapshot at tick") && text.contains("frames identical"),
        "{text}"
    );

    // A reply byte changed after the first snapshot is found where it was said.
    let first_snapshot = recording
        .ticks
        .iter()
        .position(|ticks| {
            motion_blackbox::record::records(ticks)
                .filter_map(Result::ok)
                .any(|record| record.kind == Kind::Snapshot)
        })
        .expect("a snapshot in the ring");
    // Several replies: on a loaded machine one may have come after its window and been
    // dropped as late, whatever its bytes say.
    let replies: Vec<(usize, usize)> = recording.ticks[first_snapshot + 100..]
        .iter()
        .enumerate()
        .filter_map(|(i, ticks)| {
            motion_blackbox::record::records(ticks)
                .filter_map(Result::ok)
                .find(|record| record.kind == Kind::LinkRx && record.payload.len() > 12)
                .map(|record| {
                    let offset = record.payload.as_ptr() as usize - ticks.as_ptr() as usize;
                    (
                        first_snapshot + 100 + i,
                        offset + 8 + (record.payload.len() - 8) / 2,
                    )
                })
        })
        .take(20)
        .collect();
    assert!(!replies.is_empty(), "a reply after the snapshot");
    let mut changed = recording.clone();
    for &(index, at) in &replies {
        changed.ticks[index][at] ^= 0x5a;
    }
    let copy = dir.join("changed.mcap");
    write_recording_of(&changed, &copy, &config);
    let (status, text) = replay(&copy);
    assert_eq!(status, Some(1), "{text}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Writes `recording` as a black box file with the same config (one link, `usb`).
fn write_recording(recording: &Recording, path: &Path) {
    write_recording_with(recording, path, vec!["usb".into()]);
}

/// Writes `recording` as a black box file with the same config as `config`'s links.
fn write_recording_of(recording: &Recording, path: &Path, config: &motion_config::ServerConfig) {
    let links = config.links.iter().map(|link| link.name.clone()).collect();
    write_recording_with(recording, path, links);
}

fn write_recording_with(recording: &Recording, path: &Path, link_names: Vec<String>) {
    let file = BlackboxFile {
        server_name: recording.metadata["server"].clone(),
        tick_hz: 1000,
        config_path: recording.metadata["config_path"].clone().into(),
        config_text: recording.config_text().to_owned(),
        link_names,
    };
    let first = recording.dropped();
    let ticks = motion_blackbox::file::Ticks {
        head: &recording.head,
        ticks: recording
            .ticks
            .iter()
            .enumerate()
            .map(|(n, bytes)| {
                (
                    first + n as u64,
                    std::borrow::Cow::Borrowed(bytes.as_slice()),
                )
            })
            .collect(),
        dropped: first,
    };
    file.write(path, &ticks, "test").expect("written");
}
