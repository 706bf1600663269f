//! Driver for the Trinamic SIXpack / QUADpack on RS-232 / RS-485 ([`TmcpackDriver`]).
//!
//! Start-up: `$43` unit information (firmware revision and serial for
//! [`DeviceStatus::firmware`], the reset flag); `$28` to see whether a configured motor is
//! still running (left so by a previous server: it is stopped with `$14`/`$25` and polled
//! with `$21` until it stands, because `$12`, `$13` and `$16` may only change at
//! standstill); then the configuration — `$40` with the divisor of the rate the driver
//! talks at and the configured switch-over delay (without a `baud` that is the link's own
//! rate, never changed; with one the pack was switched to it first and the link followed:
//! module `rate`), `$41` packet timeout, `$12` clkdiv chosen for the fastest motor, `$10` peak
//! currents per motor pair, and per configured motor `$11`, `$13`, `$14`, `$15`, `$16`,
//! `$18`, `$31` from its axis limits and machine keys, then `$33` and `$32` when I/O is
//! configured. Motors found active afterwards are stopped: whatever they were doing was not
//! commanded by this run. The whole configuration goes out again whenever the pack is seen
//! to have reset (`$43` reset flag, or after it stopped answering).
//!
//! The wire (manual 6.1, 7.1 "Requests must not be interlaced. Each request should wait for
//! the response of the PACK before transmitting a new command."): one request in flight on
//! the whole bus, and the next one only once the answer arrived or can no longer arrive.
//! A query's window runs from its write stamp (when the link took its last byte: a serial
//! port's `write` returns before the UART has clocked the word out, so the request's own
//! wire time counts in the window): the request on the wire, the pack's processing
//! ([`PACK_PROCESSING`], 2 ms: the manual gives it for CAN only, read for the serial line
//! too), the switch-over delay the pack has (the one the driver programmed with `$40`; the
//! longer of the factory 6 ms and the configured one until it has), the answer on the
//! wire at the rate the driver talks at, and the host's latency (`host_latency_ms`, default
//! [`DEFAULT_HOST_LATENCY`]). The window is judged only up to the link's horizon
//! (`handle_heard`), so a starved I/O thread never makes the pack look silent. After an
//! answer the line stays reserved for the switch-over time, in which the pack still drives
//! it; after a missing answer it stays silent for the `$41` packet timeout (the longest of
//! every pack on the bus, and at least the switch-over), so that a word torn on the line is
//! aborted before the next one starts. A request without an answer reserves the line for
//! its own wire time and the packet timeout ($41: "The command word always has to be
//! completely transmitted during a parameterized timeout"). Bytes that come while nothing
//! is awaited (a late answer, noise) hold the line until their word can have ended and the
//! switch-over after it passed. Queries carry the response address of
//! [`TmcpackDriverConfig::reply_address`], which no pack on the bus may have.
//!
//! Late answers (module `late`): an answer that still comes after its window (the pack or
//! its host process was starved) is told by its response address, command and motor or
//! channel, counted ([`TmcpackDriver::late_replies`]) and dropped, never paired with the
//! next request; the driver asks nothing whose answer would look like one (another motor's
//! poll, or a `$21`/`$30` probe), and on a shared bus every driver learns the others' late
//! answers from the link bus (every pack answers to the same response address).
//!
//! Command → wire: a goal's first request goes out in the tick that set it when the line is
//! free; otherwise it waits for the one exchange in flight — at most a query, the
//! switch-over, the answer and the switch-over again (15.4 ms with the processing at 19200 baud with `$40` =
//! 2 ms) — and the tick that takes the answer in. The manual allows nothing shorter ("Each
//! request should wait for the response of the PACK", 7.1); the engine test
//! `tests/engine_tmcpack/wire.rs` checks the bound.
//!
//! Polling plan: stops first ([`Priority::Stop`]: on a shared bus before every other pack's
//! message too), then output changes and other goals ([`Priority::Command`]), with the
//! back-to-back `$20` polls of a motor whose stop should have ended (see the `channel`
//! module) and the polls of motors whose data is older than half the refresh budget at the
//! same priority (the two take turns); then `$20` position/action polls round-robin over the configured motors
//! with one `$30` input poll per round when inputs are configured ([`Priority::Poll`]),
//! and a `$43` every [`RESET_CHECK_PERIOD`] to notice a pack that rebooted (reset flag).
//!
//! Verdicts, each declared with its evidence ([`DeviceStatus::declare`], module `rx`): not
//! answering ([`DeviceFault::NotResponding`]) only when at least [`MAX_TIMEOUTS`] requests
//! went unanswered in a row *and* the first of them was written `silence_ms` (default
//! [`motion_drivers::DEFAULT_SILENCE`], 500 ms: every board's) or more before; the pack is then asked for `$43` every
//! [`RETRY_PERIOD`] and configured again when it answers. A pack silent for less — its
//! answers held 50, 100, 200 ms by a starved host — keeps its configuration and its goals
//! (stops still go out meanwhile: they need no answer; the engine marks the axes stale after
//! the refresh budget). Reset ([`DeviceFault::Reset`]) only on a `$43` answer with the reset
//! flag set (manual 8.6: "during first read out 1, afterwards 0") from a pack that had been
//! online.
//!
//! Commissioning (`$42` address, `$40` rate, `$CC` factory reset) is the `commission`
//! module's.
//!
//! Goals are mapped as described in the `channel` module: Stop with `$25` velocity 0, then
//! `$23`; Position/RampPosition with `$14`, `$26`, `$23`; Velocity with `$25`; Home with
//! `$16`, `$22`; SetPosition with `$27`; Off with a stop, then `$11` at 0 %. Power is
//! unsupported (a stepper has no open-loop power). I/O is described in the `io` module.
//!
//! On a CAN link (`socketcan`, `sim-can`; manual 6.2) the same driver frames its requests
//! and answers as CAN telegrams and times them by the pack's command cache instead of the
//! serial line: the `can` module.
//! With `position_mode = "pi"` a Position goal is a `$24` PI target (the `channel` module);
//! the power-down mode (`$45`) is in the `power_down` module.

