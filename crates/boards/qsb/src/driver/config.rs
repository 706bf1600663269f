//! What a [`QsbDriver`](super::QsbDriver) is built from, and the wire budgets and unit
//! conversions that follow from it.

use core::time::Duration;

use ::qsb::{
    ACCEL_RANGE, EncoderMode, Eor, IntervalRate, JOG_RATE_RANGE, MAX_COMMAND_LEN, MAX_RESPONSE_LEN,
    PROCESSING_DELAY, ProductType, RATE_INCREMENT, STEP_RATE_RANGE, TICK, effective_rate,
};

use super::counter::CounterSetup;
pub use super::io::{EnableOutput, QsbIo};
use super::trigger::TriggerSetup;
use motion_drivers::DEFAULT_SILENCE;

/// Bits on the wire per byte (8N1).
const BITS_PER_BYTE: u64 = 10;

/// Stream periods without a sample before the driver asks the board whether it is still
/// there (and still streaming).
const SILENT_PERIODS: u32 = 4;

/// The EOR the driver writes: LF and the time stamp, no spaces, no CR
/// (`s0E00001234000ABCDE!\n`, 21 bytes). The time stamp is what the velocity is measured
/// with, and its loss (a board back at its saved EOR) is how a reset shows.
pub(crate) const DRIVER_EOR: Eor = Eor {
    line_feed: true,
    carriage_return: false,
    time_stamp: true,
    spaces: false,
};

/// Length of one response line in [`DRIVER_EOR`] format.
pub(crate) const DRIVER_LINE_LEN: u64 = 1 + 2 + 8 + 8 + 1 + 1;

/// Everything the driver needs to know about one QSB (the axis is channel 0: the encoder
/// counter and, on the -M, the stepper drive that moves it).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, PartialEq)]
pub struct QsbDriverConfig {
    /// The product the config expects (default -M). What VERSION reports wins: a -S or
    /// -D found where a -M was configured refuses drive goals with `Unsupported`.
    pub variant: ProductType,
    /// The line rate, baud (factory 230400): sizes reply timeouts and the stream period.
    pub baud: u32,
    /// Data output period in 1/512 s ticks (INTERVAL RATE, 1..=0xFFFE); `None`: the
    /// shortest period at which the encoder stream fills at most half the line (1 tick,
    /// 1.95 ms, at 230400 baud).
    pub stream_interval: Option<u16>,
    /// Extra time the host side may take to deliver bytes (USB scheduling, the serial
    /// driver's latency timer), added to every reply timeout and to the refresh budget.
    pub latency: Duration,
    /// How long the board may say nothing while it owes an answer before it is declared
    /// not answering (`silence_ms`, default [`DEFAULT_SILENCE`]): a reply delayed on the
    /// host (a stalled server, a board's process without CPU) arrives later, in order, and
    /// is waited for; nothing else is sent meanwhile (one command at a time).
    pub silence: Duration,
    /// Counter counts (in the [`CounterSetup::count`] mode: x4 by default) per motor step
    /// on the -M; negative when the encoder
    /// counts down while the motor steps forward. Default 10: a 500-cycle encoder on the
    /// shaft of a 200-step motor driven in full steps.
    pub counts_per_step: f64,
    /// The axis's velocity limit, counts/s (> 0): MD STEP RATE of plain position goals.
    pub max_velocity: f64,
    /// The axis's acceleration limit, counts/s² (> 0): MD ACCEL of plain position goals,
    /// of the home search and of the start-up stop.
    pub max_accel: f64,
    /// Home search direction in counts: `false` (default) searches towards negative
    /// counts.
    pub home_positive: bool,
    /// A home search that travels this far (counts) without an index pulse stops and
    /// reports [`DeviceFault::HomeFailed`](motion_drivers::DeviceFault::HomeFailed). Default 5000:
    /// two and a half turns of a 2000-count encoder.
    pub home_max_travel: f64,
    /// The counter value at the index (the home offset, counts): 0 uses MDR0 "reset CNTR"
    /// on the index (`W0363`); any other value is written to DTR and MDR0 "load CNTR"
    /// (transfers DTR to CNTR) is used, so the board itself sets it at the index.
    pub home_position: i32,
    /// MDR1 B3 "Encoder Index Polarity": invert the index (default: not inverted).
    pub invert_index: bool,
    /// -M: activate the motor drive (COMMAND 2) at start-up, so that channel 0 drives the
    /// stepper (default `true`; motiond sets it when an axis is configured on the -M in
    /// quadrature mode). Without it, DIG I/O bits 1 and 2 are free for signals.
    pub motor_drive: bool,
    /// -M: the external stepper driver's enable line on a DIG I/O bit. `Goal::Off` quits
    /// the motor and makes it inactive; the next motion goal (and `Stop`, which holds)
    /// makes it active first. Without it `Off` is `Unsupported` (set `enable_output` to
    /// the drive's enable line).
    pub enable: Option<EnableOutput>,
    /// MODE B1 B0: quadrature counting (default, channel 0 is an axis), or a PWM absolute
    /// encoder or the analog input, read as the `encoder` pin (no axis).
    pub input_mode: EncoderMode,
    /// The I/O pins signals read or drive.
    pub io: QsbIo,
    /// The counter mode of normal operation (MDR0, DTR).
    pub counter: CounterSetup,
    /// Capture on index, the trigger output and its compare position (MDR1 B4–B7, DIG
    /// I/O CONFIG B12, DTR).
    pub trigger: TriggerSetup,
}

