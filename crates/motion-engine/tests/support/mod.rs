//! Test support: an ideal board driver and a queue command port.
#![allow(dead_code)]

pub mod group_rig;

use core::time::Duration;
use std::collections::VecDeque;
use std::sync::{Arc, Mutex, MutexGuard};

use motion_drivers::{
    ChannelState, Commission, CommissionError, DeviceFault, DeviceStatus, Driver, Follow, Goal,
    GoalError, GoalKind, GoalKinds, LineLeg, LinkKind, Model, Pin, PinReading, Priority, RateFloor,
    Transmit,
};
use motion_engine::{AxisConfig, BusConfig, CommandPort, DeviceConfig, Engine, EngineConfig};
use motion_ipc::{ClientId, CommandKind, CommandReply, CommandRequest, GroupPath, MotionFrame};

/// What a test can see and change of an [`IdealBoard`] while the engine owns it.
#[derive(Debug, Default)]
pub struct BoardControl {
    /// Every message the driver put on the wire: (channel, goal kind).
    pub wire: Vec<(u8, u8)>,
    /// Every goal the driver accepted, in order: (channel, goal).
    pub goals: Vec<(u8, Goal)>,
    /// The board stops answering (no refresh) while set.
    pub silent: bool,
    /// A channel fault the board reports.
    pub fault: Option<DeviceFault>,
    /// Per channel: a velocity (counts/s) the board adds on its own, whatever its goal (a
    /// motor that slips, a board that runs an old ramp).
    pub drift: [f64; 4],
    /// Pins 0..8: the electrical level or ADC value the board reads.
    pub inputs: [f64; 8],
    /// Pins 0..8: the last level the driver wrote to an output (`None`: never).
    pub outputs: [Option<bool>; 8],
    /// Pins 0..8: the last value `set_pin_value` gave (`None`: never; read back as the
    /// pin's value).
    pub values: [Option<f64>; 8],
    /// Pins 0..8: events (captures, pulses) the board reported.
    pub events: [u32; 8],
    /// The board still has its start-up to do: `status().online` is false while set.
    pub starting: bool,
    /// The smallest velocity and acceleration the board represents (read when the engine
    /// is built).
    pub floor: RateFloor,
    /// How the board follows a group's path (read when the engine is built).
    pub follow: Follow,
    /// The board runs a group's line itself (`Driver::lead_line`) when set...
    pub leads: bool,
    /// ...taking this many `handle_timeout`s to prepare it...
    pub prepare_steps: u32,
    /// ...and pauses and resumes it (`pause_line` / `resume_line`) when set.
    pub pauses: bool,
    /// Every line the board took: its legs.
    pub lines: Vec<Vec<LineLeg>>,
    /// The instants the engine started the prepared line.
    pub starts: Vec<Duration>,
    /// Pauses and resumes the board did.
    pub paused: u32,
    pub resumed: u32,
    /// Every commission the driver took (`Driver::commission`, always accepted).
    pub commissions: Vec<Commission>,
    /// Every `handle_rx`: the instant the driver was given, the bytes.
    pub received: Vec<(Duration, Vec<u8>)>,
}

/// A board whose channels follow their goals with ideal trapezoidal physics, refreshing
/// every `handle_timeout`. Every goal becomes one 3-byte message on the wire.
#[derive(Debug)]
pub struct IdealBoard {
    channels: Vec<Channel>,
    supports: GoalKinds,
    control: Arc<Mutex<BoardControl>>,
    last: Option<Duration>,
    queue: VecDeque<(u8, u8)>,
    link_up: bool,
    /// A line prepared, and the `handle_timeout`s it still needs.
    line: Option<(Vec<LineLeg>, u32)>,
    /// Per channel: the ramp a pause interrupted.
    paused: Vec<Option<Goal>>,
}

#[derive(Debug, Clone, Copy)]
struct Channel {
    position: f64,
    velocity: f64,
    /// The board's own drift in the last step, counts/s (reported in the velocity).
    drift: f64,
    goal: Goal,
    refreshed_at: Option<Duration>,
}

