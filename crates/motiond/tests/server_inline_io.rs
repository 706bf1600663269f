//! A link the tick runs itself (`io = "tick"`, the default of an `spi-socket` link) on a
//! real motiond: its board comes online as on an I/O thread, a peer that hangs takes its
//! device offline while the tick goes on publishing every tick (nothing waits for the
//! peer), and the board comes back once the peer answers again.

mod support;

use core::time::Duration;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use board_qq2drv::sim::{Qq2drvSim, Qq2drvSimConfig};
use nix::sys::signal::Signal;
use support::socket_board::SocketBoard;
use support::*;

/// Distinct frames seen in `span`, looking every 5 ms.
fn frames_seen(client: &RawClient, span: Duration) -> usize {
    let end = Instant::now() + span;
    let mut seen = std::collections::BTreeSet::new();
    while Instant::now() < end {
        if let Some(frame) = client.try_frame(Duration::from_millis(100)) {
            seen.insert(frame.publish_ns);
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    seen.len()
}

#[test]
fn a_hung_spi_peer_takes_its_board_offline_without_holding_the_tick() {
    let name = unique_name("inlineio");
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

[[axis]]
name = "wheel"
device = "drive"
channel = 0
unit = "m"
counts_per_unit = 31831.0
min = -1000.0
max = 1000.0
max_velocity = 1.5
max_accel = 3.0
"#,
            socket.display()
        ),
    );
    let mut server = Server::start(&config);
    let client = RawClient::connect(&name, Duration::from_secs(10));
    let (frame, ready) = client.wait_frame(Duration::from_secs(10), axis0_online);
    assert!(ready, "{:?}", frame.axes()[0]);
    let threads = thread_names(server.pid());
    assert!(
        threads.iter().any(|t| t == "tick") && !threads.iter().any(|t| t.starts_with("io-")),
        "no I/O thread for an io = \"tick\" link: {threads:?}"
    );

    // The board's thread blocks on its model: it reads and answers nothing, as a hung
    // bridge would.
    let hung = board.lock().expect("model");
    let (frame, offline) = client.wait_frame(Duration::from_secs(10), |f| !axis0_online(f));
    assert!(
        offline,
        "a silent board stayed online: {:?}",
        frame.axes()[0]
    );
    // The tick did not wait for the peer: frames keep coming while it is hung.
    let seen = frames_seen(&client, Duration::from_secs(1));
    assert!(seen >= 20, "{seen} frames in a second with the peer hung");
    drop(hung);
    let (frame, back) = client.wait_frame(Duration::from_secs(10), axis0_online);
    assert!(back, "the board did not come back: {:?}", frame.axes()[0]);
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}