mod can;
mod channel;
mod commission;
mod config;
mod goals;
mod hunter;
mod io;
mod late;
mod line;
mod power_down;
mod rate;
mod restore;
mod rx;
mod script;
mod spec;
mod spec_drive;
mod spec_timing;
mod startup;
mod wire;

#[cfg(test)]
mod bench;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_baud;
#[cfg(test)]
mod tests_drive;
#[cfg(test)]
mod tests_goals;
#[cfg(test)]
mod tests_io;
#[cfg(test)]
mod tests_line;
#[cfg(test)]
mod tests_power_down;
#[cfg(test)]
mod tests_readings;
#[cfg(test)]
mod tests_restore;

use core::time::Duration;

use tmcpack::convert::{DEFAULT_SWITCHOVER_UNITS as FACTORY_SWITCHOVER, byte_time, units};
use tmcpack::{DEFAULT_PACKET_TIMEOUT, FRAME_LEN, Variant};

use motion_drivers::{
    ChannelState, Commission, CommissionError, DeviceFault, DeviceStatus, Driver, Goal, GoalError,
    GoalKinds, IoStamps, LateAnswer, Model, Pin, PinReading, Priority, RateFloor, Transmit,
};

use channel::Channel;
use commission::Service;
use config::{Scale, clkdiv_for};
use goals::CAPABILITIES;
use hunter::ReplyHunter;
use io::IoState;
use late::LateSet;
use line::PackLine;
use power_down::PowerDown;
use rate::LineRate;
use script::Step;
use startup::{Quiesce, StartupPlan};
use wire::Wire;

