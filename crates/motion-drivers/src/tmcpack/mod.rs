//! Driver for the Trinamic SIXpack / QUADpack on RS-232 / RS-485 ([`TmcpackDriver`]).
//!
//! Start-up: `$43` unit information (firmware revision and serial for
//! [`DeviceStatus::firmware`], the reset flag); `$28` to see whether a configured motor is
//! still running (left so by a previous server: it is stopped with `$14`/`$25` and polled
//! with `$21` until it stands, because `$12`, `$13` and `$16` may only change at
//! standstill); then the configuration — `$40` with the link's own baud divisor and the
//! configured switch-over delay (the baud rate is never changed: the link would have to
//! follow), `$41` packet timeout, `$12` clkdiv chosen for the fastest motor, `$10` peak
//! currents per motor pair, and per configured motor `$11`, `$13`, `$14`, `$15`, `$16`,
//! `$18`, `$31` from its axis limits and machine keys, then `$33` and `$32` when I/O is
//! configured. Motors found active afterwards are stopped: whatever they were doing was not
//! commanded by this run. The whole configuration goes out again whenever the pack is seen
//! to have reset (`$43` reset flag, or after it stopped answering).
//!
//! The wire (manual 6.1, 7.1): one request in flight. A query waits for its answer until
//! `request + switch-over (at least the factory 6 ms, in case the pack rebooted) + answer +`
//! [`REPLY_MARGIN`]; after an answer the line stays reserved for the switch-over time, in
//! which the pack still drives it; after a timeout it stays silent for the pack's packet
//! timeout so that a partial word on its side is aborted. A request without an answer
//! reserves the line for its own wire time and at least the packet timeout of every pack on
//! the bus ($41: "The command word always has to be completely transmitted during a
//! parameterized timeout"), so that a word torn by noise is aborted before the next one
//! starts instead of taking its first bytes. Queries carry the response address of
//! [`TmcpackDriverConfig::reply_address`], which no pack on the bus may have.
//!
//! Polling plan: goals first ([`Priority::Command`]: stops before output changes before
//! other commands), then `$20` position/action polls round-robin over the configured motors
//! with one `$30` input poll per round when inputs are configured ([`Priority::Poll`]),
//! and a `$43` every [`RESET_CHECK_PERIOD`] to notice a pack that rebooted (reset flag).
//! Three timeouts in a row take the pack offline ([`DeviceFault::NotResponding`]); it is
//! then asked for `$43` every [`RETRY_PERIOD`] and configured again when it answers.
//!
//! Goals are mapped as described in the `channel` module: Stop with `$25` velocity 0, then
//! `$23`; Position/RampPosition with `$14`, `$26`, `$23`; Velocity with `$25`; Home with
//! `$16`, `$22`; SetPosition with `$27`; Off with a stop, then `$11` at 0 %. Power is
//! unsupported (a stepper has no open-loop power). I/O is described in the `io` module.

mod channel;
mod config;
mod io;
mod reply;
mod startup;
mod wire;

#[cfg(test)]
mod bench;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_goals;
#[cfg(test)]
mod tests_io;

use core::time::Duration;

use tmcpack::convert::{DEFAULT_SWITCHOVER_UNITS as FACTORY_SWITCHOVER, byte_time, units};
use tmcpack::{
    Command, DEFAULT_PACKET_TIMEOUT, FRAME_LEN, MotorMask, Request, RequestFrame, Variant,
};

use crate::driver::{Driver, Model, Priority, Transmit};
use crate::goal::{Goal, GoalError, GoalKind, GoalKinds};
use crate::pin::{Pin, PinReading};
use crate::state::{ChannelState, DeviceFault, DeviceStatus};

use channel::{Channel, Step};
use config::{Scale, clkdiv_for};
use io::IoState;
use startup::{Quiesce, StartupPlan};
use wire::{Expect, Purpose, ReplyHunter, Wire};

