//! The state as JSON, for tools that do not want the binary layout: the JSON state the
//! bridge publishes on `motiond/<name>/state/json`, and the same views of an axis, a signal
//! and the devices that `motionctl status --json` and `watch --json` print. Written once
//! here, so the two never drift (feature `json`).
//!
//! The state is the shape of `motionctl status --json` (tick, e-stop, devices, axes with
//! their mode, flags and fault in words, signals) plus the server's name and, for a claim a
//! remote holds through the bridge, that remote's identity (`claimed_by_remote`).
//!
//! Objects are `serde_json` maps (sorted keys), so a caller adds its own keys (motionctl's
//! `text` of a signal, the wire times of an axis) without changing the others.
//!
//! ```
//! use motion_ipc::{MotionFrame, ServerInfo, write_text};
//!
//! let mut info = ServerInfo::EMPTY;
//! write_text(&mut info.name, "demo");
//! let state = motion_wire::json::state(&info, &MotionFrame::EMPTY, |_, _| None);
//! assert_eq!(state["server"], "demo");
//! assert_eq!(state["estop"], false);
//! ```

use motion_ipc::{
    AxisInfo, AxisState, ClientId, DeviceState, FaultCode, FrameFlags, MotionFrame, ServerInfo,
    SignalInfo, SignalKind, SignalState, Target,
};
use serde_json::{Value, json};

/// A client id as text (32 hex digits); `null` for none.
fn claimant(claimed_by: ClientId) -> Value {
    if claimed_by.is_none() {
        Value::Null
    } else {
        json!(format!("{:032x}", claimed_by.as_u128()))
    }
}

/// The fault of `state` in words ([`FaultCode::explain`]); `None` when the axis has none.
/// A code this build does not know is named with `reader`, the program that read it
/// ("motionctl", "motion-bridge").
pub fn fault_text(axis: &AxisInfo, state: &AxisState, reader: &str) -> Option<String> {
    match state.fault() {
        Ok(FaultCode::None) => None,
        Ok(code) => Some(code.explain(
            axis.name(),
            state.fault_value,
            state.fault_limit,
            axis.unit(),
        )),
        Err(error) => Some(format!(
            "axis `{}`: fault {} (unknown to this {reader})",
            axis.name(),
            error.0
        )),
    }
}

/// The kind of a signal as the config spells it (`kind N` for one this build does not know).
pub fn signal_kind_name(info: &SignalInfo) -> String {
    info.kind().map_or_else(
        |error| format!("kind {}", error.0),
        |kind| kind.name().to_owned(),
    )
}

/// One axis's state in a frame of server tick `tick`, named by its description; `reader`
/// as for [`fault_text`].
pub fn axis_state(info: &AxisInfo, state: &AxisState, tick: u64, reader: &str) -> Value {
    let faulted = state.fault_name().is_some();
    json!({
        "name": info.name(),
        "unit": info.unit(),
        "device": info.device(),
        "device_state": state.device_state().map_or("unknown", DeviceState::name),
        "position": state.position,
        "velocity": state.velocity,
        "target": state.target,
        "raw_counts": state.raw_counts,
        "mode": state.mode_name(),
        "flags": state.flags().names(),
        "fault": state.fault_name(),
        "fault_text": fault_text(info, state, reader),
        "fault_value": if faulted { json!(state.fault_value) } else { Value::Null },
        "fault_limit": if faulted { json!(state.fault_limit) } else { Value::Null },
        "last_refresh_tick": state.last_refresh_tick,
        "age_ticks": tick.saturating_sub(state.last_refresh_tick),
        "claimed_by": claimant(state.claimed_by),
    })
}

