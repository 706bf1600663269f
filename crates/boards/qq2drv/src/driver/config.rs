//! What a [`Qq2drvDriver`](super::Qq2drvDriver) is built from.

use core::time::Duration;

use qq2drv::limits::{
    POSITION_PID_DEFAULT, POWER_LIMIT_MAX, STREAM_TICK_NS, VELOCITY_PID_DEFAULT, VelocityRampSign,
};
use qq2drv::{CHANNELS, HistoryDimensions, InputMode};

pub use motion_drivers::spec::AxisLimits;

/// A channel's limits when no axis is configured on it, transitions/s and /s².
const DEFAULT_LIMITS: AxisLimits = AxisLimits {
    max_velocity: 5_000.0,
    max_accel: 50_000.0,
};

/// How a channel's IN pin finds home (packet 14), when something is wired to it.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub struct HomeInput {
    /// Home (acts while active), Index (active and A = B = 0) or Edge (inactive → active).
    /// `Disabled` makes the channel unable to home.
    pub mode: InputMode,
    /// Input Polarity: the pin is active when high (`true`) or low (`false`).
    pub active_high: bool,
    /// The switch is at the positive end: the search runs in the positive direction and the
    /// counter is set on a positive-end trigger (Edge `SetOnPositive`, Spacing 0: a single
    /// end-stop). `false`: negative direction, `SetOnNegative`.
    pub positive_end: bool,
    /// The value the board writes into the position counter on the trigger, transitions.
    pub position: i32,
    /// Packet 14 Spacing, transitions: 0 = a single end-stop (the Edge field names its
    /// end); any other value = two end-stops (or a rotary sensor) on the one input, with
    /// this hysteresis between a positive-end and a negative-end trigger.
    pub spacing: u16,
}

/// Position PID constants of one channel (packet 30). The datasheet documents their
/// defaults but not their units.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub struct PositionPid {
    /// Proportional constant ("Default: 100").
    pub p: u16,
    /// Integration constant ("Default: 500").
    pub i: u16,
    /// Differential constant ("Default: 500").
    pub d: u16,
    /// Integration windup limit, 0..=8191 ("Default: 600").
    pub windup: u16,
}

impl Default for PositionPid {
    /// The datasheet's defaults (packet 30).
    fn default() -> Self {
        let (p, i, d, windup) = POSITION_PID_DEFAULT;
        Self { p, i, d, windup }
    }
}

/// Velocity PID constants of one channel (packet 32).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub struct VelocityPid {
    /// Proportional constant ("Default: 100").
    pub p: u16,
    /// Integration constant ("Default: 200").
    pub i: u16,
    /// Differential constant ("Default: 500").
    pub d: u16,
}

impl Default for VelocityPid {
    /// The datasheet's defaults (packet 32).
    fn default() -> Self {
        let (p, i, d) = VELOCITY_PID_DEFAULT;
        Self { p, i, d }
    }
}

/// One of the board's four channels.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq)]
pub struct ChannelConfig {
    /// An axis is connected: the channel is streamed and takes goals. A disabled channel
    /// has no capabilities and is left out of the stream (its data mask is 0).
    pub enabled: bool,
    /// The axis limits in board counts (quadrature transitions), as configured for the
    /// axis on the channel. Start-up writes them as the channel's velocity limit (packet
    /// 26) and acceleration limit (packet 28), clipped to the board's ranges.
    pub limits: AxisLimits,
    /// Power limit written at start-up (packet 24), 0..=8191.
    pub power_limit: u16,
    /// The channel's home input; `None`: `Goal::Home` is unsupported.
    pub home: Option<HomeInput>,
    /// Position PID constants written at start-up (packet 30), always: a board left with
    /// other gains by another program is put right.
    pub position_pid: PositionPid,
    /// Velocity PID constants written at start-up (packet 32), always.
    pub velocity_pid: VelocityPid,
    /// The I/O pins of this channel a signal reads (bit `k` = pin `k` of the channel's six,
    /// see [`PINS`](super::PINS)). A channel without an axis but with a pin is streamed
    /// with its Status byte only.
    pub pins: u8,
    /// How the board reads packet 36's Velocity (the device's `velocity_ramp` key):
    /// signed (default), or forward only, when a reverse velocity goes out as packet 28
    /// (the ramp's acceleration as the limit) and packet 22, the channel's own limit
    /// written back by the next step.
    pub velocity_ramp: VelocityRampSign,
}

impl Default for ChannelConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            limits: DEFAULT_LIMITS,
            power_limit: POWER_LIMIT_MAX,
            home: None,
            position_pid: PositionPid::default(),
            velocity_pid: VelocityPid::default(),
            pins: 0,
            velocity_ramp: VelocityRampSign::Signed,
        }
    }
}

/// Everything the driver needs to know about one QuadQuad2Drv board (it has no address:
/// one board per chip select).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, PartialEq)]
pub struct Qq2drvDriverConfig {
    /// SPI clock of the link, Hz (the datasheet recommends up to 500 kHz): sizes the wire
    /// budget and the reply timeout.
    pub speed_hz: u32,
    /// How often the driver clocks out filler to read what the board has (no SRDY). The
    /// stream period is set to the largest whole number of 40.96 µs units not above it.
    pub poll_period: Duration,
    /// Velocity averaging written at start-up (packet 12). The default keeps the History
    /// Length of 31 but averages over at most 2^16 × 0.64 µs ≈ 42 ms instead of 671 ms, so
    /// the reported velocity reaches 0 soon after a stop.
    pub history: HistoryDimensions,
    /// The board's request processing time budget (the datasheet gives none).
    pub processing_time: Duration,
    /// How long the board may put no valid packet on MISO before it is declared not
    /// answering (`silence_ms`, default [`DEFAULT_SILENCE`](motion_drivers::DEFAULT_SILENCE)):
    /// MISO held back on the host (an SPI socket peer or the server without CPU) comes
    /// later, in order, and is waited for.
    pub silence: Duration,
    /// Channels 1..4 (index 0..3).
    pub channels: [ChannelConfig; CHANNELS],
}

impl Default for Qq2drvDriverConfig {
    fn default() -> Self {
        Self {
            speed_hz: 500_000,
            poll_period: Duration::from_millis(1),
            history: HistoryDimensions {
                history_length: 31,
                averaging_bits: 16,
            },
            processing_time: Duration::from_millis(1),
            silence: motion_drivers::DEFAULT_SILENCE,
            channels: [ChannelConfig::default(); CHANNELS],
        }
    }
}

impl Qq2drvDriverConfig {
    /// Wire time of `bytes` at the configured SPI clock.
    pub fn wire_time(&self, bytes: usize) -> Duration {
        let bits = 8 * bytes as u64;
        Duration::from_nanos(bits.saturating_mul(1_000_000_000) / u64::from(self.speed_hz.max(1)))
    }

    /// The Stream Period written by start-up (packet 4), in 40.96 µs units: the largest
    /// whole number of units not above `poll_period`, at least 1.
    pub fn stream_period_units(&self) -> u16 {
        let units = self.poll_period.as_nanos() / u128::from(STREAM_TICK_NS);
        u16::try_from(units).unwrap_or(u16::MAX).max(1)
    }

    /// The stream period as a duration.
    pub fn stream_period(&self) -> Duration {
        qq2drv::limits::stream_units_to_duration(self.stream_period_units())
    }
}
