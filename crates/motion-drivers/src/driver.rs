//! The one trait every board driver implements: [`Driver`].

use core::fmt;
use core::time::Duration;

use crate::commission::{Commission, CommissionError};
use crate::goal::{Goal, GoalError, GoalKinds, RateFloor};
use crate::late::LateAnswer;
use crate::pin::{Pin, PinReading};
use crate::state::{ChannelState, DeviceStatus};

/// Which board a driver speaks to (one enum with the config, the contract and the
/// simulator: `motion_base::Model`).
pub use motion_base::Model;

/// How urgent a driver's next message is; a shared bus serves higher priorities first.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash,
)]
pub enum Priority {
    /// Periodic status/position polling.
    Poll = 0,
    /// Start-up and recovery traffic (version reads, configuration).
    Setup = 1,
    /// A goal the engine set: goes before every poll (docs/ARCHITECTURE.md: commands before polls).
    Command = 2,
    /// A request of a stop (a deadman, e-stop, fault or client stop): goes before every
    /// other message on the bus — other drivers' commands and their overdue polls
    /// included — so that it waits for nothing but the one exchange in flight
    /// (docs/ARCHITECTURE.md "The deadman's bound per board").
    Stop = 3,
}

/// How a board follows a moving target: what the engine sends it while an axis group's
/// path moves one of its channels (docs/ARCHITECTURE.md "Coordinated motion").
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub enum Follow {
    /// A `Position` goal every tick, which the board's own controller tracks: for boards
    /// on links fast enough to take one every tick (SPI).
    Setpoints,
    /// `RampPosition` segments: the path's position a segment ahead with the velocity that
    /// arrives there in time, the next segment once the driver has acknowledged the last —
    /// for boards that change a position target while they move.
    #[default]
    Segments,
    /// `Velocity` goals — the path's velocity a segment ahead with the position error fed
    /// back — the next once the last is acknowledged, and a final `RampPosition` to the
    /// path's end: for boards that stop before starting a new position move.
    Velocity,
}

/// How far a board's own velocity and acceleration for a line leg may be from the leg's
/// (relative) at most: a board runs a line itself only if its units represent both within
/// the leg's [`LineLeg::rate_tolerance`], which the engine makes no larger than this, and
/// small enough that the line arrives within half the group's `goal_time_tolerance`.
pub const LINE_RATE_TOLERANCE: f64 = 0.02;

/// One channel's part of a straight line in joint space ([`Driver::lead_line`]): the line
/// ends at `counts`, reaching at most `velocity` counts/s at `accel` counts/s² — a
/// trapezoid (or triangle) from rest to rest, the same in time for every leg of the line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineLeg {
    /// The board's channel.
    pub channel: usize,
    /// Where the line ends, counts.
    pub counts: f64,
    /// The leg's peak velocity magnitude, counts/s (> 0).
    pub velocity: f64,
    /// The leg's acceleration magnitude, counts/s² (> 0).
    pub accel: f64,
    /// How far (relative) the board's own velocity and acceleration may be from the leg's
    /// (at most [`LINE_RATE_TOLERANCE`]).
    pub rate_tolerance: f64,
}

impl LineLeg {
    /// Whether a board that represents the leg's velocity as `velocity` and its
    /// acceleration as `accel` (counts/s, counts/s²) keeps its pace within
    /// [`rate_tolerance`](Self::rate_tolerance).
    pub fn represented_within(&self, velocity: f64, accel: f64) -> bool {
        let within = |represented: f64, wanted: f64| {
            wanted > 0.0 && ((represented - wanted) / wanted).abs() <= self.rate_tolerance
        };
        within(velocity, self.velocity) && within(accel, self.accel)
    }
}

/// One message a driver wrote in [`Driver::poll_transmit`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Transmit {
    /// Bytes written at the start of the buffer. On an SPI link this is one transaction
    /// (one chip-select assertion) and exactly as many MISO bytes will come back.
    pub len: usize,
    /// The driver now waits for a reply: on a shared stream bus nobody else may send until
    /// [`Driver::awaiting_reply`] turns false (manual 7.1 "Interlacing of Requests").
    pub expects_reply: bool,
    /// Bit `c`: this message carries the first request of channel `c`'s current goal (the
    /// goal [`Driver::set_goal`] set last). The engine stamps the goal with the instant
    /// this message is reported written ([`Driver::handle_written`]): command → wire.
    pub goal_starts: u8,
}

