//! motiond as users and boards see it: commands over shared memory move simulated axes, a
//! SIGKILLed client's jog stops, SIGTERM stops every board, an unplugged serial adapter
//! recovers without a restart.

mod support;

use core::time::Duration;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use board_tmcpack::sim::{TmcpackSim, TmcpackSimConfig};
use motion_ipc::{AxisFlags, AxisMode, CommandKind, DeviceState, FaultCode, MotionFrame};
use nix::sys::signal::Signal;
use support::pty_board::PtyBoard;
use support::*;

/// A stepper on a simulated SPI bus: the `focus` axis (index 0), 500 steps/s.
fn spimotor_section(command_timeout_ms: u32) -> String {
    format!(
        r#"
[server]
name = "NAME"
tick_hz = 1000
command_timeout_ms = {command_timeout_ms}
liveness_check_ms = 50

[[link]]
name = "spi"
type = "sim"
speed_hz = 1000000

[[device]]
name = "focus_drv"
link = "spi"
model = "spimotor"
drive = "stepper"

[[axis]]
name = "focus"
device = "focus_drv"
channel = 0
unit = "step"
counts_per_unit = 1.0
min = -100000.0
max = 100000.0
max_velocity = 500.0
max_accel = 5000.0
"#
    )
}

/// A SIXpack at address 1 on a serial link at `tty` (a pty served by the test): axes `x`
/// (channel 0) and `y` (channel 1) after the spimotor section.
fn tmcpack_section(tty: &std::path::Path) -> String {
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

[[axis]]
name = "y"
device = "pack"
channel = 1
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

fn config(name: &str, body: &str) -> std::path::PathBuf {
    write_config(name, &body.replace("NAME", name))
}

#[test]
fn commands_over_shared_memory_move_an_axis() {
    let name = unique_name("move");
    let mut server = Server::start(&config(&name, &spimotor_section(250)));
    let mut client = RawClient::connect(&name, Duration::from_secs(10));
    let (_, online) = client.wait_frame(Duration::from_secs(5), |f| {
        !f.axes()[0].flags().contains(AxisFlags::STALE)
    });
    assert!(online, "the simulated stepper reports in");
    let reply = client.command(0, CommandKind::RampPosition, [200.0, 0.0, 0.0]);
    assert_eq!(reply.result(), Ok(()));
    let (frame, arrived) = client.wait_frame(Duration::from_secs(5), |f| {
        f.axes()[0].flags().contains(AxisFlags::ARRIVED)
    });
    assert!(arrived, "{:?}", frame.axes()[0]);
    assert!(
        (frame.axes()[0].position - 200.0).abs() < 1e-9,
        "{:?}",
        frame.axes()[0]
    );
    let refused = client.command(0, CommandKind::RampPosition, [1e9, 0.0, 0.0]);
    assert_eq!(refused.result(), Err(motion_ipc::Reason::OutOfRange));
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}

/// Runs as a separate client process (spawned by the test below): jogs axis 0 of
/// `MOTIOND_JOG_SERVER` forever, refreshing the deadman every 50 ms.
#[test]
#[ignore = "helper process of a_sigkilled_clients_jog_stops"]
fn jog_client_process() {
    let Ok(name) = std::env::var("MOTIOND_JOG_SERVER") else {
        return;
    };
    let mut client = RawClient::connect(&name, Duration::from_secs(10));
    loop {
        let reply = client.command(0, CommandKind::Velocity, [200.0, 0.0, 0.0]);
        assert_eq!(reply.result(), Ok(()));
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn a_sigkilled_clients_jog_stops_within_the_deadman_and_liveness_bounds() {
    let name = unique_name("kill");
    let command_timeout = Duration::from_millis(300);
    let mut server = Server::start(&config(&name, &spimotor_section(300)));
    let client = RawClient::connect(&name, Duration::from_secs(10));
    let mut jogger = std::process::Command::new(std::env::current_exe().expect("test exe"))
        .args(["--exact", "jog_client_process", "--ignored", "--nocapture"])
        .env("MOTIOND_JOG_SERVER", &name)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("start the jogging client");
    let (frame, jogging) = client.wait_frame(Duration::from_secs(10), |f| {
        f.axes()[0].mode() == Ok(AxisMode::Velocity) && f.axes()[0].velocity > 100.0
    });
    assert!(
        jogging,
        "the client process jogs the axis: {:?}",
        frame.axes()[0]
    );
    // A jog that is refreshed outlives the deadman.
    std::thread::sleep(command_timeout * 2);
    assert_eq!(client.frame().axes()[0].mode(), Ok(AxisMode::Velocity));

    jogger.kill().expect("SIGKILL the client");
    let killed = Instant::now();
    let _ = jogger.wait();
    let (frame, stopping) = client.wait_frame(Duration::from_secs(5), |f| {
        f.axes()[0].mode() != Ok(AxisMode::Velocity)
    });
    let took = killed.elapsed();
    assert!(
        stopping,
        "the dead client's jog goes on: {:?}",
        frame.axes()[0]
    );
    // command_timeout (300 ms) + liveness check (50 ms) bound it; allow a loaded machine
    // half a second more.
    assert!(
        took < command_timeout + Duration::from_millis(50 + 500),
        "took {took:?}"
    );
    let (frame, held) = client.wait_frame(Duration::from_secs(3), |f| {
        f.axes()[0].velocity == 0.0 && f.axes()[0].mode() == Ok(AxisMode::Hold)
    });
    assert!(held, "{:?}", frame.axes()[0]);
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}

#[test]
fn sigterm_mid_move_stops_every_board_then_exits_zero() {
    let name = unique_name("term");
    let epoch = Instant::now();
    let pack = Arc::new(Mutex::new(TmcpackSim::new(TmcpackSimConfig::default())));
    let link = std::env::temp_dir().join(format!("{name}.tty"));
    let _board = PtyBoard::start(&link, Arc::clone(&pack), epoch, 19_200);
    let body = format!("{}{}", spimotor_section(250), tmcpack_section(&link));
    let mut server = Server::start(&config(&name, &body));
    let mut client = RawClient::connect(&name, Duration::from_secs(10));
    let (frame, online) = client.wait_frame(Duration::from_secs(10), ready);
    assert!(online, "every board reports in: {:?}", frame.axes());
    // Long moves on both boards.
    assert_eq!(
        client
            .command(0, CommandKind::RampPosition, [50_000.0, 0.0, 0.0])
            .result(),
        Ok(())
    );
    assert_eq!(
        client
            .command(1, CommandKind::RampPosition, [500.0, 0.0, 0.0])
            .result(),
        Ok(())
    );
    let (frame, moving) = client.wait_frame(Duration::from_secs(5), |f| {
        f.axes()[0].velocity > 100.0 && f.axes()[1].velocity > 1.0
    });
    let stats = pack.lock().unwrap().stats();
    assert!(
        moving,
        "{:?}\npack: {stats:?} {:?}",
        frame.axes(),
        pack.lock().unwrap().motor(0)
    );
    assert!(
        pack.lock().unwrap().motor(0).unwrap().velocity != 0,
        "the pack's motor turns"
    );
    // Manual 7.1 "Requests must not be interlaced": however late the server's ticks woke
    // (every test of this file runs at once), no request began while an answer was due or
    // the pack drove the line after one.
    assert_eq!(stats.interlaced, 0, "{stats:?}");

    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
    assert!(
        server.log.iter().any(|l| l.contains("every axis stopped")),
        "every board acknowledged: {:#?}",
        server.log
    );
    // The real pack (our model) was told to stop: its motor stands still.
    std::thread::sleep(Duration::from_millis(600));
    let motor = pack.lock().unwrap().motor(0).unwrap();
    assert_eq!(motor.velocity, 0, "{motor:?}");
}

#[test]
fn an_unplugged_serial_adapter_recovers_without_a_restart() {
    let name = unique_name("plug");
    let epoch = Instant::now();
    let pack = Arc::new(Mutex::new(TmcpackSim::new(TmcpackSimConfig::default())));
    let link = std::env::temp_dir().join(format!("{name}.tty"));
    let mut board = PtyBoard::start(&link, Arc::clone(&pack), epoch, 19_200);
    let body = format!("{}{}", spimotor_section(250), tmcpack_section(&link));
    let mut server = Server::start(&config(&name, &body));
    let mut client = RawClient::connect(&name, Duration::from_secs(10));
    let (frame, online) = client.wait_frame(Duration::from_secs(10), ready);
    assert!(
        online,
        "{:?}\npack: {:?}\n{}",
        frame.axes(),
        pack.lock().unwrap().stats(),
        server.log_text()
    );
    let stats = pack.lock().unwrap().stats();
    assert_eq!(
        stats.interlaced, 0,
        "manual 7.1: no request interlaced: {stats:?}"
    );
    assert_eq!(
        client
            .command(1, CommandKind::Velocity, [2.0, 0.0, 0.0])
            .result(),
        Ok(())
    );

    board.unplug();
    let (frame, down) = client.wait_frame(Duration::from_secs(5), |f| {
        f.axes()[1].flags().contains(AxisFlags::FAULT)
            && f.axes()[1].fault() == Ok(FaultCode::LinkDown)
    });
    assert!(
        down,
        "the pack's axes fault when its adapter goes: {:?}",
        frame.axes()
    );
    // The other link keeps refreshing, the server keeps ticking.
    let before = client.frame();
    std::thread::sleep(Duration::from_millis(300));
    let after = client.frame();
    assert!(after.tick > before.tick);
    assert!(after.axes()[0].last_refresh_tick > before.axes()[0].last_refresh_tick);
    let (frame, stale) = client.wait_frame(Duration::from_secs(3), |f| {
        f.axes()[1].flags().contains(AxisFlags::STALE)
    });
    assert!(
        stale,
        "no fresh data from an unplugged pack: {:?}",
        frame.axes()[1]
    );
    let refused = client.command(1, CommandKind::Velocity, [2.0, 0.0, 0.0]);
    assert_eq!(refused.result(), Err(motion_ipc::Reason::LinkDown));

    // Plug a (fresh) pack back in on the same path.
    let pack = Arc::new(Mutex::new(TmcpackSim::new(TmcpackSimConfig::default())));
    let _board = PtyBoard::start(&link, Arc::clone(&pack), epoch, 19_200);
    let (frame, back) = client.wait_frame(Duration::from_secs(10), |f| {
        let axis = f.axes()[1];
        !axis.flags().contains(AxisFlags::FAULT)
            && !axis.flags().contains(AxisFlags::STALE)
            && axis.device_state() == Ok(DeviceState::Online)
    });
    assert!(back, "the link recovers: {:?}", frame.axes());
    assert_ne!(
        frame.axes()[1].mode(),
        Ok(AxisMode::Velocity),
        "the old jog is not resumed"
    );
    assert_eq!(
        client
            .command(1, CommandKind::Velocity, [2.0, 0.0, 0.0])
            .result(),
        Ok(())
    );
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
}

/// Every axis fresh and every board online (probed, configured, its start-up stop
/// acknowledged): goals are accepted from now on.
fn ready(frame: &MotionFrame) -> bool {
    frame.axes().iter().all(|a| {
        !a.flags().contains(AxisFlags::STALE) && a.device_state() == Ok(DeviceState::Online)
    })
}
