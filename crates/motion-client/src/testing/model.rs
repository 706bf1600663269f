//! The fake server's state: axes, devices, signals; requests judged by the server's own
//! rulebook ([`motion_ipc::rules`]).

use core::time::Duration;

use motion_ipc::rules::{self, AxisFacts, Facts, Motion, SignalFacts, Verdict};
use motion_ipc::{
    AxisFlags, AxisInfo, AxisMode, AxisState, ClientId, CommandKind, CommandRequest, DeviceInfo,
    DeviceState, EstopCategory, FaultCode, FrameFlags, GroupAbort, MachineParams, MotionFrame,
    Reason, ServerInfo, SignalFlags, SignalInfo, SignalInfoFlags, SignalKind, SignalState, Target,
    write_text,
};

use super::FakeControl;
use super::config::{FakeAxis, FakeConfig, FakeSignal};

mod group;
mod judged;
mod stream;

use group::SimGroup;
pub(super) use group::StoredPath;
pub(super) use judged::Judged;

#[derive(Debug, Clone, Copy)]
struct SimAxis {
    state: AxisState,
    /// Speed of the current position move, units/s.
    speed: f64,
    /// Tick of the last velocity/power goal (deadman).
    goal_tick: u64,
    /// The position move `Hold` stopped, which `Resume` continues.
    held: Option<Motion>,
}

#[derive(Debug, Clone, Copy, Default)]
struct SimSignal {
    /// Inputs: the level or counts the "board" reports. Outputs: the commanded logical value.
    raw: f64,
    pending: bool,
    claimed_by: ClientId,
    safe_applied: bool,
    /// Captures / trigger pulses, and the tick of the newest.
    sequence: u32,
    event_tick: u64,
}