pub use config::{
    Currents, DEFAULT_REPLY_ADDRESS, DEFAULT_SWITCHOVER_UNITS, PACKET_TIMEOUT_SLACK_BYTES,
    TmcpackChannel, TmcpackDriverConfig, default_packet_timeout_units,
};
pub use io::{MAX_PINS, PinSet, ReadyOutput, TmcpackIo, pins};

/// Added to a query's wire and switch-over time before it counts as unanswered
/// (processing in the pack, and the host's tick granularity).
pub const REPLY_MARGIN: Duration = Duration::from_millis(6);
/// Timeouts in a row after which the pack is declared not responding.
pub const MAX_TIMEOUTS: u32 = 3;
/// How often an offline pack is asked again.
pub const RETRY_PERIOD: Duration = Duration::from_millis(250);
/// How often an online pack's reset flag is read ($43).
pub const RESET_CHECK_PERIOD: Duration = Duration::from_secs(1);

/// The goals a configured motor takes.
const CAPABILITIES: GoalKinds = GoalKinds::of(&[
    GoalKind::Off,
    GoalKind::Stop,
    GoalKind::Position,
    GoalKind::Velocity,
    GoalKind::RampPosition,
    GoalKind::Home,
    GoalKind::SetPosition,
]);

/// The poll slot of the `$30` input poll, after the six motors.
const IO_SLOT: usize = 6;

/// Where the driver is with its pack.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// The link is down.
    Down,
    /// Asking `$43` (first contact, or after the pack stopped answering).
    Identify,
    /// Asking `$28` which motors are active.
    Survey,
    /// Stopping configured motors found active, waiting until they stand.
    Quiesce,
    /// Sending start-up request `n`.
    Configure(usize),
    /// Polling and driving.
    Online,
}

/// What `pick` chose to send.
struct Pick {
    request: Request,
    expect: Option<Expect>,
    channel: Option<usize>,
}

/// The sans-I/O driver of one SIXpack / QUADpack.
#[derive(Debug)]
pub struct TmcpackDriver {
    address: u8,
    reply_address: u8,
    variant: Variant,
    word_time: Duration,
    /// The switch-over delay the pack has now, as far as the driver knows.
    switchover: Duration,
    /// The packet timeout the pack has now, as far as the driver knows.
    pack_timeout: Duration,
    /// The longest packet timeout of the other packs on the bus.
    bus_timeout: Duration,
    channels: [Option<Channel>; 6],
    io: IoState,
    plan: StartupPlan,
    quiesce: Option<Quiesce>,
    phase: Phase,
    wire: Wire,
    hunter: ReplyHunter,
    /// Sequence number of the last request sent.
    seq: u64,
    status: DeviceStatus,
    timeouts_in_row: u32,
    ever_online: bool,
    retry_at: Duration,
    reset_check_at: Duration,
    next_poll: usize,
    next_command: usize,
    budget: Duration,
}

