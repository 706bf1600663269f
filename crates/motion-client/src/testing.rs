//! A fake motiond for tests (feature `testing`): the same five services with the same
//! types, a thread ticking at a fixed rate, and a small kinematic model of each axis.
//!
//! It validates commands in the real engine's order (schema, kind, finite values, e-stop
//! and reset, stop of all axes, axis index, claims, anyone may stop, e-stop latch, claim
//! by another, capabilities, limits), so that client and CLI behaviour can be tested
//! without the real server. Positions move at the commanded speed without acceleration;
//! nothing here models a board. Every request it receives is logged for assertions.

use core::time::Duration;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, mpsc};
use std::thread::JoinHandle;
use std::time::Instant;

use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::{NodeBuilder, NodeName, ServiceName, SignalHandlingMode};
use iceoryx2::service::Service;
use motion_ipc::{
    AxisFlags, AxisInfo, AxisMode, AxisState, Capabilities, ClientId, CommandKind, CommandReply,
    CommandRequest, DeviceInfo, FrameFlags, MotionFrame, Reason, SCHEMA_VERSION, ServerInfo,
    ServerStats, ServiceNames, write_text,
};

/// One simulated axis.
#[derive(Debug, Clone)]
pub struct FakeAxis {
    /// Name.
    pub name: String,
    /// Unit.
    pub unit: String,
    /// Soft limits.
    pub min: f64,
    /// Soft limits.
    pub max: f64,
    /// Units/s.
    pub max_velocity: f64,
    /// Units/s².
    pub max_accel: f64,
    /// Accepted command kinds.
    pub capabilities: Capabilities,
}

impl FakeAxis {
    /// An axis accepting every command kind, unit "mm".
    pub fn new(name: &str, min: f64, max: f64, max_velocity: f64) -> Self {
        Self {
            name: name.to_owned(),
            unit: "mm".to_owned(),
            min,
            max,
            max_velocity,
            max_accel: max_velocity * 10.0,
            capabilities: CommandKind::ALL
                .iter()
                .fold(Capabilities::NONE, |caps, kind| caps.with(*kind)),
        }
    }
}

/// What the fake server serves.
#[derive(Debug, Clone)]
pub struct FakeConfig {
    /// Instance name.
    pub name: String,
    /// Tick rate.
    pub tick_hz: u32,
    /// Deadman, ms (0 disables).
    pub command_timeout_ms: u32,
    /// Axes.
    pub axes: Vec<FakeAxis>,
}

impl FakeConfig {
    /// Three axes: `x` and `y` (−100..100 mm, 50 mm/s), `a` (deg, no homing), 500 Hz,
    /// deadman 250 ms.
    pub fn demo(name: &str) -> Self {
        let mut a = FakeAxis::new("a", -180.0, 180.0, 90.0);
        a.unit = "deg".to_owned();
        a.capabilities = Capabilities(a.capabilities.0 & !(1 << CommandKind::Home as u32));
        Self {
            name: name.to_owned(),
            tick_hz: 500,
            command_timeout_ms: 250,
            axes: vec![
                FakeAxis::new("x", -100.0, 100.0, 50.0),
                FakeAxis::new("y", -100.0, 100.0, 50.0),
                a,
            ],
        }
    }
}

/// A name no other test of this process or of a concurrent run uses.
pub fn unique_name(prefix: &str) -> String {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let count = COUNTER.fetch_add(1, Ordering::Relaxed);
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |since| since.subsec_nanos());
    format!("{prefix}-{}-{count}-{nanos}", std::process::id())
}

/// A running fake server; stops when dropped.
#[derive(Debug)]
pub struct FakeServer {
    name: String,
    stop: Arc<AtomicBool>,
    requests: Arc<Mutex<Vec<CommandRequest>>>,
    thread: Option<JoinHandle<Result<(), String>>>,
}

impl FakeServer {
    /// Creates the services over `S` and starts ticking; returns once clients can connect.
    pub fn start<S: Service>(config: FakeConfig) -> Result<Self, String> {
        let stop = Arc::new(AtomicBool::new(false));
        let requests = Arc::new(Mutex::new(Vec::new()));
        let (ready_tx, ready_rx) = mpsc::channel();
        let name = config.name.clone();
        let thread = {
            let stop = Arc::clone(&stop);
            let requests = Arc::clone(&requests);
            std::thread::spawn(move || serve::<S>(&config, &stop, &requests, &ready_tx))
        };
        match ready_rx.recv_timeout(Duration::from_secs(10)) {
            Ok(Ok(())) => Ok(Self {
                name,
                stop,
                requests,
                thread: Some(thread),
            }),
            Ok(Err(error)) => Err(error),
            Err(_) => Err(thread
                .join()
                .map_err(|_| "fake server panicked".to_owned())
                .and_then(|result| result.map(|()| "fake server never became ready".to_owned()))
                .unwrap_or_else(|error| error)),
        }
    }