/// Signal `index`'s state in a frame of server tick `tick`, with its description's name,
/// device, pin, kind and unit.
pub fn signal_state(index: usize, info: &SignalInfo, state: &SignalState, tick: u64) -> Value {
    let digital = matches!(
        info.kind(),
        Ok(SignalKind::DigitalIn | SignalKind::DigitalOut)
    );
    // A capture's or a trigger's events: how many, and the tick that took the newest in.
    let events = matches!(info.kind(), Ok(SignalKind::Capture | SignalKind::Trigger));
    let event = |value: Value| if events { value } else { Value::Null };
    json!({
        "index": index,
        "name": info.name(),
        "device": info.device(),
        "pin": info.pin(),
        "kind": signal_kind_name(info),
        "unit": info.unit(),
        "value": state.value,
        "raw": state.raw,
        "on": if digital { json!(state.is_on()) } else { Value::Null },
        "flags": state.flags().names(),
        "last_refresh_tick": state.last_refresh_tick,
        "age_ticks": tick.saturating_sub(state.last_refresh_tick),
        "claimed_by": claimant(state.claimed_by),
        "sequence": event(json!(state.sequence)),
        "event_tick": event(json!(state.event_tick)),
    })
}

/// Every device of `info`: its name, its model's name (`DeviceInfo::model_name`), its state in
/// `frame` and its firmware.
pub fn devices(info: &ServerInfo, frame: &MotionFrame) -> Vec<Value> {
    info.devices()
        .iter()
        .enumerate()
        .map(|(index, device)| {
            json!({
                "name": device.name(),
                "model": device.model_name(),
                "state": frame.device_state(index).name(),
                "firmware": device.firmware(),
            })
        })
        .collect()
}

/// A frame: its tick, time, e-stop and shutdown flags, the devices, and the `axes` and
/// `signals` the caller wrote (all of them, or a selection).
pub fn frame(
    info: &ServerInfo,
    frame: &MotionFrame,
    axes: Vec<Value>,
    signals: Vec<Value>,
) -> Value {
    json!({
        "tick": frame.tick,
        "time_ns": frame.time_ns,
        "estop": frame.flags().contains(FrameFlags::ESTOP_LATCHED),
        "shutting_down": frame.flags().contains(FrameFlags::SHUTTING_DOWN),
        "devices": devices(info, frame),
        "axes": axes,
        "signals": signals,
    })
}

/// The bridge's JSON state of `frame`, named by `info`: every axis and signal, the server's
/// name, and `claimed_by_remote`: the identity `holder` says holds the claim of an axis or
/// a signal (by index) through the bridge, `null` for none.
pub fn state<'h>(
    info: &ServerInfo,
    frame_now: &MotionFrame,
    holder: impl Fn(Target, u32) -> Option<&'h str>,
) -> Value {
    let tick = frame_now.tick;
    // Each axis's or signal's view, with the remote that holds its claim (by index).
    let held = |target, views: Vec<Value>| -> Vec<Value> {
        views
            .into_iter()
            .zip(0u32..)
            .map(|(mut view, index)| {
                view["claimed_by_remote"] =
                    holder(target, index).map_or(Value::Null, |id| json!(id));
                view
            })
            .collect()
    };
    let axes = info.axes().iter().zip(frame_now.axes());
    let axes = axes.map(|(axis, state)| axis_state(axis, state, tick, "motion-bridge"));
    let signals = info.signals().iter().zip(frame_now.signals()).enumerate();
    let signals = signals.map(|(index, (signal, state))| signal_state(index, signal, state, tick));
    let axes = held(Target::Axis, axes.collect());
    let signals = held(Target::Signal, signals.collect());
    let mut value = frame(info, frame_now, axes, signals);
    value["server"] = json!(info.name());
    value
}

#[cfg(test)]
mod tests {
    use motion_ipc::{AxisFlags, AxisMode, DeviceInfo, SignalFlags, write_text};

    use super::*;