impl TmcpackDriver {
    /// A driver for the pack `config` describes; it starts talking at the first
    /// `poll_transmit`.
    pub fn new(config: TmcpackDriverConfig) -> Self {
        let motors = usize::from(config.variant.motors());
        let clkdiv = clkdiv_for(&config.channels[..motors.min(6)]);
        let mut channels: [Option<Channel>; 6] = [const { None }; 6];
        for (motor, (slot, cfg)) in channels.iter_mut().zip(config.channels).enumerate() {
            if motor < motors
                && let Some(cfg) = cfg
            {
                *slot = Some(Channel::new(motor as u8, cfg, Scale::new(clkdiv, &cfg)));
            }
        }
        let io = IoState::new(config.variant, config.io);
        let plan = StartupPlan::new(&config, clkdiv, &channels, &io);
        let byte = byte_time(config.baud);
        let word_time = byte.saturating_mul(FRAME_LEN as u32);
        let configured = config
            .switchover_units
            .map_or(units(FACTORY_SWITCHOVER), units);
        let polled = channels.iter().flatten().count() + usize::from(io.polls());
        let round = usize::from(config.bus_motors).max(polled).max(1) as u32;
        let query = 2 * word_time + 2 * configured + Duration::from_millis(2);
        let budget = query * round * 2 + query * 4 + Duration::from_millis(50);
        let reply_address = if config.reply_address == config.address {
            if config.address == DEFAULT_REPLY_ADDRESS {
                0xFF
            } else {
                DEFAULT_REPLY_ADDRESS
            }
        } else {
            config.reply_address
        };
        Self {
            address: config.address,
            reply_address,
            variant: config.variant,
            word_time,
            switchover: units(FACTORY_SWITCHOVER),
            pack_timeout: DEFAULT_PACKET_TIMEOUT,
            bus_timeout: units(config.bus_packet_timeout_units),
            channels,
            io,
            plan,
            quiesce: None,
            phase: Phase::Identify,
            wire: Wire::Idle,
            hunter: ReplyHunter::new(),
            seq: 0,
            status: DeviceStatus::UNKNOWN,
            timeouts_in_row: 0,
            ever_online: false,
            retry_at: Duration::ZERO,
            reset_check_at: Duration::ZERO,
            next_poll: 0,
            next_command: 0,
            budget,
        }
    }

    /// The response address the driver's queries carry.
    pub fn reply_address(&self) -> u8 {
        self.reply_address
    }

    /// The clkdiv and, per motor, the divider, vmax and amax the start-up writes
    /// (`None` for unconfigured motors).
    pub fn board_settings(&self) -> [Option<(u8, u8, u16, u16)>; 6] {
        let mut out = [None; 6];
        for (slot, channel) in out.iter_mut().zip(&self.channels) {
            *slot = channel.as_ref().map(|c| {
                let s = c.scale;
                (s.clock.clkdiv(), s.clock.div(), s.vmax, s.amax)
            });
        }
        out
    }

