//! Driver of the **QuadQuad2Drv** board (model id `qq2drv`): four DC motors with
//! quadrature encoders and the board's own PID loops, an SPI slave (mode 1, ≤ 500 kHz).
//!
//! Every byte goes through the `qq2drv` protocol crate; this module decides *what* to send
//! and *when*, and what the answers mean. It never reads a clock, never touches a file
//! descriptor and allocates nothing after [`Qq2drvDriver::new`].
//!
//! # The wire (no SRDY)
//!
//! The driver does not use the SRDY line. MISO is clocked while MOSI comes in, so the board
//! can only answer in a later transaction than the request (docs/ARCHITECTURE.md); it clocks filler
//! while it has nothing ready. Every [`Qq2drvDriverConfig::poll_period`] the driver clocks
//! out one transaction of filler (0x00) as long as one stream packet plus a reply
//! ([`POLL_SLACK`] bytes), and feeds *every* MISO byte of its transactions — polls and
//! commands alike — to a [`StreamDecoder`], which finds STX after filler or garbage and
//! drops bad sizes, ids and checksums. At 500 kHz a 4-channel stream packet with
//! position, velocity, status and the timing field is 42 bytes ≈ 0.7 ms, so a 48-byte poll
//! per 1 ms tick keeps up. The driver tracks the wire time of what it has sent: a poll is
//! skipped while half a poll period of earlier bytes is still on the wire, and goals wait
//! while a whole one is (a newer goal for a channel replaces its unsent one), so a client
//! sending goals every tick cannot build an ever-growing backlog on the bus. Requests go
//! out as their own transactions, before polls ([`Priority::Setup`] / [`Priority::Command`]); the board
//! answers requests in order, each with its packet id, so answers are matched to the
//! oldest unanswered request with that id (skipped ones are lost). A packet a transaction
//! ended in the middle of is read out entirely before the next request ("Master reads out
//! one entire packet", SPI Interface): its rest is clocked with filler at the start of the
//! request's own transaction (a packet whose size has not come yet: a poll first). A
//! goal's transaction therefore goes out in the tick that set it, behind at most the
//! link's transaction in progress (`tests/engine_qq2drv/wire.rs`).
//!
//! # Start-up
//!
//! 1. Probe: Get Version (1), Get Data Mask (7), Get Stream Config (9), Get Stream Period
//!    (5) in one transaction. The firmware text becomes `"fw <major>.<minor> protocol <p>"`.
//!    Without a complete answer it is sent again every reply timeout, after
//!    [`START_ATTEMPTS`] tries every [`OFFLINE_RETRY_PERIOD`]. The answers give the layout
//!    the board streams in now.
//! 2. If the board had been configured by this driver before and the masks, stream config
//!    or stream period are no longer ours (power-up defaults: period 0), the board has
//!    reset: [`DeviceFault::Reset`], declared with what the probe read (the verdict's
//!    evidence), every channel's goal is gone (the motors are Off).
//! 3. Configure, in one transaction: history dimensions (12), data masks (6: 32-bit
//!    absolute position, velocity and status for channels with an axis, the Status byte
//!    alone for a channel whose pins a signal reads, nothing for the others), stream
//!    config (8: Stream Period Timing), and for each channel with an axis its power limit
//!    (24, [`ChannelConfig::power_limit`]), velocity limit (26) and acceleration limit (28)
//!    from its axis limits (transitions/s and /s² shl 12, clipped to the board's ranges),
//!    position and velocity PID constants (30, 32: always written, the datasheet defaults
//!    unless configured, so a board left with other gains is put right), the home inputs'
//!    polarity and Spacing (14, Disabled), and last the stream period (4): the largest
//!    whole number of 40.96 µs units not above the poll period. Any non-zero return code
//!    is [`DeviceFault::BoardError`] and the start-up is retried. All of it is written
//!    again after every probe, so after a board reset too.
//! 4. Running: stream packets refresh the channels; the first one clears board faults.
//!
//! # Goals (counts = quadrature transitions)
//!
//! Each goal is one transaction of up to five one-entry packets for its channel. A step
//! first puts back what an earlier one left: a home input still armed (14 Disabled) and an
//! acceleration limit a stop lifted (28 ← the axis's).
//!
//! | goal | packets |
//! |---|---|
//! | `Off` | 16 Off: "Motor output will be set to zero / off"; the next goal sets its own mode again |
//! | `Power` | 16 Power, 18 round(fraction × 8191) (I16) |
//! | `Position` | 16 Position PID, 20 target (the start-up limits shape the move) |
//! | `RampPosition` | 16 Position PID, 34 target, velocity shl 12, acceleration shl 12 |
//! | `Velocity` | 16 Velocity PID, 36 velocity (plain transitions/s, ±100 000), acceleration shl 12. With `velocity_ramp = "unsigned"` (packet 36 "Range: 0 - 100,000", [`ChannelConfig::velocity_ramp`]) every reverse velocity target of this table (jog, stop reset, home search) goes out as 28 ← the ramp's acceleration (none without a ramp) and 22 instead, the channel's own limit written back by the next step |
//! | `Stop` | planned when it is sent, from the velocity the board measures then (never from a commanded one). At standstill (≤ [`STANDSTILL`]): 16 Position PID, 20 target = the reported position. Else three transactions: (1) 16 Off, 16 Velocity PID (the loop starts afresh), 28 ← 0 ("A value of zero disables acceleration limiting") and 36 velocity = the measured one with acceleration 0 ("Set to 0 to ignore this parameter"): the board's velocity setpoint is now where the motor really runs, not where the last goal asked it to run (a saturated motor would otherwise keep full power while the setpoint ramps down from the commanded speed); (2) one loop period ([`LOOP_PERIOD`]) after (1) was answered, 36 velocity 0 at `decel` (clipped to the board's range); (3) when that ramp has run (\|v\| / decel) plus a loop period, 28 ← the axis's limit, 16 Position PID, 20 target = the reported position. Always sent, also on a channel the driver believes idle; it waits for data measured after start-up, a restart or a reset |
//! | `SetPosition` | 10 position counter ← counts (I32); unless the motor is Off, 16 Position PID and 20 target = counts (hold there) |
//! | `Home` | with a [`HomeInput`] configured: 14 armed (mode, polarity, Spacing, set the counter to `position` on the switch's end), 16 Velocity PID, 36 ± velocity towards the switch; on the Input Trigger Accumulator bit of that end (positive for INDEX) in a stream status: a `Stop` at the axis's max acceleration, whose first packet disarms the input (14 Disabled). An EDGE input already active first backs off the switch. A stop or any other goal mid-search disarms the input first. Without a home input: `Unsupported` |
//!
//! Values the board cannot represent are `OutOfBoardRange`: positions beyond I32, velocity
//! targets beyond ±100 000 transitions/s, shl-12 velocities and accelerations that round to
//! 0 (which would mean "not limited") or exceed 100 000 / 1 000 000 shl 12.
//!
//! # I/O
//!
//! [`PINS`]: per channel the IN pin (Input Active) and the Status accumulators (see the
//! `pins` module docs), read from the stream; no outputs.
//!
//! # Faults
//!
//! - No stream packet for the stall time (4 stream periods + 3 × the cadence + 2 ms): the
//!   driver checks the stream with Get Stream Period (5), nothing voided, at most once a
//!   stall time; an answer other than the period start-up wrote (0 at power-up) sends it
//!   back to its probe (start-up step 1), which finds a board that reset in step 2. The
//!   cadence is the poll period, or the interval between the caller's last two
//!   `handle_timeout` calls when that is longer: a slow or late tick leaves data as old as
//!   the tick, which is not the board's fault.
//! - No valid packet at all for [`Qq2drvDriverConfig::silence`] (`silence_ms`, 500 ms by
//!   default), judged up to the link's horizon: [`DeviceFault::NotResponding`], declared
//!   with the evidence (since when, how long, the oldest request unanswered). MISO held
//!   back on the host comes later, in order, and is waited for (module `liveness`); the
//!   axes show stale data meanwhile.
//! - A goal answered with a non-zero return code: [`DeviceFault::BoardError`] on that
//!   channel; a status with the glitch or overspeed bit: [`DeviceFault::Overspeed`]. Both
//!   stay until the channel's next goal.
//! - A request past its reply timeout is lost once the board was heard for a whole reply
//!   window after that (packets it made after the reply), or when a later request's reply
//!   came first: a goal's packets are sent again, a start-up is restarted. A reply that
//!   comes for a request already lost is recognised ([`Qq2drvDriver::late_replies`]),
//!   never paired.
//! - Garbage on MISO costs the packets it hides; the channels keep their last state.

