//! Writing the frame and the server description.

use motion_drivers::Driver;
use motion_ipc::{
    AxisFlags, AxisInfo, AxisMode, AxisState, AxisWire, ClientId, DeviceInfo, FrameFlags,
    GroupInfo, MAX_GROUP_AXES, MotionFrame, SCHEMA_VERSION, ServerInfo, SignalFlags, SignalInfo,
    SignalInfoFlags, SignalState, write_text,
};

use crate::Engine;
use crate::config::EstopCategory;

impl<D: Driver> Engine<D> {
    /// Step 5: the frame of this tick. Entries past the axis count are left untouched.
    pub(crate) fn write_frame(&self, frame: &mut MotionFrame) {
        frame.schema_version = SCHEMA_VERSION;
        frame.tick = self.tick;
        frame.time_ns = u64::try_from(self.now.as_nanos()).unwrap_or(u64::MAX);
        frame.axis_count = self.axes.len() as u32;
        let mut flags = 0;
        if self.estop {
            flags |= FrameFlags::ESTOP_LATCHED.0;
        }
        if self.shutting_down {
            flags |= FrameFlags::SHUTTING_DOWN.0;
        }
        frame.flags = flags;
        frame.device_count = self.devices.len() as u32;
        for (device, out) in self.devices.iter().zip(frame.devices.iter_mut()) {
            *out = device.state as u8;
        }
        frame.signal_count = self.signals.len() as u32;
        for (signal, out) in self.signals.iter().zip(frame.signals.iter_mut()) {
            let flags = SignalFlags::default()
                .with(SignalFlags::STALE, signal.stale)
                .with(SignalFlags::CLAIMED, !signal.claimed_by.is_none())
                .with(SignalFlags::SAFE_STATE, signal.safe_applied)
                .with(SignalFlags::PENDING, signal.pending());
            *out = SignalState {
                value: signal.value(),
                raw: signal.raw,
                last_refresh_tick: signal.last_refresh_tick,
                flags: flags.0,
                kind: signal.config.kind as u8,
                reserved: [0; 3],
                claimed_by: signal.claimed_by,
                event_tick: signal.event_tick,
                sequence: signal.sequence,
                reserved2: 0,
            };
        }
        frame.group_count = self.groups.len() as u32;
        for (group, out) in self.groups.iter().zip(frame.groups.iter_mut()) {
            let mut holders = group
                .members
                .iter()
                .map(|member| self.axes[member.axis].claimed_by);
            let first = holders.next().unwrap_or(ClientId::NONE);
            let common = if holders.all(|holder| holder == first) {
                first
            } else {
                ClientId::NONE
            };
            *out = group.state(common);
        }
        for (axis, out) in self.axes.iter().zip(frame.wire.iter_mut()) {
            let (wire_tick, wire_ns) = axis
                .goal_wire
                .map_or((0, 0), |(tick, at)| (tick, self.monotonic_ns(at)));
            *out = AxisWire {
                goal_tick: axis.goal_tick,
                wire_tick,
                wire_ns,
            };
        }
        for (axis, out) in self.axes.iter().zip(frame.axes.iter_mut()) {
            let position = axis.position();
            let position_mode = matches!(axis.mode, AxisMode::Position | AxisMode::RampPosition);
            let arrived = position_mode
                && !axis.state.moving
                && (position - axis.target).abs() <= axis.tolerance;
            let at_limit = axis.state.at_limit
                || position <= axis.min - axis.tolerance
                || position >= axis.max + axis.tolerance;
            let flags = AxisFlags::default()
                .with(AxisFlags::MOVING, axis.state.moving)
                .with(AxisFlags::HOMED, axis.state.homed || axis.position_set)
                .with(AxisFlags::AT_LIMIT, at_limit)
                .with(AxisFlags::STALE, axis.stale)
                .with(AxisFlags::FAULT, axis.fault.is_some())
                .with(AxisFlags::CLAIMED, !axis.claimed_by.is_none())
                .with(AxisFlags::ARRIVED, arrived)
                .with(AxisFlags::ESTOPPED, axis.estopped)
                .with(AxisFlags::DEADMAN_EXPIRED, axis.deadman_expired)
                .with(AxisFlags::HELD, axis.held.is_some());
            *out = AxisState {
                position,
                velocity: axis.velocity(),
                target: axis.target,
                raw_counts: axis.state.raw_counts,
                last_refresh_tick: axis.last_refresh_tick,
                flags: flags.0,
                fault: axis.fault.map_or(0, |fault| fault.code as u16),
                mode: axis.mode as u8,
                device_state: self.devices[axis.device].state as u8,
                claimed_by: axis.claimed_by,
                fault_value: axis.fault.map_or(0.0, |fault| fault.value),
                fault_limit: axis.fault.map_or(0.0, |fault| fault.limit),
                desired_position: axis.desired_position(),
                desired_velocity: axis.desired_velocity(),
            };
        }
    }

