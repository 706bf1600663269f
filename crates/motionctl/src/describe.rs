//! `list` and `status`, as text tables or JSON; the JSON and text views of an axis are
//! shared with `watch`.

use motion_client::Client;
use motion_client::ipc::{
    AxisFlags, AxisInfo, AxisMode, AxisState, CommandKind, DeviceModel, FrameFlags, MotionFrame,
    ServerInfo, ServerStats, read_text,
};
use serde_json::{Value, json};

use crate::Service;

/// Names of the set flags, in bit order.
pub fn flag_names(flags: AxisFlags) -> Vec<&'static str> {
    [
        (AxisFlags::MOVING, "moving"),
        (AxisFlags::HOMED, "homed"),
        (AxisFlags::AT_LIMIT, "at-limit"),
        (AxisFlags::STALE, "stale"),
        (AxisFlags::FAULT, "fault"),
        (AxisFlags::CLAIMED, "claimed"),
        (AxisFlags::ARRIVED, "arrived"),
        (AxisFlags::ESTOPPED, "estopped"),
        (AxisFlags::DEADMAN_EXPIRED, "deadman-expired"),
    ]
    .into_iter()
    .filter(|(flag, _)| flags.contains(*flag))
    .map(|(_, name)| name)
    .collect()
}

/// The mode as the CLI spells it.
pub fn mode_name(state: &AxisState) -> String {
    match state.mode() {
        Ok(mode) => match mode {
            AxisMode::Off => "off",
            AxisMode::Hold => "hold",
            AxisMode::Power => "power",
            AxisMode::Position => "position",
            AxisMode::Velocity => "velocity",
            AxisMode::RampPosition => "ramp-position",
            AxisMode::RampVelocity => "ramp-velocity",
            AxisMode::Homing => "homing",
            AxisMode::Stopping => "stopping",
        }
        .to_owned(),
        Err(error) => format!("mode {}", error.0),
    }
}

/// The fault as the CLI spells it ("" when none).
pub fn fault_name(state: &AxisState) -> String {
    match state.fault() {
        Ok(motion_client::ipc::FaultCode::None) => String::new(),
        Ok(code) => format!("{code:?}"),
        Err(error) => format!("fault {}", error.0),
    }
}

fn axis_info_json(index: usize, axis: &AxisInfo) -> Value {
    let capabilities: Vec<&str> = CommandKind::ALL
        .iter()
        .filter(|kind| axis.capabilities().supports(**kind))
        .map(|kind| kind.name())
        .collect();
    json!({
        "index": index,
        "name": axis.name(),
        "unit": axis.unit(),
        "device": read_text(&axis.device),
        "channel": axis.channel,
        "counts_per_unit": axis.counts_per_unit,
        "min": axis.min,
        "max": axis.max,
        "max_velocity": axis.max_velocity,
        "max_accel": axis.max_accel,
        "capabilities": capabilities,
    })
}

/// The server description as JSON.
pub fn info_json(info: &ServerInfo) -> Value {
    let devices: Vec<Value> = info
        .devices()
        .iter()
        .map(|device| {
            json!({
                "name": device.name(),
                "link": read_text(&device.link),
                "model": device.model().map_or("unknown", DeviceModel::id),
                "address": device.address,
                "firmware": read_text(&device.firmware),
                "axis_count": device.axis_count,
                "online": device.state() == motion_client::ipc::DeviceState::Online,
                "state": device.state().name(),
            })
        })
        .collect();
    json!({
        "server": read_text(&info.name),
        "schema_version": info.schema_version,
        "tick_hz": info.tick_hz,
        "command_timeout_ms": info.command_timeout_ms,
        "max_clients": info.max_clients,
        "server_pid": info.server_pid,
        "axes": info.axes().iter().enumerate().map(|(i, a)| axis_info_json(i, a)).collect::<Vec<_>>(),
        "devices": devices,
    })
}

/// One axis's state in a frame as JSON.
pub fn axis_state_json(info: &AxisInfo, state: &AxisState, tick: u64) -> Value {
    json!({
        "name": info.name(),
        "unit": info.unit(),
        "position": state.position,
        "velocity": state.velocity,
        "target": state.target,
        "raw_counts": state.raw_counts,
        "mode": mode_name(state),
        "flags": flag_names(state.flags()),
        "fault": fault_name(state),
        "last_refresh_tick": state.last_refresh_tick,
        "age_ticks": tick.saturating_sub(state.last_refresh_tick),
        "claimed_by": if state.claimed_by.is_none() { Value::Null } else { json!(format!("{:032x}", state.claimed_by.as_u128())) },
    })
}

/// Server figures as JSON.
pub fn stats_json(stats: &ServerStats) -> Value {
    let latency = |summary: &motion_client::ipc::LatencySummary| {
        json!({
            "samples": summary.samples,
            "p50_ns": summary.p50_ns,
            "p99_ns": summary.p99_ns,
            "p999_ns": summary.p999_ns,
            "max_ns": summary.max_ns,
        })
    };
    let links: Vec<Value> = stats
        .links()
        .iter()
        .map(|link| {
            json!({
                "name": link.name(),
                "up": link.up != 0,
                "bytes_in": link.bytes_in,
                "bytes_out": link.bytes_out,
                "frames": link.frames,
                "errors": link.errors,
                "reconnects": link.reconnects,
            })
        })
        .collect();
    json!({
        "tick": stats.tick,
        "wakeup": latency(&stats.wakeup),
        "work": latency(&stats.work),
        "overruns": stats.overruns,
        "max_consecutive_overruns": stats.max_consecutive_overruns,
        "commands": stats.commands,
        "rejected": stats.rejected,
        "clients": stats.clients,
        "rt_flags": stats.rt_flags,
        "links": links,
    })
}