    /// The instance name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Every request received so far, in order.
    pub fn requests(&self) -> Vec<CommandRequest> {
        self.requests
            .lock()
            .map(|log| log.clone())
            .unwrap_or_default()
    }

    /// Stops the server and reports an error its thread hit.
    pub fn shutdown(mut self) -> Result<(), String> {
        self.stop_thread()
    }

    fn stop_thread(&mut self) -> Result<(), String> {
        self.stop.store(true, Ordering::Relaxed);
        match self.thread.take() {
            Some(thread) => thread
                .join()
                .map_err(|_| "fake server panicked".to_owned())?,
            None => Ok(()),
        }
    }
}

impl Drop for FakeServer {
    fn drop(&mut self) {
        let _ = self.stop_thread();
    }
}

fn fail(what: &str) -> impl Fn(&dyn core::fmt::Debug) -> String + '_ {
    move |error| format!("fake server: {what}: {error:?}")
}

fn serve<S: Service>(
    config: &FakeConfig,
    stop: &AtomicBool,
    requests: &Mutex<Vec<CommandRequest>>,
    ready: &mpsc::Sender<Result<(), String>>,
) -> Result<(), String> {
    let result = serve_inner::<S>(config, stop, requests, ready);
    if let Err(error) = &result {
        let _ = ready.send(Err(error.clone()));
    }
    result
}

fn serve_inner<S: Service>(
    config: &FakeConfig,
    stop: &AtomicBool,
    requests: &Mutex<Vec<CommandRequest>>,
    ready: &mpsc::Sender<Result<(), String>>,
) -> Result<(), String> {
    let names = ServiceNames::new(&config.name);
    let service = |name: String| ServiceName::new(&name).map_err(|e| fail("service name")(&e));
    let node_name = NodeName::new("fake-motiond").map_err(|e| fail("node name")(&e))?;
    let node = NodeBuilder::new()
        .name(&node_name)
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<S>()
        .map_err(|e| fail("node")(&e))?;
    let frames = node
        .service_builder(&service(names.frame())?)
        .publish_subscribe::<MotionFrame>()
        .history_size(1)
        .subscriber_max_buffer_size(4)
        .open_or_create()
        .map_err(|e| fail("frame service")(&e))?
        .publisher_builder()
        .create()
        .map_err(|e| fail("frame publisher")(&e))?;
    let tick = node
        .service_builder(&service(names.tick())?)
        .event()
        .open_or_create()
        .map_err(|e| fail("tick service")(&e))?
        .notifier_builder()
        .create()
        .map_err(|e| fail("tick notifier")(&e))?;
    let commands = node
        .service_builder(&service(names.command())?)
        .request_response::<CommandRequest, CommandReply>()
        .open_or_create()
        .map_err(|e| fail("command service")(&e))?
        .server_builder()
        .create()
        .map_err(|e| fail("command server")(&e))?;
    let info_publisher = node
        .service_builder(&service(names.info())?)
        .publish_subscribe::<ServerInfo>()
        .history_size(1)
        .open_or_create()
        .map_err(|e| fail("info service")(&e))?
        .publisher_builder()
        .create()
        .map_err(|e| fail("info publisher")(&e))?;
    let stats_publisher = node
        .service_builder(&service(names.stats())?)
        .publish_subscribe::<ServerStats>()
        .history_size(1)
        .open_or_create()
        .map_err(|e| fail("stats service")(&e))?
        .publisher_builder()
        .create()
        .map_err(|e| fail("stats publisher")(&e))?;

    let mut model = Model::new(config);
    info_publisher
        .send_copy(model.info(config))
        .map_err(|e| fail("info send")(&e))?;
    let _ = ready.send(Ok(()));

    let period = Duration::from_secs(1) / config.tick_hz.max(1);
    let start = Instant::now();
    let mut next = start;
    while !stop.load(Ordering::Relaxed) {
        let now = Instant::now();
        if next > now {
            std::thread::sleep(next - now);
        }
        while let Some(active) = commands.receive().map_err(|e| fail("receive")(&e))? {
            let request = *active.payload();
            if let Ok(mut log) = requests.lock() {
                log.push(request);
            }
            let reason = model.apply(&request);
            active
                .send_copy(CommandReply::to(&request, reason, model.tick))
                .map_err(|e| fail("reply")(&e))?;
        }
        model.step(period.as_secs_f64(), config.command_timeout_ms);
        let mut frame = MotionFrame::EMPTY;
        // Like the real server: the tick's deadline, then the time just before sending.
        model.write_frame(&mut frame, period * model.tick_u32(), start.elapsed());
        frames
            .send_copy(frame)
            .map_err(|e| fail("frame send")(&e))?;
        tick.notify().map_err(|e| fail("notify")(&e))?;
        // Late subscribers get the history sample when the publisher updates connections.
        info_publisher
            .update_connections()
            .map_err(|e| fail("info connections")(&e))?;
        if model.tick.is_multiple_of(u64::from(config.tick_hz.max(1))) {
            let mut stats = ServerStats::EMPTY;
            stats.tick = model.tick;
            stats.commands = model.commands;
            stats.rejected = model.rejected;
            stats_publisher
                .send_copy(stats)
                .map_err(|e| fail("stats send")(&e))?;
        }
        model.tick += 1;
        next += period;
    }
    Ok(())
}

