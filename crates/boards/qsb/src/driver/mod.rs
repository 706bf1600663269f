//! The US Digital QSB-S/-D/-M driver: [`QsbDriver`].
//!
//! One channel (0): the encoder counter, and on the -M the stepper drive that moves it.
//! Every byte goes through the `qsb` protocol crate.
//!
//! ```
//! use core::time::Duration;
//! use motion_drivers::Driver;
//! use board_qsb::driver::{QsbDriver, QsbDriverConfig};
//!
//! let mut driver = QsbDriver::new(QsbDriverConfig::default()); // a QSB-M at 230400 baud
//! let mut buf = [0u8; 256];
//! let now = Duration::ZERO;
//! let sent = driver.poll_transmit(now, &mut buf).expect("start-up");
//! assert_eq!(&buf[..sent.len], b"W161\r\n"); // COMMAND 1: quiet any old streams
//! driver.handle_rx(Duration::from_micros(700), b"w 16 00000001 !\r\n");
//! let sent = driver.poll_transmit(Duration::from_micros(700), &mut buf).expect("version");
//! assert_eq!(&buf[..sent.len], b"R14\r\n");
//! driver.handle_rx(Duration::from_millis(1), b"r 14 00001113 !\r\n");
//! assert_eq!(driver.product(), Some(qsb::ProductType::M));
//! assert_eq!(driver.status().firmware(), "QSB-M SN 00001 fw 13");
//! ```
//!
//! # Start-up
//!
//! `W161` (COMMAND 1: stop any streams left running, so the line is quiet), `R14`
//! (VERSION: serial number, product type, firmware), then the configuration for the
//! product reported, each register written unless known to hold its value:
//!
//! 1. -M: MD ACCEL from the axis's acceleration, then COMMAND 4 (a motor left running by
//!    a previous server stops, at that acceleration);
//! 2. EOR 0x5 (LF and the time stamp: `s0E00001234000ABCDE!\n`), MODE (`input_mode`:
//!    quadrature, PWM or analog), DTR = `count_limit` in range-limit and modulo-n
//!    modes, MDR0 ([`CounterSetup`]; by default 0x43: x4, free-running, index disabled,
//!    synchronous index), MDR1 (counting up, no triggers; B3 = `invert_index`),
//!    THRESHOLD 0 (a value at every tick), INTERVAL RATE (`stream_interval`, or from the
//!    line rate: 1 tick = 1.95 ms at 230400 baud);
//! 3. driving -M: MD STEP RATE from the axis's velocity;
//! 4. when DIG I/O is used (enable line, signals, capture): `R02`, DIG I/O CONFIG if the
//!    board does not hold it already (directions, capture interrupt), DIG I/O (the
//!    outputs' levels, the enable line active);
//! 5. driving -M: COMMAND 2 (motor drive mode) and `S13` (stream MD STATUS);
//! 6. `S01` (digital signals, not in analog mode), `S05` (capture), last `S0E` (stream the
//!    counter / the PWM or analog value).
//!
//! The board is online when all of that was acknowledged; goals and outputs before that
//! are refused with [`GoalError::Starting`]. Nothing is saved (COMMAND 3 is never sent).
//! After a reset the whole sequence runs again, outputs at their last levels.
//!
//! # Goals
//!
//! A "driving -M" is a -M with [`QsbDriverConfig::motor_drive`] counting quadrature.
//!
//! | goal | driving -M | -S / -D / -M without drive |
//! |---|---|---|
//! | `Off` | COMMAND 5 (quit: no more step pulses), then the enable line inactive. `Unsupported` without [`QsbDriverConfig::enable`]: the QSB itself cannot de-energise the motor (set `enable_output` to the drive's enable line) | `Unsupported`: nothing to de-energise |
//! | `Stop{decel}` | MD ACCEL = decel (rounded *up* to 16, written when it differs), COMMAND 4 — always sent, even if the motor is believed idle —, then the enable line active (a stop holds) | accepted, nothing to do |
//! | `Position`, `RampPosition` | enable line active, MD STEP RATE / MD ACCEL (axis limits, or the goal's), COMMAND 4 and wait if moving, then MD MOVE STEPS = the whole steps from the encoder reading to the target, COMMAND 8; after the drive reports done, up to two correcting moves | `Unsupported` |
//! | `Velocity` | enable line active, MD ACCEL, MD JOG RATE, COMMAND 9 (0 = COMMAND 4) | `Unsupported` |
//! | `Home{velocity}` | enable line active; MDR0 0x63 (index resets CNTR) for a home position of 0, else DTR = the home position and MDR0 0x53 (index loads CNTR from DTR); clear STR, stream STR, jog in the configured direction; the first index latch (STR IDX) is the reference: MDR0 back to 0x43, COMMAND 4 (in another `count_mode` its B1 B0 and B6 stay in all three). A search that travels `home_max_travel` (or runs twice the time that takes) without an index stops and reports [`DeviceFault::HomeFailed`] until its stop is complete | `Unsupported` (no drive to search with) |
//! | `SetPosition` | DTR = counts, LOAD REG 0 (DTR → CNTR); then COMMAND 4 if the motor moves (the engine holds after a set-position) | DTR, LOAD REG 0; in range-limit and modulo-n only 0..=`count_limit`, and DTR = `count_limit` again after the load |
//! | `Power` | `Unsupported` (step and direction only) | `Unsupported` |
//!
//! In PWM and analog input modes the channel takes no goal: it is not an axis.
//!
//! Counts are encoder counts; the -M's registers are in motor steps
//! ([`QsbDriverConfig::counts_per_step`], negative when the encoder counts down as the
//! motor steps forward). Rates and accelerations of motions are rounded down to the
//! board's 16-step increments, so a profile never exceeds the limits it was given; a limit
//! below the board's minimum is `OutOfBoardRange`. A stop rounds up and never refuses, so
//! it ends within |v| / decel once its two lines are on the wire.
//!
//! # I/O pins
//!
//! [`pins`]: `io0`..`io3` (-M), `io0` (-D): digital in or open-drain out (DIG I/O, set
//! with [`Driver::set_output`], read back as the level measured at the pin from the `S01`
//! stream, sent on change); `encoder` (-S, -M): the PWM or analog value of READ ENCODER;
//! `capture` (-M, -D, -S): CAPTURE, the count an edge of [`QsbIo::capture`]'s input (or
//! an index, [`TriggerSetup::index`]) loaded, each capture one event; `trigger` (-M, -D):
//! DIG I/O bit 0 pulsed by the counter's events ([`TriggerSetup`]), its value the compare
//! position, each pulse one event (module `trigger`).
//! While the -M drives its motor, io1 and io2 are its step and direction lines and are no
//! signals; the enable line's bit is no signal either.
//!
//! # Wire, liveness and resets
//!
//! One request in flight; its answer is matched by type and register (and data, for a
//! write) among the streamed lines. The board takes one command at a time ("At the
//! conclusion of the command response, the QSB is ready to accept another command", QSB
//! command list, Command Acknowledgement Format), so a new goal's first request waits for
//! the answer in flight and its EOR (one reply line, behind at most the streamed line
//! being sent): command → wire is at most 1 tick + that line + the USB frame + the tick
//! that takes it in. While a write awaits its answer the driver does not count on the
//! register's value, and while a motor command does, on the drive being done: a step of a
//! new plan is never skipped on what an unanswered request may still change. Position is
//! the streamed counter, velocity the count difference over the last 8 samples
//! (`VELOCITY_WINDOW`) divided by their time-stamp difference.
//!
//! An answer past its deadline is waited for while the link is silent (a host or a board's
//! process without CPU delivers everything later, in order) and declared lost once the
//! board is heard streaming past it for a reply window, or once a line where it was due
//! could not be decoded (module `liveness`): a lost request counts in `timeouts` and is
//! sent again — except COMMAND 8 (a move must never run twice): the driver measures
//! instead and corrects. A late answer is recognised (it answers the request declared
//! lost, or its time stamp is older than the lines seen before the request in flight) and
//! never paired ([`QsbDriver::late_answers`]).
//!
//! Verdicts, each declared with its evidence (`DeviceStatus::verdict`):
//! - [`DeviceFault::NotResponding`]: the board owes an answer and said nothing for
//!   [`QsbDriverConfig::silence`] (`silence_ms`, 500 ms by default), or [`MAX_ATTEMPTS`]
//!   answers in a row were lost; the driver retries its start-up every [`RESTART_DELAY`].
//! - [`DeviceFault::Reset`], the start-up runs again: two read or stream lines in a row
//!   without the time stamp EOR 5 asks for (the board is back at its saved EOR), a time
//!   stamp that went backwards over two lines ("cleared on a power-cycle"), a -M drive
//!   found disabled on two MD STATUS lines, the liveness probe's TIME STAMP below the
//!   newest stamp seen before it was sent, or VERSION naming another serial number twice.
//!
//! A stream gone quiet is not a reset: after a refresh budget without a sample the driver
//! probes `R0D`; an answer whose TIME STAMP went on says the board did not restart, and a
//! stream still quiet over two such probes is asked for again (nothing else: the board
//! holds its configuration). Garbage is skipped by the response decoder.
#![allow(clippy::module_name_repetitions)]