impl Default for QsbDriverConfig {
    fn default() -> Self {
        Self {
            variant: ProductType::M,
            baud: 230_400,
            stream_interval: None,
            latency: motion_drivers::DEFAULT_HOST_LATENCY,
            silence: DEFAULT_SILENCE,
            counts_per_step: 10.0,
            max_velocity: 10_000.0,
            max_accel: 100_000.0,
            home_positive: false,
            home_max_travel: 5_000.0,
            home_position: 0,
            invert_index: false,
            motor_drive: true,
            enable: None,
            input_mode: EncoderMode::Quadrature,
            io: QsbIo::default(),
            counter: CounterSetup::default(),
            trigger: TriggerSetup::default(),
        }
    }
}

/// Time `bytes` take on the wire at `baud` (8N1).
pub(crate) fn wire_time(baud: u32, bytes: u64) -> Duration {
    let baud = u64::from(baud.max(1));
    Duration::from_nanos((bytes * BITS_PER_BYTE).saturating_mul(1_000_000_000) / baud)
}

impl QsbDriverConfig {
    /// INTERVAL RATE the driver writes: `stream_interval`, or the automatic choice.
    pub fn interval(&self) -> IntervalRate {
        let ticks = self.stream_interval.unwrap_or_else(|| {
            let line = wire_time(self.baud, DRIVER_LINE_LEN);
            let half_line = line.as_nanos() * 2;
            let ticks = half_line.div_ceil(TICK.as_nanos()).max(1);
            u16::try_from(ticks).unwrap_or(0xFFFE)
        });
        IntervalRate(ticks.clamp(1, 0xFFFE))
    }

    /// The data output period (INTERVAL RATE × 1/512 s).
    pub fn stream_period(&self) -> Duration {
        TICK * u32::from(self.interval().0)
    }

    /// The fraction of the line one READ ENCODER line (sent at every data output tick)
    /// takes at this interval: above 1 the board skips samples. 0.47 at 230400 baud and
    /// 1 tick.
    pub fn stream_load(&self) -> f64 {
        let line = wire_time(self.baud, DRIVER_LINE_LEN).as_secs_f64();
        line / self.stream_period().as_secs_f64().max(f64::MIN_POSITIVE)
    }

    /// Streams that may each send a line at one data output tick: READ ENCODER, and (as
    /// configured) MD STATUS and STR (home search) on a driving -M, STR (trigger pulses),
    /// DIG I/O, CAPTURE.
    fn streams(&self) -> u64 {
        let drive = self.variant == ProductType::M
            && self.motor_drive
            && self.input_mode == EncoderMode::Quadrature;
        let dio = self.io.digital_in | self.io.digital_out != 0;
        let capture = self.io.capture.is_some() || self.trigger.index;
        let str_stream = drive || self.trigger.pulse;
        1 + u64::from(drive) + u64::from(str_stream) + u64::from(dio) + u64::from(capture)
    }

