//! The tmcpack keys of a `[[device]]` and of an `[[axis]]` as written (`RawDevice`,
//! `RawAxis` and the tables inside them): their fields name the keys the board has
//! (`key_names`, for the server's key check). Below every module of `keys` that reads them.

use motion_board::keys::{Int, Spanned};
use serde::Deserialize;

/// The tmcpack keys of a `[[device]]` as written; its fields name the keys the board has
/// (`key_names`, for the server's key check).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawDevice {
    pub(crate) variant: Option<Spanned<String>>,
    pub(crate) reply_address: Option<Spanned<Int>>,
    pub(crate) switchover_ms: Option<Spanned<Int>>,
    pub(crate) packet_timeout_ms: Option<Spanned<Int>>,
    pub(crate) ready_output: Option<Spanned<RawReadyOutput>>,
    pub(crate) amax_divisor: Option<Spanned<Int>>,
    pub(crate) stop_no_ref_bit: Option<Spanned<Int>>,
    pub(crate) power_down: Option<Spanned<String>>,
    pub(crate) microstep_table: Option<Spanned<Vec<Spanned<Int>>>>,
    pub(crate) baud: Option<Spanned<Int>>,
    pub(crate) host_latency_ms: Option<Spanned<f64>>,
    pub(crate) silence_ms: Option<Spanned<Int>>,
}

/// `ready_output = { motors = [0, 1], reference = [0] }`: TTLOUT1 as the ready output
/// ($32 P3) with the $33 masks.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawReadyOutput {
    pub(crate) motors: Option<Spanned<Vec<Spanned<Int>>>>,
    pub(crate) reference: Option<Spanned<Vec<Spanned<Int>>>>,
}

/// The tmcpack keys of an `[[axis]]` as written; its fields name the keys the board has
/// (`key_names`, for the server's key check).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawAxis {
    pub(crate) current: Option<Spanned<RawCurrent>>,
    pub(crate) reference: Option<Spanned<RawReference>>,
    pub(crate) rotary: Option<Spanned<bool>>,
    pub(crate) revolution: Option<Spanned<f64>>,
    pub(crate) analog_stop: Option<Spanned<RawAnalogStop>>,
    pub(crate) start_velocity: Option<Spanned<f64>>,
    pub(crate) position_mode: Option<Spanned<String>>,
    pub(crate) pi: Option<Spanned<RawPi>>,
}

/// `current = { peak, standby, standstill, constant, accel, standby_delay_ms }` ($10, $11).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawCurrent {
    pub(crate) peak: Option<Spanned<f64>>,
    pub(crate) standby: Option<Spanned<f64>>,
    pub(crate) standstill: Option<Spanned<f64>>,
    pub(crate) constant: Option<Spanned<f64>>,
    pub(crate) accel: Option<Spanned<f64>>,
    pub(crate) standby_delay_ms: Option<Spanned<Int>>,
}

/// `reference = { side, active, center, stop_at_switch, soft_stop, debounce_ms,
/// null_offset, test_range, fast, mechanical, restore }` ($15, $16, $18; `restore`: $45).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawReference {
    pub(crate) side: Option<Spanned<String>>,
    pub(crate) active: Option<Spanned<String>>,
    pub(crate) center: Option<Spanned<bool>>,
    pub(crate) stop_at_switch: Option<Spanned<bool>>,
    pub(crate) soft_stop: Option<Spanned<bool>>,
    pub(crate) debounce_ms: Option<Spanned<Int>>,
    pub(crate) null_offset: Option<Spanned<f64>>,
    pub(crate) test_range: Option<Spanned<f64>>,
    pub(crate) fast: Option<Spanned<bool>>,
    pub(crate) mechanical: Option<Spanned<bool>>,
    pub(crate) restore: Option<Spanned<bool>>,
}

/// `analog_stop = { left, right }` ($31), ADC counts 0..=1023.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawAnalogStop {
    pub(crate) left: Option<Spanned<Int>>,
    pub(crate) right: Option<Spanned<Int>>,
}

/// `pi = { propdiv, intdiv, intclip, intinpclip }` (`$19`) as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawPi {
    pub(crate) propdiv: Option<Spanned<Int>>,
    pub(crate) intdiv: Option<Spanned<Int>>,
    pub(crate) intclip: Option<Spanned<Int>>,
    pub(crate) intinpclip: Option<Spanned<Int>>,
}