mod config;
mod counter;
mod encoder;
mod goals;
mod guard;
mod io;
mod liveness;
mod program;
mod rx;
mod spec;
mod startup;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_counter;
#[cfg(test)]
mod tests_in_flight;
#[cfg(test)]
mod tests_late;
#[cfg(test)]
mod tests_line;
#[cfg(test)]
mod tests_liveness;
#[cfg(test)]
mod tests_machine;
#[cfg(test)]
mod tests_noise;
#[cfg(test)]
mod tests_trigger;
mod trigger;
mod wire;

use core::time::Duration;

use ::qsb::{MdStatus, ProductType, ResponseDecoder};

pub use config::QsbDriverConfig;
pub use counter::CounterSetup;
pub use io::{CaptureInput, EnableOutput, MOTOR_DRIVE_BITS, PinRole, QsbIo, pins};
pub use spec::{LONGEST_INTERVAL_TICKS, TICK, interval_ticks};
pub use trigger::TriggerSetup;

use encoder::EncoderTrack;
use guard::StampGuard;
use io::IoState;
use motion_drivers::{
    ChannelState, DeviceFault, DeviceStatus, Driver, Goal, GoalError, GoalKind, GoalKinds,
    IoStamps, Model, Pin, PinReading, Priority, RateFloor, Transmit,
};
use program::Program;
use trigger::EventState;
use wire::{InFlight, Origin};

