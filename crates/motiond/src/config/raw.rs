//! The TOML file as written, before validation. Every key is optional here so that a
//! missing key is reported by validation with its table's location; unknown keys and wrong
//! types are refused by serde with their span.

use serde::Deserialize;
use toml::Spanned;

/// An integer as written, whatever its size: a value beyond 64 bits is a range error
/// reported by validation with its key and allowed range, not a parse error.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Int(pub i128);

impl<'de> Deserialize<'de> for Int {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = Int;
            fn expecting(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                f.write_str("an integer")
            }
            fn visit_i64<E>(self, v: i64) -> Result<Int, E> {
                Ok(Int(i128::from(v)))
            }
            fn visit_u64<E>(self, v: u64) -> Result<Int, E> {
                Ok(Int(i128::from(v)))
            }
            fn visit_i128<E>(self, v: i128) -> Result<Int, E> {
                Ok(Int(v))
            }
            fn visit_u128<E>(self, v: u128) -> Result<Int, E> {
                Ok(Int(i128::try_from(v).unwrap_or(i128::MAX)))
            }
        }
        deserializer.deserialize_any(Visitor)
    }
}

impl Int {
    /// The value, saturated to `i64` (range checks see a saturated value out of range too).
    pub fn get(&self) -> i64 {
        i64::try_from(self.0).unwrap_or(if self.0 < 0 { i64::MIN } else { i64::MAX })
    }
}

impl core::fmt::Display for Int {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        self.0.fmt(f)
    }
}

/// A raw integer key of either representation.
pub(crate) trait IntValue {
    /// The value, widened.
    fn wide(&self) -> i128;
}

impl IntValue for i64 {
    fn wide(&self) -> i128 {
        i128::from(*self)
    }
}