    /// Fills the static server description (names, units, limits, capabilities, device
    /// models and firmware versions as the drivers know them now).
    pub fn fill_info(&self, info: &mut ServerInfo) {
        let config = &self.config;
        info.schema_version = SCHEMA_VERSION;
        info.axis_count = self.axes.len() as u32;
        info.device_count = config.devices.len() as u32;
        info.tick_hz = config.tick_hz;
        info.command_timeout_ms =
            u32::try_from(config.command_timeout.as_millis()).unwrap_or(u32::MAX);
        info.group_count = self.groups.len() as u32;
        for (group, out) in self.groups.iter().zip(&mut info.groups) {
            let config = &group.config;
            *out = GroupInfo::EMPTY;
            write_text(&mut out.name, &config.name);
            out.axis_count = config.axes.len().min(MAX_GROUP_AXES) as u32;
            out.stream_limit = match config.stream_limit {
                crate::config::StreamLimit::Clamp => 0,
                crate::config::StreamLimit::Abort => 1,
            };
            out.stream_timeout = config.stream_timeout;
            out.stream_buffer = config.stream_buffer;
            out.goal_time_tolerance = config.goal_time_tolerance.as_secs_f64();
            for (slot, axis) in config.axes.iter().take(MAX_GROUP_AXES).enumerate() {
                out.axes[slot] = *axis as u32;
                out.path_tolerance[slot] = config.path_tolerance[slot];
                out.goal_tolerance[slot] = config.goal_tolerance[slot];
            }
        }
        write_text(&mut info.name, &config.name);
        for ((axis, axis_config), out) in self.axes.iter().zip(&config.axes).zip(&mut info.axes) {
            *out = AxisInfo::EMPTY;
            write_text(&mut out.name, &axis_config.name);
            write_text(&mut out.unit, &axis_config.unit);
            write_text(&mut out.device, &config.devices[axis_config.device].name);
            out.counts_per_unit = axis.counts_per_unit;
            out.min = axis.min;
            out.max = axis.max;
            out.max_velocity = axis.max_velocity;
            out.max_accel = axis.max_accel;
            out.capabilities = axis.capabilities.0;
            out.channel = axis.channel as u16;
            out.device_index = axis_config.device as u16;
            out.following_error = axis.following_error;
            out.overspeed_factor = axis.overspeed_factor;
            out.home_max_travel = axis.home_max_travel;
            out.estop = match axis.estop {
                EstopCategory::Hold => motion_ipc::EstopCategory::Hold,
                EstopCategory::StopOff => motion_ipc::EstopCategory::StopOff,
                EstopCategory::Off => motion_ipc::EstopCategory::Off,
            } as u32;
        }
        info.signal_count = self.signals.len() as u32;
        for (signal, out) in self.signals.iter().zip(&mut info.signals) {
            let config = &signal.config;
            *out = SignalInfo::EMPTY;
            write_text(&mut out.name, &config.name);
            write_text(&mut out.unit, &config.unit);
            write_text(&mut out.device, &self.config.devices[config.device].name);
            write_text(&mut out.pin, &config.pin_name);
            out.scale = config.scale;
            out.offset = config.offset;
            out.full_scale = config.full_scale;
            out.kind = config.kind as u8;
            let mut flags = 0;
            if config.invert {
                flags |= SignalInfoFlags::INVERT.0;
            }
            if let Some(safe) = config.safe {
                flags |= SignalInfoFlags::HAS_SAFE_STATE.0;
                if safe {
                    flags |= SignalInfoFlags::SAFE_ON.0;
                }
            }
            out.flags = flags;
            out.device_index = config.device as u16;
        }
        for (index, (device, out)) in config.devices.iter().zip(&mut info.devices).enumerate() {
            *out = DeviceInfo::EMPTY;
            write_text(&mut out.name, &device.name);
            write_text(&mut out.link, &config.links[device.link].name);
            out.address = device.address;
            out.axis_count = config.axes.iter().filter(|a| a.device == index).count() as u32;
            if let Some(driver) = self.driver(index) {
                let status = driver.status();
                write_text(&mut out.firmware, status.firmware());
                out.state = u32::from(self.devices[index].state as u8);
                out.model = driver.model().code();
                write_text(&mut out.model_id, driver.model().id());
            }
        }
    }
}