    /// The requests the start-up writes after the survey, in order (with the outputs as
    /// they are now).
    pub fn startup_requests(&self) -> impl Iterator<Item = Request> + '_ {
        (0..startup::MAX_STARTUP)
            .map_while(|index| self.plan.get(index))
            .map(|request| self.resolve(request))
    }

    /// A plan entry as it goes on the wire: the `$32` placeholder carries the current
    /// output levels.
    fn resolve(&self, request: Request) -> Request {
        match request {
            Request::Outputs { .. } => self.io.outputs_request(),
            other => other,
        }
    }

    /// The smallest spacing between the starts of two words: their wire time, and the
    /// packet timeout of every pack on the bus.
    fn spacing(&self) -> Duration {
        self.word_time.max(self.pack_timeout).max(self.bus_timeout)
    }

    fn any_ready(&self) -> bool {
        self.io.outputs_pending || self.channels.iter().flatten().any(Channel::ready)
    }

    /// What the driver would send now.
    fn next_message(&self, now: Duration) -> Option<Priority> {
        if self.wire != Wire::Idle {
            return None;
        }
        match self.phase {
            Phase::Down => None,
            Phase::Identify => (now >= self.retry_at).then_some(Priority::Setup),
            Phase::Survey | Phase::Quiesce | Phase::Configure(_) => Some(Priority::Setup),
            Phase::Online if self.any_ready() => Some(Priority::Command),
            Phase::Online => {
                let polls = self.channels.iter().any(Option::is_some) || self.io.polls();
                (polls || now >= self.reset_check_at).then_some(Priority::Poll)
            }
        }
    }

    fn query(
        &self,
        request: Request,
        command: Command,
        motor: Option<u8>,
        purpose: Purpose,
    ) -> Pick {
        Pick {
            request,
            expect: Some(Expect {
                command,
                motor,
                purpose,
            }),
            channel: None,
        }
    }

    /// Picks the request to send now; the core of `poll_transmit`.
    fn pick(&mut self, now: Duration) -> Option<Pick> {
        let priority = self.next_message(now)?;
        let reply_to = self.reply_address;
        match self.phase {
            Phase::Down => None,
            Phase::Identify => Some(self.query(
                Request::UnitInfo { reply_to },
                Command::UnitInfo,
                None,
                Purpose::Startup,
            )),
            Phase::Survey => Some(self.query(
                Request::QueryActions {
                    reply_to,
                    delay_mask: MotorMask::EMPTY,
                },
                Command::QueryActions,
                None,
                Purpose::Survey,
            )),
            Phase::Quiesce => self.pick_quiesce(now),
            Phase::Configure(index) => {
                let request = self.resolve(self.plan.get(index)?);
                Some(Pick {
                    request,
                    expect: None,
                    channel: None,
                })
            }
            Phase::Online if priority == Priority::Command => self.pick_command(),
            Phase::Online => self.pick_poll(now),
        }
    }

    fn pick_quiesce(&mut self, now: Duration) -> Option<Pick> {
        let quiesce = self.quiesce.as_mut()?;
        if let Some(request) = quiesce.command() {
            return Some(Pick {
                request,
                expect: None,
                channel: None,
            });
        }
        if quiesce.done(now) {
            self.quiesce = None;
            self.phase = Phase::Configure(0);
            return self.pick(now);
        }
        let motor = quiesce.poll_motor()?;
        Some(self.query(
            Request::QueryVelocity {
                motor,
                reply_to: self.reply_address,
            },
            Command::QueryVelocity,
            Some(motor),
            Purpose::Quiesce,
        ))
    }

    /// Stops first, then output changes, then the other goals round-robin.
    fn pick_command(&mut self) -> Option<Pick> {
        let urgent = self.channels.iter().flatten().find(|c| c.urgent());
        if let Some(channel) = urgent
            && let Some(Step::Send(request)) = channel.current()
        {
            return Some(Pick {
                request,
                expect: None,
                channel: Some(usize::from(channel.motor)),
            });
        }
        if self.io.outputs_pending {
            return Some(Pick {
                request: self.io.outputs_request(),
                expect: None,
                channel: None,
            });
        }
        for offset in 0..6 {
            let index = (self.next_command + offset) % 6;
            if let Some(Some(channel)) = self.channels.get(index)
                && let Some(Step::Send(request)) = channel.current()
            {
                self.next_command = (index + 1) % 6;
                return Some(Pick {
                    request,
                    expect: None,
                    channel: Some(index),
                });
            }
        }
        None
    }

    fn pick_poll(&mut self, now: Duration) -> Option<Pick> {
        let reply_to = self.reply_address;
        if now >= self.reset_check_at {
            return Some(self.query(
                Request::UnitInfo { reply_to },
                Command::UnitInfo,
                None,
                Purpose::ResetCheck,
            ));
        }
        let urgent = self
            .channels
            .iter()
            .flatten()
            .find(|c| c.wants_rest_poll(now))
            .map(|c| usize::from(c.motor));
        let slot = urgent.or_else(|| {
            (0..=IO_SLOT)
                .map(|offset| (self.next_poll + offset) % (IO_SLOT + 1))
                .find(|&i| match i {
                    IO_SLOT => self.io.polls(),
                    _ => matches!(self.channels.get(i), Some(Some(_))),
                })
        })?;
        if urgent.is_none() {
            self.next_poll = (slot + 1) % (IO_SLOT + 1);
        }
        if slot == IO_SLOT {
            let channel = self.io.next_channel();
            return Some(self.query(
                Request::ReadInput { channel, reply_to },
                Command::ReadInput,
                Some(channel),
                Purpose::Io,
            ));
        }
        let motor = slot as u8;
        Some(self.query(
            Request::QueryPosition { motor, reply_to },
            Command::QueryPosition,
            Some(motor),
            Purpose::Poll,
        ))
    }

    /// The reply timeout of a query sent at `now`: request, switch-over (at least the
    /// factory delay), reply, margin.
    fn reply_deadline(&self, now: Duration) -> Duration {
        let switchover = self.switchover.max(units(FACTORY_SWITCHOVER));
        now + self.word_time * 2 + switchover + REPLY_MARGIN
    }

    fn go_online(&mut self, now: Duration) {
        self.phase = Phase::Online;
        self.status.online = true;
        self.status.fault = None;
        self.ever_online = true;
        self.reset_check_at = now + RESET_CHECK_PERIOD;
        // The start-up wrote the outputs as they are now.
        self.io.outputs_pending = false;
    }

    /// The pack lost what it was told (reboot, silence, link): channels keep their last
    /// state but are faulted until fresh data, and their goals are void.
    fn restart(&mut self, fault: DeviceFault) {
        self.status.online = false;
        self.status.fault = Some(fault);
        self.quiesce = None;
        for channel in self.channels.iter_mut().flatten() {
            channel.restart(fault);
        }
    }

    /// Whatever the pack has now (it may have rebooted to the factory settings).
    fn assume_factory_line(&mut self) {
        self.switchover = units(FACTORY_SWITCHOVER);
        self.pack_timeout = DEFAULT_PACKET_TIMEOUT;
    }
}