    /// Stream lines that may be queued in the board's UART ahead of a reply: every
    /// stream's line of one data output tick, and of the tick after.
    fn lines_ahead_of_a_reply(&self) -> u64 {
        2 * self.streams()
    }

    /// How long a request may wait for its answer: the request and the answer on the
    /// wire, the stream lines queued ahead of it, the processing time and the host
    /// latency.
    pub(crate) fn reply_timeout(&self) -> Duration {
        let bytes = MAX_COMMAND_LEN as u64
            + MAX_RESPONSE_LEN as u64
            + self.lines_ahead_of_a_reply() * DRIVER_LINE_LEN;
        wire_time(self.baud, bytes) + PROCESSING_DELAY * 2 + self.latency
    }

    /// How old the encoder data may become in normal operation.
    pub(crate) fn refresh_budget(&self) -> Duration {
        self.stream_period() * SILENT_PERIODS
            + wire_time(self.baud, self.lines_ahead_of_a_reply() * DRIVER_LINE_LEN)
            + self.latency
    }

    /// Whether `counts_per_step` can convert anything.
    fn step_scale(&self) -> Option<f64> {
        (self.counts_per_step.is_finite() && self.counts_per_step != 0.0)
            .then_some(self.counts_per_step)
    }

    /// Counts → signed steps (unrounded).
    pub(crate) fn steps(&self, counts: f64) -> Option<f64> {
        let steps = counts / self.step_scale()?;
        steps.is_finite().then_some(steps)
    }

    /// The smallest rates and acceleration of the drive, in counts: MD JOG RATE "Motor
    /// rate will change in increments of 16 steps/second", MD STEP RATE (a move's profile)
    /// "from 32 – 13000 steps/second", MD ACCEL "from 64 – 360000 steps/second^2".
    pub(crate) fn rate_floor(&self) -> motion_drivers::RateFloor {
        let per_step = self.step_scale().map_or(0.0, f64::abs);
        motion_drivers::RateFloor {
            velocity: f64::from(RATE_INCREMENT) * per_step,
            profile_velocity: f64::from(*STEP_RATE_RANGE.start()) * per_step,
            accel: f64::from(*ACCEL_RANGE.start()) * per_step,
        }
    }

    /// A rate limit (counts/s, > 0) as MD STEP RATE: steps/s rounded down to the 16-step
    /// increment, capped at the board's 13000. `None` when it is below the board's 32.
    pub(crate) fn step_rate(&self, counts_per_s: f64) -> Option<u32> {
        let steps = self.steps(counts_per_s)?.abs();
        let capped = steps.min(f64::from(*STEP_RATE_RANGE.end()));
        let rate = effective_rate(capped as u32);
        STEP_RATE_RANGE.contains(&rate).then_some(rate)
    }

    /// An acceleration limit (counts/s², > 0) as MD ACCEL: rounded down to 16, capped at
    /// the board's 360000. `None` when it is below the board's 64.
    pub(crate) fn accel(&self, counts_per_s2: f64) -> Option<u32> {
        let steps = self.steps(counts_per_s2)?.abs();
        let capped = steps.min(f64::from(*ACCEL_RANGE.end()));
        let accel = effective_rate(capped as u32);
        ACCEL_RANGE.contains(&accel).then_some(accel)
    }

    /// MD ACCEL for a stop at `counts_per_s2`: never refused (a stop must always work)
    /// and never gentler than asked, so that the stop ends within |v| / decel: rounded
    /// *up* to the 16-step increment, at least the board's 64 and at most its 360000
    /// steps/s². A decel that converts to nothing (NaN) stops at the axis limit.
    pub(crate) fn stop_decel(&self, counts_per_s2: f64) -> u32 {
        let Some(steps) = self.steps(counts_per_s2).map(f64::abs) else {
            return self.default_profile().1;
        };
        let max = *ACCEL_RANGE.end();
        let capped = steps.min(f64::from(max)).ceil() as u32;
        capped
            .div_ceil(RATE_INCREMENT)
            .saturating_mul(RATE_INCREMENT)
            .clamp(*ACCEL_RANGE.start(), max)
    }

