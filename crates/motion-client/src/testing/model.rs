//! The fake server's state: axes, devices, signals; validation in the engine's order.

use core::time::Duration;

use motion_ipc::{
    AxisFlags, AxisInfo, AxisMode, AxisState, ClientId, CommandKind, CommandRequest, DeviceInfo,
    DeviceState, EstopCategory, FaultCode, FrameFlags, MachineParams, MotionFrame, Reason,
    SCHEMA_VERSION, ServerInfo, SignalFlags, SignalInfo, SignalInfoFlags, SignalKind, SignalState,
    Target, write_text,
};

use super::FakeControl;
use super::config::{FakeAxis, FakeConfig, FakeSignal};

#[derive(Debug, Clone, Copy)]
struct SimAxis {
    state: AxisState,
    /// Speed of the current position move, units/s.
    speed: f64,
    /// Tick of the last velocity/power goal (deadman).
    goal_tick: u64,
}

#[derive(Debug, Clone, Copy, Default)]
struct SimSignal {
    /// Inputs: the level or counts the "board" reports. Outputs: the commanded logical value.
    raw: f64,
    pending: bool,
    claimed_by: ClientId,
    safe_applied: bool,
}

pub(super) struct Model {
    axes: Vec<(FakeAxis, SimAxis)>,
    signals: Vec<(FakeSignal, SimSignal)>,
    forced: Vec<Option<DeviceState>>,
    starting_ticks: u64,
    pub(super) estop: bool,
    pub(super) tick: u64,
    pub(super) commands: u64,
    pub(super) rejected: u64,
    tick_hz: u32,
}

impl Model {
    pub(super) fn new(config: &FakeConfig) -> Self {
        let fresh = SimAxis {
            state: AxisState {
                flags: 0,
                mode: AxisMode::Hold as u8,
                ..AxisState::UNKNOWN
            },
            speed: 0.0,
            goal_tick: 0,
        };
        Self {
            axes: config
                .axes
                .iter()
                .map(|axis| (axis.clone(), fresh))
                .collect(),
            signals: config
                .signals
                .iter()
                .map(|signal| (signal.clone(), SimSignal::default()))
                .collect(),
            forced: vec![None; config.devices.len()],
            starting_ticks: config.starting_ticks,
            estop: false,
            tick: 0,
            commands: 0,
            rejected: 0,
            tick_hz: config.tick_hz.max(1),
        }
    }

    pub(super) fn device_state(&self, device: usize) -> DeviceState {
        match self.forced.get(device).copied().flatten() {
            Some(state) => state,
            None if self.tick < self.starting_ticks => DeviceState::Starting,
            None => DeviceState::Online,
        }
    }

    pub(super) fn device_states(&self) -> Vec<DeviceState> {
        (0..self.forced.len())
            .map(|d| self.device_state(d))
            .collect()
    }

    pub(super) fn info(&self, config: &FakeConfig, start_ns: u64) -> ServerInfo {
        let mut info = ServerInfo::EMPTY;
        info.axis_count = self.axes.len() as u32;
        info.device_count = config.devices.len() as u32;
        info.signal_count = self.signals.len() as u32;
        info.tick_hz = config.tick_hz;
        info.command_timeout_ms = config.command_timeout_ms;
        info.max_clients = u32::try_from(config.max_clients).unwrap_or(u32::MAX);
        info.server_pid = std::process::id();
        info.start_time_ns = start_ns;
        write_text(&mut info.name, &config.name);
        let device_name = |index: usize| config.devices.get(index).map_or("", |d| d.name.as_str());
        for (channel, ((axis, _), out)) in self.axes.iter().zip(info.axes.iter_mut()).enumerate() {
            *out = AxisInfo::EMPTY;
            write_text(&mut out.name, &axis.name);
            write_text(&mut out.unit, &axis.unit);
            write_text(&mut out.device, device_name(axis.device));
            out.device_index = u16::try_from(axis.device).unwrap_or(u16::MAX);
            out.channel = u16::try_from(channel).unwrap_or(u16::MAX);
            out.counts_per_unit = 1000.0;
            out.min = axis.min;
            out.max = axis.max;
            out.max_velocity = axis.max_velocity;
            out.max_accel = axis.max_accel;
            out.capabilities = axis.capabilities.0;
            out.following_error = axis.following_error;
            out.overspeed_factor = axis.overspeed_factor;
            out.home_max_travel = axis.home_max_travel;
            out.estop = axis.estop as u32;
        }
        for (index, (device, out)) in config
            .devices
            .iter()
            .zip(info.devices.iter_mut())
            .enumerate()
        {
            let state = self.device_state(index);
            *out = DeviceInfo::EMPTY;
            write_text(&mut out.name, &device.name);
            write_text(&mut out.link, &device.link);
            if state != DeviceState::Starting {
                write_text(&mut out.firmware, &device.firmware);
            }
            out.model = device.model as u32;
            out.address = u32::try_from(index + 1).unwrap_or(0);
            out.axis_count = self.axes.iter().filter(|(a, _)| a.device == index).count() as u32;
            out.state = u32::from(state as u8);
        }
        for ((signal, _), out) in self.signals.iter().zip(info.signals.iter_mut()) {
            *out = SignalInfo::EMPTY;
            write_text(&mut out.name, &signal.name);
            write_text(&mut out.unit, &signal.unit);
            write_text(&mut out.device, device_name(signal.device));
            write_text(&mut out.pin, &signal.pin);
            out.scale = signal.scale;
            out.offset = signal.offset;
            out.full_scale = signal.full_scale;
            out.kind = signal.kind as u8;
            out.device_index = u16::try_from(signal.device).unwrap_or(u16::MAX);
            let mut flags = 0;
            if signal.invert {
                flags |= SignalInfoFlags::INVERT.0;
            }
            if let Some(on) = signal.safe {
                flags |= SignalInfoFlags::HAS_SAFE_STATE.0;
                if on {
                    flags |= SignalInfoFlags::SAFE_ON.0;
                }
            }
            out.flags = flags;
        }
        info
    }

