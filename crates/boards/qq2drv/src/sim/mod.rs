//! Simulated QuadQuad2Drv: four DC motors with quadrature encoders behind the board's SPI
//! slave firmware.
//!
//! The model decodes requests and encodes replies with the `qq2drv` protocol crate, so the
//! bytes are the crate's. Wire rules it keeps:
//! - a reply becomes ready [`Qq2drvSimConfig::processing_time`] after its request finished
//!   arriving and never starts in the transaction that carried the request (MISO is clocked
//!   while MOSI comes in); until then, and whenever nothing is ready, MISO carries
//!   [`Qq2drvSimConfig::filler`] (the master polls without SRDY by clocking filler out);
//! - bytes are placed in time at [`Qq2drvSimConfig::spi_clock_hz`] inside a transaction,
//!   which completes at the `now` it is given;
//! - stream packets (packet 3) fall every Stream Period from the moment packet 4 was
//!   processed, are available [`Qq2drvSimConfig::stream_overhead`] later, and a period is
//!   missed while the previous stream packet has not been read out entirely.
//!
//! Return codes other than 0 are not documented; this model answers 1 when a payload does
//! not decode ([`RC_MALFORMED`]) and 2 when a value is outside its documented range
//! ([`RC_OUT_OF_RANGE`]), applying nothing of that packet. Targets sent while the channel is
//! in another control mode succeed and are forgotten on the next mode change (the datasheet
//! only says the mode "must be set"): entering position mode holds the current position,
//! entering velocity mode ramps from the current velocity towards 0, until a target arrives.
//!
//! Physics and loop: each channel is a first-order DC motor (dead band for static friction)
//! driving an encoder; velocity is reported from capture events (one per detent) averaged
//! over the History Dimensions; the loop runs every 2 ms on the integer counter with the
//! PID scaling documented in `control.rs`; the velocity and acceleration limits bound the
//! loop's setpoint profile, the power limit its output.

mod channel;
mod config;
mod control;
mod inputs;
pub(crate) mod machine;
mod physics;
mod ramp;
mod registers;
#[cfg(test)]
mod tests;
mod wire;

use core::time::Duration;

use motion_link::sim::SpiDevice;
use qq2drv::{
    CHANNELS, ControlMode, DataMask, HistoryDimensions, InputConfig, MotionLayout,
    PositionPidEntry, VelocityPidEntry,
};

pub use config::{InputPin, InputSource, MotorConfig, Qq2drvSimConfig};

use channel::Channel;
use motion_sim::rng::SimRng;
use wire::{StreamClock, Wire};

/// Return code of a request whose payload does not decode (a choice of this model).
pub const RC_MALFORMED: u8 = 1;
/// Return code of a request with a value outside its documented range (a choice of this model).
pub const RC_OUT_OF_RANGE: u8 = 2;

/// The PID loop period (500 Hz).
const CONTROL_PERIOD: Duration = Duration::from_millis(2);
/// Longest physics integration step.
const SUBSTEP: Duration = Duration::from_micros(100);

/// Board registers that survive between packets.
#[derive(Debug, Clone, Copy, Default)]
struct Registers {
    /// Data masks (packet 6) and stream config (packet 8).
    layout: MotionLayout,
    history: HistoryDimensions,
}

/// Counters of what the model has done on the wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Qq2drvSimStats {
    /// Requests decoded from MOSI (including rejected ones).
    pub requests: u64,
    /// Requests answered with a non-zero return code.
    pub rejected: u64,
    /// Replies dropped because too many were queued.
    pub dropped_replies: u64,
    /// Stream packets produced.
    pub stream_packets: u64,
    /// Stream periods missed because the master had not read the previous packet out.
    pub stream_missed: u64,
    /// Bad MOSI packets (wrong checksum, size or id).
    pub bad_packets: u64,
    /// Requests that began while a packet begun in an earlier transaction was still being
    /// clocked out: the master had not read out that packet entirely ("Master reads out
    /// one entire packet", SPI Interface). A master that keeps to it never makes one.
    pub interlaced: u64,
}

/// The simulated board.
#[derive(Debug)]
pub struct Qq2drvSim {
    config: Qq2drvSimConfig,
    rng: SimRng,
    /// Physics time.
    now: Duration,
    next_control: Duration,
    channels: [Channel; CHANNELS],
    regs: Registers,
    wire: Wire,
    stream: StreamClock,
    requests: u64,
    rejected: u64,
    interlaced: u64,
}

impl Qq2drvSim {
    /// A board at power-up with the shafts at position 0.
    pub fn new(config: Qq2drvSimConfig) -> Self {
        let mut rng = SimRng::new(config.seed);
        let channels = core::array::from_fn(|i| {
            let motor = config.motors.get(i).copied().unwrap_or_default();
            let pin = config.inputs.get(i).copied().unwrap_or_default();
            let gain = 1.0 + motor.gain_spread * (2.0 * rng.next_f64() - 1.0);
            Channel::new(motor, gain, pin)
        });
        let wire = Wire::new(config.max_queued_replies);
        Self {
            config,
            rng,
            now: Duration::ZERO,
            next_control: CONTROL_PERIOD,
            channels,
            regs: Registers::default(),
            wire,
            stream: StreamClock::default(),
            requests: 0,
            rejected: 0,
            interlaced: 0,
        }
    }

