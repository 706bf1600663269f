//! A complete client program: connect to a running motiond, describe it, wait for the axis's
//! board to be ready, move the axis to a position and wait for it, show a refusal, jog for a
//! second under a guard, and stop.
//!
//! Run the server first (`motiond --config config/sim.toml`), then
//! `cargo run -p motion-client --example jog_and_move -- [SERVER] [AXIS]`
//! (defaults: `demo` and the first axis).

use core::time::Duration;

use iceoryx2::prelude::ipc;
use motion_client::{Client, ClientError};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let server = args.next().unwrap_or_else(|| "demo".to_owned());
    let client = Client::<ipc::Service>::connect(&server)?;

    let info = client.info()?;
    println!(
        "motiond \"{server}\": {} Hz, {} axes",
        info.tick_hz,
        info.axes().len()
    );
    for axis in info.axes() {
        println!(
            "  {:<12} {:>8} .. {:<8} {} (max {} {}/s)",
            axis.name(),
            axis.min,
            axis.max,
            axis.unit(),
            axis.max_velocity,
            axis.unit()
        );
    }
    let name = match args.next() {
        Some(name) => name,
        None => info
            .axes()
            .first()
            .map(|axis| axis.name().to_owned())
            .ok_or("the server has no axes")?,
    };
    drop(info);

    let axis = client.axis(&name)?;
    // Its board answered, was configured and acknowledged its start-up stop.
    axis.wait_ready(Duration::from_secs(30))?;
    let limits = axis.info();
    let start = axis.state()?.position;
    let goal = (start + (limits.max - limits.min) / 10.0).clamp(limits.min, limits.max);
    println!("{name}: at {start:.3}, moving to {goal:.3}");
    axis.ramp_to(goal, 0.0, 0.0)?;
    let frame = axis.wait_until_arrived(Duration::from_secs(30))?;
    println!("{name}: arrived at tick {}", frame.tick);
    drop(frame);

    match axis.position(limits.max + 1.0) {
        Err(ClientError::Refused { reason, .. }) => {
            println!("{name}: beyond max refused: {reason}")
        }
        Ok(_) => println!("{name}: beyond max accepted?!"),
        Err(error) => return Err(error.into()),
    }

    let jog = axis.jog(-limits.max_velocity / 10.0, 0.0)?;
    let period = 1.0 / f64::from(client.info()?.tick_hz.max(1));
    let ticks = (1.0 / period) as usize;
    for frame in client.frames(Duration::from_secs(1)).take(ticks) {
        let frame = frame?;
        if frame.tick.is_multiple_of(100) {
            let state = frame.axes()[axis.index() as usize];
            println!(
                "tick {:>8}  {name} {:>10.3}  {:>8.3}/s",
                frame.tick, state.position, state.velocity
            );
        }
    }
    jog.stop()?;
    println!("{name}: stopped at {:.3}", axis.state()?.position);
    Ok(())
}