    pub(super) fn params(config: &FakeConfig) -> MachineParams {
        let mut params = MachineParams::EMPTY;
        for (param, out) in config.params.iter().zip(params.entries.iter_mut()) {
            write_text(&mut out.key, &param.key);
            write_text(&mut out.value, &param.value);
            out.owner_kind = param.owner as u8;
            out.owner_index = param.index;
            out.from_config = u8::from(param.from_config);
        }
        params.count = config.params.len().min(params.entries.len()) as u32;
        params
    }

    pub(super) fn control(&mut self, control: FakeControl) {
        match control {
            FakeControl::DeviceState { device, state } => {
                if let Some(slot) = self.forced.get_mut(device) {
                    *slot = Some(state);
                }
            }
            FakeControl::Input { signal, raw } => {
                if let Some((_, sim)) = self.signals.get_mut(signal) {
                    sim.raw = raw;
                }
            }
            FakeControl::Fault {
                axis,
                code,
                value,
                limit,
            } => {
                if let Some((config, sim)) = self.axes.get_mut(axis) {
                    Self::stop(config, sim);
                    sim.state.fault = code as u16;
                    sim.state.fault_value = value;
                    sim.state.fault_limit = limit;
                    sim.state.flags = AxisFlags(sim.state.flags).with(AxisFlags::FAULT, true).0;
                }
            }
        }
    }

    pub(super) fn apply(&mut self, request: &CommandRequest, sender: ClientId) -> Reason {
        let reason = self.validate_and_apply(request, sender);
        self.commands += 1;
        if reason != Reason::Accepted {
            self.rejected += 1;
        }
        reason
    }

    fn stop(_axis: &FakeAxis, sim: &mut SimAxis) {
        sim.state.mode = AxisMode::Hold as u8;
        sim.state.velocity = 0.0;
        sim.state.target = sim.state.position;
    }

    fn off(sim: &mut SimAxis) {
        sim.state.mode = AxisMode::Off as u8;
        sim.state.velocity = 0.0;
        sim.state.target = sim.state.position;
    }

    /// Latches the e-stop: every axis stops with its category, outputs go to safe states.
    pub(super) fn latch_estop(&mut self) {
        self.estop = true;
        for (axis, sim) in &mut self.axes {
            match axis.estop {
                EstopCategory::Hold => Self::stop(axis, sim),
                EstopCategory::StopOff | EstopCategory::Off => Self::off(sim),
            }
        }
        for (signal, sim) in &mut self.signals {
            if let Some(on) = signal.safe {
                sim.raw = if on { 1.0 } else { 0.0 };
                sim.safe_applied = true;
                sim.pending = true;
            }
        }
    }

