//! The TOML file's general keys as written, before validation. Every key is optional here
//! so that a missing key is reported by validation with its table's location; wrong types
//! are refused by serde with their span. A board's own keys of a `[[device]]` or `[[axis]]`
//! (and of an axis's `home` table) are split off first (`validate/machine/split.rs`) and
//! read by the board's crate; a key that is neither general nor any board's is refused
//! there.

use core::fmt;

use serde::Deserialize;
use serde::de::{IgnoredAny, MapAccess, SeqAccess, Visitor};
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
    #[serde(default)]
    pub group: Vec<Spanned<RawGroup>>,
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
    pub blackbox_seconds: Option<Spanned<Int>>,
    pub blackbox_on_exit: Option<Spanned<bool>>,
    pub blackbox_dir: Option<Spanned<String>>,
    pub blackbox_keep: Option<Spanned<Int>>,
    pub state_dir: Option<Spanned<String>>,
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
    pub io: Option<Spanned<String>>,
    pub io_budget_us: Option<Spanned<Int>>,
    /// `socketcan`: the network interface (`can0`).
    pub interface: Option<Spanned<String>>,
    /// `socketcan`, `sim-can`: the CAN bit rate.
    pub bitrate: Option<Spanned<Int>>,
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

/// `[[group]]`: axes of any boards that move together.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawGroup {
    pub name: Option<Spanned<String>>,
    pub axes: Option<Spanned<Vec<Spanned<String>>>>,
    pub path_tolerance: Option<Spanned<RawTolerance>>,
    pub goal_tolerance: Option<Spanned<RawTolerance>>,
    pub goal_time_tolerance_ms: Option<Spanned<Int>>,
    pub stream_limit: Option<Spanned<String>>,
    pub stream_timeout: Option<Spanned<Int>>,
    pub stream_buffer: Option<Spanned<Int>>,
}

/// A group's tolerance as written: one number for every axis, or a table of numbers by
/// axis name. Any value is taken, so that a wrong type is reported by validation with the
/// group's other issues rather than ending the reading of the file.
#[derive(Debug)]
pub(crate) enum RawTolerance {
    /// `path_tolerance = 0.5` (or a value that is neither a number nor a table).
    One(RawNumber),
    /// `path_tolerance = { x = 0.5, feeder = 2.0 }`, in file order.
    PerAxis(Vec<(Spanned<String>, Spanned<RawNumber>)>),
}

/// A value that should be a number: the number, or what was written instead.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum RawNumber {
    /// An integer or a float, as `f64`.
    Number(f64),
    /// Something else: "a string", "a boolean", "an array", "a table", "a date".
    Not(&'static str),
}

/// The key under which the TOML deserializer hands over a date or time as a map.
const TOML_DATETIME: &str = "$__toml_private_datetime";

/// Reads any value as a [`RawTolerance`] (`table`: a map is a table of numbers) or a
/// [`RawNumber`] (a map is "a table"). Integers beyond 64 bits become floats.
struct Loose {
    table: bool,
}

impl<'de> Visitor<'de> for Loose {
    type Value = RawTolerance;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a number or a table of numbers")
    }

    fn visit_bool<E>(self, _: bool) -> Result<RawTolerance, E> {
        Ok(RawTolerance::One(RawNumber::Not("a boolean")))
    }

    fn visit_i64<E>(self, v: i64) -> Result<RawTolerance, E> {
        Ok(RawTolerance::One(RawNumber::Number(v as f64)))
    }

    fn visit_u64<E>(self, v: u64) -> Result<RawTolerance, E> {
        Ok(RawTolerance::One(RawNumber::Number(v as f64)))
    }

    fn visit_i128<E>(self, v: i128) -> Result<RawTolerance, E> {
        Ok(RawTolerance::One(RawNumber::Number(v as f64)))
    }

    fn visit_u128<E>(self, v: u128) -> Result<RawTolerance, E> {
        Ok(RawTolerance::One(RawNumber::Number(v as f64)))
    }

    fn visit_f64<E>(self, v: f64) -> Result<RawTolerance, E> {
        Ok(RawTolerance::One(RawNumber::Number(v)))
    }

    fn visit_str<E>(self, _: &str) -> Result<RawTolerance, E> {
        Ok(RawTolerance::One(RawNumber::Not("a string")))
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<RawTolerance, A::Error> {
        while seq.next_element::<IgnoredAny>()?.is_some() {}
        Ok(RawTolerance::One(RawNumber::Not("an array")))
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<RawTolerance, A::Error> {
        let mut entries = Vec::new();
        let mut date = false;
        loop {
            // A date or time comes as a map of one private key that cannot be read with
            // its span: the only map whose key is not a spanned string.
            let Ok(key) = map.next_key::<Spanned<String>>() else {
                date = true;
                break;
            };
            let Some(key) = key else { break };
            if key.get_ref() == TOML_DATETIME {
                date = true;
                map.next_value::<IgnoredAny>()?;
            } else if self.table {
                entries.push((key, map.next_value::<Spanned<RawNumber>>()?));
            } else {
                map.next_value::<IgnoredAny>()?;
            }
        }
        Ok(match (date, self.table) {
            (true, _) => RawTolerance::One(RawNumber::Not("a date")),
            (false, true) => RawTolerance::PerAxis(entries),
            (false, false) => RawTolerance::One(RawNumber::Not("a table")),
        })
    }
}

impl<'de> Deserialize<'de> for RawTolerance {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        deserializer.deserialize_any(Loose { table: true })
    }
}

impl<'de> Deserialize<'de> for RawNumber {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        match deserializer.deserialize_any(Loose { table: false })? {
            RawTolerance::One(number) => Ok(number),
            RawTolerance::PerAxis(_) => Ok(Self::Not("a table")),
        }
    }
}