pub use commission::RESET_WAIT;
pub use config::{
    Currents, DEFAULT_HOST_LATENCY, DEFAULT_REPLY_ADDRESS, DEFAULT_SWITCHOVER_UNITS,
    PACKET_TIMEOUT_SLACK_BYTES, PiParams, TmcpackChannel, TmcpackDriverConfig,
    default_packet_timeout_units,
};
pub use io::{MAX_PINS, PinSet, ReadyOutput, TmcpackIo, pins};
pub use power_down::POWER_CHECK_PERIOD;
pub use spec::{MAX_DEBOUNCE_MS, MAX_POSLIMIT, is_current_level, is_weak_current, word_time};

/// The longest the pack takes from a request's last byte to the start of its switch-over
/// delay. The manual gives it for CAN only (6.2, "internal processing time is approx. 2 ms
/// per command"); the firmware works in 2 ms cycles on RS-232 / RS-485 too (the ramps'
/// "accumulated with 500Hz", "The controller works at 500Hz", the ready output "switched
/// within 2 ms"), so a word is read as taken in within one cycle (docs/ARCHITECTURE.md,
/// "How the datasheets are read"). Part of every reply window.
pub const PACK_PROCESSING: Duration = Duration::from_millis(2);
/// Requests unanswered in a row (spanning at least `silence_ms`) after which the pack
/// is declared not answering.
pub const MAX_TIMEOUTS: u32 = 3;
/// How often an offline pack is asked again.
pub const RETRY_PERIOD: Duration = Duration::from_millis(250);
/// How often an online pack's reset flag is read ($43).
pub const RESET_CHECK_PERIOD: Duration = Duration::from_secs(1);

/// Where the driver is with its pack.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
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
    /// The `$45` power-down steps after the configuration (the `power_down` module).
    PowerDown,
    /// Polling and driving.
    Online,
}

/// The sans-I/O driver of one SIXpack / QUADpack.
#[derive(serde::Serialize, serde::Deserialize, Debug)]
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
    /// A `$50` line waiting for its legs' scripts.
    line: Option<PackLine>,
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
    /// The last message was the poll of a motor awaiting rest: an overdue poll of another
    /// motor may go next (the two alternate).
    rest_polled: bool,
    budget: Duration,
    stamps: IoStamps,
    /// On a CAN link: its framing and the pack's command cache (`None` on a serial line).
    can: Option<can::CanLine>,
    /// The `$45` power-down mode.
    power: PowerDown,
    /// A `$24` went out since the last query: the next `$24` waits for one (the PI
    /// controller's targets take turns with the polls).
    pi_since_poll: bool,
    /// The line rate: the link's, the `baud` the pack is switched to, the probing.
    rate: LineRate,
    /// A change of the pack's own settings waiting for the line (module `commission`).
    service: Option<Service>,
    /// The address the config gives (what the rotary switches are taken to say).
    home_address: u8,
    /// The configured `$40` switch-over delay, 2 ms units.
    switchover_units: Option<u16>,
    /// The `$41` packet timeout the start-up programs.
    configured_timeout: Duration,
    /// Key `host_latency_ms`: part of every reply window.
    host_latency: Duration,
    /// Key `silence_ms`: the silence before a verdict, and how long an unanswered
    /// query's answer is taken for late.
    not_answering: Duration,
    /// Answers that may still come late (module `late`).
    late: LateSet,
    /// Words recognised as late answers and dropped.
    late_replies: u32,
    /// When the first request of the current run of unanswered ones was written.
    silent_since: Duration,
    /// The last request that went unanswered.
    unanswered: Option<rx::Unanswered>,
    /// When the last answer was paired.
    last_answer_at: Option<Duration>,
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
                *slot = Some(Channel::new(
                    motor as u8,
                    cfg,
                    Scale::new(clkdiv, &cfg, config.amax_divisor),
                ));
            }
        }
        let io = IoState::new(config.variant, config.io);
        let plan = StartupPlan::new(&config, clkdiv, &channels, &io);
        let can = config.can_bitrate.map(can::CanLine::new);
        let byte = byte_time(config.baud);
        let word_time = can
            .as_ref()
            .map_or(byte.saturating_mul(FRAME_LEN as u32), |c| c.frame_time);
        let configured = match &can {
            // No switch-over on CAN; the cache's processing stands in the query below.
            Some(_) => Duration::ZERO,
            None => config
                .switchover_units
                .map_or(units(FACTORY_SWITCHOVER), units),
        };
        let polled = channels.iter().flatten().count() + usize::from(io.polls());
        let round = usize::from(config.bus_motors).max(polled).max(1) as u32;
        // Polled at the slower of the link's rate and the one the pack is switched to.
        let slowest = config
            .target_baud
            .map_or(config.baud, |t| t.min(config.baud));
        let slow_word = byte_time(slowest).saturating_mul(FRAME_LEN as u32);
        let query = 2 * slow_word + 2 * configured + Duration::from_millis(2);
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
        let mut driver = Self {
            address: config.address,
            reply_address,
            variant: config.variant,
            word_time,
            switchover: units(FACTORY_SWITCHOVER),
            pack_timeout: DEFAULT_PACKET_TIMEOUT,
            bus_timeout: units(config.bus_packet_timeout_units),
            channels,
            line: None,
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
            rest_polled: false,
            budget,
            stamps: IoStamps::default(),
            can,
            power: PowerDown::new(config.power_down),
            pi_since_poll: false,
            rate: LineRate::new(config.baud, config.target_baud),
            service: None,
            home_address: config.address,
            switchover_units: config.switchover_units,
            configured_timeout: units(config.packet_timeout()),
            host_latency: config.host_latency,
            not_answering: config.not_answering,
            late: LateSet::new(),
            late_replies: 0,
            silent_since: Duration::ZERO,
            unanswered: None,
            last_answer_at: None,
        };
        driver.assume_unknown_line();
        driver
    }

    /// Words recognised as late answers (to a query that had timed out, this pack's or,
    /// on a shared bus, another's) and dropped, never paired (module `late`).
    pub fn late_replies(&self) -> u32 {
        self.late_replies
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
}