    fn signal_command(
        &mut self,
        kind: CommandKind,
        index: usize,
        client: ClientId,
        value: f64,
    ) -> Reason {
        let device_state = match self.signals.get(index) {
            Some((signal, _)) => self.device_state(signal.device),
            None => return Reason::UnknownSignal,
        };
        let estop = self.estop;
        let Some((signal, sim)) = self.signals.get_mut(index) else {
            return Reason::UnknownSignal;
        };
        let claimed_by_other = !sim.claimed_by.is_none() && sim.claimed_by != client;
        match kind {
            CommandKind::Claim | CommandKind::Release if client.is_none() => Reason::NoClientId,
            CommandKind::Claim if claimed_by_other => Reason::ClaimedByOther,
            CommandKind::Claim => {
                sim.claimed_by = client;
                Reason::Accepted
            }
            CommandKind::Release if sim.claimed_by != client => Reason::NotClaimed,
            CommandKind::Release => {
                sim.claimed_by = ClientId::NONE;
                Reason::Accepted
            }
            CommandKind::SetOutput if signal.kind != SignalKind::DigitalOut => Reason::NotAnOutput,
            CommandKind::SetOutput if estop => Reason::EstopLatched,
            CommandKind::SetOutput if claimed_by_other => Reason::ClaimedByOther,
            CommandKind::SetOutput => match device_state {
                DeviceState::Starting => Reason::DeviceStarting,
                DeviceState::Offline => Reason::DeviceOffline,
                DeviceState::Online | DeviceState::Faulted => {
                    sim.raw = if value >= 0.5 { 1.0 } else { 0.0 };
                    sim.pending = true;
                    sim.safe_applied = false;
                    Reason::Accepted
                }
            },
            _ => Reason::UnknownKind,
        }
    }

    fn validate_and_apply(&mut self, request: &CommandRequest, sender: ClientId) -> Reason {
        if request.schema_version != SCHEMA_VERSION {
            return Reason::SchemaMismatch;
        }
        let Ok(kind) = request.kind() else {
            return Reason::UnknownKind;
        };
        if request.values.iter().any(|value| !value.is_finite()) {
            return Reason::NotFinite;
        }
        if !request.client.is_none() && request.client != sender {
            return Reason::IdentityMismatch;
        }
        let client = sender;
        let Ok(target) = request.target() else {
            return Reason::UnknownTarget;
        };
        if target == Target::Signal {
            return self.signal_command(kind, request.axis as usize, client, request.values[0]);
        }
        match kind {
            CommandKind::EStop => {
                self.latch_estop();
                return Reason::Accepted;
            }
            CommandKind::Reset => {
                self.estop = false;
                for (_, sim) in &mut self.axes {
                    sim.state.fault = 0;
                    sim.state.fault_value = 0.0;
                    sim.state.fault_limit = 0.0;
                    sim.state.flags = AxisFlags(sim.state.flags).with(AxisFlags::FAULT, false).0;
                }
                return Reason::Accepted;
            }
            CommandKind::Stop if request.axis == CommandRequest::ALL_AXES => {
                for (axis, sim) in &mut self.axes {
                    Self::stop(axis, sim);
                }
                return Reason::Accepted;
            }
            CommandKind::Off if request.axis == CommandRequest::ALL_AXES => {
                let mut skipped = false;
                for (axis, sim) in &mut self.axes {
                    if !sim.state.claimed_by.is_none() && sim.state.claimed_by != client {
                        skipped = true;
                    } else if axis.capabilities.supports(CommandKind::Off) {
                        Self::off(sim);
                    }
                }
                return if skipped {
                    Reason::ClaimedByOther
                } else {
                    Reason::Accepted
                };
            }
            CommandKind::SetOutput => return Reason::UnknownTarget,
            _ => {}
        }
        let tick = self.tick;
        let estop = self.estop;
        let Some(device) = self.axes.get(request.axis as usize).map(|(a, _)| a.device) else {
            return Reason::UnknownAxis;
        };
        let device_state = self.device_state(device);
        let Some((axis, sim)) = self.axes.get_mut(request.axis as usize) else {
            return Reason::UnknownAxis;
        };
        let claimed_by_other = !sim.state.claimed_by.is_none() && sim.state.claimed_by != client;
        match kind {
            CommandKind::Claim | CommandKind::Release if client.is_none() => {
                return Reason::NoClientId;
            }
            CommandKind::Claim if claimed_by_other => return Reason::ClaimedByOther,
            CommandKind::Claim => {
                sim.state.claimed_by = client;
                return Reason::Accepted;
            }
            CommandKind::Release if sim.state.claimed_by != client => return Reason::NotClaimed,
            CommandKind::Release => {
                sim.state.claimed_by = ClientId::NONE;
                return Reason::Accepted;
            }
            CommandKind::Stop => {
                Self::stop(axis, sim);
                return Reason::Accepted;
            }
            CommandKind::Off if claimed_by_other => return Reason::ClaimedByOther,
            CommandKind::Off if !axis.capabilities.supports(kind) => return Reason::Unsupported,
            CommandKind::Off => {
                Self::off(sim);
                return Reason::Accepted;
            }
            _ => {}
        }
        if estop {
            return Reason::EstopLatched;
        }
        if claimed_by_other {
            return Reason::ClaimedByOther;
        }
        if !axis.capabilities.supports(kind) {
            return Reason::Unsupported;
        }
        match device_state {
            DeviceState::Starting => return Reason::DeviceStarting,
            DeviceState::Offline => return Reason::DeviceOffline,
            DeviceState::Online | DeviceState::Faulted => {}
        }
        if sim.state.fault != FaultCode::None as u16 {
            return Reason::AxisFaulted;
        }
        Self::goal(axis, sim, kind, request.values, tick)
    }

