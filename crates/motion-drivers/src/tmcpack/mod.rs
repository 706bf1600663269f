//! Driver for the Trinamic SIXpack / QUADpack on RS-232 / RS-485 ([`TmcpackDriver`]).
//!
//! Start-up: `$43` unit information (firmware revision and serial for
//! [`DeviceStatus::firmware`], the reset flag), then the configuration — `$40` with the
//! link's own baud divisor and a 2 ms switch-over delay (the baud rate is never changed:
//! the link would have to follow), `$12` clkdiv chosen for the fastest motor, and per
//! configured motor `$11`, `$13`, `$14`, `$15`, `$16`, `$18` from its axis limits. Motors
//! found active afterwards are stopped: whatever they were doing was not commanded by this
//! run.
//!
//! The wire (manual 6.1, 7.1): one request in flight. A query waits for its answer until
//! `request + switch-over (at least the factory 6 ms, in case the pack rebooted) + answer +`
//! [`REPLY_MARGIN`]; after an answer the line stays reserved for the switch-over time, in
//! which the pack still drives it; after a timeout it stays silent for the pack's packet
//! timeout so that a partial word on its side is aborted. Requests without an answer
//! reserve the line for their own wire time. Queries carry the response address of
//! [`TmcpackDriverConfig::reply_address`], which no pack on the bus may have.
//!
//! Polling plan: goals first ([`Priority::Command`]), then `$20` position/action polls
//! round-robin over the configured motors ([`Priority::Poll`]), with a `$43` every
//! [`RESET_CHECK_PERIOD`] to notice a pack that rebooted (reset flag). Three timeouts in a
//! row take the pack offline ([`DeviceFault::NotResponding`]); it is then asked for `$43`
//! every [`RETRY_PERIOD`] and configured again when it answers.
//!
//! Goals are mapped as described in the `channel` module: Stop with `$25` velocity 0, then
//! `$23`; Position/RampPosition with `$14`, `$26`, `$23`; Velocity with `$25`; Home with
//! `$16`, `$22`; SetPosition with `$27`; Off with `$11` at 0 %. Power is unsupported (a
//! stepper has no open-loop power).

mod channel;
mod config;
mod startup;
mod wire;

#[cfg(test)]
mod tests;

use core::fmt::Write as _;
use core::time::Duration;

use tmcpack::convert::{DEFAULT_SWITCHOVER_UNITS as FACTORY_SWITCHOVER, byte_time, units};
use tmcpack::{Command, DEFAULT_PACKET_TIMEOUT, FRAME_LEN, Reply, Request, RequestFrame, Variant};

use crate::driver::{Driver, Model, Priority, Transmit};
use crate::goal::{Goal, GoalError, GoalKind, GoalKinds};
use crate::state::{ChannelState, DeviceFault, DeviceStatus, FIRMWARE_LEN};

use channel::{Channel, Step};
use config::{Scale, clkdiv_for};
use startup::StartupPlan;
use wire::{Expect, Purpose, ReplyHunter, Wire};

pub use config::{
    Currents, DEFAULT_REPLY_ADDRESS, DEFAULT_SWITCHOVER_UNITS, TmcpackChannel, TmcpackDriverConfig,
};

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