impl IdealBoard {
    /// A board with `channels` channels taking `supports`, boxed as the engine holds it in
    /// tests, and its control.
    pub fn boxed(
        channels: usize,
        supports: &[GoalKind],
    ) -> (Box<dyn Driver>, Arc<Mutex<BoardControl>>) {
        let control = Arc::new(Mutex::new(BoardControl::default()));
        let board = Box::new(Self {
            channels: vec![
                Channel {
                    position: 0.0,
                    velocity: 0.0,
                    drift: 0.0,
                    goal: Goal::Off,
                    refreshed_at: None,
                };
                channels
            ],
            supports: GoalKinds::of(supports),
            control: Arc::clone(&control),
            last: None,
            queue: VecDeque::with_capacity(64),
            link_up: true,
            line: None,
            paused: vec![None; channels],
        });
        (board, control)
    }

    fn control(&self) -> MutexGuard<'_, BoardControl> {
        self.control.lock().expect("control lock")
    }
}

fn approach(current: f64, target: f64, step: f64) -> f64 {
    if step == f64::INFINITY || (target - current).abs() <= step {
        target
    } else {
        current + step.copysign(target - current)
    }
}

impl Driver for IdealBoard {
    fn model(&self) -> Model {
        Model::TMCPACK
    }
    fn channel_count(&self) -> usize {
        self.channels.len()
    }
    fn capabilities(&self, channel: usize) -> GoalKinds {
        if channel < self.channels.len() {
            self.supports
        } else {
            GoalKinds::NONE
        }
    }
    fn rate_floor(&self, channel: usize) -> RateFloor {
        if channel < self.channels.len() {
            self.control().floor
        } else {
            RateFloor::NONE
        }
    }
    fn follow(&self, _: usize) -> Follow {
        self.control().follow
    }
    fn refresh_budget(&self) -> Duration {
        Duration::from_millis(20)
    }
    fn handle_rx(&mut self, now: Duration, bytes: &[u8]) {
        self.control().received.push((now, bytes.to_vec()));
    }
    fn lead_line(&mut self, _: Duration, legs: &[LineLeg]) -> Result<bool, GoalError> {
        let mut control = self.control.lock().expect("control lock");
        let at_rest = legs.iter().all(|leg| {
            self.channels
                .get(leg.channel)
                .is_some_and(|c| c.velocity == 0.0)
        });
        if !control.leads || self.line.is_some() || !at_rest {
            return Ok(false);
        }
        control.lines.push(legs.to_vec());
        self.line = Some((legs.to_vec(), control.prepare_steps));
        Ok(true)
    }
    fn line_ready(&self) -> bool {
        self.line.as_ref().is_some_and(|(_, steps)| *steps == 0)
    }
    fn start_line(&mut self, now: Duration) {
        let Some((legs, _)) = self.line.take() else {
            return;
        };
        self.control().starts.push(now);
        for leg in legs {
            if let Some(channel) = self.channels.get_mut(leg.channel) {
                channel.goal = Goal::RampPosition {
                    counts: leg.counts,
                    velocity: leg.velocity,
                    accel: leg.accel,
                };
            }
        }
    }
    fn pause_line(&mut self, _: Duration, channel: usize) -> Result<bool, GoalError> {
        let Some(slot) = self.channels.get_mut(channel) else {
            return Err(GoalError::NoSuchChannel(channel));
        };
        let mut control = self.control.lock().expect("control lock");
        match slot.goal {
            Goal::RampPosition { accel, .. } if control.pauses => {
                self.paused[channel] = Some(slot.goal);
                slot.goal = Goal::Stop { decel: accel };
                control.paused += 1;
                Ok(true)
            }
            _ => Ok(false),
        }
    }
    fn resume_line(&mut self, _: Duration, channel: usize) -> Result<bool, GoalError> {
        let Some(goal) = self.paused.get_mut(channel).and_then(Option::take) else {
            return Ok(false);
        };
        self.channels[channel].goal = goal;
        self.control().resumed += 1;
        Ok(true)
    }
    fn handle_timeout(&mut self, now: Duration) {
        if let Some((_, steps)) = self.line.as_mut() {
            *steps = steps.saturating_sub(1);
        }
        let dt = self.last.map_or(0.0, |last| (now - last).as_secs_f64());
        self.last = Some(now);
        let (silent, fault, drift) = {
            let control = self.control();
            (control.silent, control.fault, control.drift)
        };
        for (index, channel) in self.channels.iter_mut().enumerate() {
            let (target_velocity, accel) = match channel.goal {
                Goal::Off
                | Goal::Power { .. }
                | Goal::Position { .. }
                | Goal::SetPosition { .. } => (0.0, f64::INFINITY),
                Goal::Stop { decel } => (0.0, decel),
                Goal::Velocity { velocity, accel } => (velocity, accel),
                Goal::RampPosition {
                    counts,
                    velocity,
                    accel,
                } => {
                    let remaining = counts - channel.position;
                    let brake = (2.0 * accel * remaining.abs()).sqrt();
                    (velocity.min(brake).copysign(remaining), accel)
                }
                Goal::Home { velocity } => (-velocity, f64::INFINITY),
            };
            if let Goal::Power { fraction } = channel.goal {
                channel.velocity = fraction * 1000.0;
            } else {
                let step = if accel.is_infinite() {
                    accel
                } else {
                    accel * dt
                };
                channel.velocity = approach(channel.velocity, target_velocity, step);
            }
            let drift = drift.get(index).copied().unwrap_or(0.0);
            channel.drift = drift;
            let before = channel.position;
            channel.position += (channel.velocity + drift) * dt;
            // A ramp that reaches (or would step over) its target this step ends on it.
            if let Goal::RampPosition { counts, .. } = channel.goal
                && drift == 0.0
                && ((counts - channel.position).abs() < 1e-6
                    || (counts - before).signum() != (counts - channel.position).signum()
                    || channel.velocity == 0.0 && (counts - channel.position).abs() < 1.0)
            {
                channel.position = counts;
                channel.velocity = 0.0;
            }
            if let Goal::Position { counts } = channel.goal
                && drift == 0.0
            {
                channel.position = counts;
            }
            if !silent && self.link_up && fault.is_none() {
                channel.refreshed_at = Some(now);
            }
        }
    }
    fn poll_timeout(&self) -> Option<Duration> {
        None
    }
    fn wants_transmit(&self, _: Duration) -> Option<Priority> {
        (!self.queue.is_empty() && self.link_up).then_some(Priority::Command)
    }
    fn poll_transmit(&mut self, _: Duration, buf: &mut [u8]) -> Option<Transmit> {
        if !self.link_up {
            return None;
        }
        let (channel, kind) = self.queue.pop_front()?;
        buf[..3].copy_from_slice(&[0xA5, channel, kind]);
        self.control().wire.push((channel, kind));
        Some(Transmit {
            len: 3,
            expects_reply: false,
            goal_starts: 1 << channel,
        })
    }
    fn awaiting_reply(&self) -> bool {
        false
    }
    fn goals_pending(&self) -> bool {
        !self.queue.is_empty()
    }
    fn set_goal(&mut self, _: Duration, channel: usize, goal: Goal) -> Result<(), GoalError> {
        if !self.link_up {
            return Err(GoalError::Offline);
        }
        if !self.supports.contains(goal.kind()) && goal.kind() != GoalKind::Stop {
            return Err(GoalError::Unsupported(goal.kind()));
        }
        if channel >= self.channels.len() {
            return Err(GoalError::NoSuchChannel(channel));
        }
        self.control().goals.push((channel as u8, goal));
        let slot = self
            .channels
            .get_mut(channel)
            .ok_or(GoalError::NoSuchChannel(channel))?;
        if let Goal::SetPosition { counts } = goal {
            slot.position = counts;
        } else {
            slot.goal = goal;
        }
        // A goal ends a paused or prepared line on the channel.
        self.paused[channel] = None;
        if self
            .line
            .as_ref()
            .is_some_and(|(legs, _)| legs.iter().any(|leg| leg.channel == channel))
        {
            self.line = None;
        }
        if self.queue.len() < 64 {
            self.queue.push_back((channel as u8, goal.kind() as u8));
        }
        Ok(())
    }
    fn channel(&self, channel: usize) -> ChannelState {
        let Some(slot) = self.channels.get(channel) else {
            return ChannelState::UNKNOWN;
        };
        ChannelState {
            position: slot.position,
            velocity: slot.velocity + slot.drift,
            raw_counts: slot.position.round() as i64,
            refreshed_at: slot.refreshed_at,
            moving: slot.velocity + slot.drift != 0.0,
            homed: false,
            at_limit: false,
            arrived: false,
            fault: if self.link_up {
                self.control().fault
            } else {
                Some(DeviceFault::LinkDown)
            },
        }
    }
    fn status(&self) -> DeviceStatus {
        let mut status = DeviceStatus::UNKNOWN;
        status.online = self.link_up && !self.control().starting;
        status.set_firmware("ideal 1.0");
        status
    }
    fn read_pin(&self, pin: Pin) -> Option<PinReading> {
        let control = self.control();
        let index = usize::from(pin.0);
        let value = match (control.outputs.get(index)?, control.values[index]) {
            (_, Some(value)) => value,
            (Some(level), None) => f64::from(u8::from(*level)),
            (None, None) => control.inputs[index],
        };
        Some(PinReading {
            value,
            refreshed_at: self.last,
            events: control.events[index],
        })
    }
    fn set_pin_value(&mut self, _: Duration, pin: Pin, value: f64) -> Result<(), GoalError> {
        if !self.link_up {
            return Err(GoalError::Offline);
        }
        if value.abs() > 1e9 {
            return Err(GoalError::OutOfBoardRange(GoalKind::Position));
        }
        let mut control = self.control();
        let slot = control
            .values
            .get_mut(usize::from(pin.0))
            .ok_or(GoalError::NoSuchPin(pin))?;
        *slot = Some(value.round());
        Ok(())
    }
    fn set_output(&mut self, _: Duration, pin: Pin, high: bool) -> Result<(), GoalError> {
        if !self.link_up {
            return Err(GoalError::Offline);
        }
        let mut control = self.control();
        let slot = control
            .outputs
            .get_mut(usize::from(pin.0))
            .ok_or(GoalError::NoSuchPin(pin))?;
        *slot = Some(high);
        Ok(())
    }
    fn link_down(&mut self, _: Duration) {
        self.link_up = false;
        self.queue.clear();
    }
    fn link_up(&mut self, _: Duration) {
        self.link_up = true;
        for channel in &mut self.channels {
            channel.goal = Goal::Off;
            channel.velocity = 0.0;
        }
    }
    fn commission(&mut self, _: Duration, change: Commission) -> Result<(), CommissionError> {
        self.control().commissions.push(change);
        Ok(())
    }
}