/// The size of the buffer a driver's message is written into
/// ([`Driver::poll_transmit`]), and of the chunks received bytes are handed over in: every
/// board's longest message fits.
pub const MESSAGE_LEN: usize = 256;

/// A sans-I/O board driver: axis goals, received bytes and `now` in; bytes to send and
/// channel state out. It never reads a clock and never touches a file descriptor: the
/// engine (or a test) moves the bytes and passes the time. The shape follows quinn-proto:
/// `handle_rx` / `handle_timeout` feed it, `poll_transmit` / `poll_timeout` drain it.
///
/// Call order within one engine step: `handle_written` for this driver's messages the link
/// wrote since the last step, `handle_rx` with everything received for this driver,
/// `handle_heard`, then `handle_timeout(now)`, then goals (`set_goal`), then
/// `poll_transmit` until it returns `None` or the bus holds the driver back.
///
/// Time on the link side: a message queued by `poll_transmit` reaches the wire when the
/// I/O side gets to it, and received bytes reach the driver when the I/O side read them.
/// A driver starts a reply timeout when its request was written (`handle_written`), and
/// judges silence only up to the link's horizon (`handle_heard`), so an I/O thread that
/// did not run (a starved process, a full transmit buffer) never makes a board look dead;
/// a board that does not answer requests that went out is still found within the same
/// bounds. Both are stamps passed in: the driver still reads no clock.
pub trait Driver: Send + fmt::Debug {
    /// The board model.
    fn model(&self) -> Model;

    /// Channels (motors / encoders) on the board as configured.
    fn channel_count(&self) -> usize;

    /// The goals `channel` accepts; empty for a channel the board does not have.
    fn capabilities(&self, channel: usize) -> GoalKinds;

    /// The smallest nonzero velocity and acceleration the board represents on `channel`
    /// (its velocity and acceleration units: the Trinamic pack's velocity and amax units,
    /// the QSB's step-rate and acceleration minimums, the QuadQuad2Drv's transitions/s and
    /// shl-12 steps, the SPI_motor's slowest step delay), in counts. Fixed once the driver
    /// is configured; [`RateFloor::NONE`] by default.
    fn rate_floor(&self, channel: usize) -> RateFloor {
        let _ = channel;
        RateFloor::NONE
    }

    /// How `channel` follows a group's path ([`Follow`]); [`Follow::Segments`] by default.
    fn follow(&self, channel: usize) -> Follow {
        let _ = channel;
        Follow::Segments
    }

    /// Prepares a group's straight line in joint space on several of this board's channels,
    /// from rest, to be run with the board's own function (the Trinamic pack's `$26` +
    /// `$50` linear interpolation; the QSB-M's own move): everything but the start goes
    /// out now; [`start_line`](Self::start_line) starts it once
    /// [`line_ready`](Self::line_ready) says the rest is out, so that the boards of a group
    /// on several links start together. Returns `Ok(true)` when the board took every leg
    /// (it then runs each to its end by itself and the engine only supervises it),
    /// `Ok(false)` when it has no such function or cannot now (a motor not at rest, a line
    /// already prepared): the engine then follows the line with goals
    /// ([`Driver::follow`]). By default `Ok(false)`. A goal set on a leg's channel later
    /// ends the board's line (or its preparation).
    fn lead_line(&mut self, now: Duration, legs: &[LineLeg]) -> Result<bool, GoalError> {
        let _ = (now, legs);
        Ok(false)
    }

    /// Whether the line prepared with [`lead_line`](Self::lead_line) waits only for
    /// [`start_line`](Self::start_line). By default `true`.
    fn line_ready(&self) -> bool {
        true
    }

    /// Starts the line prepared with [`lead_line`](Self::lead_line) (its last request goes
    /// out next). By default nothing.
    fn start_line(&mut self, now: Duration) {
        let _ = now;
    }

    /// Whether the start of a line ([`start_line`](Self::start_line)) has not gone out to
    /// the board yet (the path waits for it). By default `false`.
    fn line_starting(&self) -> bool {
        false
    }

