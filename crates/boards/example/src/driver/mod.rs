//! Driver of the **AS-2** ASCII stepper controller (model id `example`): two stepper
//! channels on a serial link, one request in flight at a time.
//!
//! Every byte goes through [`crate::codec`]; this module decides what to send and when,
//! and what the replies mean. It never reads a clock, never touches a file descriptor and
//! allocates nothing after [`ExampleDriver::new`].
//!
//! ```
//! use core::time::Duration;
//! use board_example::driver::{ExampleDriver, ExampleDriverConfig};
//! use motion_drivers::{Driver, Goal, GoalError};
//!
//! let mut driver = ExampleDriver::new(ExampleDriverConfig::default());
//! let mut buf = [0u8; 256];
//! let sent = driver.poll_transmit(Duration::ZERO, &mut buf).expect("the identify");
//! assert_eq!(&buf[..sent.len], b"?\r");
//! // Until the board has answered, goals are refused.
//! let goal = Goal::Position { counts: 10.0 };
//! assert_eq!(driver.set_goal(Duration::ZERO, 0, goal), Err(GoalError::Starting));
//! driver.handle_written(Duration::from_micros(200));
//! driver.handle_rx(Duration::from_millis(1), b"AS2 1.4\r");
//! assert!(driver.status().online);
//! driver.set_goal(Duration::from_millis(1), 0, goal).expect("online");
//! let sent = driver.poll_transmit(Duration::from_millis(1), &mut buf).expect("the move");
//! assert_eq!(&buf[..sent.len], b"M0 10 1000 10000\r");
//! ```
//!
//! # Start-up
//!
//! `?` until the board answers `AS2 <version>` (the firmware text becomes `AS2
//! <version>`): one at a time, its reply waited for (below); a reply lost to a line that
//! could not be taken is asked again after [`RETRY_PERIOD`], a board silent for
//! [`ExampleDriverConfig::silence`] is [`DeviceFault::NotResponding`] and asked every
//! [`OFFLINE_RETRY_PERIOD`]. Then the board is online and polled; a fault from before
//! clears with the first position reply.
//!
//! # Polling
//!
//! Every [`ExampleDriverConfig::poll_period`], `P<ch>?` for each channel that carries an
//! axis; goals go first (a stop or an off before a move). [`Driver::refresh_budget`] is
//! three poll periods and 20 ms.
//!
//! # Goals (counts = steps)
//!
//! | goal | request |
//! |---|---|
//! | `Position` | `M<ch> <target> <max_velocity> <max_accel>` (the axis's limits) |
//! | `RampPosition` | `M<ch> <target> <velocity> <accel>`, capped at 50 000 steps/s and 1 000 000 steps/s² |
//! | `Velocity` | `V<ch> <velocity> <accel>`; \|v\| > 50 000 steps/s is `OutOfBoardRange` |
//! | `Stop` | `S<ch> <decel>` |
//! | `SetPosition` | `Z<ch> <position>` (the channel is `homed` once the board acknowledged it) |
//! | `Off` | `O<ch>` |
//! | `Power`, `Home` | unsupported |
//!
//! A goal replaces the channel's goal not sent yet. It is pending ([`Driver::goals_pending`])
//! until the board answered `OK`; an `E<n>` answer faults the channel with
//! [`DeviceFault::BoardError`] until the next goal.
//!
//! # Faults
//!
//! - One request at a time (README "Commands"): a request unanswered
//!   [`ExampleDriverConfig::reply_timeout`] after it was written (judged only up to the
//!   link's horizon) is waited for while the link is silent — a reply held up on the host
//!   comes later, in order — and nothing else is sent. It is lost when a line that could
//!   not be taken came where its reply was due: counted in [`DeviceStatus::timeouts`], a
//!   goal's request sent again; a reply to it that still comes is recognised
//!   ([`ExampleDriver::late_replies`]), never paired. [`MISS_LIMIT`] lost in a row, or
//!   [`ExampleDriverConfig::silence`] (500 ms) without a word while a reply is due:
//!   [`DeviceFault::NotResponding`], declared with its evidence (`DeviceStatus::verdict`),
//!   the board offline, goals dropped, start-up again.
//! - A line that is no reply, or a reply that does not answer the request in flight,
//!   counts in [`DeviceStatus::bad_replies`] and is dropped; [`PROTOCOL_LIMIT`] in a row
//!   raise [`DeviceFault::Protocol`] until a good reply arrives.
//! - The link down: [`DeviceFault::LinkDown`], requests in flight void, goals dropped.