    fn one_axis_one_signal() -> (ServerInfo, MotionFrame) {
        let mut info = ServerInfo::EMPTY;
        write_text(&mut info.name, "demo");
        info.axis_count = 1;
        info.device_count = 1;
        info.signal_count = 1;
        let mut axis = AxisInfo::EMPTY;
        write_text(&mut axis.name, "x");
        write_text(&mut axis.unit, "mm");
        info.axes[0] = axis;
        let mut device = DeviceInfo::EMPTY;
        write_text(&mut device.name, "pack");
        write_text(&mut device.model_id, "widget");
        device.model = 99;
        info.devices[0] = device;
        let mut signal = SignalInfo::EMPTY;
        write_text(&mut signal.name, "door");
        signal.kind = SignalKind::DigitalIn as u8;
        info.signals[0] = signal;

        let mut frame = MotionFrame::EMPTY;
        frame.tick = 1200;
        frame.flags = FrameFlags::ESTOP_LATCHED.0;
        frame.axis_count = 1;
        frame.device_count = 1;
        frame.signal_count = 1;
        frame.devices[0] = DeviceState::Online as u8;
        frame.axes[0].position = 2.5;
        frame.axes[0].mode = AxisMode::Hold as u8;
        frame.axes[0].fault = FaultCode::FollowingError as u16;
        frame.axes[0].fault_value = 3.0;
        frame.axes[0].fault_limit = 1.0;
        frame.axes[0].last_refresh_tick = 1190;
        frame.axes[0].flags = AxisFlags::FAULT.with(AxisFlags::CLAIMED, true).0;
        frame.axes[0].claimed_by = ClientId::from_u128(5);
        frame.signals[0].value = 1.0;
        frame.signals[0].last_refresh_tick = 1199;
        frame.signals[0].flags = SignalFlags::CLAIMED.0;
        (info, frame)
    }

    #[test]
    fn state_names_everything_and_shows_remote_claims() {
        let (info, frame) = one_axis_one_signal();
        let value = state(&info, &frame, |target, index| {
            (target == Target::Axis && index == 0).then_some("panel")
        });
        assert_eq!(value["server"], "demo");
        assert_eq!(value["estop"], true);
        assert_eq!(value["devices"][0]["state"], "online");
        assert_eq!(
            value["devices"][0]["model"], "widget",
            "a board no client knows"
        );
        let x = &value["axes"][0];
        assert_eq!(x["name"], "x");
        assert_eq!(x["position"], 2.5);
        assert_eq!(x["mode"], "hold");
        assert_eq!(x["fault"], "following-error");
        assert!(
            x["fault_text"]
                .as_str()
                .is_some_and(|t| t.contains("tolerance 1.0000 mm"))
        );
        assert_eq!(x["flags"], json!(["fault", "claimed"]));
        assert_eq!(x["age_ticks"], 10);
        assert_eq!(x["claimed_by"], "00000000000000000000000000000005");
        assert_eq!(x["claimed_by_remote"], "panel");
        let door = &value["signals"][0];
        assert_eq!(door["name"], "door");
        assert_eq!(door["kind"], "digital-in");
        assert_eq!(door["on"], true);
        assert_eq!(door["age_ticks"], 1);
        assert_eq!(door["claimed_by_remote"], Value::Null);
        assert_eq!(door["sequence"], Value::Null, "an input has no events");
    }

    #[test]
    fn a_capture_shows_its_sequence_and_the_tick_of_its_newest_event() {
        let (mut info, mut frame) = one_axis_one_signal();
        info.signals[0].kind = SignalKind::Capture as u8;
        frame.signals[0].sequence = 7;
        frame.signals[0].event_tick = 1180;
        let probe = signal_state(0, &info.signals[0], &frame.signals[0], frame.tick);
        assert_eq!(probe["kind"], "capture");
        assert_eq!(
            (probe["sequence"].clone(), probe["event_tick"].clone()),
            (json!(7), json!(1180))
        );
        assert_eq!(probe["on"], Value::Null);
    }

    #[test]
    fn codes_this_build_does_not_know_are_named_by_number() {
        let (mut info, mut frame) = one_axis_one_signal();
        frame.axes[0].fault = 999;
        info.signals[0].kind = 250;
        info.devices[0].model_id = [0; motion_ipc::MODEL_ID_LEN];
        assert_eq!(devices(&info, &frame)[0]["model"], "model 99");
        let x = axis_state(&info.axes[0], &frame.axes[0], frame.tick, "motionctl");
        assert_eq!(x["fault"], "fault 999");
        assert_eq!(
            x["fault_text"],
            "axis `x`: fault 999 (unknown to this motionctl)"
        );
        assert_eq!(x["fault_value"], 3.0);
        let door = signal_state(0, &info.signals[0], &frame.signals[0], frame.tick);
        assert_eq!(door["kind"], "kind 250");
        assert_eq!(door["on"], Value::Null, "not known to be digital");
    }
}
