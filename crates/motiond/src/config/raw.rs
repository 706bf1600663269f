//! The TOML file as written, before validation. Every key is optional here so that a
//! missing key is reported by validation with its table's location; unknown keys and wrong
//! types are refused by serde with their span.

use serde::Deserialize;
use toml::Spanned;

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
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawServer {
    pub name: Option<Spanned<String>>,
    pub tick_hz: Option<Spanned<i64>>,
    pub command_timeout_ms: Option<Spanned<i64>>,
    pub rt_priority: Option<Spanned<i64>>,
    pub cpu: Option<Spanned<i64>>,
    pub lock_memory: Option<Spanned<bool>>,
    pub max_clients: Option<Spanned<i64>>,
    pub max_consecutive_overruns: Option<Spanned<i64>>,
    pub liveness_check_ms: Option<Spanned<i64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawLink {
    pub name: Option<Spanned<String>>,
    #[serde(rename = "type")]
    pub kind: Option<Spanned<String>>,
    pub path: Option<Spanned<String>>,
    pub baud: Option<Spanned<i64>>,
    pub speed_hz: Option<Spanned<i64>>,
    pub mode: Option<Spanned<i64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawDevice {
    pub name: Option<Spanned<String>>,
    pub link: Option<Spanned<String>>,
    pub model: Option<Spanned<String>>,
    pub address: Option<Spanned<i64>>,
    pub variant: Option<Spanned<String>>,
    pub drive: Option<Spanned<String>>,
    pub sim: Option<Spanned<RawSim>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSim {
    pub seed: Option<Spanned<i64>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawAxis {
    pub name: Option<Spanned<String>>,
    pub device: Option<Spanned<String>>,
    pub channel: Option<Spanned<i64>>,
    pub unit: Option<Spanned<String>>,
    pub counts_per_unit: Option<Spanned<f64>>,
    pub min: Option<Spanned<f64>>,
    pub max: Option<Spanned<f64>>,
    pub max_velocity: Option<Spanned<f64>>,
    pub max_accel: Option<Spanned<f64>>,
    pub position_tolerance: Option<Spanned<f64>>,
    pub home: Option<Spanned<RawHome>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawHome {
    pub input: Option<Spanned<String>>,
    pub active_high: Option<Spanned<bool>>,
    pub positive_end: Option<Spanned<bool>>,
    pub position: Option<Spanned<f64>>,
}