mod channel;
mod config;
mod goals;
mod liveness;
mod pins;
mod rx;
mod spec;
mod startup;
mod wire;

use core::time::Duration;

use qq2drv::{CHANNELS, DataMask, MotionLayout, PositionSize, StreamConfig, StreamDecoder};

use motion_drivers::{
    ChannelState, DeviceFault, DeviceStatus, Driver, Goal, GoalError, GoalKinds, IoStamps, Model,
    Pin, PinReading, Priority, RateFloor, Transmit,
};

pub use channel::{ARRIVED_WITHIN, LOOP_PERIOD, STANDSTILL, STOP_SETTLE};
pub use config::{
    AxisLimits, ChannelConfig, HomeInput, PositionPid, Qq2drvDriverConfig, VelocityPid,
};
pub use pins::{PINS, PINS_PER_CHANNEL, pin_of};
pub use wire::IN_FLIGHT_CAPACITY;

use channel::Channel;
use pins::InputBits;
use startup::ProbeReplies;
use wire::InFlight;

/// Probe attempts before the board is declared not responding.
pub const START_ATTEMPTS: u32 = 3;
/// Probe period once the board has been declared not responding.
pub const OFFLINE_RETRY_PERIOD: Duration = Duration::from_millis(100);
/// Bytes a poll clocks beyond one stream packet (room for a reply).
pub const POLL_SLACK: usize = 6;
/// The MOSI filler byte of a poll.
pub const FILLER: u8 = 0x00;
/// Data mask of an enabled channel: 32-bit absolute position, velocity, status.
pub const STREAM_MASK: DataMask = DataMask::new(PositionSize::I32, false, true, true);
/// Data mask of a channel without an axis whose pins a signal reads: Status only.
pub const STATUS_MASK: DataMask = DataMask::new(PositionSize::Omitted, false, false, true);
/// Stream config: Stream Period Timing only.
pub const STREAM_CONFIG: StreamConfig = StreamConfig::new(true, false);
/// Configuration requests written at start-up, at most.
const CONFIGURE_REQUESTS: usize = 10;