    /// Holds a line this board leads on `channel` with the board's own pause, where the
    /// board is running it now (the QSB-M's COMMAND 6, "Pause the motor using the MD
    /// ACCEL rate"): `Ok(true)` when it will come to rest and wait for
    /// [`resume_line`](Self::resume_line). By default `Ok(false)` (the engine then holds
    /// the line with goals).
    fn pause_line(&mut self, now: Duration, channel: usize) -> Result<bool, GoalError> {
        let _ = (now, channel);
        Ok(false)
    }

    /// Continues a line paused with [`pause_line`](Self::pause_line) (the QSB-M's
    /// COMMAND 7): `Ok(true)` when the board resumes it; by default `Ok(false)`.
    fn resume_line(&mut self, now: Duration, channel: usize) -> Result<bool, GoalError> {
        let _ = (now, channel);
        Ok(false)
    }

    /// How old a channel's data may become in normal operation before the engine marks
    /// the axis stale (the board's polling or streaming period plus wire time and margin).
    fn refresh_budget(&self) -> Duration;

    /// Bytes received from the link that belong to this driver, in wire order and any
    /// chunking (on SPI: the MISO bytes of this driver's own transactions).
    fn handle_rx(&mut self, now: Duration, bytes: &[u8]);

    /// Lets time pass: reply timeouts, poll periods, start-up retries.
    fn handle_timeout(&mut self, now: Duration);

    /// The oldest of this driver's messages not reported yet went out whole at `at` (the
    /// link accepted its last byte). Every message is reported once, in the order of
    /// `poll_transmit` (a [`LinkBus`](crate::LinkBus) routes the reports); a link that
    /// went down voids the reports still owed. A reply timeout runs from here, not from
    /// the `now` the message was queued at. A shell without write stamps has the bus
    /// report each message at once, at the `now` it was made.
    fn handle_written(&mut self, at: Duration) {
        let _ = at;
    }

    /// The link's horizon: every byte that arrived before `until` has been handed to
    /// `handle_rx`, and every message queued before it was written. Silence (a reply
    /// timeout, a stream gone quiet) is judged up to `min(until, now)`, never beyond: a
    /// link whose I/O side did not look cannot show that the board stayed silent. Given
    /// before every `handle_timeout` by a shell that stamps; without it, up to `now`.
    fn handle_heard(&mut self, until: Duration) {
        let _ = until;
    }

    /// Answers this driver's board may still send although their reply window ended
    /// ([`LateAnswer`]: a board or its host process that was starved): the driver takes a
    /// word that begins with one for late, never for an answer, and asks no question whose
    /// answer would begin with one. A [`LinkBus`](crate::LinkBus) hands them to the other
    /// drivers on the same stream link ([`handle_late_answers`](Self::handle_late_answers)).
    /// None by default.
    fn late_answers(&self) -> &[LateAnswer] {
        &[]
    }

    /// The answers the *other* boards on this stream link may still send late (their
    /// drivers' [`late_answers`](Self::late_answers)), each kept until its
    /// [`LateAnswer::until`]: this driver asks no question whose answer would begin like one,
    /// and takes a word that begins like one for late. Given by a bus with several drivers
    /// before it picks the next sender and before it routes received bytes. Ignored by
    /// default.
    fn handle_late_answers(&mut self, others: &[LateAnswer]) {
        let _ = others;
    }

    /// The earliest instant at which [`handle_timeout`](Self::handle_timeout) has work.
    #[must_use]
    fn poll_timeout(&self) -> Option<Duration>;

    /// The priority of the message the driver would send now, or `None`.
    fn wants_transmit(&self, now: Duration) -> Option<Priority>;

    /// Writes the next message into `buf` (which holds at least [`MESSAGE_LEN`] bytes).
    #[must_use]
    fn poll_transmit(&mut self, now: Duration, buf: &mut [u8]) -> Option<Transmit>;

    /// Whether the driver still waits for the reply to its last request.
    fn awaiting_reply(&self) -> bool;

    /// Whether a goal set with [`set_goal`](Self::set_goal) has not yet been acknowledged
    /// by the board (sent and answered, or for boards without answers, sent). A shutdown
    /// waits for this to turn false on every driver.
    fn goals_pending(&self) -> bool;

