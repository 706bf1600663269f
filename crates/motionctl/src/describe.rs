//! `list` and `status`, as text tables or JSON; the JSON and text views of an axis, a device
//! and a frame are shared with `watch`, and the JSON of an axis, the devices and a frame
//! with the bridge's JSON state (`motion_wire::json`).

use motion_client::ipc::{
    AxisFlags, AxisInfo, AxisState, CommandKind, DeviceState, FrameFlags, MotionFrame, ServerInfo,
    ServerStats, read_text,
};
use motion_client::{Client, Params};
use motion_wire::json;
use serde_json::{Value, json};

use crate::Service;
use crate::io::{signal_info_json, signal_states_json, signals_text};
use crate::machine::{ParamTable, params_lines};

/// Names of the set flags, in bit order.
pub fn flag_names(flags: AxisFlags) -> Vec<&'static str> {
    flags.names()
}

/// The mode as the CLI spells it.
pub fn mode_name(state: &AxisState) -> String {
    state.mode_name()
}

/// The fault's name ("following-error"), `None` when the axis has none.
pub fn fault_name(state: &AxisState) -> Option<String> {
    state.fault_name()
}

/// The fault in words ([`FaultCode::explain`](motion_client::ipc::FaultCode::explain)),
/// `None` when the axis has none.
pub fn fault_text(axis: &AxisInfo, state: &AxisState) -> Option<String> {
    json::fault_text(axis, state, "motionctl")
}

/// The e-stop category as the config spells it.
fn estop_name(axis: &AxisInfo) -> String {
    axis.estop().map_or_else(
        |error| format!("estop {}", error.0),
        |category| category.name().to_owned(),
    )
}

/// A supervision figure: `null` when 0 (not supervised).
fn supervised(value: f64) -> Value {
    if value == 0.0 {
        Value::Null
    } else {
        json!(value)
    }
}

fn axis_info_json(index: usize, axis: &AxisInfo, params: &ParamTable) -> Value {
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
        "device_index": axis.device_index,
        "channel": axis.channel,
        "counts_per_unit": axis.counts_per_unit,
        "min": axis.min,
        "max": axis.max,
        "max_velocity": axis.max_velocity,
        "max_accel": axis.max_accel,
        "capabilities": capabilities,
        "following_error": supervised(axis.following_error),
        "overspeed_factor": supervised(axis.overspeed_factor),
        "home_max_travel": supervised(axis.home_max_travel),
        "estop": estop_name(axis),
        "params": params.axis_json(index),
    })
}