impl Driver for TmcpackDriver {
    fn model(&self) -> Model {
        Model::Tmcpack
    }

    fn channel_count(&self) -> usize {
        usize::from(self.variant.motors())
    }

    fn capabilities(&self, channel: usize) -> GoalKinds {
        match self.channels.get(channel) {
            Some(Some(_)) if channel < self.channel_count() => CAPABILITIES,
            _ => GoalKinds::NONE,
        }
    }

    fn refresh_budget(&self) -> Duration {
        self.budget
    }

    fn handle_rx(&mut self, now: Duration, bytes: &[u8]) {
        if bytes.is_empty() {
            return;
        }
        let Wire::Awaiting {
            expect, sent_at, ..
        } = self.wire
        else {
            // A late answer, an echo or noise: nobody asked.
            self.status.bad_replies = self.status.bad_replies.saturating_add(1);
            return;
        };
        let Some(reply) = self.hunter.push(self.reply_address, expect, bytes) else {
            return;
        };
        if self.hunter.skipped > 0 {
            self.status.bad_replies = self.status.bad_replies.saturating_add(1);
        }
        // The pack keeps driving the line for the switch-over time after its answer.
        self.wire = Wire::Quiet {
            until: now + self.switchover,
        };
        self.on_reply(now, expect, sent_at, reply);
    }

    fn handle_timeout(&mut self, now: Duration) {
        match self.wire {
            Wire::Sending { until } | Wire::Quiet { until } if now >= until => {
                self.wire = Wire::Idle;
            }
            Wire::Awaiting { deadline, .. } if now >= deadline => self.on_timeout(now),
            _ => {}
        }
    }

    fn poll_timeout(&self) -> Option<Duration> {
        let phase = match self.phase {
            Phase::Identify => Some(self.retry_at),
            Phase::Online => Some(self.reset_check_at),
            Phase::Quiesce => self.quiesce.as_ref().map(|q| q.deadline),
            Phase::Down | Phase::Survey | Phase::Configure(_) => None,
        };
        let rest = self
            .channels
            .iter()
            .flatten()
            .filter(|c| c.current() == Some(Step::AwaitRest))
            .filter_map(|c| c.rest_at)
            .min();
        [self.wire.deadline(), phase, rest]
            .into_iter()
            .flatten()
            .min()
    }

    fn wants_transmit(&self, now: Duration) -> Option<Priority> {
        self.next_message(now)
    }

