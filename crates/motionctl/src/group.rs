//! `motionctl group …`: list, move (a synchronized line), follow (a CSV trajectory), hold,
//! resume, cancel, stop, feed, claim.

use core::fmt;
use core::time::Duration;
use std::path::Path;
use std::time::Instant;

use anyhow::Context as _;
use motion_client::ipc::{GroupInfo, Reason, ServerInfo};
use motion_client::{Client, ClientError, Group, GroupRun, GroupStatus, Trajectory};
use serde_json::{Value, json};

use crate::Service;
use crate::cli::GroupCommand;
use crate::group_csv::parse_trajectory;
use crate::group_report::{GroupReport, ReportAxis};

/// Arguments that make no sense for the server's groups (an axis given twice, an axis not
/// in the group): exit status 2, like clap's own.
#[derive(Debug)]
pub struct BadArguments(pub String);

impl fmt::Display for BadArguments {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BadArguments {}

/// Runs one `group` subcommand.
pub fn run(client: &Client<Service>, command: &GroupCommand) -> anyhow::Result<()> {
    match command {
        GroupCommand::List { json } => list(client, *json),
        GroupCommand::Move {
            group,
            targets,
            velocity_scale,
            accel_scale,
            wait,
            json,
            timeout,
        } => {
            let handle = client.group(group)?;
            let positions = ordered_targets(&handle, targets)?;
            let scales = (velocity_scale.unwrap_or(1.0), accel_scale.unwrap_or(1.0));
            let words = targets
                .iter()
                .map(|(axis, position)| format!("{axis}={position}"))
                .collect::<Vec<_>>()
                .join(" ");
            let send = || handle.move_to_scaled(&positions, scales.0, scales.1);
            let what = format!("move {group} to {words}");
            execute(
                client, &handle, &what, &positions, send, *wait, *json, *timeout,
            )
        }
        GroupCommand::Follow {
            group,
            file,
            wait,
            json,
            timeout,
        } => {
            let handle = client.group(group)?;
            let trajectory = read_trajectory(file, &handle.axes())?;
            let last = trajectory.len().saturating_sub(1);
            let finals = trajectory.positions(last).unwrap_or_default().to_vec();
            let what = format!(
                "follow {} ({} points, {:.3} s) with {group}",
                file.display(),
                trajectory.len(),
                trajectory.times().last().copied().unwrap_or(0.0)
            );
            let send = || handle.follow(&trajectory);
            execute(
                client, &handle, &what, &finals, send, *wait, *json, *timeout,
            )
        }
        GroupCommand::Hold { group } => steer(client, group, "hold", |g| g.hold()),
        GroupCommand::Resume { group } => steer(client, group, "resume", |g| g.resume()),
        GroupCommand::Cancel { group } => steer(client, group, "cancel", |g| g.cancel()),
        GroupCommand::Stop { group } => steer(client, group, "stop", |g| g.stop()),
        GroupCommand::Feed { group, feed } => {
            let handle = client.group(group)?;
            let accepted = handle
                .set_feed(*feed)
                .with_context(|| format!("feed {group} {}%", feed * 100.0))?;
            out!("{group}: feed {}% (tick {})", feed * 100.0, accepted.tick);
            Ok(())
        }
        GroupCommand::Claim { group, duration } => claim(client, group, *duration),
    }
}

/// The trajectory in `file` for a group of `axes`.
fn read_trajectory(file: &Path, axes: &[String]) -> anyhow::Result<Trajectory> {
    let text = std::fs::read_to_string(file).with_context(|| format!("read {}", file.display()))?;
    parse_trajectory(&text, axes).with_context(|| file.display().to_string())
}

/// The positions of `targets` in the group's order; every axis of the group once.
fn ordered_targets(
    group: &Group<'_, Service>,
    targets: &[(String, f64)],
) -> anyhow::Result<Vec<f64>> {
    let axes = group.axes();
    let mut positions = vec![None; axes.len()];
    for (axis, position) in targets {
        let Some(slot) = axes.iter().position(|a| a == axis) else {
            return Err(BadArguments(format!(
                "`{axis}` is not an axis of group {} (its axes: {})",
                group.name(),
                axes.join(", ")
            ))
            .into());
        };
        if positions[slot].replace(*position).is_some() {
            return Err(BadArguments(format!("`{axis}` is given twice")).into());
        }
    }
    let missing: Vec<&str> = axes
        .iter()
        .zip(&positions)
        .filter(|(_, position)| position.is_none())
        .map(|(axis, _)| axis.as_str())
        .collect();
    if !missing.is_empty() {
        return Err(BadArguments(format!(
            "every axis of group {} needs a target; missing: {}",
            group.name(),
            missing.join(", ")
        ))
        .into());
    }
    Ok(positions.into_iter().flatten().collect())
}

/// Sends a line or a trajectory (`send`), and with `wait` waits for its end and reports.
#[allow(clippy::too_many_arguments)]
fn execute(
    client: &Client<Service>,
    group: &Group<'_, Service>,
    what: &str,
    finals: &[f64],
    send: impl Fn() -> Result<GroupRun, ClientError>,
    wait: bool,
    json: bool,
    timeout: Duration,
) -> anyhow::Result<()> {
    let name = group.name();
    if !wait {
        let run = send().with_context(|| what.to_owned())?;
        if json {
            out!(
                "{}",
                json!({"group": name, "path_id": run.path_id, "tick": run.tick, "state": "moving"})
            );
        } else {
            out!(
                "{name}: {what}: running (path {}, tick {})",
                run.path_id,
                run.tick
            );
        }
        return Ok(());
    }
    let deadline = Instant::now() + timeout;
    let devices = member_devices(group);
    // As `move --wait`: ready devices first; a path refused because a device is (again)
    // starting is sent again (under a new id) after the next readiness.
    let sent = loop {
        let left = deadline.saturating_duration_since(Instant::now());
        if let Err(error) = client.wait_devices_ready(&devices, left) {
            break Err(error);
        }
        match send() {
            Err(error)
                if error.reason() == Some(Reason::DeviceStarting) && Instant::now() < deadline =>
            {
                std::thread::sleep(Duration::from_millis(5));
            }
            other => break other,
        }
    };
    let run = stop_if_interrupted(group, sent).with_context(|| what.to_owned())?;
    let mut report = GroupReport::new(
        &name,
        group.index() as usize,
        run.path_id,
        report_axes(client, group, finals)?,
    );
    let remaining = deadline.saturating_duration_since(Instant::now());
    let waited = group.wait_done_observing(remaining, |frame| report.observe(frame));
    let end = match (&waited, report.last()) {
        (Ok(_) | Err(ClientError::GroupAborted(_)), Some((tick, state))) => {
            let info = client.info()?;
            Some(GroupStatus::from_state(
                &info,
                group.index() as usize,
                tick,
                state,
            )?)
        }
        (Ok(_) | Err(ClientError::GroupAborted(_)), None) => Some(group.state()?),
        _ => None,
    };
    if let Some(end) = &end {
        if json {
            out!("{}", report.json(end));
        } else {
            for line in report.lines(end) {
                out!("{line}");
            }
        }
    }
    stop_if_interrupted(group, waited).with_context(|| what.to_owned())?;
    Ok(())
}

/// The devices of the group's axes (for the readiness wait).
fn member_devices(group: &Group<'_, Service>) -> Vec<usize> {
    let mut devices = Vec::new();
    for axis in group.axis_handles() {
        let device = usize::from(axis.info().device_index);
        if !devices.contains(&device) {
            devices.push(device);
        }
    }
    devices
}

/// The report's axes: names, units, final targets and goal tolerances.
fn report_axes(
    client: &Client<Service>,
    group: &Group<'_, Service>,
    finals: &[f64],
) -> anyhow::Result<Vec<ReportAxis>> {
    let info = client.info()?;
    let group_info = group.info();
    Ok(group_info
        .axes()
        .iter()
        .zip(finals)
        .enumerate()
        .map(|(slot, (&axis, &target))| {
            let axis_info = info.axes().get(axis as usize);
            ReportAxis {
                name: axis_info.map_or_else(|| format!("#{axis}"), |a| a.name().to_owned()),
                index: axis as usize,
                unit: axis_info.map_or_else(String::new, |a| a.unit().to_owned()),
                target,
                goal_tolerance: group_info.goal_tolerance[slot],
            }
        })
        .collect())
}

/// Ctrl-C while a group moves means "abort": the group is stopped before exiting.
fn stop_if_interrupted<T>(
    group: &Group<'_, Service>,
    result: Result<T, ClientError>,
) -> anyhow::Result<T> {
    match result {
        Err(ClientError::Interrupted) => {
            let stopped = match group.stop() {
                Ok(_) => format!("group {} stopped", group.name()),
                Err(error) => format!("stopping group {} failed too: {error}", group.name()),
            };
            Err(anyhow::Error::new(ClientError::Interrupted).context(stopped))
        }
        other => Ok(other?),
    }
}

/// hold, resume, cancel, stop.
fn steer(
    client: &Client<Service>,
    name: &str,
    verb: &str,
    send: impl FnOnce(&Group<'_, Service>) -> Result<motion_client::Accepted, ClientError>,
) -> anyhow::Result<()> {
    let group = client.group(name)?;
    let accepted = send(&group).with_context(|| format!("{verb} {name}"))?;
    out!("{name}: {verb} (tick {})", accepted.tick);
    Ok(())
}

/// `motionctl group claim NAME [--duration D]`.
fn claim(client: &Client<Service>, name: &str, duration: Option<Duration>) -> anyhow::Result<()> {
    let group = client.group(name)?;
    let guard = group.claim().with_context(|| format!("claim {name}"))?;
    let axes = group.axes().join(", ");
    match duration {
        Some(duration) => {
            eprintln!("claimed group {name} ({axes}) for {duration:?}; Ctrl-C releases")
        }
        None => eprintln!("claimed group {name} ({axes}); Ctrl-C releases"),
    }
    let until = duration.map(|duration| Instant::now() + duration);
    let outcome = crate::act::hold_claims(client, std::slice::from_ref(&guard), until);
    let released = match guard.release() {
        Ok(_) | Err(ClientError::ServerRestarted(_)) => Ok(()),
        Err(error) => Err(anyhow::Error::new(error).context(format!("release {name}"))),
    };
    outcome?;
    released?;
    eprintln!("released group {name}");
    Ok(())
}

/// A figure that is 0 when not supervised: `null` then.
fn supervised(value: f64) -> Value {
    if value == 0.0 {
        Value::Null
    } else {
        json!(value)
    }
}

/// One group of the description as JSON.
pub fn group_info_json(info: &ServerInfo, index: usize, group: &GroupInfo) -> Value {
    let axes: Vec<Value> = group
        .axes()
        .iter()
        .enumerate()
        .map(|(slot, &axis)| {
            let axis_info = info.axes().get(axis as usize);
            json!({
                "name": axis_info.map(|a| a.name()),
                "index": axis,
                "unit": axis_info.map(|a| a.unit()),
                "path_tolerance": supervised(group.path_tolerance[slot]),
                "goal_tolerance": group.goal_tolerance[slot],
            })
        })
        .collect();
    json!({
        "index": index,
        "name": group.name(),
        "axes": axes,
        "goal_time_tolerance": group.goal_time_tolerance,
        "stream_limit": if group.stream_limit == 0 { "clamp" } else { "abort" },
        "stream_timeout_ticks": group.stream_timeout,
        "stream_buffer_ticks": group.stream_buffer,
    })
}

/// `motionctl group list [--json]`.
fn list(client: &Client<Service>, json: bool) -> anyhow::Result<()> {
    let info = client.info()?;
    if json {
        let groups: Vec<Value> = info
            .groups()
            .iter()
            .enumerate()
            .map(|(index, group)| group_info_json(&info, index, group))
            .collect();
        out!(
            "{}",
            serde_json::to_string_pretty(&json!({ "groups": groups }))?
        );
        return Ok(());
    }
    if info.groups().is_empty() {
        out!("no groups ([[group]] in the server's config)");
        return Ok(());
    }
    for group in info.groups() {
        let names: Vec<&str> = group
            .axes()
            .iter()
            .map(|&axis| info.axes().get(axis as usize).map_or("?", |a| a.name()))
            .collect();
        out!(
            "{}: {} (goal time {} s)",
            group.name(),
            names.join(" "),
            group.goal_time_tolerance
        );
        for (slot, &axis) in group.axes().iter().enumerate() {
            let (name, unit) = info
                .axes()
                .get(axis as usize)
                .map_or(("?", ""), |a| (a.name(), a.unit()));
            let path = match group.path_tolerance[slot] {
                0.0 => "not checked".to_owned(),
                tolerance => format!("{tolerance} {unit}"),
            };
            out!(
                "  {name:<14} path tolerance {path:<14} goal tolerance {} {unit}",
                group.goal_tolerance[slot]
            );
        }
    }
    Ok(())
}

/// One line about a group for `watch`: motion, point, time, feed, abort.
pub fn group_line(status: &GroupStatus) -> String {
    let mut line = format!(
        "{:<12} {:<8} point {:<5} {:>8.3}/{:<8.3} s  feed {:>3.0}% (set {:.0}%)",
        status.name,
        status.motion.name(),
        status.point,
        status.time,
        status.duration,
        status.feed * 100.0,
        status.feed_set * 100.0
    );
    if status.motion == motion_client::ipc::GroupMotion::Aborted {
        line.push_str(&format!("  aborted: {}", status.abort.name()));
        if let Some(axis) = &status.abort_axis {
            line.push_str(&format!(
                " ({axis}: {:.4} / {:.4} {})",
                status.abort_value, status.abort_limit, status.abort_unit
            ));
        }
    }
    line
}

/// Every group of `frame` as JSON (for `watch --json`).
pub fn groups_json(info: &ServerInfo, frame: &motion_client::ipc::MotionFrame) -> Value {
    let groups: Vec<Value> = (0..info.groups().len())
        .filter_map(|index| GroupStatus::read(info, frame, index).ok())
        .map(|status| {
            let aborted = status.motion == motion_client::ipc::GroupMotion::Aborted;
            json!({
                "name": status.name,
                "motion": status.motion.name(),
                "abort": aborted.then(|| status.abort.name()),
                "abort_axis": status.abort_axis,
                "path_id": status.path_id,
                "kind": status.kind.name(),
                "point": status.point,
                "time": status.time,
                "duration": status.duration,
                "feed": status.feed,
                "feed_set": status.feed_set,
            })
        })
        .collect();
    Value::Array(groups)
}
