//! The Trinamic `baud` key in a running motiond: a SIXpack served on a pty that models the
//! line rate (a word at the wrong rate arrives as garbage) is switched from its factory
//! 19200 to 115200 at start-up, the serial link following; a motiond started again later
//! finds it at 115200 though its link opens at 19200; one without the key cannot reach it.
//! And the simulated robot (`config/sim.toml`) runs both packs of its RS-485 bus at 115200.

mod support;

use core::time::Duration;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use board_tmcpack::sim::{TmcpackSim, TmcpackSimConfig};
use motion_ipc::{CommandKind, DeviceState, MotionFrame};
use nix::sys::signal::Signal;
use support::pty_board::{PtyBoard, PtyOptions};
use support::*;

fn all_online(frame: &MotionFrame) -> bool {
    frame.device_count > 0
        && (0..frame.device_count as usize).all(|i| frame.device_state(i) == DeviceState::Online)
}

/// One SIXpack on a serial link at 19200 with `device_keys`, axis `x` on motor 0.
fn pack_config(name: &str, tty: &Path, device_keys: &str) -> PathBuf {
    write_config(
        name,
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
{device_keys}

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
        ),
    )
}

#[test]
fn a_pack_switched_to_its_baud_is_found_there_by_the_next_server_and_only_with_the_key() {
    let name = unique_name("baud");
    let epoch = Instant::now();
    let pack = Arc::new(Mutex::new(TmcpackSim::new(TmcpackSimConfig::default())));
    let tty = std::env::temp_dir().join(format!("{name}.tty"));
    let _board = PtyBoard::try_start(
        &tty,
        Arc::clone(&pack),
        epoch,
        19_200,
        PtyOptions {
            follow_rate: true,
            ..PtyOptions::default()
        },
    )
    .expect("pty");
    let keyed = pack_config(&name, &tty, "baud = 115200");

    // 1. From the factory rate to 115200.
    let mut server = Server::start(&keyed);
    let mut client = RawClient::connect(&name, Duration::from_secs(10));
    let (frame, online) = client.wait_frame(Duration::from_secs(10), all_online);
    assert!(online, "{:?}\n{:#?}", frame.axes(), server.log_text());
    assert_eq!(pack.lock().unwrap().baud_rate(), 115_200);
    assert!(
        server.wait_for_log("line rate now 115200 baud", Duration::from_secs(2)),
        "{}",
        server.log_text()
    );
    // It moves at the new rate.
    assert_eq!(
        client
            .command(0, CommandKind::RampPosition, [2.0, 0.0, 0.0])
            .result(),
        Ok(())
    );
    let (frame, arrived) = client.wait_frame(Duration::from_secs(10), |f| {
        (f.axes()[0].position - 2.0).abs() < 0.01
    });
    assert!(arrived, "{:?}", frame.axes()[0]);
    drop(client);
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
    assert_eq!(
        pack.lock().unwrap().baud_rate(),
        115_200,
        "the pack keeps it"
    );

    // 2. Without the key the server's words at 19200 arrive as garbage: never online.
    let plain = pack_config(&format!("{name}p"), &tty, "");
    let plain_name = format!("{name}p");
    let mut server = Server::start(&plain);
    let client = RawClient::connect(&plain_name, Duration::from_secs(10));
    let (frame, online) = client.wait_frame(Duration::from_secs(2), all_online);
    assert!(!online, "{:?}", frame.device_state(0));
    let executed = pack.lock().unwrap().stats().executed;
    drop(client);
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
    assert_eq!(pack.lock().unwrap().stats().executed, executed);

    // 3. With it, a new server opens the link at 19200, hears nothing, and finds the pack
    // at 115200 without switching it again.
    let started = Instant::now();
    let mut server = Server::start(&keyed);
    let client = RawClient::connect(&name, Duration::from_secs(10));
    let (frame, online) = client.wait_frame(Duration::from_secs(10), all_online);
    assert!(online, "{:?}\n{}", frame.device_state(0), server.log_text());
    assert!(started.elapsed() < Duration::from_secs(5));
    assert_eq!(pack.lock().unwrap().baud_rate(), 115_200);
    drop(client);
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}

#[test]
fn the_simulated_robot_runs_both_packs_of_its_bus_at_115200() {
    let name = unique_name("robot115");
    let text = std::fs::read_to_string(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../config/sim.toml"),
    )
    .expect("config/sim.toml")
    .replacen("name = \"demo\"", &format!("name = \"{name}\""), 1)
    .replace(
        "variant = \"sixpack\"",
        "variant = \"sixpack\"\nbaud = 115200",
    )
    .replace(
        "variant = \"quadpack\"",
        "variant = \"quadpack\"\nbaud = 115200",
    );
    let path = write_config(&name, &text);
    let mut server = Server::start(&path);
    let mut client = RawClient::connect(&name, Duration::from_secs(10));
    let (frame, online) = client.wait_frame(Duration::from_secs(15), all_online);
    assert!(
        online,
        "{:?}",
        &frame.devices[..frame.device_count as usize]
    );
    assert!(
        server.wait_for_log(
            "rs485 @ 115200 8N1: line rate now 115200",
            Duration::from_secs(2)
        ),
        "{}",
        server.log_text()
    );
    // x (axis 4) on the SIXpack moves.
    assert_eq!(
        client
            .command(4, CommandKind::RampPosition, [5.0, 0.0, 0.0])
            .result(),
        Ok(())
    );
    let (frame, arrived) = client.wait_frame(Duration::from_secs(10), |f| {
        (f.axes()[4].position - 5.0).abs() < 0.01
    });
    assert!(arrived, "{:?}", frame.axes()[4]);
    drop(client);
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}