/// Tries of one request before the board is declared not responding.
pub const MAX_ATTEMPTS: u8 = 3;

/// Pause before a start-up is tried again after the board stopped answering.
pub const RESTART_DELAY: Duration = Duration::from_millis(100);

/// Registers the driver remembers the board's value of (00–16).
const REGISTERS: usize = 0x17;

/// A sans-I/O driver for one US Digital QSB (see the module docs).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub struct QsbDriver {
    config: QsbDriverConfig,
    decoder: ResponseDecoder,
    decoder_bad_seen: u64,
    status: DeviceStatus,
    link_up: bool,
    /// Product and serial number VERSION reported.
    product: Option<ProductType>,
    serial: Option<u32>,
    setup: Program,
    /// Set-position requests: kept apart so that a stop right after a set-position
    /// cannot void it.
    preset: Program,
    goal: Program,
    goal_kind: Option<GoalKind>,
    in_flight: Option<InFlight>,
    attempts: u8,
    restart_at: Option<Duration>,
    probe_due: bool,
    samples_since_probe: bool,
    /// What the board holds, per register number, as far as the driver knows.
    board: [Option<u32>; REGISTERS],
    eor_configured: bool,
    /// The board's timeline, guarded against corrupted stamps.
    stamps: StampGuard,
    /// The last MD STATUS line said the drive is disabled (a reset, if the next agrees).
    md_disabled_once: bool,
    /// A VERSION answer that named another board or no product: asked again before it
    /// counts.
    version_doubt: Option<u32>,
    encoder: EncoderTrack,
    /// The next encoder sample follows a load or an index reset of the counter.
    rebase_pending: bool,
    position: i32,
    last_sample_at: Option<Duration>,
    online_at: Duration,
    md: Option<MdStatus>,
    /// The drive's done flag counts only from samples with this time stamp on (two data
    /// output ticks after the last motor command).
    done_after: u32,
    str_streaming: bool,
    index_armed: bool,
    index_seen: bool,
    home_start: Option<i32>,
    /// A search that has not found the index by then has failed (the encoder may not
    /// count at all).
    home_deadline: Option<Duration>,
    /// The last home search ended without an index; cleared once its stop is complete
    /// or by the next goal other than `Stop`.
    home_failed: bool,
    homed: bool,
    arrived: bool,
    io: IoState,
    /// Captures, trigger pulses and the compare position.
    events: EventState,
    /// The link's write reports and horizon.
    io_stamps: IoStamps,
    /// No request of the goal set last has been sent yet.
    goal_unsent: bool,
    /// When the last line (of any kind) arrived: the board talks (module `liveness`).
    heard_at: Option<Duration>,
    /// The request whose answer was declared lost last: a line answering it is late.
    late: Option<::qsb::Request>,
    /// Late lines recognised (module `liveness`).
    late_answers: u64,
    /// Probes answered in a row with the stream quiet between them.
    quiet_probes: u8,
    /// An answer was decoded at its `!` and its EOR has not arrived yet: no command
    /// before it has (or before this instant).
    eor_until: Option<Duration>,
}

