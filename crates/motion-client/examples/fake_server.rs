//! Serves the test fake of motiond (devices pack and aux; axes x, y in mm, a in deg; signals
//! door, lamp, pressure, valve) until Ctrl-C, so that
//! motionctl and client programs can be tried without the real server or any board:
//! `cargo run -p motion-client --features testing --example fake_server -- [NAME]`
//! (default name `fake`), then `motionctl --server fake watch`.

use core::time::Duration;

use iceoryx2::prelude::{NodeBuilder, ipc};
use motion_client::testing::{FakeConfig, FakeServer};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let name = std::env::args().nth(1).unwrap_or_else(|| "fake".to_owned());
    let server = FakeServer::start::<ipc::Service>(FakeConfig::demo(&name))?;
    println!(
        "fake motiond \"{name}\" running (axes x, y, a; signals door, lamp, pressure, valve; \
         500 Hz); Ctrl-C stops it"
    );
    // A node of our own, only for its SIGINT/SIGTERM handling.
    let signals = NodeBuilder::new().create::<ipc::Service>()?;
    while signals.wait(Duration::from_millis(100)).is_ok() {}
    server.shutdown()?;
    println!("stopped");
    Ok(())
}
