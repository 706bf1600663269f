//! The TOML file's general keys as written, before validation. Every key is optional here
//! so that a missing key is reported by validation with its table's location; wrong types
//! are refused by serde with their span. A board's own keys of a `[[device]]` or `[[axis]]`
//! (and of an axis's `home` table) are split off first (`validate/machine/split.rs`) and
//! read by the board's crate; a key that is neither general nor any board's is refused
//! there.

use serde::Deserialize;
use toml::Spanned;

/// Integers as written (a value beyond 64 bits is a range error, not a parse error): the
/// boards' key tables use the same types.
pub(crate) use motion_board::keys::{Int, IntValue};

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
    pub sim: Option<Spanned<RawSim>>,
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
    pub direction: Option<Spanned<String>>,
    pub max_travel: Option<Spanned<f64>>,
    pub position: Option<Spanned<f64>>,
}
