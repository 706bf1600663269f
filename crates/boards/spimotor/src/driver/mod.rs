//! Driver of the **SPI_motor** board (model id `spimotor`): one stepper, or two brushed DC
//! motors, on an SPI bus shared by address byte.
//!
//! Every byte goes through the `spimotor` protocol crate; this module decides *what* to
//! send and *when*, and what the answers mean. It never reads a clock, never touches a file
//! descriptor and allocates nothing after [`SpimotorDriver::new`].
//!
//! ```
//! use core::time::Duration;
//! use board_spimotor::driver::{AxisLimits, SpimotorDriver, SpimotorDriverConfig};
//! use motion_drivers::{Driver, Goal, GoalKind};
//!
//! let driver_config = SpimotorDriverConfig {
//!     limits: [AxisLimits { max_velocity: 2_000.0, max_accel: 20_000.0 }; 2],
//!     ..SpimotorDriverConfig::default() // stepper at 0x90, 1 MHz, polled every 2 ms
//! };
//! let mut driver = SpimotorDriver::new(driver_config);
//! assert!(driver.capabilities(0).contains(GoalKind::RampPosition));
//! assert!(!driver.capabilities(0).contains(GoalKind::Home));
//!
//! // Start-up begins with the datasheet's "read identification": 0x91, 0x01, then xx.
//! let mut buf = [0u8; 256];
//! driver.handle_timeout(Duration::ZERO);
//! let transmit = driver.poll_transmit(Duration::ZERO, &mut buf).expect("a read");
//! assert_eq!(&buf[..2], &[0x91, 0x01]);
//! // The MISO bytes of that transaction go back through `handle_rx`; until the board has
//! // answered, motion goals are refused.
//! assert!(driver.set_goal(Duration::ZERO, 0, Goal::Position { counts: 10.0 }).is_err());
//! # let _ = transmit;
//! ```
//!
//! # The wire
//!
//! Every exchange is one SPI transaction (address byte, port byte, data). A read's answer
//! starts at MISO offset 2 ([`spimotor::REPLY_OFFSET`]); the [`LinkBus`](motion_drivers::LinkBus)
//! hands each transaction's MISO bytes back to the driver that wrote it, so several boards
//! (distinct addresses) share one bus. Nothing on the wire tells a present board from an
//! absent one — an undriven MISO reads 0xFF, so a position read of an absent board returns
//! −1 — therefore the driver identifies its board by reading port 0x01 (an identification
//! string terminated by 0; 0xFF bytes never terminate it) at start-up and periodically.
//!
//! # Start-up
//!
//! 1. Read the identification (0x01). A missing or invalid string is retried every
//!    [`RETRY_PERIOD`]; after [`START_ATTEMPTS`] failures the board is reported
//!    [`DeviceFault::NotResponding`] and retried every [`OFFLINE_RETRY_PERIOD`].
//! 2. Read the serial number (0x02); the firmware text becomes `"<identification> sn
//!    <serial, hex>"`.
//! 3. Stepper: survey before writing anything — read position (0x40), target (0x41) and
//!    step delay (0x43), twice; believed when two readings agree (same target and delay, a
//!    position no farther on than the delay allows), else read again (after
//!    [`SURVEY_ATTEMPTS`] disagreements:
//!    [`DeviceFault::Protocol`] and start over). The board is then online.
//! 4. Configure. A standing stepper: 0x42 ← 0 (target = current position: stop where it
//!    is), 0x44 ← coils, 0x43 ← the step delay of the axis's `max_velocity`, 0x10 ←
//!    intensity ([`SpimotorDriverConfig::stepper_intensity`], 0 after an `Off`). A stepper
//!    that moves (left running by another program, or by this server before it
//!    restarted): 0x44 and 0x10 only, and a stop that ramps its step rate down from the
//!    rate it steps at (the delay it was read with) at the axis's max acceleration — never
//!    a stop dead, which a stepper at speed would answer by losing steps. Brushed: 0x22
//!    and 0x32 (stop A and B). All of it again after every restart, so after a board reset
//!    (power cycle) too.
//! 5. Poll. The first consistent poll after start-up clears the channel faults; goals from
//!    before are gone (the engine needs a new command).
//!
//! # Stepper (channel 0), counts = full steps of the board's position counter
//!
//! The board steps towards its target (0x41) at one constant rate, one step per step
//! delay (0x43, 0.1 ms … 25.5 ms), and has no acceleration of its own. The driver ramps
//! that rate ([`ramp`]) so that moves respect the axis's velocity and acceleration: the
//! step delay is rewritten every `poll_period`, always rounded to step no faster than the
//! profile, and never faster than the goal's velocity. The board's slowest rate, 39.2
//! steps/s, is its start/stop rate (reached and left within one step). A goal reaches the
//! wire in the tick that set it when it slows the motor (a reverse jog, a stop: the delay
//! written is that of the rate the profile will have at its next update, so the board is
//! never faster than the profile); a speed-up shows in the first tick whose profile rate
//! has another 0.1 ms delay, the profile being updated every tick until it does
//! (`tests/engine_spimotor/wire.rs`).
//!
//! | goal | what the board gets |
//! |---|---|
//! | `Position` | target 0x41 ← counts, rate ramped with the axis's `max_velocity` / `max_accel` |
//! | `RampPosition` | target 0x41 ← counts, rate ramped with the goal's velocity (≥ 39.2 steps/s, capped at 10 000) and acceleration |
//! | `Velocity` | target 2³⁰ steps ahead in the direction of travel, rate ramped to \|v\| (39.2 ≤ \|v\| ≤ 10 000 steps/s, else `OutOfBoardRange`; 0 stops); the board runs at the fastest rate 10 000/n not above \|v\| |
//! | `Stop` | rate ramped down at `decel` from the rate the board steps at now (the step delay in force towards its target; 0 when it stands), not from the profile's; then 0x42 ← 0 (stop where it is), so it ends within (\|rate\| − 39.2) / decel plus one profile period. Always sent, also on a standing stepper (0x42 ← 0 at once). Should the next poll show the target elsewhere (a firmware that counts 0x42 from the old target), 0x41 ← the position read |
//! | `SetPosition` | 0x43 ← 255 (so no step can slip in), 0x40 ← counts, 0x41 ← counts, 0x43 ← the resting delay (writing 0x40 alone would walk back to the old target); stops motion |
//! | `Off` | 0x42 ← 0, then intensity 0x10 ← 0 (coils de-energised: stop category 0, no ramp); the next goal that moves or holds writes the configured intensity first |
//! | `Home` | unsupported: the board has no reference input |
//!
//! Reported state: position = the board's position counter (open loop, no encoder);
//! velocity = ±(rate of the step delay read back) while position ≠ target; moving while
//! the board's position differs from its target or a run/stop ramp is in progress;
//! `homed` after a set-position (until the board resets); `arrived` when a position goal's
//! target is reached.
//!
//! # Brushed (channel 0 = motor A, 1 = motor B)
//!
//! `Power { fraction }` spins the motor in direction A (fraction > 0, ports 0x20/0x30) or
//! B (< 0, 0x21/0x31) with intensity `round(|fraction| × 255)`; a fraction that rounds to
//! 0, `Stop` and `Off` write the stop port (0x22/0x32) at once: the board has no speed
//! ramp and no coasting mode, so a stop's deceleration cannot be chosen. A brushed motor
//! stopped with no power on its bridge *is* de-energised: `Off` and `Stop` are the same
//! write. Every other goal
//! is `Unsupported`. The board has no encoder: position and velocity are reported as 0
//! (configure brushed axes with `min < 0 < max`), `moving` means "the bridge is driven",
//! and a channel is fresh when its board answered the last identification read.
//!
//! # Commissioning
//!
//! `motionctl commission DEVICE --address N` moves the board to a new address with the
//! unlock sequence (module `commission`) and starts it there again.
//!
//! # Faults
//!
//! - Polls are checked against what the driver wrote: the step delay and target read back
//!   must be the ones in force when the read was sent, and the position may not move
//!   faster than the board can step. A poll that disagrees is discarded (the channel keeps
//!   its last known state) and counted in [`DeviceStatus::bad_replies`]; garbage on MISO
//!   therefore never reaches the axis. (A stepper poll — three reads — counts as one reply
//!   in [`DeviceStatus::replies`] or `bad_replies`.)
//! - The same disagreeing poll [`CONFIRMATIONS`] times in a row is real: all bytes 0xFF
//!   (position −1, target −1, delay 255) is an absent board ([`DeviceFault::NotResponding`]);
//!   power-on registers (position and target 0, or the step delay 200) a board that lost
//!   its registers ([`DeviceFault::Reset`]: power cycle); anything else somebody else writing the board or a stuck MISO line
//!   ([`DeviceFault::Protocol`]). [`PROTOCOL_LIMIT`] disagreeing polls in a row without a
//!   repeat raise [`DeviceFault::Protocol`] too, until a good poll arrives.
//! - [`CONFIRMATIONS`] failed identification reads in a row (periodic presence check)
//!   raise `NotResponding`. MISO that has not come back (an SPI socket peer or the server
//!   without CPU holds it; a spidev transfer returns it at once) is waited for up to
//!   [`SpimotorDriverConfig::silence`] (`silence_ms`, 500 ms by default), judged up to the
//!   link's horizon; then `NotResponding`, and the bytes still owed by the transactions
//!   given up on are dropped when they come ([`SpimotorDriver::late_miso`]), never taken
//!   for a later transaction's (module `liveness`).
//! - Each `NotResponding` and `Reset` is declared with its evidence (`DeviceStatus::verdict`:
//!   which reads, what they showed, how long).
//! - After any of these the board is started again from step 1.
//!
//! Every transaction carries its own answer (a read's at MISO offset 2), so no request can
//! meet the answer of an earlier one, and MISO is attributed by transaction order alone.