/// Where the driver is with its pack.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// The link is down.
    Down,
    /// Asking `$43` (first contact, or after the pack stopped answering).
    Identify,
    /// Sending start-up request `n`.
    Configure(usize),
    /// Polling and driving.
    Online,
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
    channels: [Option<Channel>; 6],
    plan: StartupPlan,
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
        let plan = StartupPlan::new(&config, clkdiv, &channels);
        let byte = byte_time(config.baud);
        let word_time = byte.saturating_mul(FRAME_LEN as u32);
        let configured = config
            .switchover_units
            .map_or(units(FACTORY_SWITCHOVER), units);
        let polled = channels.iter().flatten().count();
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
            channels,
            plan,
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

    fn any_ready(&self) -> bool {
        self.channels.iter().flatten().any(Channel::ready)
    }

    /// What the driver would send now.
    fn next_message(&self, now: Duration) -> Option<Priority> {
        if self.wire != Wire::Idle {
            return None;
        }
        match self.phase {
            Phase::Down => None,
            Phase::Identify => (now >= self.retry_at).then_some(Priority::Setup),
            Phase::Configure(_) => Some(Priority::Setup),
            Phase::Online if self.any_ready() => Some(Priority::Command),
            Phase::Online => {
                let polls = self.channels.iter().any(Option::is_some);
                (polls || now >= self.reset_check_at).then_some(Priority::Poll)
            }
        }
    }

    /// Picks the request to send now; the closure-free core of `poll_transmit`.
    fn pick(&mut self, now: Duration) -> Option<(Request, Option<Expect>, Option<usize>)> {
        let query = |command, motor, purpose| {
            Some(Expect {
                command,
                motor,
                purpose,
            })
        };
        match (self.next_message(now)?, self.phase) {
            (_, Phase::Identify) => Some((
                Request::UnitInfo {
                    reply_to: self.reply_address,
                },
                query(Command::UnitInfo, None, Purpose::Startup),
                None,
            )),
            (_, Phase::Configure(index)) => {
                let request = self.plan.get(index)?;
                Some((request, None, None))
            }
            (Priority::Command, _) => {
                for offset in 0..6 {
                    let index = (self.next_command + offset) % 6;
                    if let Some(Some(channel)) = self.channels.get(index)
                        && let Some(Step::Send(request)) = channel.current()
                    {
                        self.next_command = (index + 1) % 6;
                        return Some((request, None, Some(index)));
                    }
                }
                None
            }
            _ => {
                if now >= self.reset_check_at {
                    return Some((
                        Request::UnitInfo {
                            reply_to: self.reply_address,
                        },
                        query(Command::UnitInfo, None, Purpose::ResetCheck),
                        None,
                    ));
                }
                let urgent = self
                    .channels
                    .iter()
                    .flatten()
                    .find(|c| c.wants_rest_poll(now))
                    .map(|c| usize::from(c.motor));
                let index = urgent.or_else(|| {
                    (0..6)
                        .map(|offset| (self.next_poll + offset) % 6)
                        .find(|&i| matches!(self.channels.get(i), Some(Some(_))))
                })?;
                if urgent.is_none() {
                    self.next_poll = (index + 1) % 6;
                }
                let motor = index as u8;
                Some((
                    Request::QueryPosition {
                        motor,
                        reply_to: self.reply_address,
                    },
                    query(Command::QueryPosition, Some(motor), Purpose::Poll),
                    None,
                ))
            }
        }
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
    }

    /// The pack lost what it was told (reboot, silence, link): channels keep their last
    /// state but are faulted until fresh data, and their goals are void.
    fn restart(&mut self, fault: DeviceFault) {
        self.status.online = false;
        self.status.fault = Some(fault);
        for channel in self.channels.iter_mut().flatten() {
            channel.restart(fault);
        }
    }

    fn on_timeout(&mut self, now: Duration) {
        self.status.timeouts = self.status.timeouts.saturating_add(1);
        self.timeouts_in_row = self.timeouts_in_row.saturating_add(1);
        // Silence long enough for the pack to abort any partial word (6.1, $41).
        self.wire = Wire::Quiet {
            until: now + DEFAULT_PACKET_TIMEOUT + self.switchover,
        };
        if self.timeouts_in_row < MAX_TIMEOUTS {
            return;
        }
        self.timeouts_in_row = 0;
        self.restart(DeviceFault::NotResponding);
        // Whatever the pack has now (it may have rebooted to the factory delay).
        self.switchover = units(FACTORY_SWITCHOVER);
        self.phase = Phase::Identify;
        self.retry_at = now + RETRY_PERIOD;
    }

    fn on_reply(&mut self, now: Duration, expect: Expect, sent_at: Duration, reply: Reply) {
        self.status.replies = self.status.replies.saturating_add(1);
        self.timeouts_in_row = 0;
        match (reply, expect.purpose) {
            (
                Reply::UnitInfo {
                    firmware,
                    reset,
                    serial,
                    ..
                },
                purpose,
            ) => {
                self.set_firmware(firmware, serial);
                let rebooted = reset && self.ever_online;
                if rebooted {
                    self.status.resets = self.status.resets.saturating_add(1);
                    self.restart(DeviceFault::Reset);
                    self.switchover = units(FACTORY_SWITCHOVER);
                }
                match purpose {
                    Purpose::Startup => self.phase = Phase::Configure(0),
                    _ if rebooted => self.phase = Phase::Configure(0),
                    _ => self.reset_check_at = now + RESET_CHECK_PERIOD,
                }
            }
            (
                Reply::Position {
                    motor,
                    position,
                    action,
                    stopped,
                },
                Purpose::Poll,
            ) => {
                let seq = self.seq;
                let Some(Some(channel)) = self.channels.get_mut(usize::from(motor)) else {
                    return;
                };
                if channel.on_poll(now, seq, sent_at, position, action, stopped) {
                    let decel = channel.cfg.max_accel;
                    // A motor found moving after a (re)start: not ours to keep running.
                    let _ = channel.plan(Goal::Stop { decel });
                }
            }
            _ => {
                self.status.bad_replies = self.status.bad_replies.saturating_add(1);
            }
        }
    }

    fn set_firmware(&mut self, revision: u8, serial: u16) {
        let mut text = FixedText::default();
        let name = match self.variant {
            Variant::SixPack => "SIXpack",
            Variant::QuadPack => "QUADpack",
        };
        // "firmware-revision (e.g. 148=V1.4.8)"
        let _ = write!(
            text,
            "{name} V{}.{}.{} s/n {serial}",
            revision / 100,
            revision / 10 % 10,
            revision % 10
        );
        self.status.set_firmware(text.as_str());
    }
}