/// A command port over a queue; replies are collected. Paths a test "published" wait in
/// `paths` with their publisher's identity.
#[derive(Debug, Default)]
pub struct Queue {
    pub requests: VecDeque<CommandRequest>,
    pub replies: Vec<CommandReply>,
    pub paths: Vec<(ClientId, Box<GroupPath>)>,
    taken: Option<Box<GroupPath>>,
}

impl CommandPort for Queue {
    fn next_request(&mut self) -> Option<CommandRequest> {
        self.requests.pop_front()
    }
    fn reply(&mut self, reply: CommandReply) {
        self.replies.push(reply);
    }
    fn take_path(&mut self, client: ClientId, id: u64) -> Option<&GroupPath> {
        let index = self
            .paths
            .iter()
            .rposition(|(from, path)| *from == client && path.id == id)?;
        self.taken = Some(self.paths.remove(index).1);
        self.taken.as_deref()
    }
}

pub const ALL_GOALS: [GoalKind; 8] = GoalKind::ALL;
pub const PERIOD: Duration = Duration::from_millis(1);
pub const CLIENT_A: ClientId = ClientId { lo: 1, hi: 0 };
pub const CLIENT_B: ClientId = ClientId { lo: 2, hi: 0 };

pub fn axis(name: &str, device: usize, channel: usize) -> AxisConfig {
    AxisConfig {
        name: name.into(),
        unit: "mm".into(),
        device,
        channel,
        counts_per_unit: 100.0,
        min: -100.0,
        max: 100.0,
        max_velocity: 50.0,
        max_accel: 500.0,
        position_tolerance: 0.01,
        ..AxisConfig::default()
    }
}

