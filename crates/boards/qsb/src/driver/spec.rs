//! The driver config of a QSB from the neutral [`DriverSpec`]: the link's baud, the axis's
//! limits and home, the machine keys (`docs/keys/qsb.md`), the signals; the board facts
//! the config is validated against; and the parameters that config gives the board, as
//! `motionctl list` shows them.

use core::time::Duration;

use ::qsb::{CountMode, CycleMode, EncoderMode, IndexMode, IntervalRate, ProductType};

use super::{
    CaptureInput, CounterSetup, EnableOutput, PinRole, QsbDriverConfig, QsbIo, TriggerSetup,
};
use crate::{QsbDeviceKeys, QsbInputMode, QsbVariant};
use motion_drivers::Pin;
use motion_drivers::spec::{
    Direction, DriverAxis, DriverSpec, FromSpec, Param, ParamOwner, SpecError,
};

/// One data output tick (INTERVAL RATE's unit): 1/512 s.
pub const TICK: Duration = ::qsb::TICK;

/// The longest INTERVAL RATE, in [`TICK`]s (0xFFFF disables the stream).
pub const LONGEST_INTERVAL_TICKS: u16 = IntervalRate::LONGEST.0;

/// The INTERVAL RATE, in [`TICK`]s, nearest to `period` (halves up); `None` beyond
/// [`LONGEST_INTERVAL_TICKS`].
pub fn interval_ticks(period: Duration) -> Option<u16> {
    IntervalRate::nearest(period).map(|rate| rate.0)
}

impl From<QsbVariant> for ProductType {
    fn from(variant: QsbVariant) -> Self {
        match variant {
            QsbVariant::M => Self::M,
            QsbVariant::S => Self::S,
            QsbVariant::D => Self::D,
        }
    }
}

impl From<QsbInputMode> for EncoderMode {
    fn from(mode: QsbInputMode) -> Self {
        match mode {
            QsbInputMode::Quadrature => Self::Quadrature,
            QsbInputMode::Pwm => Self::Pwm,
            QsbInputMode::Analog => Self::Analog,
        }
    }
}

impl QsbVariant {
    /// Bits of DIG I/O the product has (-M 4, -D 1, -S none).
    pub fn digital_io_bits(self) -> u8 {
        ProductType::from(self).digital_io_bits()
    }

    /// What `pin` of this product is (`None`: not a pin of this product).
    pub fn pin_role(self, pin: Pin) -> Option<PinRole> {
        PinRole::of(self.into(), pin)
    }
}

/// The axis on channel 0, with its index in `spec.axes`.
fn axis_of(spec: &DriverSpec) -> Option<(usize, &DriverAxis)> {
    spec.axis_on(0)
}

/// The device's qsb keys (all `None` for a device without them).
fn keys_of(spec: &DriverSpec) -> QsbDeviceKeys {
    spec.machine.get_or_default()
}

/// The trigger output and capture on index of the device's keys; the compare position in
/// counts of the axis on channel 0 (`compare_position` × `counts_per_unit`, rounded).
fn trigger_of(keys: &QsbDeviceKeys, axis: Option<&DriverAxis>) -> Result<TriggerSetup, SpecError> {
    let sources = keys.trigger_on.unwrap_or_default();
    let compare = match (keys.compare_position, axis) {
        (Some(position), Some(axis)) => {
            let counts = (position * axis.counts_per_unit).round();
            let value = motion_base::counts_to_i32(counts).ok_or_else(|| SpecError {
                channel: None,
                key: "compare_position",
                message: format!(
                    "{position} {} is {counts} counts: beyond the 32-bit counter (DTR)",
                    axis.unit
                ),
            })?;
            Some(value)
        }
        _ => None,
    };
    Ok(TriggerSetup {
        index: sources.index || keys.capture_index.unwrap_or(false),
        on_match: sources.on_match,
        underflow: sources.underflow,
        overflow: sources.overflow,
        pulse: sources.any(),
        active_high: keys.trigger_active_high.unwrap_or(false),
        compare: compare.filter(|_| sources.on_match),
    })
}

/// A number as the config would write it (no trailing `.0` noise, full precision).
fn number(value: f64) -> String {
    format!("{value}")
}

