//! The client process of campaign 1: this binary run as `reliability jogger`, a motion-client
//! program that jogs one axis with a [`motion_client::JogGuard`] and keeps reading frames
//! (which renews the guard every third of the deadman) until it is killed or stopped.

use core::time::Duration;

use anyhow::Context;
use iceoryx2::prelude::ipc;
use motion_client::{Client, ClientBuilder};

/// Connects to `server`, waits for `axis`'s board, jogs it at `velocity` and reads frames
/// forever. Prints `jogging` on stdout once the jog was accepted.
pub fn run(server: &str, axis: &str, velocity: f64) -> anyhow::Result<()> {
    let client: Client<ipc::Service> = ClientBuilder::new(server)
        .connect_timeout(Duration::from_secs(10))
        .connect()
        .with_context(|| format!("connect to {server}"))?;
    let axis = client.axis(axis)?;
    axis.wait_ready(Duration::from_secs(10))?;
    let _jog = axis.jog(velocity, 0.0)?;
    println!("jogging");
    loop {
        // Each read renews the jog when it is due (a third of the deadman).
        client.next_frame(Duration::from_secs(1))?;
    }
}