mod config;
mod exchange;
mod goals;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_late;

use core::time::Duration;

use motion_drivers::{
    ChannelState, DeviceFault, DeviceStatus, Driver, Goal, GoalError, GoalKinds, Model, Priority,
    RateFloor, Transmit,
};

use crate::codec::{CHANNELS, ReplyDecoder, Request};

pub use config::{AxisLimits, DEFAULT_BAUD, ExampleDriverConfig};

/// Retry period of the identify during start-up.
pub const RETRY_PERIOD: Duration = Duration::from_millis(50);
/// Retry period once the board has been declared not responding.
pub const OFFLINE_RETRY_PERIOD: Duration = Duration::from_millis(500);
/// Identify attempts before the board is declared not responding.
pub const START_ATTEMPTS: u32 = 3;
/// Reply timeouts in a row that declare a running board not responding.
pub const MISS_LIMIT: u32 = 3;
/// Bad or unmatched replies in a row that raise [`DeviceFault::Protocol`].
pub const PROTOCOL_LIMIT: u32 = 10;
/// Margin of the reply timeout beyond the wire time.
pub const REPLY_MARGIN: Duration = Duration::from_millis(20);

/// Start-up and running.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// Sending `?` at `next_at`.
    Identify { attempts: u32, next_at: Duration },
    /// Identified; polling.
    Running,
}

/// The request on the wire, and when it went out whole.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy)]
struct InFlight {
    request: Request,
    written_at: Option<Duration>,
    /// A line that may have been its reply could not be taken (no reply, or not one to
    /// this request): once due, its reply is lost rather than late.
    garbled: bool,
}

/// What the driver knows of one channel besides the board's last reply.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy)]
struct Channel {
    state: ChannelState,
    /// The target of the position goal set last (for `arrived`).
    target: Option<i32>,
    /// A fault of this channel alone (an `E<n>` answer to its goal).
    fault: Option<DeviceFault>,
}

/// Sans-I/O driver of one AS-2. See the module docs.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub struct ExampleDriver {
    config: ExampleDriverConfig,
    status: DeviceStatus,
    phase: Phase,
    link_up: bool,
    decoder: ReplyDecoder,
    in_flight: Option<InFlight>,
    /// Per channel the goal's request not sent yet.
    commands: [Option<Request>; CHANNELS],
    /// Per channel: its position read is due in this poll round.
    poll_due: [bool; CHANNELS],
    next_poll_at: Duration,
    /// The link's horizon (`None`: judge up to `now`).
    heard: Option<Duration>,
    /// Reply timeouts in a row.
    misses: u32,
    /// Bad replies in a row.
    bad_in_row: u32,
    channels: [Channel; CHANNELS],
    /// Bit `c`: no request of channel `c`'s goal set last has been sent yet.
    goal_unsent: u8,
    /// When the last line (of any kind) arrived: the board talks.
    heard_at: Option<Duration>,
    /// The request whose reply was declared lost last: a reply to it that comes later is
    /// late.
    lost: Option<Request>,
    /// Late replies recognised.
    late_replies: u64,
}

impl ExampleDriver {
    /// A driver for the board `config` describes; it identifies the board on its first
    /// `poll_transmit`.
    #[must_use]
    pub fn new(config: ExampleDriverConfig) -> Self {
        Self {
            config,
            status: DeviceStatus::UNKNOWN,
            phase: Phase::Identify {
                attempts: 0,
                next_at: Duration::ZERO,
            },
            link_up: true,
            decoder: ReplyDecoder::new(),
            in_flight: None,
            commands: [None; CHANNELS],
            poll_due: [false; CHANNELS],
            next_poll_at: Duration::ZERO,
            heard: None,
            misses: 0,
            bad_in_row: 0,
            channels: [Channel {
                state: ChannelState::UNKNOWN,
                target: None,
                fault: None,
            }; CHANNELS],
            goal_unsent: 0,
            heard_at: None,
            lost: None,
            late_replies: 0,
        }
    }

    /// Replies that came for a request already declared lost (never paired).
    #[must_use]
    pub fn late_replies(&self) -> u64 {
        self.late_replies
    }

    /// The configuration the driver was built from.
    #[must_use]
    pub fn config(&self) -> &ExampleDriverConfig {
        &self.config
    }

    /// Raises `fault` on the board (and so on every channel).
    fn raise(&mut self, fault: DeviceFault) {
        self.status.fault = Some(fault);
    }