    fn goal(
        axis: &FakeAxis,
        sim: &mut SimAxis,
        kind: CommandKind,
        values: [f64; 3],
        tick: u64,
    ) -> Reason {
        let [v0, v1, v2] = values;
        let or_max = |value: f64, max: f64| if value == 0.0 { max } else { value };
        let in_range = |position: f64| position >= axis.min && position <= axis.max;
        let state = &mut sim.state;
        match kind {
            CommandKind::Position | CommandKind::RampPosition | CommandKind::SetPosition
                if !in_range(v0) =>
            {
                Reason::OutOfRange
            }
            CommandKind::Power if v0.abs() > 1.0 => Reason::PowerLimit,
            CommandKind::Velocity | CommandKind::RampVelocity if v0.abs() > axis.max_velocity => {
                Reason::VelocityLimit
            }
            CommandKind::RampVelocity if or_max(v1, axis.max_accel) > axis.max_accel => {
                Reason::AccelLimit
            }
            CommandKind::RampPosition
                if or_max(v1, axis.max_velocity) > axis.max_velocity || v1 < 0.0 =>
            {
                Reason::VelocityLimit
            }
            CommandKind::RampPosition
                if or_max(v2, axis.max_accel) > axis.max_accel || v2 < 0.0 =>
            {
                Reason::AccelLimit
            }
            CommandKind::Home if v0 < 0.0 || v0 > axis.max_velocity => Reason::VelocityLimit,
            CommandKind::Position | CommandKind::RampPosition => {
                state.target = v0;
                state.mode = kind as u8;
                sim.speed = if kind == CommandKind::Position {
                    axis.max_velocity
                } else {
                    or_max(v1, axis.max_velocity)
                };
                Reason::Accepted
            }
            CommandKind::Velocity | CommandKind::RampVelocity | CommandKind::Power => {
                let velocity = if kind == CommandKind::Power {
                    v0 * axis.max_velocity
                } else {
                    v0
                };
                state.target = v0;
                state.velocity = velocity;
                state.mode = match kind {
                    CommandKind::Velocity => AxisMode::Velocity,
                    CommandKind::RampVelocity => AxisMode::RampVelocity,
                    _ => AxisMode::Power,
                } as u8;
                state.flags = AxisFlags(state.flags)
                    .with(AxisFlags::DEADMAN_EXPIRED, false)
                    .0;
                sim.goal_tick = tick;
                Reason::Accepted
            }
            CommandKind::Home => {
                state.mode = AxisMode::Homing as u8;
                state.target = 0.0;
                sim.speed = or_max(v0, axis.max_velocity / 4.0);
                Reason::Accepted
            }
            CommandKind::SetPosition => {
                state.position = v0;
                state.target = v0;
                state.mode = AxisMode::Hold as u8;
                state.flags = AxisFlags(state.flags).with(AxisFlags::HOMED, true).0;
                Reason::Accepted
            }
            _ => Reason::UnknownKind,
        }
    }