mod brushed;
mod commission;
mod config;
mod goals;
mod liveness;
pub mod ramp;
mod rx;
mod spec;
mod startup;
mod stepper;
mod wire;

use core::time::Duration;

use spimotor::Identification;

use motion_drivers::{
    ChannelState, Commission, CommissionError, DeviceFault, DeviceStatus, Driver, Goal, GoalError,
    GoalKind, GoalKinds, IoStamps, Model, Priority, RateFloor, Transmit,
};

pub use config::{AxisLimits, SpimotorDrive, SpimotorDriverConfig};
pub use startup::SURVEY_ATTEMPTS;

use brushed::BrushedMotor;
use stepper::Stepper;
use wire::{InFlight, OpQueue, Registers};

/// Retry period of the identification read during start-up.
pub const RETRY_PERIOD: Duration = Duration::from_millis(20);
/// Retry period once the board has been declared not responding.
pub const OFFLINE_RETRY_PERIOD: Duration = Duration::from_millis(200);
/// Identification attempts before the board is declared not responding.
pub const START_ATTEMPTS: u32 = 3;
/// Identical disagreeing polls (or failed presence reads) in a row that are taken as real.
pub const CONFIRMATIONS: u32 = 3;
/// Disagreeing polls in a row that raise [`DeviceFault::Protocol`].
pub const PROTOCOL_LIMIT: u32 = 20;
/// Every this many stepper polls, the identification is read as a presence check.
pub const PRESENCE_EVERY: u32 = 16;
/// Margin of the reply timeout beyond the wire time of what is in flight.
pub const REPLY_MARGIN: Duration = Duration::from_millis(100);