    /// The configuration the model was built from.
    pub fn config(&self) -> &Qq2drvSimConfig {
        &self.config
    }

    /// Physics time the model has reached.
    pub fn now(&self) -> Duration {
        self.now
    }

    /// True shaft position of `channel` (0-based) in quadrature transitions since power-up.
    pub fn true_position(&self, channel: usize) -> Option<f64> {
        self.channels.get(channel).map(|c| c.motor.position())
    }

    /// True shaft velocity in transitions/s.
    pub fn true_velocity(&self, channel: usize) -> Option<f64> {
        self.channels.get(channel).map(|c| c.motor.velocity())
    }

    /// The position counter the board reports (32-bit register).
    pub fn counter(&self, channel: usize) -> Option<i32> {
        self.channels.get(channel).map(Channel::counter_i32)
    }

    /// The velocity the board would report now (capture-event average).
    pub fn measured_velocity(&self, channel: usize) -> Option<i32> {
        let (len, avg) = self.history_params();
        let t = self.now.as_secs_f64();
        self.channels
            .get(channel)
            .map(|c| c.motor.measured_velocity(t, len, avg))
    }

    /// Power applied to the motor output, −8191..=8191.
    pub fn motor_power(&self, channel: usize) -> Option<i16> {
        self.channels.get(channel).map(|c| c.motor.power())
    }

    /// Control mode of the channel.
    pub fn control_mode(&self, channel: usize) -> Option<ControlMode> {
        self.channels.get(channel).map(|c| c.control.mode)
    }

    /// The loop's internal position setpoint (position mode), in counter units.
    pub fn position_setpoint(&self, channel: usize) -> Option<f64> {
        self.channels
            .get(channel)
            .map(|c| c.control.profile.position)
    }

    /// Whether the position setpoint has reached its target and stopped.
    pub fn setpoint_settled(&self, channel: usize) -> Option<bool> {
        self.channels.get(channel).map(|c| c.control.profile.done())
    }

    /// The loop's internal velocity setpoint (velocity mode), transitions/s.
    pub fn velocity_setpoint(&self, channel: usize) -> Option<f64> {
        self.channels
            .get(channel)
            .map(|c| c.control.velocity_ramp.velocity)
    }

    /// The input configuration of packet 14 (mode, polarity, edge) and its Spacing.
    pub fn input_config(&self, channel: usize) -> Option<(InputConfig, u16)> {
        self.channels
            .get(channel)
            .map(|c| (c.input.config, c.input.spacing))
    }

    /// The power limit of packet 24, 0..=8191.
    pub fn power_limit(&self, channel: usize) -> Option<u16> {
        self.channels.get(channel).map(|c| c.control.power_limit)
    }

    /// The acceleration limit of packet 28, shl 12 (0 = not limited).
    pub fn acceleration_limit(&self, channel: usize) -> Option<u32> {
        self.channels
            .get(channel)
            .map(|c| c.control.acceleration_limit)
    }

    /// The position and velocity PID constants of packets 30 and 32.
    pub fn pid(&self, channel: usize) -> Option<(PositionPidEntry, VelocityPidEntry)> {
        self.channels
            .get(channel)
            .map(|c| (c.control.position_pid, c.control.velocity_pid))
    }

    /// Input Active (after polarity) as last evaluated.
    pub fn input_active(&self, channel: usize) -> Option<bool> {
        self.channels.get(channel).map(|c| c.input.active())
    }

    /// The last position recorded by a record-only input trigger.
    pub fn recorded_position(&self, channel: usize) -> Option<i64> {
        self.channels.get(channel).and_then(|c| c.input.recorded())
    }

    /// The configured data masks (packet 6/7).
    pub fn data_masks(&self) -> [DataMask; CHANNELS] {
        self.regs.layout.data_masks
    }

    /// The configured Stream Period (packet 4/5).
    pub fn stream_period(&self) -> u16 {
        self.stream.period
    }

    /// SRDY: a packet is ready to be read (the master may poll instead).
    pub fn packet_ready(&self, now: Duration) -> bool {
        self.wire.packet_ready(now)
    }

    /// The earliest instant something new becomes ready on MISO (a reply, a stream tick).
    pub fn next_event(&self) -> Option<Duration> {
        match (self.wire.next_ready(), self.stream.next_tick()) {
            (Some(a), Some(b)) => Some(a.min(b + self.config.stream_overhead)),
            (a, b) => a.or(b.map(|t| t + self.config.stream_overhead)),
        }
    }