    /// A signed velocity (counts/s) as MD JOG RATE: the magnitude rounded down to the
    /// 16-step increment. `None` beyond ±13000 steps/s, or for a velocity that is not
    /// zero but rounds to zero.
    pub(crate) fn jog_rate(&self, counts_per_s: f64) -> Option<i32> {
        let steps = self.steps(counts_per_s)?;
        if steps.abs() > f64::from(*JOG_RATE_RANGE.end()) {
            return None;
        }
        let magnitude = effective_rate(steps.abs() as u32);
        if magnitude < RATE_INCREMENT && steps != 0.0 {
            return None;
        }
        let rate = i32::try_from(magnitude).ok()?;
        Some(if steps < 0.0 { -rate } else { rate })
    }

    /// MD STEP RATE and MD ACCEL of plain position goals, from the axis limits (clamped
    /// into the board's ranges).
    pub(crate) fn default_profile(&self) -> (u32, u32) {
        let rate = self
            .step_rate(self.max_velocity)
            .unwrap_or(*STEP_RATE_RANGE.start());
        let accel = self.accel(self.max_accel).unwrap_or(*ACCEL_RANGE.start());
        (rate, accel)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interval_is_one_tick_at_230400_and_longer_on_slow_lines() {
        let config = QsbDriverConfig::default();
        assert_eq!(config.interval(), IntervalRate(1));
        let slow = QsbDriverConfig {
            baud: 9600,
            ..QsbDriverConfig::default()
        };
        // 21 bytes at 9600 baud = 21.9 ms; twice that in 1.953 ms ticks.
        assert_eq!(slow.interval(), IntervalRate(23));
        let fixed = QsbDriverConfig {
            stream_interval: Some(0xFFFF),
            ..QsbDriverConfig::default()
        };
        assert_eq!(
            fixed.interval(),
            IntervalRate(0xFFFE),
            "never disables output"
        );
    }

    #[test]
    fn rates_round_down_to_16_and_respect_the_command_list_ranges() {
        let config = QsbDriverConfig::default(); // 10 counts per step
        // "MD STEP RATE … 32 – 13000 steps/second … increments of 16".
        assert_eq!(config.step_rate(10_000.0), Some(992));
        assert_eq!(config.step_rate(1e9), Some(12_992));
        assert_eq!(config.step_rate(300.0), None);
        // "MD ACCEL … 64 – 360000 steps/second^2".
        assert_eq!(config.accel(100_000.0), Some(10_000));
        assert_eq!(config.accel(600.0), None);
        assert_eq!(config.accel(1e12), Some(360_000));
        assert_eq!(config.stop_decel(1.0), 64);
        // A stop rounds up to the increment of 16: never gentler than asked.
        assert_eq!(config.stop_decel(10_010.0), 1008);
        assert_eq!(config.stop_decel(10_000.0), 1008);
        assert_eq!(config.stop_decel(16_000.0), 1600);
        assert_eq!(config.stop_decel(1e12), 360_000);
        assert_eq!(config.stop_decel(f64::NAN), 10_000, "the axis limit");
        // "MD JOG RATE … Range -13000 to 13000".
        assert_eq!(config.jog_rate(-10_000.0), Some(-992));
        assert_eq!(config.jog_rate(0.0), Some(0));
        assert_eq!(config.jog_rate(100.0), None, "10 steps/s rounds to 0");
        assert_eq!(config.jog_rate(130_010.0), None);
        let broken = QsbDriverConfig {
            counts_per_step: 0.0,
            ..QsbDriverConfig::default()
        };
        assert_eq!(broken.steps(5.0), None);
    }

    #[test]
    fn budgets_follow_the_wire() {
        let config = QsbDriverConfig::default();
        assert_eq!(wire_time(230_400, 23_040), Duration::from_secs(1));
        assert!(config.reply_timeout() > Duration::from_millis(5));
        assert!(config.reply_timeout() < Duration::from_millis(15));
        assert!(config.refresh_budget() > config.stream_period() * 3);
        assert!(config.refresh_budget() < Duration::from_millis(25));
    }
}
