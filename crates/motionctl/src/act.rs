//! Commands that act on axes: move, jog, power, stop, off, home, claim, release, and the
//! readiness wait in front of every `--wait`.

use core::time::Duration;
use std::time::Instant;

use anyhow::Context as _;
use motion_client::ipc::Reason;
use motion_client::{Accepted, Axis, ClaimGuard, Client, ClientError, JogGuard};

use crate::Service;

/// How long a frame may take before we call the server silent while holding a jog.
const FRAME_TIMEOUT: Duration = Duration::from_secs(2);
/// How often `claim` renews its claims (a claim lease of the server ends claims that are
/// not renewed).
const CLAIM_RENEWAL: Duration = Duration::from_secs(1);

/// Waits for the axis's device to be ready, then sends the goal; a goal refused because
/// the device is (again) starting is sent again after the next readiness, until `deadline`.
fn when_ready(
    axis: &Axis<'_, Service>,
    deadline: Instant,
    mut send: impl FnMut() -> Result<Accepted, ClientError>,
) -> Result<Accepted, ClientError> {
    loop {
        axis.wait_ready(deadline.saturating_duration_since(Instant::now()))?;
        match send() {
            Err(error)
                if error.reason() == Some(Reason::DeviceStarting) && Instant::now() < deadline =>
            {
                std::thread::sleep(Duration::from_millis(5));
            }
            other => return other,
        }
    }
}

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
    let send = || axis.ramp_to(position, velocity.unwrap_or(0.0), accel.unwrap_or(0.0));
    let Some(timeout) = wait else {
        send().with_context(|| format!("move {name} to {position} {unit}"))?;
        out!("{name}: moving to {position} {unit}");
        return Ok(());
    };
    let deadline = Instant::now() + timeout;
    stop_if_interrupted(&axis, when_ready(&axis, deadline, send))
        .with_context(|| format!("move {name} to {position} {unit}"))?;
    let remaining = deadline.saturating_duration_since(Instant::now());
    let frame = stop_if_interrupted(&axis, axis.wait_until_arrived(remaining))
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
/// Ends with an error when a renewal is refused or the server restarts (the guard then
/// sends nothing to the new server).
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
        if let Err(error) = guard.check() {
            break Err(error);
        }
    };
    let stopped = guard.stop();
    if let Err(error @ ClientError::ServerRestarted(_)) = outcome {
        return Err(anyhow::Error::new(error).context(format!(
            "jog {name} ended: nothing more is sent to the new server"
        )));
    }
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

/// `motionctl stop AXIS…` (the names need the server's description, nothing else).
pub fn stop(client: &Client<Service>, names: &[String]) -> anyhow::Result<()> {
    for name in names {
        client.axis(name)?.stop()?;
        out!("{name}: stopping");
    }
    Ok(())
}

/// `motionctl off AXIS…|--all`: one `Off` per axis, each refusal reported for its axis.
pub fn off(client: &Client<Service>, names: &[String], all: bool) -> anyhow::Result<()> {
    let axes = if all {
        client.axes()
    } else {
        names
            .iter()
            .map(|name| client.axis(name))
            .collect::<Result<Vec<_>, _>>()?
    };
    let mut first_error = None;
    let mut refused = Vec::new();
    for axis in axes {
        let name = axis.name();
        match axis.off() {
            Ok(_) => out!("{name}: off"),
            Err(error) => {
                refused.push(name);
                first_error.get_or_insert(error);
            }
        }
    }
    match first_error {
        // One line: which axes stayed energised, then the first refusal's reason.
        Some(error) => Err(anyhow::Error::new(error)
            .context(format!("off: not de-energised: {}", refused.join(", ")))),
        None => Ok(()),
    }
}

/// `motionctl wait-ready [--timeout T] [AXIS…]`.
pub fn wait_ready(
    client: &Client<Service>,
    names: &[String],
    timeout: Duration,
) -> anyhow::Result<()> {
    if names.is_empty() {
        client.wait_ready(timeout).context("wait-ready")?;
    } else {
        let mut devices = Vec::new();
        for name in names {
            let device = usize::from(client.axis(name)?.info().device_index);
            if !devices.contains(&device) {
                devices.push(device);
            }
        }
        client
            .wait_devices_ready(&devices, timeout)
            .context("wait-ready")?;
    }
    let devices: Vec<String> = client.devices()?.into_iter().map(|d| d.name).collect();
    if names.is_empty() {
        out!("ready: every device is online ({})", devices.join(", "));
    } else {
        out!("ready: the devices of {} are online", names.join(", "));
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
    let send = || axis.home(velocity.unwrap_or(0.0));
    let Some(timeout) = wait else {
        send().with_context(|| format!("home {name}"))?;
        out!("{name}: homing");
        return Ok(());
    };
    let deadline = Instant::now() + timeout;
    stop_if_interrupted(&axis, when_ready(&axis, deadline, send))
        .with_context(|| format!("home {name}"))?;
    let remaining = deadline.saturating_duration_since(Instant::now());
    let frame = stop_if_interrupted(&axis, axis.wait_until_homed(remaining))
        .with_context(|| format!("home {name}"))?;
    out!("{name}: homed (tick {})", frame.tick);
    Ok(())
}

/// Holds `guards` until Ctrl-C or `until`, renewing them; ends with the restart if the
/// server restarted (the claims died with it).
pub fn hold_claims(
    client: &Client<Service>,
    guards: &[ClaimGuard<'_, Service>],
    until: Option<Instant>,
) -> anyhow::Result<()> {
    let mut renewed = Instant::now();
    loop {
        if until.is_some_and(|until| Instant::now() >= until) {
            return Ok(());
        }
        match client.next_frame(FRAME_TIMEOUT) {
            Ok(_) => {}
            Err(ClientError::Interrupted) => return Ok(()),
            Err(error) => return Err(error.into()),
        }
        for guard in guards {
            guard.check()?;
        }
        if renewed.elapsed() >= CLAIM_RENEWAL {
            for guard in guards {
                guard
                    .renew()
                    .with_context(|| format!("renew the claim on {}", guard.label()))?;
            }
            renewed = Instant::now();
        }
    }
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
    let mut guards = Vec::new();
    for axis in &axes {
        let guard = axis
            .claim_guard()
            .with_context(|| format!("claim {}", axis.name()))?;
        guards.push(guard);
    }
    let list = names.join(", ");
    match duration {
        Some(duration) => eprintln!("claimed {list} for {duration:?}; Ctrl-C releases"),
        None => eprintln!("claimed {list}; Ctrl-C releases"),
    }
    let until = duration.map(|duration| Instant::now() + duration);
    let outcome = hold_claims(client, &guards, until);
    let mut released = Ok(());
    for guard in guards {
        let label = guard.label();
        match guard.release() {
            Ok(_) | Err(ClientError::ServerRestarted(_)) => {}
            Err(error) => {
                released = Err(anyhow::Error::new(error).context(format!("release {label}")));
            }
        }
    }
    outcome?;
    released?;
    eprintln!("released {list}");
    Ok(())
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
