//! motiond as a process: frames at the configured rate to a plain iceoryx2 subscriber in
//! another process (this test), SIGTERM exits 0 and releases the shared memory so that a
//! restart on the same name works, and a second instance on the same name is refused.

mod support;

use core::time::Duration;

use iceoryx2::prelude::*;
use nix::sys::signal::Signal;
use support::*;

/// The smallest config a server accepts: one simulated SPI_motor stepper.
fn small_config(name: &str) -> std::path::PathBuf {
    write_config(
        name,
        &format!(
            r#"[server]
name = "{name}"
tick_hz = 1000

[[link]]
name = "spi"
type = "sim"

[[device]]
name = "m"
link = "spi"
model = "spimotor"

[[axis]]
name = "a"
device = "m"
channel = 0
unit = "mm"
counts_per_unit = 100.0
min = -10.0
max = 10.0
max_velocity = 10.0
max_accel = 100.0
"#
        ),
    )
}

#[test]
fn frames_flow_at_the_tick_rate_and_sigterm_exits_cleanly_and_restarts() {
    let name = unique_name("life");
    let path = small_config(&name);
    let node = NodeBuilder::new().create::<ipc::Service>().expect("node");
    for round in 0..2 {
        let mut server = Server::start(&path);
        let subscriber =
            open_frames(&node, &name, Duration::from_secs(10)).expect("frame service appears");
        let first = next_frame(&subscriber, Duration::from_secs(5)).expect("a first frame");
        let start = std::time::Instant::now();
        std::thread::sleep(Duration::from_millis(500));
        let second = next_frame(&subscriber, Duration::from_secs(5)).expect("a later frame");
        let elapsed = start.elapsed().as_secs_f64();
        assert!(second.tick > first.tick, "round {round}: ticks increase");
        let rate = (second.tick - first.tick) as f64 / elapsed;
        // Correctness, not timing: the server ticks at about its configured 1 kHz (a loaded
        // 2-core machine may lose some ticks, never gain them).
        assert!(
            rate > 200.0 && rate < 1300.0,
            "round {round}: {rate} ticks/s"
        );
        let period = (second.time_ns - first.time_ns) as f64 / (second.tick - first.tick) as f64;
        assert!(
            (period - 1e6).abs() < 1.0,
            "frame time advances one period per tick: {period}"
        );
        assert!(second.publish_ns >= second.time_ns);
        drop(subscriber);
        let code = server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10));
        assert_eq!(
            code,
            Some(0),
            "round {round}: exit status; log: {:#?}",
            server.log
        );
    }
}

#[test]
fn a_second_server_on_the_same_name_is_refused() {
    let name = unique_name("dup");
    let path = small_config(&name);
    let node = NodeBuilder::new().create::<ipc::Service>().expect("node");
    let mut first = Server::start(&path);
    let _subscriber = open_frames(&node, &name, Duration::from_secs(10)).expect("first server up");
    let second = std::process::Command::new(env!("CARGO_BIN_EXE_motiond"))
        .arg("--config")
        .arg(&path)
        .output()
        .expect("run a second motiond");
    let stderr = String::from_utf8_lossy(&second.stderr);
    assert_eq!(second.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("another motiond"), "{stderr}");
    assert_eq!(
        first.signal_and_wait(Signal::SIGINT, Duration::from_secs(10)),
        Some(0)
    );
}