/// Start-up and running phases.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// Reading the identification string.
    Identify { attempts: u32, next_at: Duration },
    /// Reading the serial number.
    Serial,
    /// Stepper: reading what the board does now (position, target, step delay) before
    /// anything is written, so that a motor left running is ramped down from its rate.
    Survey,
    /// Configured; polling.
    Running,
}

/// Sans-I/O driver of one SPI_motor board. See the module docs.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub struct SpimotorDriver {
    config: SpimotorDriverConfig,
    status: DeviceStatus,
    phase: Phase,
    link_up: bool,
    identification: Option<Identification>,
    /// Setup and goal traffic, in order.
    commands: OpQueue<24>,
    /// Poll reads.
    polls: OpQueue<8>,
    in_flight: InFlight<32>,
    /// Registers as transmitted (what reads are checked against).
    written: Registers,
    /// Registers after every queued write.
    planned: Registers,
    /// Bumped by every write of the position counter.
    epoch: u32,
    next_poll_at: Duration,
    polls_done: u32,
    presence_misses: u32,
    /// Last time the board answered a presence read or a consistent poll.
    refreshed_at: Option<Duration>,
    stepper: Stepper,
    motors: [BrushedMotor; 2],
    /// The start-up survey's readings so far.
    survey: startup::Survey,
    /// The link's write reports and horizon.
    io_stamps: IoStamps,
    /// Bit `c`: no transaction of channel `c`'s goal set last has been sent yet.
    goal_unsent: u8,
    /// MISO bytes still owed by transactions given up on (module `liveness`).
    discard_miso: usize,
    /// Late MISO bytes recognised and dropped.
    late_miso: u64,
}