    /// Starts the board again from the identify at `now`: goals and requests are void.
    fn restart(&mut self, now: Duration, attempts: u32) {
        self.status.online = false;
        self.phase = Phase::Identify {
            attempts,
            next_at: now,
        };
        self.in_flight = None;
        self.commands = [None; CHANNELS];
        self.poll_due = [false; CHANNELS];
        self.goal_unsent = 0;
        self.misses = 0;
        self.decoder.clear();
    }
}

impl Driver for ExampleDriver {
    fn model(&self) -> Model {
        crate::MODEL
    }

    fn channel_count(&self) -> usize {
        CHANNELS
    }

    fn capabilities(&self, channel: usize) -> GoalKinds {
        if channel < CHANNELS {
            goals::KINDS
        } else {
            GoalKinds::NONE
        }
    }

    /// One step a second, and one step a second², the board's integer units.
    fn rate_floor(&self, channel: usize) -> RateFloor {
        if channel < CHANNELS {
            RateFloor {
                velocity: 1.0,
                profile_velocity: 1.0,
                accel: 1.0,
            }
        } else {
            RateFloor::NONE
        }
    }

    fn refresh_budget(&self) -> Duration {
        self.config
            .poll_period
            .saturating_mul(3)
            .saturating_add(Duration::from_millis(20))
    }

    fn handle_rx(&mut self, now: Duration, bytes: &[u8]) {
        self.receive(now, bytes);
    }

    fn handle_timeout(&mut self, now: Duration) {
        self.pass_time(now);
    }

    fn handle_written(&mut self, at: Duration) {
        if let Some(in_flight) = &mut self.in_flight {
            in_flight.written_at.get_or_insert(at);
        }
    }

    fn handle_heard(&mut self, until: Duration) {
        self.heard = Some(until);
    }

    fn poll_timeout(&self) -> Option<Duration> {
        if !self.link_up {
            return None;
        }
        let reply_deadline = self.reply_deadline();
        let next = match self.phase {
            Phase::Identify { next_at, .. } => next_at,
            Phase::Running => self.next_poll_at,
        };
        Some(reply_deadline.map_or(next, |deadline| deadline.min(next)))
    }

    fn wants_transmit(&self, now: Duration) -> Option<Priority> {
        self.next_request(now).map(|(_, priority)| priority)
    }

    fn poll_transmit(&mut self, now: Duration, buf: &mut [u8]) -> Option<Transmit> {
        self.transmit(now, buf)
    }

    fn awaiting_reply(&self) -> bool {
        self.in_flight.is_some()
    }

    fn goals_pending(&self) -> bool {
        self.commands.iter().any(Option::is_some)
            || self
                .in_flight
                .is_some_and(|f| exchange::is_command(&f.request))
    }

    fn set_goal(&mut self, now: Duration, channel: usize, goal: Goal) -> Result<(), GoalError> {
        let _ = now;
        if channel >= CHANNELS {
            return Err(GoalError::NoSuchChannel(channel));
        }
        if !goals::KINDS.contains(goal.kind()) {
            return Err(GoalError::Unsupported(goal.kind()));
        }
        if !self.link_up || self.status.fault == Some(DeviceFault::NotResponding) {
            return Err(GoalError::Offline);
        }
        if self.phase != Phase::Running {
            return Err(GoalError::Starting);
        }
        let request = goals::request(channel as u8, goal, self.config.limits[channel])?;
        let slot = &mut self.channels[channel];
        slot.target = match request {
            Request::Move { target, .. } => Some(target),
            _ => None,
        };
        slot.state.arrived = false;
        slot.fault = None;
        self.commands[channel] = Some(request);
        self.goal_unsent |= 1 << channel;
        Ok(())
    }

    fn channel(&self, channel: usize) -> ChannelState {
        let Some(slot) = self.channels.get(channel) else {
            return ChannelState::UNKNOWN;
        };
        let mut state = slot.state;
        state.fault = self.status.fault.or(slot.fault);
        state
    }

    fn status(&self) -> DeviceStatus {
        self.status
    }

    fn link_down(&mut self, now: Duration) {
        self.link_up = false;
        self.heard = None;
        self.raise(DeviceFault::LinkDown);
        self.restart(now, 0);
    }

    fn link_up(&mut self, now: Duration) {
        self.link_up = true;
        self.heard = None;
        self.restart(now, 0);
    }
}