/// Start-up and running phases.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// Reading version and stream layout; the next probe at `next_at`.
    Probe { attempts: u32, next_at: Duration },
    /// The configuration is written; waiting for its answers.
    Configure,
    /// Streaming.
    Running,
}

/// Sans-I/O driver of one QuadQuad2Drv board. See the module docs.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub struct Qq2drvDriver {
    config: Qq2drvDriverConfig,
    status: DeviceStatus,
    phase: Phase,
    link_up: bool,
    channels: [Channel; CHANNELS],
    /// The Status bits of each channel, for the pins.
    inputs: [InputBits; CHANNELS],
    decoder: StreamDecoder,
    in_flight: InFlight,
    /// The layout the board streams in, as acknowledged.
    layout: MotionLayout,
    probe: ProbeReplies,
    probe_due: bool,
    configure_due: bool,
    /// Configuration writes not yet answered.
    setup_unanswered: u32,
    configured_once: bool,
    next_poll_at: Duration,
    /// When the bus is done with the transactions this driver wrote.
    line_free_at: Duration,
    last_valid_at: Option<Duration>,
    last_stream_at: Duration,
    stream_packets: u64,
    /// The previous `handle_timeout` call and the interval before this one.
    last_call_at: Option<Duration>,
    call_interval: Duration,
    /// The link's write reports and horizon.
    io_stamps: IoStamps,
    /// The message the last probe went out in.
    probe_number: u64,
    /// Since when the driver listens (its first `handle_timeout`, or the link's coming
    /// up): silence before any valid packet counts from here.
    listening_since: Option<Duration>,
    /// The stream stalls: a Get Stream Period is due (module `liveness`).
    check_due: bool,
    /// No stream check before this instant.
    check_after: Duration,
    /// Packet ids of the requests declared lost last: a reply with one of them that
    /// matches nothing in flight is late, not bad.
    lost_ids: motion_base::FixedQueue<qq2drv::PacketId, LOST_IDS>,
    /// Late replies recognised (module `liveness`).
    late_replies: u64,
}

/// Lost requests whose late replies are recognised.
const LOST_IDS: usize = 16;

impl Qq2drvDriver {
    /// A driver for the board `config` describes; it starts the board on its first
    /// `handle_timeout` / `poll_transmit`.
    pub fn new(config: Qq2drvDriverConfig) -> Self {
        let channels = config.channels.map(Channel::new);
        Self {
            config,
            status: DeviceStatus::UNKNOWN,
            phase: Phase::Probe {
                attempts: 0,
                next_at: Duration::ZERO,
            },
            link_up: true,
            channels,
            inputs: [InputBits::default(); CHANNELS],
            decoder: StreamDecoder::new(),
            in_flight: InFlight::new(),
            layout: MotionLayout::default(),
            probe: ProbeReplies::default(),
            probe_due: false,
            configure_due: false,
            setup_unanswered: 0,
            configured_once: false,
            next_poll_at: Duration::ZERO,
            line_free_at: Duration::ZERO,
            last_valid_at: None,
            last_stream_at: Duration::ZERO,
            stream_packets: 0,
            last_call_at: None,
            call_interval: Duration::ZERO,
            io_stamps: IoStamps::default(),
            probe_number: 0,
            listening_since: None,
            check_due: false,
            check_after: Duration::ZERO,
            lost_ids: motion_base::FixedQueue::new(),
            late_replies: 0,
        }
    }