/// Two links, one ideal board each, two axes per board: x, y on link 0; z, w on link 1.
pub fn two_link_engine() -> (Engine, Vec<Arc<Mutex<BoardControl>>>) {
    let config = EngineConfig {
        name: "test".into(),
        tick_hz: 1000,
        command_timeout: Duration::from_millis(250),
        links: vec![
            BusConfig {
                name: "bus0".into(),
                kind: LinkKind::Stream,
            },
            BusConfig {
                name: "bus1".into(),
                kind: LinkKind::Stream,
            },
        ],
        devices: vec![
            DeviceConfig {
                name: "board0".into(),
                link: 0,
                address: 1,
            },
            DeviceConfig {
                name: "board1".into(),
                link: 1,
                address: 2,
            },
        ],
        axes: vec![
            axis("x", 0, 0),
            axis("y", 0, 1),
            axis("z", 1, 0),
            axis("w", 1, 1),
        ],
        ..EngineConfig::default()
    };
    let (board0, control0) = IdealBoard::boxed(2, &ALL_GOALS);
    let (board1, control1) = IdealBoard::boxed(2, &ALL_GOALS);
    let engine = Engine::new(config, vec![board0, board1]).expect("valid config");
    (engine, vec![control0, control1])
}

/// Drives an engine tick by tick with a fake clock.
pub struct Harness {
    pub engine: Engine,
    pub frame: Box<MotionFrame>,
    pub port: Queue,
    pub now: Duration,
    pub sequence: u64,
}

