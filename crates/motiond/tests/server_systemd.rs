//! motiond under a (fake) service manager: `Type=notify` readiness only once every device is
//! online, the watchdog fed while the tick runs, `STOPPING=1` on SIGTERM
//! (deploy/motiond.service; crates/motiond/src/systemd.rs).

mod deploy_support;
mod support;

use core::time::Duration;
use std::process::Command;

use deploy_support::{FakeManager, Motiond, Scratch, config_text};
use motion_ipc::DeviceState;
use nix::sys::signal::Signal;

#[test]
fn ready_waits_for_every_device_then_the_watchdog_is_fed_until_stopping() {
    let scratch = Scratch::new("notify");
    let mut manager = FakeManager::new(&scratch.dir);
    let name = support::unique_name("notify");
    let config = scratch.file("motiond.toml", &config_text(&name, ""));
    let mut command = Command::new(env!("CARGO_BIN_EXE_motiond"));
    command
        .arg("--config")
        .arg(&config)
        .env("NOTIFY_SOCKET", &manager.path)
        .env("WATCHDOG_USEC", "400000")
        .env_remove("WATCHDOG_PID");
    let mut server = Motiond::spawn_command(command).expect("start motiond");

    let ready = manager.wait_for(Duration::from_secs(20), |m| m.contains("READY=1"));
    assert!(
        ready.is_some(),
        "no READY=1; notifications {:?}; log:\n{}",
        manager.messages,
        server.log_text()
    );
    // Before READY the server said it was waiting for its devices.
    let before: Vec<&String> = manager
        .messages
        .iter()
        .take_while(|m| !m.contains("READY=1"))
        .collect();
    assert!(
        before
            .iter()
            .any(|m| m.contains("STATUS=starting: services up, waiting for")
                && m.contains("of 2 device(s) online")),
        "{:?}",
        manager.messages
    );
    assert!(
        ready
            .as_deref()
            .is_some_and(|m| m.contains("STATUS=ready: 2 device(s)")),
        "{ready:?}"
    );
    // READY means what it says: the frames show every device online.
    let client = support::RawClient::connect(&name, Duration::from_secs(5));
    let frame = client.frame();
    for device in 0..2 {
        assert_eq!(
            frame.device_state(device),
            DeviceState::Online,
            "device {device}"
        );
    }
    drop(client);

    // WATCHDOG_USEC = 400 ms: a ping every 200 ms while the tick runs.
    manager.collect(Duration::from_millis(1500));
    let pings = manager
        .messages
        .iter()
        .filter(|m| *m == "WATCHDOG=1")
        .count();
    assert!(pings >= 2, "{:?}", manager.messages);
    assert!(
        manager.messages.iter().all(|m| !m.contains("stuck")),
        "{:?}",
        manager.messages
    );

    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
    assert!(
        manager
            .wait_for(Duration::from_secs(2), |m| m.starts_with("STOPPING=1"))
            .is_some(),
        "{:?}",
        manager.messages
    );
    assert_eq!(
        manager
            .messages
            .iter()
            .filter(|m| m.contains("READY=1"))
            .count(),
        1
    );
    let log = server.log_text();
    assert!(log.contains("systemd: notifying readiness"), "{log}");
    assert!(log.contains("feeding the watchdog (400 ms)"), "{log}");
}

#[test]
fn a_bad_notify_socket_is_only_a_warning() {
    let scratch = Scratch::new("badnotify");
    let name = support::unique_name("badnotify");
    let config = scratch.file("motiond.toml", &config_text(&name, ""));
    let mut command = Command::new(env!("CARGO_BIN_EXE_motiond"));
    command
        .arg("--config")
        .arg(&config)
        .env("NOTIFY_SOCKET", "relative/socket");
    let mut server = Motiond::spawn_command(command).expect("start motiond");
    assert!(
        server.wait_for_log("device `pumps` online", Duration::from_secs(20)),
        "{}",
        server.log_text()
    );
    assert_eq!(
        server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10)),
        Some(0)
    );
    let log = server.log_text();
    assert!(
        log.contains("systemd notification disabled: NOTIFY_SOCKET=\"relative/socket\""),
        "{log}"
    );
}