pub(super) struct Model {
    axes: Vec<(FakeAxis, SimAxis)>,
    signals: Vec<(FakeSignal, SimSignal)>,
    forced: Vec<Option<DeviceState>>,
    starting_ticks: u64,
    pub(super) estop: bool,
    /// After [`FakeControl::ShutDown`]: motion is refused as during the server's shutdown.
    shutting_down: bool,
    pub(super) tick: u64,
    pub(super) commands: u64,
    pub(super) rejected: u64,
    tick_hz: u32,
    groups: Vec<SimGroup>,
    /// Paths received on `paths`, not run yet.
    paths: Vec<StoredPath>,
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
            held: None,
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
            shutting_down: false,
            tick: 0,
            commands: 0,
            rejected: 0,
            tick_hz: config.tick_hz.max(1),
            groups: config.groups.iter().map(SimGroup::new).collect(),
            paths: Vec::new(),
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
            out.model = device.model.code();
            write_text(&mut out.model_id, device.model.id());
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
        self.group_info(&mut info);
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
            FakeControl::Event { signal, raw } => {
                let tick = self.tick;
                if let Some((_, sim)) = self.signals.get_mut(signal) {
                    if let Some(raw) = raw {
                        sim.raw = raw;
                    }
                    sim.sequence = sim.sequence.wrapping_add(1);
                    sim.event_tick = tick;
                }
            }
            FakeControl::FaultGone { axis } => {
                if let Some((_, sim)) = self.axes.get_mut(axis) {
                    let by_server = matches!(
                        FaultCode::try_from(sim.state.fault),
                        Ok(FaultCode::FollowingError
                            | FaultCode::Overspeed
                            | FaultCode::LimitExceeded
                            | FaultCode::HomeFailed
                            | FaultCode::Overrun)
                    );
                    if !by_server {
                        sim.state.fault = 0;
                        sim.state.fault_value = 0.0;
                        sim.state.fault_limit = 0.0;
                        sim.state.flags =
                            AxisFlags(sim.state.flags).with(AxisFlags::FAULT, false).0;
                    }
                }
            }
            FakeControl::ShutDown => {
                self.shutting_down = true;
                self.abort_groups_of(None, GroupAbort::ShuttingDown);
                for (axis, sim) in &mut self.axes {
                    Self::stop(axis, sim);
                }
            }
            FakeControl::Fault {
                axis,
                code,
                value,
                limit,
            } => {
                self.abort_groups_of(Some(axis), GroupAbort::AxisFault);
                if let Some((config, sim)) = self.axes.get_mut(axis) {
                    Self::stop(config, sim);
                    sim.state.fault = code as u16;
                    sim.state.fault_value = value;
                    sim.state.fault_limit = limit;
                    sim.state.flags = AxisFlags(sim.state.flags).with(AxisFlags::FAULT, true).0;
                }
            }
            FakeControl::AbortGroup {
                group,
                abort,
                axis,
                value,
                limit,
            } => self.abort_group(group, abort, axis, (value, limit)),
        }
    }

    pub(super) fn apply(&mut self, request: &CommandRequest, sender: ClientId) -> Judged {
        let judged = match rules::identify(request, Some(sender)) {
            Ok(client) if request.target() == Ok(Target::Group) => {
                self.apply_group(request, client)
            }
            _ => self.validate_and_apply(request, sender).into(),
        };
        self.commands += 1;
        if judged.reason != Reason::Accepted {
            self.rejected += 1;
        }
        judged
    }

    fn stop(_axis: &FakeAxis, sim: &mut SimAxis) {
        sim.held = None;
        sim.state.flags = AxisFlags(sim.state.flags).with(AxisFlags::HELD, false).0;
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
        self.abort_groups_of(None, GroupAbort::EStop);
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

    /// The server's rulebook ([`motion_ipc::rules`]) decides; the model only carries out.
    fn validate_and_apply(&mut self, request: &CommandRequest, sender: ClientId) -> Reason {
        let client = match rules::identify(request, Some(sender)) {
            Ok(client) => client,
            Err(reason) => return reason,
        };
        match rules::judge(request, client, &*self) {
            Verdict::Refused(reason) => return reason,
            Verdict::EStop => self.latch_estop(),
            Verdict::Reset => self.reset(),
            Verdict::StopAll => {
                self.abort_groups_of(None, GroupAbort::Stopped);
                for (axis, sim) in &mut self.axes {
                    Self::stop(axis, sim);
                }
            }
            Verdict::OffAll => {
                let mut skipped = false;
                for index in 0..self.axes.len() {
                    let Some(facts) = Facts::axis(&*self, index) else {
                        continue;
                    };
                    if rules::off_all_skips(&facts, client) {
                        skipped = true;
                    } else if facts.capabilities.supports(CommandKind::Off) {
                        Self::off(&mut self.axes[index].1);
                    }
                }
                if skipped {
                    return Reason::ClaimedByOther;
                }
            }
            Verdict::ClaimAxis(index) => self.axes[index].1.state.claimed_by = client,
            Verdict::ReleaseAxis(index) => self.axes[index].1.state.claimed_by = ClientId::NONE,
            Verdict::StopAxis(index) => {
                self.abort_groups_of(Some(index), GroupAbort::Stopped);
                let (axis, sim) = &mut self.axes[index];
                Self::stop(axis, sim);
            }
            Verdict::OffAxis(index) => {
                self.abort_groups_of(Some(index), GroupAbort::Stopped);
                Self::off(&mut self.axes[index].1);
            }
            Verdict::Move { axis, motion } => {
                let tick = self.tick;
                let (config, sim) = &mut self.axes[axis];
                Self::start(config, sim, motion, tick);
            }
            Verdict::ClaimSignal(index) => self.signals[index].1.claimed_by = client,
            Verdict::ReleaseSignal(index) => self.signals[index].1.claimed_by = ClientId::NONE,
            Verdict::SetOutput { signal, on } => {
                let sim = &mut self.signals[signal].1;
                sim.raw = if on { 1.0 } else { 0.0 };
                sim.pending = true;
                sim.safe_applied = false;
            }
            Verdict::SetValue { signal, value } => {
                let (config, sim) = &mut self.signals[signal];
                sim.raw = ((value - config.offset) / config.scale).round();
                sim.pending = true;
            }
            Verdict::HoldAxis(index) => {
                let (axis, sim) = &mut self.axes[index];
                if sim.held.is_none() {
                    let state = sim.state;
                    let motion = match state.mode() {
                        _ if state.position == state.target => return Reason::NotMoving,
                        Ok(AxisMode::Position) => Motion::Position {
                            target: state.target,
                        },
                        Ok(AxisMode::RampPosition) => Motion::RampPosition {
                            target: state.target,
                            velocity: sim.speed,
                            accel: axis.max_accel,
                        },
                        _ => return Reason::NotMoving,
                    };
                    Self::stop(axis, sim);
                    sim.held = Some(motion);
                    sim.state.flags = AxisFlags(sim.state.flags).with(AxisFlags::HELD, true).0;
                }
            }
            Verdict::ResumeAxis(index) => {
                let tick = self.tick;
                let (axis, sim) = &mut self.axes[index];
                let Some(motion) = sim.held.take() else {
                    return Reason::NotMoving;
                };
                sim.state.flags = AxisFlags(sim.state.flags).with(AxisFlags::HELD, false).0;
                Self::start(axis, sim, motion, tick);
            }
        }
        Reason::Accepted
    }

    /// Reset, as the server does it: the e-stop, deadman expiries and the faults (an
    /// injected fault's cause is gone once reset); claims and running goals stay.
    fn reset(&mut self) {
        self.estop = false;
        for (_, sim) in &mut self.axes {
            sim.state.fault = 0;
            sim.state.fault_value = 0.0;
            sim.state.fault_limit = 0.0;
            sim.state.flags = AxisFlags(sim.state.flags)
                .with(AxisFlags::FAULT, false)
                .with(AxisFlags::DEADMAN_EXPIRED, false)
                .0;
            let running = matches!(
                sim.state.mode(),
                Ok(AxisMode::Power
                    | AxisMode::Position
                    | AxisMode::Velocity
                    | AxisMode::RampPosition
                    | AxisMode::RampVelocity
                    | AxisMode::Homing)
            );
            if sim.state.mode != AxisMode::Off as u8 && !running {
                sim.state.mode = AxisMode::Hold as u8;
                sim.state.target = sim.state.position;
                sim.state.velocity = 0.0;
            }
        }
        for (_, sim) in &mut self.signals {
            sim.safe_applied = false;
        }
    }

    /// Starts an accepted motion on the simulated axis.
    fn start(axis: &FakeAxis, sim: &mut SimAxis, motion: Motion, tick: u64) {
        sim.held = None;
        let state = &mut sim.state;
        state.flags = AxisFlags(state.flags).with(AxisFlags::HELD, false).0;
        state.mode = motion.mode() as u8;
        match motion {
            Motion::Position { target } => {
                state.target = target;
                sim.speed = axis.max_velocity;
            }
            Motion::RampPosition {
                target, velocity, ..
            } => {
                state.target = target;
                sim.speed = velocity;
            }
            Motion::Velocity { velocity, .. } | Motion::RampVelocity { velocity, .. } => {
                state.target = velocity;
                state.velocity = velocity;
            }
            Motion::Power { fraction } => {
                state.target = fraction;
                state.velocity = fraction * axis.max_velocity;
            }
            Motion::Home { velocity } => {
                state.target = 0.0;
                sim.speed = velocity;
            }
            Motion::SetPosition { target } => {
                state.position = target;
                state.target = target;
                state.flags = AxisFlags(state.flags).with(AxisFlags::HOMED, true).0;
            }
        }
        if motion.needs_renewal() {
            state.flags = AxisFlags(state.flags)
                .with(AxisFlags::DEADMAN_EXPIRED, false)
                .0;
            sim.goal_tick = tick;
        }
    }

    pub(super) fn step(&mut self, dt: f64, command_timeout_ms: u32) {
        let deadman_ticks = u64::from(command_timeout_ms) * u64::from(self.tick_hz) / 1000;
        let tick = self.tick;
        self.step_groups(dt);
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
                AxisMode::Group => {}
                _ => state.velocity = 0.0,
            }
            if mode != AxisMode::Group {
                state.desired_position = state.position;
                state.desired_velocity = state.velocity;
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
            SignalKind::AnalogIn | SignalKind::Capture | SignalKind::Trigger => {
                (sim.raw * signal.scale + signal.offset, sim.raw)
            }
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
            event_tick: sim.event_tick,
            sequence: sim.sequence,
            reserved2: 0,
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
        frame.group_count = self.groups.len().min(frame.groups.len()) as u32;
        for (state, out) in self.group_states().zip(frame.groups.iter_mut()) {
            *out = state;
        }
        // An output commanded this tick is acknowledged by the next frame.
        for (_, sim) in &mut self.signals {
            sim.pending = false;
        }
    }
}