impl Harness {
    pub fn new(engine: Engine) -> Self {
        Self {
            engine,
            frame: Box::new(MotionFrame::EMPTY),
            port: Queue::default(),
            now: Duration::ZERO,
            sequence: 0,
        }
    }

    /// One tick: step, then drain every link's transmit queue. Returns bytes sent.
    pub fn tick(&mut self) -> usize {
        self.engine.step(self.now, &mut self.port, &mut self.frame);
        let mut sent = 0;
        let mut buf = [0u8; 256];
        for link in 0..self.engine.config().links.len() {
            while let Some(len) = self.engine.poll_link_transmit(link, self.now, &mut buf) {
                sent += len;
            }
        }
        self.now += PERIOD;
        sent
    }

    pub fn ticks(&mut self, count: usize) {
        for _ in 0..count {
            self.tick();
        }
    }

    /// Sends one command in the next tick and returns its reply.
    pub fn command(
        &mut self,
        client: ClientId,
        axis: u32,
        kind: CommandKind,
        values: [f64; 3],
    ) -> CommandReply {
        self.sequence += 1;
        let request = CommandRequest::new(client, self.sequence, axis, kind).with_values(values);
        self.port.requests.push_back(request);
        self.tick();
        let reply = self.port.replies.pop().expect("every request is answered");
        assert_eq!(reply.sequence, self.sequence);
        reply
    }

    pub fn axis(&self, index: usize) -> motion_ipc::AxisState {
        self.frame.axes[index]
    }
}