/// A stack buffer for the firmware text (no allocation).
#[derive(Default)]
struct FixedText {
    buf: [u8; FIRMWARE_LEN],
    len: usize,
}

impl FixedText {
    fn as_str(&self) -> &str {
        self.buf
            .get(..self.len)
            .and_then(|b| core::str::from_utf8(b).ok())
            .unwrap_or("")
    }
}

impl core::fmt::Write for FixedText {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        for &byte in s.as_bytes() {
            let slot = self.buf.get_mut(self.len).ok_or(core::fmt::Error)?;
            *slot = byte;
            self.len += 1;
        }
        Ok(())
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
            Phase::Down | Phase::Configure(_) => None,
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
        let (request, expect, channel) = self.pick(now)?;
        let len = RequestFrame::new(self.address, request).encode(buf).ok()?;
        self.seq += 1;
        let wire_end = now + self.word_time;
        match expect {
            Some(expect) => {
                self.hunter.reset();
                self.wire = Wire::Awaiting {
                    expect,
                    sent_at: now,
                    deadline: self.reply_deadline(now),
                };
            }
            None => self.wire = Wire::Sending { until: wire_end },
        }
        if let Request::SetBaud { switchover, .. } = request {
            self.switchover = units(switchover);
        }
        if let Phase::Configure(index) = self.phase {
            let next = index + 1;
            self.phase = if self.plan.get(next).is_some() {
                Phase::Configure(next)
            } else {
                Phase::Online
            };
            if self.phase == Phase::Online {
                self.go_online(now);
            }
        }
        if let Some(Some(channel)) = channel.and_then(|i| self.channels.get_mut(i)) {
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
        self.channels.iter().flatten().any(Channel::pending)
    }

    fn set_goal(&mut self, _now: Duration, channel: usize, goal: Goal) -> Result<(), GoalError> {
        if channel >= self.channel_count() {
            return Err(GoalError::NoSuchChannel(channel));
        }
        let Some(Some(slot)) = self.channels.get_mut(channel) else {
            return Err(GoalError::Unsupported(goal.kind()));
        };
        if self.phase != Phase::Online {
            return Err(GoalError::Offline);
        }
        slot.plan(goal)
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
        self.switchover = units(FACTORY_SWITCHOVER);
    }
}

/// The pack's I/O pins for `variant` (manual 8.5). Filled in with the board's I/O
/// support; empty until then.
pub fn pins(variant: ::tmcpack::Variant) -> &'static [crate::PinInfo] {
    let _ = variant;
    &[]
}