/// A frame (the chosen axes) as JSON.
pub fn frame_json(info: &ServerInfo, frame: &MotionFrame, axes: &[usize]) -> Value {
    let states: Vec<Value> = axes
        .iter()
        .filter_map(|&index| {
            let state = frame.axes().get(index)?;
            let axis = info.axes().get(index)?;
            Some(axis_state_json(axis, state, frame.tick))
        })
        .collect();
    json!({
        "tick": frame.tick,
        "time_ns": frame.time_ns,
        "estop": frame.flags().contains(FrameFlags::ESTOP_LATCHED),
        "shutting_down": frame.flags().contains(FrameFlags::SHUTTING_DOWN),
        "axes": states,
    })
}

/// Axis indices for the names given (all axes when none).
pub fn select_axes(client: &Client<Service>, names: &[String]) -> anyhow::Result<Vec<usize>> {
    if names.is_empty() {
        return Ok((0..client.axes().len()).collect());
    }
    names
        .iter()
        .map(|name| Ok(client.axis(name)?.index() as usize))
        .collect()
}

/// `motionctl list`.
pub fn list(client: &Client<Service>, json: bool) -> anyhow::Result<()> {
    let info = client.info()?;
    if json {
        out!("{}", serde_json::to_string_pretty(&info_json(&info))?);
        return Ok(());
    }
    out!(
        "motiond \"{}\": {} Hz tick, deadman {} ms, {} axes, {} devices",
        read_text(&info.name),
        info.tick_hz,
        info.command_timeout_ms,
        info.axes().len(),
        info.devices().len()
    );
    out!(
        "{:<4} {:<14} {:<6} {:<12} {:>10} {:>10} {:>10} {:>11}",
        "#",
        "axis",
        "unit",
        "device",
        "min",
        "max",
        "max vel",
        "max accel"
    );
    for (index, axis) in info.axes().iter().enumerate() {
        out!(
            "{:<4} {:<14} {:<6} {:<12} {:>10} {:>10} {:>10} {:>11}",
            index,
            axis.name(),
            axis.unit(),
            read_text(&axis.device),
            axis.min,
            axis.max,
            axis.max_velocity,
            axis.max_accel
        );
    }
    out!(
        "{:<14} {:<10} {:<10} {:<8} firmware",
        "device",
        "model",
        "link",
        "online"
    );
    for device in info.devices() {
        out!(
            "{:<14} {:<10} {:<10} {:<8} {}",
            device.name(),
            device.model().map_or("unknown", DeviceModel::id),
            read_text(&device.link),
            device.state().name(),
            read_text(&device.firmware)
        );
    }
    Ok(())
}

/// `motionctl status`.
pub fn status(client: &Client<Service>, names: &[String], json: bool) -> anyhow::Result<()> {
    let axes = select_axes(client, names)?;
    let info = client.info()?;
    let frame = client.latest()?;
    if json {
        let mut value = frame_json(&info, &frame, &axes);
        // The stats service is opened on first use; the server hands a new subscriber its
        // latest sample within a tick or two.
        let mut stats = client.stats()?;
        for _ in 0..40 {
            if stats.is_some() {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
            stats = client.stats()?;
        }
        if let Some(stats) = stats {
            value["stats"] = stats_json(&stats);
        }
        out!("{}", serde_json::to_string_pretty(&value)?);
        return Ok(());
    }
    let estop = if frame.flags().contains(FrameFlags::ESTOP_LATCHED) {
        "  E-STOP LATCHED"
    } else {
        ""
    };
    out!("tick {}{estop}", frame.tick);
    out!("{}", table_header());
    for index in axes {
        if let (Some(axis), Some(state)) = (info.axes().get(index), frame.axes().get(index)) {
            out!("{}", table_row(axis, state, frame.tick));
        }
    }
    Ok(())
}

/// Header of the axis table of `status` and `watch`.
pub fn table_header() -> String {
    format!(
        "{:<14} {:>12} {:>12} {:>12} {:<5} {:<14} {:>6}  {}",
        "axis", "position", "velocity", "target", "unit", "mode", "age", "flags"
    )
}

/// One row of the axis table.
pub fn table_row(axis: &AxisInfo, state: &AxisState, tick: u64) -> String {
    let mut flags = flag_names(state.flags()).join(",");
    let fault = fault_name(state);
    if !fault.is_empty() {
        flags = format!("{flags} [{fault}]");
    }
    format!(
        "{:<14} {:>12.4} {:>12.4} {:>12.4} {:<5} {:<14} {:>6}  {}",
        axis.name(),
        state.position,
        state.velocity,
        state.target,
        axis.unit(),
        mode_name(state),
        tick.saturating_sub(state.last_refresh_tick),
        flags
    )
}