impl Driver for TmcpackDriver {
    fn model(&self) -> Model {
        Model::TMCPACK
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

    /// One velocity unit and one amax unit of the motor's step clock.
    fn rate_floor(&self, channel: usize) -> RateFloor {
        match self.channels.get(channel) {
            Some(Some(c)) if channel < self.channel_count() => c.scale.floor(),
            _ => RateFloor::NONE,
        }
    }

    fn refresh_budget(&self) -> Duration {
        self.budget
    }

    /// A motor in the PI position mode follows a group's path with a `Position` goal per
    /// change (`$24` reprograms the PI controller's target on the fly); the others with
    /// `RampPosition` segments (`$26` moves a running ramp's target).
    fn follow(&self, channel: usize) -> motion_drivers::Follow {
        match self.channels.get(channel) {
            Some(Some(c)) if c.cfg.position_mode == crate::PositionMode::Pi => {
                motion_drivers::Follow::Setpoints
            }
            _ => motion_drivers::Follow::Segments,
        }
    }

    fn handle_rx(&mut self, now: Duration, bytes: &[u8]) {
        self.receive(now, bytes);
    }

    fn handle_timeout(&mut self, now: Duration) {
        self.prune_can(now);
        self.late.expire(now);
        match self.wire {
            Wire::Sending { until, .. } | Wire::Quiet { until } if now >= until => {
                self.wire = Wire::Idle;
            }
            // Unanswered only if the link was looked at after the deadline.
            Wire::Awaiting { deadline, .. } if self.stamps.judged(now) >= deadline => {
                self.on_timeout(now);
            }
            _ => {}
        }
        self.judge_silence(now);
    }

    fn handle_written(&mut self, at: Duration) {
        self.on_written(at);
    }

    fn handle_heard(&mut self, until: Duration) {
        self.stamps.heard(until);
    }

    fn late_answers(&self) -> &[LateAnswer] {
        self.late.own()
    }

    fn handle_late_answers(&mut self, others: &[LateAnswer]) {
        self.late.set_others(others);
    }

    fn poll_timeout(&self) -> Option<Duration> {
        let phase = match self.phase {
            Phase::Identify => Some(self.retry_at),
            Phase::Online => Some(
                self.power_check_at()
                    .map_or(self.reset_check_at, |at| at.min(self.reset_check_at)),
            ),
            Phase::Quiesce => self.quiesce.as_ref().map(|q| q.deadline),
            Phase::Down | Phase::Survey | Phase::Configure(_) | Phase::PowerDown => None,
        };
        let rest = self
            .channels
            .iter()
            .flatten()
            .filter(|c| c.current() == Some(Step::AwaitRest))
            .filter_map(|c| c.rest_poll_at.or(c.rest_at))
            .min();
        [
            self.wire.deadline(),
            phase,
            rest,
            self.can_held_until(),
            self.late.next_expiry(),
        ]
        .into_iter()
        .flatten()
        .min()
    }

    fn wants_transmit(&self, now: Duration) -> Option<Priority> {
        self.next_message(now)
    }

    fn poll_transmit(&mut self, now: Duration, buf: &mut [u8]) -> Option<Transmit> {
        self.transmit(now, buf)
    }

    fn awaiting_reply(&self) -> bool {
        self.wire != Wire::Idle
    }

    fn goals_pending(&self) -> bool {
        self.io.outputs_pending
            || self.line.is_some()
            || self.channels.iter().flatten().any(Channel::pending)
    }

    fn lead_line(
        &mut self,
        _now: Duration,
        legs: &[motion_drivers::LineLeg],
    ) -> Result<bool, GoalError> {
        self.prepare_line(legs)
    }

    fn line_ready(&self) -> bool {
        self.line_prepared()
    }

    fn start_line(&mut self, _now: Duration) {
        if let Some(line) = self.line.as_mut() {
            line.started = true;
        }
    }

    fn line_starting(&self) -> bool {
        self.line.is_some_and(|line| line.started)
    }

    fn set_goal(&mut self, _now: Duration, channel: usize, goal: Goal) -> Result<(), GoalError> {
        self.plan_goal(channel, goal)
    }

    fn channel(&self, channel: usize) -> ChannelState {
        match self.channels.get(channel) {
            Some(Some(c)) if channel < self.channel_count() => c.state,
            _ => ChannelState::UNKNOWN,
        }
    }

    fn keeps_references(&self) -> bool {
        self.power.mode == crate::PowerDownMode::Restore
    }

    fn restore_references(&mut self, saved: &[motion_drivers::SavedReference]) {
        self.take_saved_references(saved);
    }

    fn status(&self) -> DeviceStatus {
        self.status
    }

    fn link_down(&mut self, _now: Duration) {
        self.stamps.link_reset();
        self.late.clear();
        if let Some(can) = self.can.as_mut() {
            can.reset();
        }
        self.service = None;
        self.phase = Phase::Down;
        self.wire = Wire::Idle;
        self.timeouts_in_row = 0;
        self.restart(DeviceFault::LinkDown);
    }

    fn link_up(&mut self, now: Duration) {
        self.stamps.link_reset();
        self.late.clear();
        if let Some(can) = self.can.as_mut() {
            can.reset();
        }
        self.phase = Phase::Identify;
        self.wire = Wire::Idle;
        self.retry_at = now;
        self.timeouts_in_row = 0;
        self.assume_unknown_line();
        self.service = None;
        self.rate.link_up();
        self.retime();
    }

    fn read_pin(&self, pin: Pin) -> Option<PinReading> {
        self.io.read(pin)
    }

    fn set_output(&mut self, _now: Duration, pin: Pin, high: bool) -> Result<(), GoalError> {
        self.drive_output(pin, high)
    }

    /// The rate the pack listens at as far as the driver knows: module `rate`.
    fn line_rate(&self) -> Option<u32> {
        self.rate.wanted()
    }

    /// `$42`, `$40`, `$CC`: module `commission`.
    fn commission(&mut self, _now: Duration, change: Commission) -> Result<(), CommissionError> {
        self.start_commission(change)
    }
}