    /// The configuration the driver was built from.
    pub fn config(&self) -> &Qq2drvDriverConfig {
        &self.config
    }

    /// Stream packets decoded since creation.
    pub fn stream_packets(&self) -> u64 {
        self.stream_packets
    }

    /// The MISO decoder's counters (filler skipped, bad packets).
    pub fn decoder_stats(&self) -> qq2drv::DecoderStats {
        self.decoder.stats()
    }

    /// Whether the board is configured and streaming.
    pub fn running(&self) -> bool {
        self.link_up && self.phase == Phase::Running
    }

    fn raise(&mut self, fault: DeviceFault) {
        if self.link_up || fault == DeviceFault::LinkDown {
            self.status.fault = Some(fault);
        }
    }
}

impl Driver for Qq2drvDriver {
    fn model(&self) -> Model {
        Model::QQ2DRV
    }

    fn channel_count(&self) -> usize {
        CHANNELS
    }

    fn capabilities(&self, channel: usize) -> GoalKinds {
        self.kinds(channel)
    }

    /// Packet 36's velocity is plain transitions/s (the step of a velocity goal and of a
    /// search); packet 34's profile velocity and every acceleration are transitions/s (/s²)
    /// shl 12.
    /// The board's own trapezoid (packet 34 with velocity and acceleration) takes a new
    /// target in any SPI transaction; a bare position target (its PID alone) saturates and
    /// lags a moving path by whole millimetres.
    fn follow(&self, channel: usize) -> motion_drivers::Follow {
        let _ = channel;
        motion_drivers::Follow::Segments
    }

    fn rate_floor(&self, channel: usize) -> RateFloor {
        if self.kinds(channel) == GoalKinds::NONE {
            return RateFloor::NONE;
        }
        let fixed = 1.0 / f64::from(1u32 << qq2drv::limits::FIXED_SHIFT);
        RateFloor {
            velocity: 1.0,
            profile_velocity: fixed,
            accel: fixed,
        }
    }

    fn refresh_budget(&self) -> Duration {
        self.stall_timeout()
            .saturating_add(self.cadence().saturating_mul(4))
            .saturating_add(Duration::from_millis(4))
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
        let reply = self
            .in_flight
            .front()
            .map(|sent| sent.at.saturating_add(self.reply_timeout()));
        let phase = match self.phase {
            Phase::Probe { next_at, .. } => Some(next_at),
            Phase::Configure => None,
            Phase::Running => Some(
                self.next_poll_at
                    .min(self.last_stream_at.saturating_add(self.stall_timeout())),
            ),
        };
        let poll = (!self.in_flight.is_empty()).then_some(self.next_poll_at);
        [reply, phase, poll].into_iter().flatten().min()
    }

    fn wants_transmit(&self, now: Duration) -> Option<Priority> {
        self.next(now).map(|(_, priority)| priority)
    }

    fn poll_transmit(&mut self, now: Duration, buf: &mut [u8]) -> Option<Transmit> {
        self.transmit(now, buf)
    }

    fn awaiting_reply(&self) -> bool {
        !self.in_flight.is_empty()
    }

    fn goals_pending(&self) -> bool {
        self.channels
            .iter()
            .any(|c| c.config.enabled && c.pending())
    }

    fn set_goal(&mut self, _now: Duration, channel: usize, goal: Goal) -> Result<(), GoalError> {
        self.plan_goal(channel, goal)
    }

    fn channel(&self, channel: usize) -> ChannelState {
        match self.channels.get(channel) {
            Some(c) if c.config.enabled => {
                let mut state = c.state();
                state.fault = self.status.fault.or(state.fault);
                state
            }
            _ => ChannelState::UNKNOWN,
        }
    }

    fn status(&self) -> DeviceStatus {
        self.status
    }

    fn link_down(&mut self, now: Duration) {
        self.io_stamps.link_reset();
        self.link_up = false;
        self.raise(DeviceFault::LinkDown);
        self.status.online = false;
        self.restart(now);
        for channel in &mut self.channels {
            channel.stop_after_link_loss();
        }
    }

    fn link_up(&mut self, now: Duration) {
        self.io_stamps.link_reset();
        self.link_up = true;
        self.listening_since = None;
        self.line_free_at = now;
        self.next_poll_at = now;
        self.last_valid_at = None;
        self.restart(now);
    }

    fn read_pin(&self, pin: Pin) -> Option<PinReading> {
        let (channel, index) = pins::locate(pin)?;
        let configured = self.config.channels.get(channel)?.pins & (1 << index) != 0;
        configured.then(|| self.inputs.get(channel).map(|bits| bits.reading(index)))?
    }
}

#[cfg(test)]
mod tests;