impl SpimotorDriver {
    /// A driver for the board `config` describes; it starts the board on its first
    /// `poll_transmit`.
    pub fn new(config: SpimotorDriverConfig) -> Self {
        let stepper = Stepper::new(&config);
        Self {
            config,
            status: DeviceStatus::UNKNOWN,
            phase: Phase::Identify {
                attempts: 0,
                next_at: Duration::ZERO,
            },
            link_up: true,
            identification: None,
            commands: OpQueue::new(),
            polls: OpQueue::new(),
            in_flight: InFlight::new(),
            written: Registers::UNKNOWN,
            planned: Registers::UNKNOWN,
            epoch: 0,
            next_poll_at: Duration::ZERO,
            polls_done: 0,
            presence_misses: 0,
            refreshed_at: None,
            stepper,
            motors: [BrushedMotor::default(); 2],
            survey: startup::Survey::default(),
            io_stamps: IoStamps::default(),
            goal_unsent: 0,
            discard_miso: 0,
            late_miso: 0,
        }
    }

    /// The configuration the driver was built from.
    pub fn config(&self) -> &SpimotorDriverConfig {
        &self.config
    }

    /// The identification string the board answered at start-up.
    pub fn identification(&self) -> Option<Identification> {
        self.identification
    }

    fn is_stepper(&self) -> bool {
        self.config.drive == SpimotorDrive::Stepper
    }

    fn running(&self) -> bool {
        self.link_up && self.phase == Phase::Running
    }

    /// Raises `fault` on the board (and so on every channel).
    fn raise(&mut self, fault: DeviceFault) {
        if self.link_up || fault == DeviceFault::LinkDown {
            self.status.fault = Some(fault);
        }
    }
}

impl Driver for SpimotorDriver {
    fn model(&self) -> Model {
        Model::SPIMOTOR
    }

    fn channel_count(&self) -> usize {
        self.config.drive.channels()
    }

    fn capabilities(&self, channel: usize) -> GoalKinds {
        self.kinds(channel)
    }

    /// A stepper's slowest rate is one step per longest step delay (255 × 0.1 ms: 39.2
    /// steps/s); its acceleration is the driver's own profile, integrated continuously (no
    /// floor). Brushed channels take power only.
    /// A position move (the driver's own step-rate ramp) is retargeted every tick over SPI.
    fn follow(&self, channel: usize) -> motion_drivers::Follow {
        let _ = channel;
        motion_drivers::Follow::Setpoints
    }