/// The server description (and the machine parameters) as JSON.
pub fn info_json(info: &ServerInfo, params: &ParamTable) -> Value {
    let devices: Vec<Value> = info
        .devices()
        .iter()
        .enumerate()
        .map(|(index, device)| {
            json!({
                "index": index,
                "name": device.name(),
                "link": read_text(&device.link),
                "model": device.model_name(),
                "address": device.address,
                "firmware": device.firmware(),
                "axis_count": device.axis_count,
                "online": device.state() == DeviceState::Online,
                "state": device.state().name(),
                "params": params.device_json(index),
            })
        })
        .collect();
    let mut value = json!({
        "server": read_text(&info.name),
        "schema_version": info.schema_version,
        "tick_hz": info.tick_hz,
        "command_timeout_ms": info.command_timeout_ms,
        "max_clients": info.max_clients,
        "server_pid": info.server_pid,
        "axes": info.axes().iter().enumerate().map(|(i, a)| axis_info_json(i, a, params)).collect::<Vec<_>>(),
        "devices": devices,
        "signals": info.signals().iter().enumerate().map(|(i, s)| signal_info_json(i, s)).collect::<Vec<_>>(),
        "params_truncated": params.truncated(),
    });
    if let Some(error) = params.error() {
        value["params_error"] = json!(error);
    }
    value
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
    let stamp = |ns: u64| if ns == 0 { Value::Null } else { json!(ns) };
    let links: Vec<Value> = stats
        .links()
        .iter()
        .zip(stats.link_io())
        .map(|(link, io)| {
            json!({
                "name": link.name(),
                "up": link.up != 0,
                "bytes_in": link.bytes_in,
                "bytes_out": link.bytes_out,
                "frames": link.frames,
                "errors": link.errors,
                "reconnects": link.reconnects,
                "deferred": link.deferred,
                "last_write_ns": stamp(io.last_write_ns),
                "last_read_ns": stamp(io.last_read_ns),
                "transactions": io.transactions,
                "reads": io.reads,
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
        "faults": stats.faults,
        "frames_lost": stats.frames_lost,
        "publish_failures": stats.publish_failures,
        "replies_lost": stats.replies_lost,
        "events_dropped": stats.events_dropped,
        "nodes_cleaned": stats.nodes_cleaned,
        "blackbox_lost": stats.blackbox_lost,
        "paths_dropped": stats.paths_dropped,
        "setpoints_dropped": stats.setpoints_dropped,
        "links": links,
    })
}

/// A frame (the chosen axes, every device and signal) as JSON.
pub fn frame_json(info: &ServerInfo, frame: &MotionFrame, axes: &[usize]) -> Value {
    let states: Vec<Value> = axes
        .iter()
        .filter_map(|&index| {
            let state = frame.axes().get(index)?;
            let axis = info.axes().get(index)?;
            let mut value = json::axis_state(axis, state, frame.tick, "motionctl");
            if let Some(wire) = frame.wire().get(index) {
                value["goal_tick"] = json!(wire.goal_tick);
                value["wire_tick"] = if wire.written() {
                    json!(wire.wire_tick)
                } else {
                    Value::Null
                };
                value["wire_ns"] = if wire.written() {
                    json!(wire.wire_ns)
                } else {
                    Value::Null
                };
            }
            Some(value)
        })
        .collect();
    let signals = signal_states_json(info, frame);
    json::frame(info, frame, states, signals)
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
    let params: Result<Params<Service>, _> = client.machine_params();
    let params = ParamTable::new(params);
    if json {
        out!(
            "{}",
            serde_json::to_string_pretty(&info_json(&info, &params))?
        );
        return Ok(());
    }
    out!(
        "motiond \"{}\": {} Hz tick, deadman {} ms, {} axes, {} devices, {} signals",
        read_text(&info.name),
        info.tick_hz,
        info.command_timeout_ms,
        info.axes().len(),
        info.devices().len(),
        info.signals().len()
    );
    out!(
        "{:<4} {:<14} {:<6} {:<12} {:>10} {:>10} {:>10} {:>11} {:>9} {:>8} {:>10} {:<8}",
        "#",
        "axis",
        "unit",
        "device",
        "min",
        "max",
        "max vel",
        "max accel",
        "foll err",
        "overspd",
        "home trav",
        "estop"
    );
    let figure = |value: f64| {
        if value == 0.0 {
            "-".to_owned()
        } else {
            significant(value)
        }
    };
    for (index, axis) in info.axes().iter().enumerate() {
        out!(
            "{:<4} {:<14} {:<6} {:<12} {:>10} {:>10} {:>10} {:>11} {:>9} {:>8} {:>10} {:<8}",
            index,
            axis.name(),
            axis.unit(),
            read_text(&axis.device),
            axis.min,
            axis.max,
            axis.max_velocity,
            axis.max_accel,
            figure(axis.following_error),
            figure(axis.overspeed_factor),
            figure(axis.home_max_travel),
            estop_name(axis)
        );
    }
    out!(
        "{:<14} {:<10} {:<10} {:<9} firmware",
        "device",
        "model",
        "link",
        "state"
    );
    for device in info.devices() {
        out!(
            "{:<14} {:<10} {:<10} {:<9} {}",
            device.name(),
            device.model_name(),
            read_text(&device.link),
            device.state().name(),
            device.firmware()
        );
    }
    for line in signals_text(&info, None) {
        out!("{line}");
    }
    for line in params_lines(&info, &params) {
        out!("{line}");
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
    out!("devices: {}", devices_line(&info, &frame));
    out!("{}", table_header());
    let mut faults = Vec::new();
    for index in axes {
        if let (Some(axis), Some(state)) = (info.axes().get(index), frame.axes().get(index)) {
            out!("{}", table_row(axis, state, frame.tick));
            faults.extend(fault_text(axis, state));
        }
    }
    for fault in faults {
        out!("fault: {fault}");
    }
    for line in signals_text(&info, Some(&frame)) {
        out!("{line}");
    }
    Ok(())
}

/// "pack online, aux starting".
pub fn devices_line(info: &ServerInfo, frame: &MotionFrame) -> String {
    let list: Vec<String> = info
        .devices()
        .iter()
        .enumerate()
        .map(|(index, device)| format!("{} {}", device.name(), frame.device_state(index).name()))
        .collect();
    if list.is_empty() {
        "none".to_owned()
    } else {
        list.join(", ")
    }
}

/// Header of the axis table of `status` and `watch`.
pub fn table_header() -> String {
    format!(
        "{:<14} {:>12} {:>12} {:>12} {:<5} {:<14} {:>6}  {}",
        "axis", "position", "velocity", "target", "unit", "mode", "age", "flags"
    )
}

/// The flags of an axis with its fault name appended.
pub fn flags_with_fault(state: &AxisState) -> String {
    let flags = flag_names(state.flags()).join(",");
    match fault_name(state) {
        Some(fault) => format!("{flags} [{fault}]"),
        None => flags,
    }
}

/// One row of the axis table.
pub fn table_row(axis: &AxisInfo, state: &AxisState, tick: u64) -> String {
    format!(
        "{:<14} {:>12.4} {:>12.4} {:>12.4} {:<5} {:<14} {:>6}  {}",
        axis.name(),
        state.position,
        state.velocity,
        state.target,
        axis.unit(),
        mode_name(state),
        tick.saturating_sub(state.last_refresh_tick),
        flags_with_fault(state)
    )
}

/// `value` with at most six significant digits (17.99998560001152 reads as 18).
fn significant(value: f64) -> String {
    if !value.is_finite() || value == 0.0 {
        return format!("{value}");
    }
    let digits = 5 - value.abs().log10().floor() as i32;
    let rounded = if digits > 0 {
        let scale = 10f64.powi(digits);
        (value * scale).round() / scale
    } else {
        value.round()
    };
    format!("{rounded}")
}
