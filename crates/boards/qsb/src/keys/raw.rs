//! The qsb keys of a `[[device]]` as written (`RawDevice`, whose fields name the keys the
//! board has), and the one helper every qsb key table checks a string key with (`choice`).
//! Below the checks of `keys` and its `counter` and `trigger` tables, which all read them.

use motion_board::keys::{Int, KeyIssues, Spanned};
use serde::Deserialize;

/// The qsb keys of a `[[device]]` as written; its fields name the keys the board has
/// (`key_names`, for the server's key check).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawDevice {
    pub(crate) variant: Option<Spanned<String>>,
    pub(crate) counts_per_step: Option<Spanned<f64>>,
    pub(crate) home_direction: Option<Spanned<String>>,
    pub(crate) home_max_travel: Option<Spanned<f64>>,
    pub(crate) home_offset: Option<Spanned<f64>>,
    pub(crate) index_polarity: Option<Spanned<String>>,
    pub(crate) stream_interval_ms: Option<Spanned<f64>>,
    pub(crate) host_latency_ms: Option<Spanned<f64>>,
    pub(crate) silence_ms: Option<Spanned<Int>>,
    pub(crate) enable_output: Option<Spanned<Int>>,
    pub(crate) enable_active: Option<Spanned<String>>,
    pub(crate) input_mode: Option<Spanned<String>>,
    pub(crate) capture_input: Option<Spanned<Int>>,
    pub(crate) capture_edge: Option<Spanned<String>>,
    pub(crate) count_mode: Option<Spanned<String>>,
    pub(crate) count_range: Option<Spanned<String>>,
    pub(crate) count_limit: Option<Spanned<Int>>,
    pub(crate) index_action: Option<Spanned<String>>,
    pub(crate) index_sync: Option<Spanned<String>>,
    pub(crate) capture_index: Option<Spanned<bool>>,
    pub(crate) trigger_on: Option<Spanned<Vec<Spanned<String>>>>,
    pub(crate) compare_position: Option<Spanned<f64>>,
    pub(crate) trigger_active: Option<Spanned<String>>,
}

/// One of `allowed` (name, value) for a string key; an issue naming them otherwise.
pub(crate) fn choice<T: Copy>(
    v: &mut dyn KeyIssues,
    value: &Spanned<String>,
    key: &str,
    allowed: &[(&str, T)],
) -> Option<T> {
    let names: Vec<String> = allowed.iter().map(|(n, _)| format!("{n:?}")).collect();
    v.one_of(value, key, allowed, "value", &names.join(", "))
}