    fn rate_floor(&self, channel: usize) -> RateFloor {
        if self.is_stepper() && self.kinds(channel).contains(GoalKind::Velocity) {
            RateFloor {
                velocity: ramp::slowest_rate(),
                profile_velocity: ramp::slowest_rate(),
                accel: 0.0,
            }
        } else {
            RateFloor::NONE
        }
    }

    fn refresh_budget(&self) -> Duration {
        self.config
            .poll_period
            .saturating_mul(3)
            .saturating_add(Duration::from_millis(25))
    }

    fn handle_rx(&mut self, now: Duration, bytes: &[u8]) {
        self.receive(now, bytes);
    }

    fn handle_timeout(&mut self, now: Duration) {
        self.pass_time(now);
    }

    fn handle_written(&mut self, at: Duration) {
        let number = self.io_stamps.written();
        self.in_flight.written(number, at);
    }

    fn handle_heard(&mut self, until: Duration) {
        self.io_stamps.heard(until);
    }

    fn poll_timeout(&self) -> Option<Duration> {
        let timeout = self
            .in_flight
            .oldest()
            .map(|sent| sent.at.saturating_add(self.reply_timeout()));
        let phase = match self.phase {
            _ if !self.link_up => None,
            Phase::Identify { next_at, .. } => Some(next_at),
            Phase::Serial | Phase::Survey => None,
            Phase::Running => Some(self.next_poll_at),
        };
        match (timeout, phase) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    fn wants_transmit(&self, _now: Duration) -> Option<Priority> {
        self.next_queued().map(|queued| queued.priority)
    }

    fn poll_transmit(&mut self, now: Duration, buf: &mut [u8]) -> Option<Transmit> {
        self.transmit(now, buf)
    }

    fn awaiting_reply(&self) -> bool {
        !self.in_flight.is_empty()
    }

    fn goals_pending(&self) -> bool {
        self.commands
            .iter()
            .any(|queued| queued.priority == Priority::Command)
            || self.stepper.ramping()
    }

    fn set_goal(&mut self, now: Duration, channel: usize, goal: Goal) -> Result<(), GoalError> {
        self.plan_goal(now, channel, goal)?;
        if channel < 8 {
            self.goal_unsent |= 1 << channel;
        }
        Ok(())
    }

    fn channel(&self, channel: usize) -> ChannelState {
        if channel >= self.channel_count() {
            return ChannelState::UNKNOWN;
        }
        let mut state = if self.is_stepper() {
            self.stepper.state()
        } else {
            let mut state = ChannelState::UNKNOWN;
            state.refreshed_at = self.refreshed_at;
            state.moving = self.motors.get(channel).is_some_and(|m| m.driven());
            state
        };
        state.fault = self.status.fault;
        state
    }

    fn status(&self) -> DeviceStatus {
        self.status
    }

    fn link_down(&mut self, now: Duration) {
        self.io_stamps.link_reset();
        self.link_up = false;
        self.in_flight.clear();
        self.discard_miso = 0;
        self.raise(DeviceFault::LinkDown);
        self.restart(now, 0);
    }

    fn link_up(&mut self, now: Duration) {
        self.io_stamps.link_reset();
        self.link_up = true;
        self.in_flight.clear();
        self.discard_miso = 0;
        self.restart(now, 0);
    }

    /// The board's address (0xf1, 0xf2, 0xf0): module `commission`.
    fn commission(&mut self, _now: Duration, change: Commission) -> Result<(), CommissionError> {
        self.start_commission(change)
    }
}

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_late_replies;

/// The SPI_motor protocol page defines no I/O port: no pins.
pub const PINS: &[motion_drivers::PinInfo] = &[];

#[cfg(test)]
mod tests_commission;
