//! The JSON state published on `motiond/<name>/state/json` for tools that do not want the
//! binary layout: the shape of `motionctl status --json` (tick, e-stop, devices, axes with
//! their mode, flags and fault in words, signals), plus the server's name and, for a claim
//! a remote holds through this bridge, that remote's identity.

use motion_ipc::{
    AxisFlags, AxisInfo, AxisMode, AxisState, DeviceState, FaultCode, FrameFlags, MotionFrame,
    ServerInfo, SignalFlags, SignalInfo, SignalKind, SignalState, Target,
};
use serde_json::{Value, json};

use crate::policy::Policy;

fn axis_flag_names(flags: AxisFlags) -> Vec<&'static str> {
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

fn signal_flag_names(flags: SignalFlags) -> Vec<&'static str> {
    [
        (SignalFlags::STALE, "stale"),
        (SignalFlags::CLAIMED, "claimed"),
        (SignalFlags::SAFE_STATE, "safe-state"),
        (SignalFlags::PENDING, "pending"),
    ]
    .into_iter()
    .filter(|(flag, _)| flags.contains(*flag))
    .map(|(_, name)| name)
    .collect()
}

fn mode_name(state: &AxisState) -> String {
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

fn claimant(claimed_by: motion_ipc::ClientId) -> Value {
    if claimed_by.is_none() {
        Value::Null
    } else {
        json!(format!("{:032x}", claimed_by.as_u128()))
    }
}

fn remote_holder(policy: &Policy, target: Target, index: usize) -> Value {
    u32::try_from(index)
        .ok()
        .and_then(|index| policy.holder(target, index))
        .map_or(Value::Null, |remote| json!(remote.identity))
}

fn axis_json(info: &AxisInfo, state: &AxisState, tick: u64, remote: Value) -> Value {
    let fault = state.fault().ok().filter(|code| *code != FaultCode::None);
    json!({
        "name": info.name(),
        "unit": info.unit(),
        "device": info.device(),
        "device_state": state.device_state().map_or("unknown", DeviceState::name),
        "position": state.position,
        "velocity": state.velocity,
        "target": state.target,
        "raw_counts": state.raw_counts,
        "mode": mode_name(state),
        "flags": axis_flag_names(state.flags()),
        "fault": fault.map(FaultCode::name),
        "fault_text": fault.map(|code| code.explain(
            info.name(), state.fault_value, state.fault_limit, info.unit())),
        "last_refresh_tick": state.last_refresh_tick,
        "age_ticks": tick.saturating_sub(state.last_refresh_tick),
        "claimed_by": claimant(state.claimed_by),
        "claimed_by_remote": remote,
    })
}

fn signal_json(
    index: usize,
    info: &SignalInfo,
    state: &SignalState,
    tick: u64,
    remote: Value,
) -> Value {
    let digital = matches!(
        info.kind(),
        Ok(SignalKind::DigitalIn | SignalKind::DigitalOut)
    );
    json!({
        "index": index,
        "name": info.name(),
        "device": info.device(),
        "pin": info.pin(),
        "kind": info.kind().map_or("unknown", SignalKind::name),
        "unit": info.unit(),
        "value": state.value,
        "raw": state.raw,
        "on": if digital { json!(state.is_on()) } else { Value::Null },
        "flags": signal_flag_names(state.flags()),
        "last_refresh_tick": state.last_refresh_tick,
        "age_ticks": tick.saturating_sub(state.last_refresh_tick),
        "claimed_by": claimant(state.claimed_by),
        "claimed_by_remote": remote,
    })
}

/// The JSON state of `frame`, named by `info`; `policy` tells which remote holds a claim.
pub fn state(info: &ServerInfo, frame: &MotionFrame, policy: &Policy) -> Value {
    let axes: Vec<Value> = info
        .axes()
        .iter()
        .zip(frame.axes())
        .enumerate()
        .map(|(index, (axis, state))| {
            axis_json(
                axis,
                state,
                frame.tick,
                remote_holder(policy, Target::Axis, index),
            )
        })
        .collect();
    let signals: Vec<Value> = info
        .signals()
        .iter()
        .zip(frame.signals())
        .enumerate()
        .map(|(index, (signal, state))| {
            signal_json(
                index,
                signal,
                state,
                frame.tick,
                remote_holder(policy, Target::Signal, index),
            )
        })
        .collect();
    let devices: Vec<Value> = info
        .devices()
        .iter()
        .enumerate()
        .map(|(index, device)| {
            json!({
                "name": device.name(),
                "state": frame.device_state(index).name(),
                "firmware": device.firmware(),
            })
        })
        .collect();
    json!({
        "server": info.name(),
        "tick": frame.tick,
        "time_ns": frame.time_ns,
        "estop": frame.flags().contains(FrameFlags::ESTOP_LATCHED),
        "shutting_down": frame.flags().contains(FrameFlags::SHUTTING_DOWN),
        "devices": devices,
        "axes": axes,
        "signals": signals,
    })
}

#[cfg(test)]
mod tests {
    use motion_ipc::{
        AxisInfo, ClientId, CommandKind, CommandReply, CommandRequest, DeviceInfo, Reason,
        write_text,
    };

    use super::*;
    use crate::keys::SessionId;
    use crate::policy::{KindSet, Remote, RemoteRule};

    #[test]
    fn state_names_everything_and_shows_remote_claims() {
        let mut info = ServerInfo::EMPTY;
        write_text(&mut info.name, "demo");
        info.axis_count = 1;
        info.device_count = 1;
        let mut axis = AxisInfo::EMPTY;
        write_text(&mut axis.name, "x");
        write_text(&mut axis.unit, "mm");
        info.axes[0] = axis;
        let mut device = DeviceInfo::EMPTY;
        write_text(&mut device.name, "pack");
        info.devices[0] = device;

        let mut frame = MotionFrame::EMPTY;
        frame.tick = 1200;
        frame.flags = FrameFlags::ESTOP_LATCHED.0;
        frame.axis_count = 1;
        frame.device_count = 1;
        frame.devices[0] = DeviceState::Online as u8;
        frame.axes[0].position = 2.5;
        frame.axes[0].mode = AxisMode::Hold as u8;
        frame.axes[0].fault = FaultCode::FollowingError as u16;
        frame.axes[0].fault_value = 3.0;
        frame.axes[0].fault_limit = 1.0;
        frame.axes[0].last_refresh_tick = 1190;
        frame.axes[0].flags = AxisFlags::FAULT.with(AxisFlags::CLAIMED, true).0;
        frame.axes[0].claimed_by = ClientId::from_u128(5);

        let mut policy = Policy::new(
            vec![RemoteRule {
                identity: "*".to_owned(),
                allow: KindSet::all(),
                rate: 10.0,
                burst: 10.0,
            }],
            None,
        );
        let claim = CommandRequest::new(ClientId::NONE, 1, 0, CommandKind::Claim);
        let remote = Remote {
            identity: "panel".to_owned(),
            session: SessionId(1),
        };
        policy.on_reply(
            &remote,
            &claim,
            &CommandReply::to(&claim, Reason::Accepted, 1),
        );

        let value = state(&info, &frame, &policy);
        assert_eq!(value["server"], "demo");
        assert_eq!(value["estop"], true);
        assert_eq!(value["devices"][0]["state"], "online");
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
        assert_eq!(x["claimed_by_remote"], "panel");
        assert_eq!(value["signals"], json!([]));
    }
}
