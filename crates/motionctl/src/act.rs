//! Commands that act on axes: move, jog, power, stop, home, claim, release.

use core::time::Duration;
use std::time::Instant;

use anyhow::Context as _;
use motion_client::{Axis, Client, ClientError, JogGuard};

use crate::Service;

/// How long a frame may take before we call the server silent while holding a jog.
const FRAME_TIMEOUT: Duration = Duration::from_secs(2);

/// `motionctl move AXIS POS [--velocity V] [--accel A] [--wait]`.
pub fn move_axis(
    client: &Client<Service>,
    name: &str,
    position: f64,
    velocity: Option<f64>,
    accel: Option<f64>,
    wait: Option<Duration>,
) -> anyhow::Result<()> {
    let axis = client.axis(name)?;
    let unit = axis.info().unit().to_owned();
    axis.ramp_to(position, velocity.unwrap_or(0.0), accel.unwrap_or(0.0))
        .with_context(|| format!("move {name} to {position} {unit}"))?;
    let Some(timeout) = wait else {
        out!("{name}: moving to {position} {unit}");
        return Ok(());
    };
    let frame = stop_if_interrupted(&axis, axis.wait_until_arrived(timeout))
        .with_context(|| format!("move {name} to {position} {unit}"))?;
    let reached = frame
        .axes()
        .get(axis.index() as usize)
        .map_or(f64::NAN, |state| state.position);
    out!("{name}: arrived at {reached} {unit} (tick {})", frame.tick);
    Ok(())
}

/// Ctrl-C while waiting for a move means "abort": the axis is stopped before exiting.
fn stop_if_interrupted<T>(
    axis: &Axis<'_, Service>,
    result: Result<T, ClientError>,
) -> anyhow::Result<T> {
    match result {
        Err(ClientError::Interrupted) => {
            let stopped = match axis.stop() {
                Ok(_) => "axis stopped".to_owned(),
                Err(error) => format!("stopping it failed too: {error}"),
            };
            Err(anyhow::Error::new(ClientError::Interrupted).context(stopped))
        }
        other => Ok(other?),
    }
}

/// Holds `guard` until Ctrl-C/SIGTERM, renewing it as frames come, then stops the axis.
fn hold_until_interrupted(
    client: &Client<Service>,
    name: &str,
    unit: &str,
    guard: JogGuard<'_, Service>,
) -> anyhow::Result<()> {
    let index = guard.axis() as usize;
    let outcome = loop {
        match client.next_frame(FRAME_TIMEOUT) {
            Ok(_) => {}
            Err(ClientError::Interrupted) => break Ok(()),
            Err(error) => break Err(error),
        }
        if let Some(reason) = guard.refused() {
            break Err(ClientError::Refused {
                kind: "renewal",
                axis: format!("axis {name}"),
                reason,
                tick: 0,
            });
        }
    };
    let stopped = guard.stop();
    let position = client
        .latest()
        .ok()
        .and_then(|frame| frame.axes().get(index).map(|state| state.position));
    outcome.with_context(|| format!("jog {name}"))?;
    stopped.with_context(|| format!("stop {name}"))?;
    match position {
        Some(position) => eprintln!("{name}: stopped at {position} {unit}"),
        None => eprintln!("{name}: stopped"),
    }
    Ok(())
}

/// `motionctl jog AXIS VEL [--accel A]`: runs until Ctrl-C, then stops the axis.
pub fn jog(
    client: &Client<Service>,
    name: &str,
    velocity: f64,
    accel: Option<f64>,
) -> anyhow::Result<()> {
    let axis = client.axis(name)?;
    let unit = axis.info().unit().to_owned();
    let guard = axis
        .jog(velocity, accel.unwrap_or(0.0))
        .with_context(|| format!("jog {name} at {velocity} {unit}/s"))?;
    eprintln!("{name}: jogging at {velocity} {unit}/s; Ctrl-C stops");
    hold_until_interrupted(client, name, &unit, guard)
}

/// `motionctl power AXIS P`: open-loop power until Ctrl-C, then stop.
pub fn power(client: &Client<Service>, name: &str, power: f64) -> anyhow::Result<()> {
    let axis = client.axis(name)?;
    let unit = axis.info().unit().to_owned();
    let guard = axis
        .power_guarded(power)
        .with_context(|| format!("power {name} at {power}"))?;
    eprintln!("{name}: power {power}; Ctrl-C stops");
    hold_until_interrupted(client, name, &unit, guard)
}

/// `motionctl stop [AXIS…]`.
pub fn stop(client: &Client<Service>, names: &[String]) -> anyhow::Result<()> {
    if names.is_empty() {
        client.stop_all()?;
        out!("all axes stopping");
        return Ok(());
    }
    for name in names {
        client.axis(name)?.stop()?;
        out!("{name}: stopping");
    }
    Ok(())
}

/// `motionctl home AXIS [--velocity V] [--wait]`.
pub fn home(
    client: &Client<Service>,
    name: &str,
    velocity: Option<f64>,
    wait: Option<Duration>,
) -> anyhow::Result<()> {
    let axis = client.axis(name)?;
    axis.home(velocity.unwrap_or(0.0))
        .with_context(|| format!("home {name}"))?;
    let Some(timeout) = wait else {
        out!("{name}: homing");
        return Ok(());
    };
    let frame = stop_if_interrupted(&axis, axis.wait_until_homed(timeout))
        .with_context(|| format!("home {name}"))?;
    out!("{name}: homed (tick {})", frame.tick);
    Ok(())
}

/// `motionctl claim AXIS… [--duration D]`: holds the claims, then releases them.
pub fn claim(
    client: &Client<Service>,
    names: &[String],
    duration: Option<Duration>,
) -> anyhow::Result<()> {
    let axes = names
        .iter()
        .map(|name| client.axis(name))
        .collect::<Result<Vec<_>, _>>()?;
    let mut claimed = Vec::new();
    let mut outcome = Ok(());
    for axis in &axes {
        match axis.claim() {
            Ok(_) => claimed.push(*axis),
            Err(error) => {
                outcome = Err(error).with_context(|| format!("claim {}", axis.name()));
                break;
            }
        }
    }
    if outcome.is_ok() {
        let list = names.join(", ");
        match duration {
            Some(duration) => eprintln!("claimed {list} for {duration:?}; Ctrl-C releases"),
            None => eprintln!("claimed {list}; Ctrl-C releases"),
        }
        let until = duration.map(|duration| Instant::now() + duration);
        outcome = loop {
            if until.is_some_and(|until| Instant::now() >= until) {
                break Ok(());
            }
            match client.next_frame(FRAME_TIMEOUT) {
                Ok(_) => {}
                Err(ClientError::Interrupted) => break Ok(()),
                Err(error) => break Err(error.into()),
            }
        };
    }
    for axis in claimed {
        axis.release()
            .with_context(|| format!("release {}", axis.name()))?;
    }
    if outcome.is_ok() {
        eprintln!("released {}", names.join(", "));
    }
    outcome
}

/// `motionctl release AXIS…`.
pub fn release(client: &Client<Service>, names: &[String]) -> anyhow::Result<()> {
    for name in names {
        client
            .axis(name)?
            .release()
            .with_context(|| format!("release {name} (a claim belongs to the process that made it: end that process to release)"))?;
        out!("{name}: released");
    }
    Ok(())
}