    fn poll_transmit(&mut self, now: Duration, buf: &mut [u8]) -> Option<Transmit> {
        let pick = self.pick(now)?;
        let request = pick.request;
        let len = RequestFrame::new(self.address, request).encode(buf).ok()?;
        self.seq += 1;
        let wire_end = now + self.word_time;
        match request {
            Request::SetBaud { switchover, .. } => self.switchover = units(switchover),
            Request::PacketTimeout { timeout } => self.pack_timeout = units(timeout),
            Request::Outputs { .. } => {
                self.io.on_outputs_sent(now, request);
                if self.phase == Phase::Online {
                    self.io.outputs_pending = false;
                }
            }
            _ => {}
        }
        match pick.expect {
            Some(expect) => {
                self.hunter.reset();
                self.wire = Wire::Awaiting {
                    expect,
                    sent_at: now,
                    deadline: self.reply_deadline(now),
                };
            }
            None => {
                self.wire = Wire::Sending {
                    until: now + self.spacing(),
                };
            }
        }
        match self.phase {
            Phase::Quiesce => {
                if let Some(quiesce) = self.quiesce.as_mut()
                    && pick.expect.is_none()
                {
                    quiesce.sent();
                }
            }
            Phase::Configure(index) => {
                let next = index + 1;
                if self.plan.get(next).is_some() {
                    self.phase = Phase::Configure(next);
                } else {
                    self.go_online(now);
                }
            }
            _ => {}
        }
        if let Some(Some(channel)) = pick.channel.and_then(|i| self.channels.get_mut(i)) {
            channel.on_sent(request, self.seq, wire_end);
            channel.advance();
        }
        Some(Transmit {
            len,
            expects_reply: true,
        })
    }

    fn awaiting_reply(&self) -> bool {
        self.wire != Wire::Idle
    }

    fn goals_pending(&self) -> bool {
        self.io.outputs_pending || self.channels.iter().flatten().any(Channel::pending)
    }

    fn set_goal(&mut self, _now: Duration, channel: usize, goal: Goal) -> Result<(), GoalError> {
        if channel >= self.channel_count() {
            return Err(GoalError::NoSuchChannel(channel));
        }
        let phase = self.phase;
        let Some(Some(slot)) = self.channels.get_mut(channel) else {
            return Err(GoalError::Unsupported(goal.kind()));
        };
        match phase {
            Phase::Online => slot.plan(goal),
            Phase::Survey | Phase::Quiesce | Phase::Configure(_) => Err(GoalError::Starting),
            Phase::Down | Phase::Identify => Err(GoalError::Offline),
        }
    }

    fn channel(&self, channel: usize) -> ChannelState {
        match self.channels.get(channel) {
            Some(Some(c)) if channel < self.channel_count() => c.state,
            _ => ChannelState::UNKNOWN,
        }
    }

    fn status(&self) -> DeviceStatus {
        self.status
    }

    fn link_down(&mut self, _now: Duration) {
        self.phase = Phase::Down;
        self.wire = Wire::Idle;
        self.timeouts_in_row = 0;
        self.restart(DeviceFault::LinkDown);
    }

    fn link_up(&mut self, now: Duration) {
        self.phase = Phase::Identify;
        self.wire = Wire::Idle;
        self.retry_at = now;
        self.timeouts_in_row = 0;
        self.assume_factory_line();
    }

    fn read_pin(&self, pin: Pin) -> Option<PinReading> {
        self.io.read(pin)
    }

    fn set_output(&mut self, _now: Duration, pin: Pin, high: bool) -> Result<(), GoalError> {
        if !self.io.config().outputs.contains(pin) {
            return Err(GoalError::NoSuchPin(pin));
        }
        match self.phase {
            Phase::Online => {}
            Phase::Survey | Phase::Quiesce | Phase::Configure(_) => {
                return Err(GoalError::Starting);
            }
            Phase::Down | Phase::Identify => return Err(GoalError::Offline),
        }
        if self.io.set(pin, high) {
            Ok(())
        } else {
            Err(GoalError::NoSuchPin(pin))
        }
    }
}