    /// Sets a channel's goal; the driver turns it into wire traffic on its next
    /// `poll_transmit` calls. A goal replaces the previous one.
    fn set_goal(&mut self, now: Duration, channel: usize, goal: Goal) -> Result<(), GoalError>;

    /// The channel's last known state (`ChannelState::UNKNOWN` for an unknown channel).
    fn channel(&self, channel: usize) -> ChannelState;

    /// The board's status.
    fn status(&self) -> DeviceStatus;

    /// The link went down: in-flight requests are void, channels are faulted
    /// ([`DeviceFault::LinkDown`](crate::DeviceFault::LinkDown)) but keep their last known
    /// state.
    fn link_down(&mut self, now: Duration);

    /// The link is (re)open: start the board's start-up sequence again. Channels stay
    /// faulted until fresh data arrives and need a new goal.
    fn link_up(&mut self, now: Duration);

    /// The last known value of `pin` (an index into the board's pin table), for a pin the
    /// driver was configured to read or drive; `None` for any other pin. Inputs are polled
    /// or streamed by the driver within its wire budget.
    fn read_pin(&self, pin: Pin) -> Option<PinReading> {
        let _ = pin;
        None
    }

    /// Drives the digital output `pin` to the electrical level `high`; the driver turns it
    /// into wire traffic (commands before polls). Errors: `NoSuchPin` for a pin the driver
    /// was not configured to drive, `Offline` while the board is not online.
    fn set_output(&mut self, now: Duration, pin: Pin, high: bool) -> Result<(), GoalError> {
        let _ = (now, high);
        Err(GoalError::NoSuchPin(pin))
    }

    /// Sets the value of a pin that holds a number rather than a level — the compare
    /// position of a trigger pin, in counts (what [`read_pin`](Self::read_pin) reports
    /// back once the board holds it). Errors: `NoSuchPin` for a pin without such a value,
    /// `OutOfBoardRange` for a value the board cannot hold, `Offline` / `Starting` while
    /// the board is not online.
    fn set_pin_value(&mut self, now: Duration, pin: Pin, value: f64) -> Result<(), GoalError> {
        let _ = (now, value);
        Err(GoalError::NoSuchPin(pin))
    }

    /// The line rate (baud) the link must run at when this driver's next message goes out,
    /// for a board whose rate the driver changes (the Trinamic pack's `$40`): the driver
    /// never touches the link — a [`LinkBus`](crate::LinkBus) sees the rate differ from
    /// the link's before it lets the message go and asks its shell to change the link's
    /// rate first ([`LinkBus::take_rate_change`](crate::LinkBus::take_rate_change)), in
    /// order with the messages before (which go at the old rate). `None` (the default):
    /// whatever rate the link runs at. A driver that returns `Some` assumes, after
    /// [`link_up`](Self::link_up), that the link runs at its configured rate again.
    fn line_rate(&self) -> Option<u32> {
        None
    }

    /// Changes one of the board's own settings (module `commission`): the driver sends it
    /// and finds the board again where it now answers; until then its status is not
    /// online. The engine refuses it while an axis of the board moves. By default
    /// [`CommissionError::Unsupported`].
    fn commission(&mut self, now: Duration, change: Commission) -> Result<(), CommissionError> {
        let _ = (now, change);
        Err(CommissionError::Unsupported)
    }

    /// Whether the server should keep, across its own restarts, which axes of this board
    /// are referenced and at rest (with their positions), and hand them back through
    /// [`restore_references`](Self::restore_references) at its next start. `false` (the
    /// default): the board cannot tell whether its positions survived (the Trinamic pack
    /// can, with `power_down = "restore"`: its `$45`).
    fn keeps_references(&self) -> bool {
        false
    }

    /// Start-up hook, called once before the driver's first step (never on the tick): the
    /// axes a previous run of the server last saw referenced and at rest, with their
    /// positions in the board's counts; the server has already refused a record whose
    /// identity (server, device, address, axis, channel, the axis's keys) does not match
    /// this config. The driver decides from what the board says whether any of them is
    /// referenced again; by default it ignores them (the axes need a new reference).
    fn restore_references(&mut self, saved: &[SavedReference]) {
        let _ = saved;
    }
}