#[derive(Debug, Clone, Copy)]
struct SimAxis {
    state: AxisState,
    /// Speed of the current position move, units/s.
    speed: f64,
    /// Tick of the last velocity/power goal (deadman).
    goal_tick: u64,
}

struct Model {
    axes: Vec<(FakeAxis, SimAxis)>,
    estop: bool,
    tick: u64,
    commands: u64,
    rejected: u64,
    tick_hz: u32,
}

impl Model {
    fn new(config: &FakeConfig) -> Self {
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
            estop: false,
            tick: 0,
            commands: 0,
            rejected: 0,
            tick_hz: config.tick_hz.max(1),
        }
    }

    fn info(&self, config: &FakeConfig) -> ServerInfo {
        let mut info = ServerInfo::EMPTY;
        info.axis_count = self.axes.len() as u32;
        info.device_count = 1;
        info.tick_hz = config.tick_hz;
        info.command_timeout_ms = config.command_timeout_ms;
        info.max_clients = 32;
        info.server_pid = std::process::id();
        write_text(&mut info.name, &config.name);
        for ((axis, _), out) in self.axes.iter().zip(info.axes.iter_mut()) {
            *out = AxisInfo::EMPTY;
            write_text(&mut out.name, &axis.name);
            write_text(&mut out.unit, &axis.unit);
            write_text(&mut out.device, "fake");
            out.counts_per_unit = 1000.0;
            out.min = axis.min;
            out.max = axis.max;
            out.max_velocity = axis.max_velocity;
            out.max_accel = axis.max_accel;
            out.capabilities = axis.capabilities.0;
        }
        let mut device = DeviceInfo::EMPTY;
        write_text(&mut device.name, "fake");
        write_text(&mut device.link, "none");
        write_text(&mut device.firmware, "fake 1.0");
        device.axis_count = info.axis_count;
        device.state = u32::from(motion_ipc::DeviceState::Online as u8);
        info.devices[0] = device;
        info
    }

    fn apply(&mut self, request: &CommandRequest) -> Reason {
        let reason = self.validate_and_apply(request);
        self.commands += 1;
        if reason != Reason::Accepted {
            self.rejected += 1;
        }
        reason
    }

    fn stop(sim: &mut SimAxis) {
        sim.state.mode = AxisMode::Hold as u8;
        sim.state.velocity = 0.0;
        sim.state.target = sim.state.position;
    }

    fn validate_and_apply(&mut self, request: &CommandRequest) -> Reason {
        if request.schema_version != SCHEMA_VERSION {
            return Reason::SchemaMismatch;
        }
        let Ok(kind) = request.kind() else {
            return Reason::UnknownKind;
        };
        if request.values.iter().any(|value| !value.is_finite()) {
            return Reason::NotFinite;
        }
        match kind {
            CommandKind::EStop => {
                self.estop = true;
                for (_, sim) in &mut self.axes {
                    Self::stop(sim);
                }
                return Reason::Accepted;
            }
            CommandKind::Reset => {
                self.estop = false;
                return Reason::Accepted;
            }
            CommandKind::Stop if request.axis == CommandRequest::ALL_AXES => {
                for (_, sim) in &mut self.axes {
                    Self::stop(sim);
                }
                return Reason::Accepted;
            }
            _ => {}
        }
        let tick = self.tick;
        let estop = self.estop;
        let Some((axis, sim)) = self.axes.get_mut(request.axis as usize) else {
            return Reason::UnknownAxis;
        };
        let client = request.client;
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
                Self::stop(sim);
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
        let [v0, v1, v2] = request.values;
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

    fn step(&mut self, dt: f64, command_timeout_ms: u32) {
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

    fn tick_u32(&self) -> u32 {
        u32::try_from(self.tick).unwrap_or(u32::MAX)
    }

    fn write_frame(&self, frame: &mut MotionFrame, deadline: Duration, now: Duration) {
        let nanos = |time: Duration| u64::try_from(time.as_nanos()).unwrap_or(u64::MAX);
        frame.tick = self.tick;
        frame.time_ns = nanos(deadline);
        frame.publish_ns = nanos(now);
        frame.axis_count = self.axes.len() as u32;
        frame.flags = if self.estop {
            FrameFlags::ESTOP_LATCHED.0
        } else {
            0
        };
        for ((_, sim), out) in self.axes.iter().zip(frame.axes.iter_mut()) {
            *out = sim.state;
        }
    }
}