/// The fake's state as the server's rulebook sees it.
impl Facts for Model {
    fn estop(&self) -> bool {
        self.estop
    }

    fn shutting_down(&self) -> bool {
        self.shutting_down
    }

    fn axis(&self, index: usize) -> Option<AxisFacts> {
        let (axis, sim) = self.axes.get(index)?;
        Some(AxisFacts {
            min: axis.min,
            max: axis.max,
            max_velocity: axis.max_velocity,
            max_accel: axis.max_accel,
            min_velocity: axis.min_velocity,
            min_profile_velocity: axis.min_profile_velocity,
            min_accel: axis.min_accel,
            capabilities: axis.capabilities,
            claimed_by: sim.state.claimed_by,
            device: self.device_state(axis.device),
            link_up: true,
            fault: FaultCode::try_from(sim.state.fault).unwrap_or(FaultCode::None),
            position: sim.state.position,
            position_fresh: true,
            tolerance: axis.position_tolerance,
            group_motion: self.in_group_motion(index),
        })
    }

    fn signal(&self, index: usize) -> Option<SignalFacts> {
        let (signal, sim) = self.signals.get(index)?;
        Some(SignalFacts {
            kind: signal.kind,
            claimed_by: sim.claimed_by,
            device: self.device_state(signal.device),
            link_up: true,
        })
    }
}