    pub(super) fn step(&mut self, dt: f64, command_timeout_ms: u32) {
        let deadman_ticks = u64::from(command_timeout_ms) * u64::from(self.tick_hz) / 1000;
        let tick = self.tick;
        for (axis, sim) in &mut self.axes {
            let state = &mut sim.state;
            let mut flags = AxisFlags(state.flags);
            let mode = state.mode().unwrap_or(AxisMode::Off);
            match mode {
                AxisMode::Position | AxisMode::RampPosition | AxisMode::Homing => {
                    let to_go = state.target - state.position;
                    let step = sim.speed * dt;
                    if to_go.abs() <= step {
                        state.position = state.target;
                        state.velocity = 0.0;
                        if mode == AxisMode::Homing {
                            state.mode = AxisMode::Hold as u8;
                            flags = flags.with(AxisFlags::HOMED, true);
                        }
                    } else {
                        state.velocity = sim.speed.copysign(to_go);
                        state.position += step.copysign(to_go);
                    }
                }
                AxisMode::Velocity | AxisMode::RampVelocity | AxisMode::Power => {
                    if deadman_ticks > 0 && tick.saturating_sub(sim.goal_tick) > deadman_ticks {
                        state.mode = AxisMode::Hold as u8;
                        state.velocity = 0.0;
                        flags = flags.with(AxisFlags::DEADMAN_EXPIRED, true);
                    } else {
                        let next = state.position + state.velocity * dt;
                        state.position = next.clamp(axis.min, axis.max);
                        if next != state.position {
                            state.mode = AxisMode::Hold as u8;
                            state.velocity = 0.0;
                        }
                    }
                }
                _ => state.velocity = 0.0,
            }
            let mode = state.mode().unwrap_or(AxisMode::Off);
            let positional = matches!(mode, AxisMode::Position | AxisMode::RampPosition);
            state.flags = flags
                .with(AxisFlags::MOVING, state.velocity != 0.0)
                .with(
                    AxisFlags::ARRIVED,
                    positional && state.position == state.target,
                )
                .with(
                    AxisFlags::AT_LIMIT,
                    state.position <= axis.min || state.position >= axis.max,
                )
                .with(AxisFlags::CLAIMED, !state.claimed_by.is_none())
                .with(AxisFlags::ESTOPPED, self.estop)
                .0;
            state.raw_counts = (state.position * 1000.0).round() as i64;
            state.last_refresh_tick = tick;
        }
    }

    pub(super) fn tick_u32(&self) -> u32 {
        u32::try_from(self.tick).unwrap_or(u32::MAX)
    }

    fn signal_state(&self, signal: &FakeSignal, sim: &SimSignal) -> SignalState {
        let online = self.device_state(signal.device) == DeviceState::Online;
        let (value, raw) = match signal.kind {
            SignalKind::DigitalIn => {
                let level = sim.raw >= 0.5;
                (
                    f64::from(u8::from(level != signal.invert)),
                    f64::from(u8::from(level)),
                )
            }
            SignalKind::DigitalOut => {
                let on = sim.raw >= 0.5;
                (
                    f64::from(u8::from(on)),
                    f64::from(u8::from(on != signal.invert)),
                )
            }
            SignalKind::AnalogIn => (sim.raw * signal.scale + signal.offset, sim.raw),
        };
        let flags = SignalFlags::default()
            .with(SignalFlags::STALE, !online)
            .with(SignalFlags::CLAIMED, !sim.claimed_by.is_none())
            .with(SignalFlags::SAFE_STATE, sim.safe_applied)
            .with(SignalFlags::PENDING, sim.pending);
        SignalState {
            value,
            raw,
            last_refresh_tick: if online { self.tick } else { 0 },
            flags: flags.0,
            kind: signal.kind as u8,
            reserved: [0; 3],
            claimed_by: sim.claimed_by,
        }
    }

    pub(super) fn write_frame(
        &mut self,
        frame: &mut MotionFrame,
        deadline: Duration,
        now: Duration,
    ) {
        let nanos = |time: Duration| u64::try_from(time.as_nanos()).unwrap_or(u64::MAX);
        frame.tick = self.tick;
        frame.time_ns = nanos(deadline);
        frame.publish_ns = nanos(now);
        frame.axis_count = self.axes.len() as u32;
        frame.device_count = self.forced.len().min(frame.devices.len()) as u32;
        frame.signal_count = self.signals.len().min(frame.signals.len()) as u32;
        frame.flags = if self.estop {
            FrameFlags::ESTOP_LATCHED.0
        } else {
            0
        };
        for (index, out) in frame.devices.iter_mut().take(self.forced.len()).enumerate() {
            *out = self.device_state(index) as u8;
        }
        for ((axis, sim), out) in self.axes.iter().zip(frame.axes.iter_mut()) {
            *out = sim.state;
            out.device_state = self.device_state(axis.device) as u8;
        }
        for ((signal, sim), out) in self.signals.iter().zip(frame.signals.iter_mut()) {
            *out = self.signal_state(signal, sim);
        }
        // An output commanded this tick is acknowledged by the next frame.
        for (_, sim) in &mut self.signals {
            sim.pending = false;
        }
    }
}
