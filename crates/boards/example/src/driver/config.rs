//! What an [`ExampleDriver`](super::ExampleDriver) is built from, and how it is built from
//! the server's neutral [`DriverSpec`]: the link's baud, the channels that carry an axis,
//! and each axis's limits converted into steps (`counts_per_unit`, `max_velocity`,
//! `max_accel`).

use core::time::Duration;

pub use motion_drivers::spec::AxisLimits;
use motion_drivers::spec::{DriverSpec, FromSpec, Param, ParamOwner, SpecError};

use crate::codec::{CHANNELS, MAX_ACCEL, MAX_SPEED};

/// The AS-2's factory baud (8N1).
pub const DEFAULT_BAUD: u32 = 115_200;

/// A channel's limits when no axis is configured on it, steps/s and steps/s².
const DEFAULT_LIMITS: AxisLimits = AxisLimits {
    max_velocity: 1_000.0,
    max_accel: 10_000.0,
};

/// Everything the driver needs to know about one AS-2.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, PartialEq)]
pub struct ExampleDriverConfig {
    /// Baud of the serial link: sizes the reply timeout from the wire time.
    pub baud: u32,
    /// How often each polled channel's position is read.
    pub poll_period: Duration,
    /// Per channel: whether an axis is on it (only those are polled).
    pub polled: [bool; CHANNELS],
    /// Per channel the axis limits in steps: the speed (1..=50 000 steps/s) and the ramp
    /// (1..=1 000 000 steps/s²) of a `Position` goal's move.
    pub limits: [AxisLimits; CHANNELS],
    /// How long the board may say nothing while a reply is due before it is declared not
    /// answering: a reply held up on the host comes later and is waited for. The AS-2 has
    /// no machine keys; every board's `silence_ms` default,
    /// [`DEFAULT_SILENCE`](motion_drivers::DEFAULT_SILENCE).
    pub silence: Duration,
}

impl Default for ExampleDriverConfig {
    fn default() -> Self {
        Self {
            baud: DEFAULT_BAUD,
            poll_period: Duration::from_millis(10),
            polled: [true; CHANNELS],
            limits: [DEFAULT_LIMITS; CHANNELS],
            silence: motion_drivers::DEFAULT_SILENCE,
        }
    }
}

/// `value` (steps/s or steps/s²) checked against the board's `1..=max`.
fn board_rate(
    value: f64,
    max: u32,
    channel: usize,
    key: &'static str,
    unit: &str,
) -> Result<f64, SpecError> {
    if value >= 1.0 && value <= f64::from(max) {
        return Ok(value);
    }
    Err(SpecError {
        channel: Some(channel),
        key,
        message: format!(
            "{value} {unit} (in steps, after counts_per_unit) is outside the AS-2's 1..={max} {unit}"
        ),
    })
}

impl ExampleDriverConfig {
    /// How long a reply may take: the wire time of the longest request and reply at the
    /// link's baud (10 bits a byte), and a margin for the board and the host.
    #[must_use]
    pub fn reply_timeout(&self) -> Duration {
        let bits = 2 * crate::codec::MAX_LINE as u64 * 10;
        let wire = Duration::from_micros(bits * 1_000_000 / u64::from(self.baud.max(1)));
        wire + super::REPLY_MARGIN
    }
}

impl FromSpec for ExampleDriverConfig {
    /// The driver configuration of the AS-2 `spec` describes.
    ///
    /// # Errors
    /// An axis on a channel other than 0 and 1, or whose `max_velocity` or `max_accel`
    /// (times `|counts_per_unit|`) is outside what the board runs (1..=50 000 steps/s,
    /// 1..=1 000 000 steps/s²).
    fn from_spec(spec: &DriverSpec) -> Result<Self, SpecError> {
        let mut config = Self {
            baud: spec.line_rate.unwrap_or(DEFAULT_BAUD),
            polled: [false; CHANNELS],
            ..Self::default()
        };
        for axis in &spec.axes {
            let channel = axis.channel;
            if channel >= CHANNELS {
                return Err(SpecError {
                    channel: Some(channel),
                    key: "channel",
                    message: format!("the AS-2 has channels 0 and 1, not {channel}"),
                });
            }
            let limits = axis.limits();
            config.limits[channel] = AxisLimits {
                max_velocity: board_rate(
                    limits.max_velocity,
                    MAX_SPEED,
                    channel,
                    "max_velocity",
                    "steps/s",
                )?,
                max_accel: board_rate(
                    limits.max_accel,
                    MAX_ACCEL,
                    channel,
                    "max_accel",
                    "steps/s²",
                )?,
            };
            config.polled[channel] = true;
        }
        Ok(config)
    }

    /// What the driver makes of each axis's limits: the speed and acceleration of its
    /// `Position` moves (`M<ch> <target> <speed> <accel>`), in steps.
    fn params(&self, spec: &DriverSpec) -> Vec<Param> {
        let mut params = Vec::new();
        for (index, axis) in spec.axes.iter().enumerate() {
            let Some(limits) = self.limits.get(axis.channel) else {
                continue;
            };
            params.push(Param {
                owner: ParamOwner::Axis(index),
                key: "max_velocity",
                value: format!("{} steps/s (M speed)", limits.max_velocity.round()),
            });
            params.push(Param {
                owner: ParamOwner::Axis(index),
                key: "max_accel",
                value: format!("{} steps/s² (M accel)", limits.max_accel.round()),
            });
        }
        params
    }
}