impl IntValue for Int {
    fn wide(&self) -> i128 {
        self.0
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawConfig {
    pub server: Option<Spanned<RawServer>>,
    #[serde(default)]
    pub link: Vec<Spanned<RawLink>>,
    #[serde(default)]
    pub device: Vec<Spanned<RawDevice>>,
    #[serde(default)]
    pub axis: Vec<Spanned<RawAxis>>,
    #[serde(default)]
    pub signal: Vec<Spanned<RawSignal>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawServer {
    pub name: Option<Spanned<String>>,
    pub tick_hz: Option<Spanned<Int>>,
    pub command_timeout_ms: Option<Spanned<Int>>,
    pub rt_priority: Option<Spanned<Int>>,
    pub io_rt_priority: Option<Spanned<Int>>,
    pub cpu: Option<Spanned<Int>>,
    pub io_cpu: Option<Spanned<Int>>,
    pub lock_memory: Option<Spanned<bool>>,
    pub max_clients: Option<Spanned<Int>>,
    pub max_consecutive_overruns: Option<Spanned<Int>>,
    pub liveness_check_ms: Option<Spanned<Int>>,
    pub claim_lease_ms: Option<Spanned<Int>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawLink {
    pub name: Option<Spanned<String>>,
    #[serde(rename = "type")]
    pub kind: Option<Spanned<String>>,
    pub path: Option<Spanned<String>>,
    pub baud: Option<Spanned<Int>>,
    pub speed_hz: Option<Spanned<Int>>,
    pub mode: Option<Spanned<Int>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawDevice {
    pub name: Option<Spanned<String>>,
    pub link: Option<Spanned<String>>,
    pub model: Option<Spanned<String>>,
    pub address: Option<Spanned<Int>>,
    pub variant: Option<Spanned<String>>,
    pub drive: Option<Spanned<String>>,
    pub sim: Option<Spanned<RawSim>>,
    // qsb machine keys (config/machine/qsb.rs)
    pub counts_per_step: Option<Spanned<f64>>,
    pub home_direction: Option<Spanned<String>>,
    pub home_max_travel: Option<Spanned<f64>>,
    pub home_offset: Option<Spanned<f64>>,
    pub index_polarity: Option<Spanned<String>>,
    pub stream_interval_ms: Option<Spanned<f64>>,
    pub host_latency_ms: Option<Spanned<f64>>,
    pub enable_output: Option<Spanned<Int>>,
    pub enable_active: Option<Spanned<String>>,
    pub input_mode: Option<Spanned<String>>,
    pub capture_input: Option<Spanned<Int>>,
    pub capture_edge: Option<Spanned<String>>,
    // tmcpack machine keys (config/machine/tmcpack.rs)
    pub reply_address: Option<Spanned<Int>>,
    pub switchover_ms: Option<Spanned<Int>>,
    pub packet_timeout_ms: Option<Spanned<Int>>,
    pub ready_output: Option<Spanned<RawReadyOutput>>,
    // spimotor machine keys (config/machine/spimotor.rs)
    pub intensity: Option<Spanned<Int>>,
    pub coils: Option<Spanned<Int>>,
}

/// tmcpack `ready_output = { motors = [0, 1], reference = [0] }`: TTLOUT1 as the ready
/// output ($32 P3) with the $33 masks.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawReadyOutput {
    pub motors: Option<Spanned<Vec<Spanned<Int>>>>,
    pub reference: Option<Spanned<Vec<Spanned<Int>>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSim {
    pub seed: Option<Spanned<Int>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawAxis {
    pub name: Option<Spanned<String>>,
    pub device: Option<Spanned<String>>,
    pub channel: Option<Spanned<Int>>,
    pub unit: Option<Spanned<String>>,
    pub counts_per_unit: Option<Spanned<f64>>,
    pub min: Option<Spanned<f64>>,
    pub max: Option<Spanned<f64>>,
    pub max_velocity: Option<Spanned<f64>>,
    pub max_accel: Option<Spanned<f64>>,
    pub position_tolerance: Option<Spanned<f64>>,
    pub home: Option<Spanned<RawHome>>,
    // supervision and stop category (every model)
    pub following_error: Option<Spanned<f64>>,
    pub overspeed_factor: Option<Spanned<f64>>,
    pub estop: Option<Spanned<String>>,
    // tmcpack machine keys (config/machine/tmcpack.rs)
    pub current: Option<Spanned<RawCurrent>>,
    pub reference: Option<Spanned<RawReference>>,
    pub rotary: Option<Spanned<bool>>,
    pub revolution: Option<Spanned<f64>>,
    pub analog_stop: Option<Spanned<RawAnalogStop>>,
    // qq2drv machine keys (config/machine/qq2drv.rs)
    pub pid_position: Option<Spanned<RawPid>>,
    pub pid_velocity: Option<Spanned<RawPid>>,
    pub power_limit: Option<Spanned<f64>>,
}

/// tmcpack `current = { peak, standby, standstill, constant, accel, standby_delay_ms }`
/// ($10, $11).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawCurrent {
    pub peak: Option<Spanned<f64>>,
    pub standby: Option<Spanned<f64>>,
    pub standstill: Option<Spanned<f64>>,
    pub constant: Option<Spanned<f64>>,
    pub accel: Option<Spanned<f64>>,
    pub standby_delay_ms: Option<Spanned<Int>>,
}

/// tmcpack `reference = { side, active, center, stop_at_switch, soft_stop, debounce_ms,
/// null_offset, test_range, fast, mechanical }` ($15, $16, $18).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawReference {
    pub side: Option<Spanned<String>>,
    pub active: Option<Spanned<String>>,
    pub center: Option<Spanned<bool>>,
    pub stop_at_switch: Option<Spanned<bool>>,
    pub soft_stop: Option<Spanned<bool>>,
    pub debounce_ms: Option<Spanned<Int>>,
    pub null_offset: Option<Spanned<f64>>,
    pub test_range: Option<Spanned<f64>>,
    pub fast: Option<Spanned<bool>>,
    pub mechanical: Option<Spanned<bool>>,
}

/// tmcpack `analog_stop = { left, right }` ($31), ADC counts 0..=1023.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawAnalogStop {
    pub left: Option<Spanned<Int>>,
    pub right: Option<Spanned<Int>>,
}

/// qq2drv `pid_position = { p, i, d, windup }` (packet 30) / `pid_velocity = { p, i, d }`
/// (packet 32).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawPid {
    pub p: Option<Spanned<Int>>,
    pub i: Option<Spanned<Int>>,
    pub d: Option<Spanned<Int>>,
    pub windup: Option<Spanned<Int>>,
}

/// `[[signal]]`: a named board I/O pin.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSignal {
    pub name: Option<Spanned<String>>,
    pub device: Option<Spanned<String>>,
    pub kind: Option<Spanned<String>>,
    pub pin: Option<Spanned<String>>,
    pub invert: Option<Spanned<bool>>,
    pub scale: Option<Spanned<f64>>,
    pub offset: Option<Spanned<f64>>,
    pub unit: Option<Spanned<String>>,
    pub safe: Option<Spanned<bool>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawHome {
    // every model that homes (qq2drv, tmcpack, qsb)
    pub direction: Option<Spanned<String>>,
    pub max_travel: Option<Spanned<f64>>,
    pub position: Option<Spanned<f64>>,
    // qq2drv only
    pub input: Option<Spanned<String>>,
    pub active_high: Option<Spanned<bool>>,
    pub positive_end: Option<Spanned<bool>>,
    pub spacing: Option<Spanned<f64>>,
}