impl FromSpec for QsbDriverConfig {
    /// The driver config of the qsb device `spec` describes: the link's baud, the axis's
    /// limits and home, the machine keys, the signals.
    fn from_spec(spec: &DriverSpec) -> Result<Self, SpecError> {
        let keys = keys_of(spec);
        let variant = ProductType::from(keys.variant);
        let mut driver = Self {
            variant,
            ..Self::default()
        };
        if let Some(baud) = spec.line_rate {
            driver.baud = baud;
        }
        if let Some(limits) = spec.channel_limits(0) {
            driver.max_velocity = limits.max_velocity;
            driver.max_accel = limits.max_accel;
        }
        let axis = axis_of(spec);
        if let Some((_, axis)) = axis {
            let cpu = axis.counts_per_unit;
            // The search direction in counts: a negative counts_per_unit turns it round.
            driver.home_positive = (axis.home.direction == Direction::Positive) == (cpu > 0.0);
            driver.home_max_travel = axis.home.max_travel * cpu.abs();
            // (Validation keeps it within the 32-bit counter.)
            driver.home_position = (axis.home.position * cpu).round() as i32;
        }
        if let Some(c) = keys.counts_per_step {
            driver.counts_per_step = c;
        }
        driver.invert_index = keys.index_inverted.unwrap_or(false);
        driver.stream_interval = keys.stream_interval_ticks;
        if let Some(latency) = keys.host_latency {
            driver.latency = latency;
        }
        if let Some(silence) = keys.silence {
            driver.silence = silence;
        }
        driver.input_mode = keys.input_mode.unwrap_or_default().into();
        let count = keys.count_mode.unwrap_or(CountMode::X4);
        driver.counter = CounterSetup {
            count,
            cycle: keys.count_range.unwrap_or(CycleMode::FreeRunning),
            limit: keys.count_limit.unwrap_or(0),
            index: keys.index_action.unwrap_or(IndexMode::Disabled),
            synchronous_index: keys.index_sync.unwrap_or(count != CountMode::NonQuadrature),
        };
        driver.motor_drive = driver.input_mode == EncoderMode::Quadrature && axis.is_some();
        driver.enable = keys.enable_output.map(|bit| EnableOutput {
            bit,
            active_high: keys.enable_active_high.unwrap_or(false),
        });
        let mut io = QsbIo {
            capture: keys.capture_input.map(|bit| CaptureInput {
                bit,
                falling: keys.capture_falling.unwrap_or(false),
            }),
            ..QsbIo::default()
        };
        for signal in &spec.signals {
            io.add(variant, signal.pin, signal.kind);
        }
        driver.io = io;
        driver.trigger = trigger_of(&keys, axis.map(|(_, axis)| axis))?;
        Ok(driver)
    }

    /// The machine parameters of the device, as the driver uses them.
    fn params(&self, spec: &DriverSpec) -> Vec<Param> {
        let mut out = Vec::new();
        let mut row = |key: &'static str, value: String| {
            out.push(Param {
                owner: ParamOwner::Device,
                key,
                value,
            });
        };
        row("counts_per_step", number(self.counts_per_step));
        if let Some((_, axis)) = axis_of(spec) {
            row("home_direction", axis.home.direction.id().to_owned());
            row(
                "home_max_travel",
                format!("{} {}", number(axis.home.max_travel), axis.unit),
            );
            row(
                "home_offset",
                format!("{} {}", number(axis.home.position), axis.unit),
            );
        }
        let polarity = if self.invert_index {
            "inverted"
        } else {
            "normal"
        };
        row("index_polarity", polarity.to_owned());
        let ticks = self.interval().0;
        let ms = f64::from(ticks) * TICK.as_secs_f64() * 1000.0;
        let plural = if ticks == 1 { "" } else { "s" };
        row(
            "stream_interval_ms",
            format!("{} ms ({ticks} tick{plural})", number(ms)),
        );
        row(
            "host_latency_ms",
            format!("{} ms", number(self.latency.as_secs_f64() * 1000.0)),
        );
        row(
            "silence_ms",
            format!("{} ms", number(self.silence.as_secs_f64() * 1000.0)),
        );
        let enable = self.enable;
        row(
            "enable_output",
            enable.map_or_else(|| "none".to_owned(), |e| e.bit.to_string()),
        );
        let active = enable.map_or_else(
            || keys_of(spec).enable_active_high.unwrap_or(false),
            |e| e.active_high,
        );
        row(
            "enable_active",
            if active { "high" } else { "low" }.to_owned(),
        );
        let mode = match self.input_mode {
            EncoderMode::Quadrature => "quadrature",
            EncoderMode::Pwm => "pwm",
            EncoderMode::Analog => "analog",
        };
        row("input_mode", mode.to_owned());
        let counter = self.counter;
        row("count_mode", counter.count_text().to_owned());
        row("count_range", counter.range_text());
        row("index_action", counter.index_text().to_owned());
        let sync = if counter.mdr0().synchronous_index {
            "synchronous"
        } else {
            "asynchronous"
        };
        row("index_sync", sync.to_owned());
        let capture = self.io.capture;
        row(
            "capture_input",
            capture.map_or_else(|| "none".to_owned(), |c| c.bit.to_string()),
        );
        let falling = capture.map_or_else(
            || keys_of(spec).capture_falling.unwrap_or(false),
            |c| c.falling,
        );
        row(
            "capture_edge",
            if falling { "falling" } else { "rising" }.to_owned(),
        );
        let trigger = self.trigger;
        // MDR1 B4 "Trigger/Capture on Index": `capture_index`, or "index" in trigger_on.
        row("capture_index", trigger.index.to_string());
        row("trigger_on", trigger.sources_text());
        let compare = match (trigger.compare, axis_of(spec)) {
            (Some(counts), Some((_, axis))) => format!(
                "{} {} ({counts} counts)",
                number(f64::from(counts) / axis.counts_per_unit),
                axis.unit
            ),
            _ => "none".to_owned(),
        };
        row("compare_position", compare);
        row(
            "trigger_active",
            if trigger.active_high { "high" } else { "low" }.to_owned(),
        );
        if trigger.pulse {
            // One register: the pulse is as long as the stream's data output interval.
            row(
                "trigger_pulse_ms",
                format!("{} ms (INTERVAL RATE)", number(ms)),
            );
        }
        out
    }
}