impl QsbDriver {
    /// A driver for the board of `config`; its start-up begins with the first
    /// [`poll_transmit`](Driver::poll_transmit).
    pub fn new(mut config: QsbDriverConfig) -> Self {
        io::sanitise(&mut config);
        let wrap = config.counter.wrap();
        let events = EventState {
            compare: config.trigger.compare,
            ..EventState::default()
        };
        let mut driver = Self {
            config,
            decoder: ResponseDecoder::new(),
            decoder_bad_seen: 0,
            status: DeviceStatus::UNKNOWN,
            link_up: true,
            product: None,
            serial: None,
            setup: Program::new(),
            preset: Program::new(),
            goal: Program::new(),
            goal_kind: None,
            in_flight: None,
            attempts: 0,
            restart_at: None,
            probe_due: false,
            samples_since_probe: false,
            board: [None; REGISTERS],
            eor_configured: false,
            stamps: StampGuard::default(),
            md_disabled_once: false,
            version_doubt: None,
            encoder: EncoderTrack::with_wrap(wrap),
            rebase_pending: false,
            position: 0,
            last_sample_at: None,
            online_at: Duration::ZERO,
            md: None,
            done_after: 0,
            str_streaming: false,
            index_armed: false,
            index_seen: false,
            home_start: None,
            home_deadline: None,
            home_failed: false,
            homed: false,
            arrived: false,
            io: IoState::new(),
            events,
            io_stamps: IoStamps::default(),
            goal_unsent: false,
            heard_at: None,
            late: None,
            late_answers: 0,
            quiet_probes: 0,
            eor_until: None,
        };
        driver.begin_startup();
        driver
    }

    /// The configuration.
    pub fn config(&self) -> &QsbDriverConfig {
        &self.config
    }

    /// The product VERSION reported (`None` before the first answer).
    pub fn product(&self) -> Option<ProductType> {
        self.product
    }

    /// The product whose goals apply: the reported one, else the configured one.
    fn effective_product(&self) -> ProductType {
        self.product.unwrap_or(self.config.variant)
    }

    /// Whether the drive runs a motor command (MD STATUS moving or jogging).
    fn drive_moving(&self) -> bool {
        self.md.is_some_and(|md| md.moving || md.jogging)
    }

    /// Whether the drive reports done, from samples taken after the last motor command
    /// (never while a motor command awaits its answer).
    fn drive_done(&self) -> bool {
        if self.motor_command_in_flight() {
            return false;
        }
        let fresh = self
            .encoder
            .latest()
            .is_some_and(|s| s.time_stamp.wrapping_sub(self.done_after) < u32::MAX / 2);
        fresh
            && self
                .md
                .is_some_and(|md| md.done && !md.moving && !md.jogging)
    }
}

impl Driver for QsbDriver {
    fn model(&self) -> Model {
        Model::QSB
    }

    fn channel_count(&self) -> usize {
        1
    }

    fn capabilities(&self, channel: usize) -> GoalKinds {
        if channel == 0 {
            self.kinds()
        } else {
            GoalKinds::NONE
        }
    }

    /// A position move starts with COMMAND 4 and waits for the drive to stop, so position segments would stop at every segment; a jog rate changes on the fly.
    fn follow(&self, channel: usize) -> motion_drivers::Follow {
        let _ = channel;
        motion_drivers::Follow::Velocity
    }

    fn rate_floor(&self, channel: usize) -> RateFloor {
        if channel == 0 && self.kinds().contains(GoalKind::Velocity) {
            self.config.rate_floor()
        } else {
            RateFloor::NONE
        }
    }