    /// Wire counters.
    pub fn stats(&self) -> Qq2drvSimStats {
        Qq2drvSimStats {
            requests: self.requests,
            rejected: self.rejected,
            dropped_replies: self.wire.dropped,
            stream_packets: self.stream.produced,
            stream_missed: self.stream.missed,
            bad_packets: self.wire.rx.stats().bad_packets(),
            interlaced: self.interlaced,
        }
    }

    /// Test hook: move a channel's IN pin source (e.g. shift a switch position).
    pub fn set_input_pin(&mut self, channel: usize, pin: InputPin) {
        if let Some(c) = self.channels.get_mut(channel) {
            c.pin = pin;
        }
    }

    /// Test hook: force the IN pin's electrical level (`None` returns it to its source).
    pub fn force_input_level(&mut self, channel: usize, level_high: Option<bool>) {
        if let Some(c) = self.channels.get_mut(channel) {
            c.pin_override = level_high;
            c.evaluate_input();
        }
    }

    /// Test hook: an invalid A/B transition on the channel's quadrature lines.
    pub fn inject_glitch(&mut self, channel: usize) {
        if let Some(c) = self.channels.get_mut(channel) {
            c.latch_glitch();
        }
    }

    /// Test hook: an external force moves the shaft by `delta` transitions.
    pub fn displace_shaft(&mut self, channel: usize, delta: f64) {
        if let Some(c) = self.channels.get_mut(channel) {
            c.motor.displace(delta);
            c.evaluate_input();
        }
    }

    /// Test hook: power cycle / MCLR reset. Registers, counters and loops return to their
    /// start-up state, queued packets are lost; the shafts stay where they are (coasting).
    pub fn reset(&mut self) {
        self.regs = Registers::default();
        self.stream = StreamClock::default();
        self.wire.clear();
        for c in &mut self.channels {
            c.power_cycle();
        }
    }

    fn history_params(&self) -> (u8, f64) {
        let h = self.regs.history;
        let avg = qq2drv::limits::averaging_time(h.averaging_bits).as_secs_f64();
        (h.history_length, avg)
    }

    /// Advances physics, control loops and the stream clock to `until`.
    fn run_until(&mut self, until: Duration) {
        while self.now < until {
            let mut next = until.min(self.now + SUBSTEP).min(self.next_control);
            if let Some(t) = self.stream.next_tick() {
                next = next.min(t.max(self.now));
            }
            let dt = (next - self.now).as_secs_f64();
            let t_end = next.as_secs_f64();
            let glitch_velocity = self.config.glitch_velocity;
            let glitch_p = self.config.glitch_rate * dt;
            for c in &mut self.channels {
                c.step(dt, t_end, glitch_velocity);
                if glitch_p > 0.0 && self.rng.next_f64() < glitch_p {
                    c.latch_glitch();
                }
            }
            self.now = next;
            if self.now >= self.next_control {
                let period = CONTROL_PERIOD.as_secs_f64();
                for c in &mut self.channels {
                    c.control_tick(period);
                }
                self.next_control += CONTROL_PERIOD;
            }
            while let Some(t) = self.stream.next_tick()
                && t <= self.now
            {
                self.stream_tick(t);
            }
        }
    }

    fn stream_tick(&mut self, t: Duration) {
        let overhead = self.config.stream_overhead;
        let Some((timing, elapsed)) = self.stream.tick(t, overhead, self.wire.stream_in_flight())
        else {
            return;
        };
        if let Some(packet) = self.stream_packet(timing, elapsed) {
            self.wire.queue_stream(t + overhead, packet);
        }
    }

    fn byte_time(&self) -> Duration {
        let hz = u64::from(self.config.spi_clock_hz.max(1));
        Duration::from_nanos(8_000_000_000 / hz)
    }
}

impl SpiDevice for Qq2drvSim {
    fn transfer(&mut self, now: Duration, mosi: &[u8], miso: &mut [u8]) -> bool {
        let byte = self.byte_time();
        let total = byte.saturating_mul(u32::try_from(mosi.len()).unwrap_or(u32::MAX));
        let start = now.saturating_sub(total).max(self.now);
        self.run_until(start);
        self.wire.txn += 1;
        let filler = self.config.filler;
        let mut t = start;
        for i in 0..mosi.len().max(miso.len()) {
            let out = self.wire.miso_byte(t, filler);
            if let Some(m) = miso.get_mut(i) {
                *m = out;
            }
            t = (t + byte).min(now.max(start));
            if let Some(&b) = mosi.get(i) {
                let request_starts = b == qq2drv::STX && self.wire.rx.missing().is_none();
                if request_starts && self.wire.reading_older_packet() {
                    self.interlaced += 1;
                }
                self.receive_byte(t, b);
            }
        }
        self.run_until(now);
        true
    }

    fn advance(&mut self, now: Duration) {
        self.run_until(now);
    }
}

impl Default for Qq2drvSim {
    fn default() -> Self {
        Self::new(Qq2drvSimConfig::default())
    }
}