/// One axis a previous run of the server saw referenced and at rest
/// ([`Driver::restore_references`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SavedReference {
    /// The axis's channel on the board.
    pub channel: usize,
    /// Its position then, in the board's counts.
    pub counts: i64,
}

/// A boxed driver is a driver: tests and tools hold drivers of any board as
/// `Box<dyn Driver>` (the server holds an enum of the registered boards' drivers instead).
impl<T: Driver + ?Sized> Driver for Box<T> {
    fn model(&self) -> Model {
        (**self).model()
    }
    fn channel_count(&self) -> usize {
        (**self).channel_count()
    }
    fn capabilities(&self, channel: usize) -> GoalKinds {
        (**self).capabilities(channel)
    }
    fn rate_floor(&self, channel: usize) -> RateFloor {
        (**self).rate_floor(channel)
    }
    fn follow(&self, channel: usize) -> Follow {
        (**self).follow(channel)
    }
    fn refresh_budget(&self) -> Duration {
        (**self).refresh_budget()
    }
    fn lead_line(&mut self, now: Duration, legs: &[LineLeg]) -> Result<bool, GoalError> {
        (**self).lead_line(now, legs)
    }
    fn line_ready(&self) -> bool {
        (**self).line_ready()
    }
    fn start_line(&mut self, now: Duration) {
        (**self).start_line(now);
    }
    fn line_starting(&self) -> bool {
        (**self).line_starting()
    }
    fn pause_line(&mut self, now: Duration, channel: usize) -> Result<bool, GoalError> {
        (**self).pause_line(now, channel)
    }
    fn resume_line(&mut self, now: Duration, channel: usize) -> Result<bool, GoalError> {
        (**self).resume_line(now, channel)
    }
    fn handle_rx(&mut self, now: Duration, bytes: &[u8]) {
        (**self).handle_rx(now, bytes);
    }
    fn handle_timeout(&mut self, now: Duration) {
        (**self).handle_timeout(now);
    }
    fn handle_written(&mut self, at: Duration) {
        (**self).handle_written(at);
    }
    fn handle_heard(&mut self, until: Duration) {
        (**self).handle_heard(until);
    }
    fn late_answers(&self) -> &[LateAnswer] {
        (**self).late_answers()
    }
    fn handle_late_answers(&mut self, others: &[LateAnswer]) {
        (**self).handle_late_answers(others);
    }
    fn poll_timeout(&self) -> Option<Duration> {
        (**self).poll_timeout()
    }
    fn wants_transmit(&self, now: Duration) -> Option<Priority> {
        (**self).wants_transmit(now)
    }
    fn poll_transmit(&mut self, now: Duration, buf: &mut [u8]) -> Option<Transmit> {
        (**self).poll_transmit(now, buf)
    }
    fn awaiting_reply(&self) -> bool {
        (**self).awaiting_reply()
    }
    fn goals_pending(&self) -> bool {
        (**self).goals_pending()
    }
    fn set_goal(&mut self, now: Duration, channel: usize, goal: Goal) -> Result<(), GoalError> {
        (**self).set_goal(now, channel, goal)
    }
    fn channel(&self, channel: usize) -> ChannelState {
        (**self).channel(channel)
    }
    fn status(&self) -> DeviceStatus {
        (**self).status()
    }
    fn link_down(&mut self, now: Duration) {
        (**self).link_down(now);
    }
    fn link_up(&mut self, now: Duration) {
        (**self).link_up(now);
    }
    fn read_pin(&self, pin: Pin) -> Option<PinReading> {
        (**self).read_pin(pin)
    }
    fn set_output(&mut self, now: Duration, pin: Pin, high: bool) -> Result<(), GoalError> {
        (**self).set_output(now, pin, high)
    }
    fn set_pin_value(&mut self, now: Duration, pin: Pin, value: f64) -> Result<(), GoalError> {
        (**self).set_pin_value(now, pin, value)
    }
    fn line_rate(&self) -> Option<u32> {
        (**self).line_rate()
    }
    fn commission(&mut self, now: Duration, change: Commission) -> Result<(), CommissionError> {
        (**self).commission(now, change)
    }
    fn keeps_references(&self) -> bool {
        (**self).keeps_references()
    }
    fn restore_references(&mut self, saved: &[SavedReference]) {
        (**self).restore_references(saved);
    }
}