    fn refresh_budget(&self) -> Duration {
        self.config.refresh_budget()
    }

    fn handle_rx(&mut self, now: Duration, bytes: &[u8]) {
        self.receive(now, bytes);
    }

    fn handle_timeout(&mut self, now: Duration) {
        self.pass_time(now);
    }

    fn handle_written(&mut self, at: Duration) {
        self.on_written(at);
    }

    fn handle_heard(&mut self, until: Duration) {
        self.io_stamps.heard(until);
    }

    fn poll_timeout(&self) -> Option<Duration> {
        if !self.link_up {
            return None;
        }
        let probe =
            (self.status.online && !self.probe_due && self.in_flight.is_none()).then(|| {
                self.last_sample_at
                    .map_or(self.online_at, |at| at.max(self.online_at))
                    .saturating_add(self.config.refresh_budget())
            });
        [
            self.in_flight_look_by(),
            self.restart_at,
            probe,
            self.eor_until,
        ]
        .into_iter()
        .flatten()
        .min()
    }

    fn wants_transmit(&self, _now: Duration) -> Option<Priority> {
        self.next_request().map(|(_, _, priority)| priority)
    }

    fn poll_transmit(&mut self, now: Duration, buf: &mut [u8]) -> Option<Transmit> {
        self.transmit(now, buf)
    }

    fn awaiting_reply(&self) -> bool {
        self.in_flight.is_some()
    }

    fn goals_pending(&self) -> bool {
        let in_flight = self
            .in_flight
            .is_some_and(|f| matches!(f.origin, Origin::Preset | Origin::Goal | Origin::Io));
        let outputs = self.status.online && self.outputs_due().is_some();
        in_flight || outputs || !self.preset.is_empty() || !self.goal.is_empty()
    }

    fn lead_line(
        &mut self,
        _now: Duration,
        legs: &[motion_drivers::LineLeg],
    ) -> Result<bool, GoalError> {
        self.prepare_line(legs)
    }

    fn line_ready(&self) -> bool {
        self.line_armed()
    }

    fn start_line(&mut self, _now: Duration) {
        self.fire_line();
    }

    fn line_starting(&self) -> bool {
        self.line_firing()
    }

    fn pause_line(&mut self, _now: Duration, channel: usize) -> Result<bool, GoalError> {
        self.pause_move(channel)
    }

    fn resume_line(&mut self, _now: Duration, channel: usize) -> Result<bool, GoalError> {
        self.resume_move(channel)
    }

    fn set_goal(&mut self, now: Duration, channel: usize, goal: Goal) -> Result<(), GoalError> {
        let result = self.plan_goal(now, channel, goal);
        if result.is_ok() {
            self.goal_unsent = true;
        }
        self.settle(now);
        result
    }

    fn channel(&self, channel: usize) -> ChannelState {
        if channel == 0 {
            self.channel_state()
        } else {
            ChannelState::UNKNOWN
        }
    }

    fn status(&self) -> DeviceStatus {
        self.status
    }

    fn link_down(&mut self, _now: Duration) {
        self.io_stamps.link_reset();
        self.begin_startup();
        self.setup.clear();
        self.link_up = false;
        self.decoder.clear();
        self.status.fault = Some(DeviceFault::LinkDown);
    }

    fn link_up(&mut self, _now: Duration) {
        self.io_stamps.link_reset();
        self.link_up = true;
        self.decoder.clear();
        self.begin_startup();
    }

    fn read_pin(&self, pin: Pin) -> Option<PinReading> {
        self.pin_reading(pin)
    }

    fn set_output(&mut self, now: Duration, pin: Pin, high: bool) -> Result<(), GoalError> {
        let result = self.drive_output(pin, high);
        self.settle(now);
        result
    }

    /// The `trigger` pin's compare position (counts), with `trigger_on` "match" in
    /// free-running or single-cycle counting.
    fn set_pin_value(&mut self, now: Duration, pin: Pin, value: f64) -> Result<(), GoalError> {
        if PinRole::of(self.config.variant, pin) != Some(PinRole::Trigger) {
            return Err(GoalError::NoSuchPin(pin));
        }
        let result = self.set_compare(pin, value);
        self.settle(now);
        result
    }
}
