//! The keys of the pack's line timing that depend on the host and on how long a silence
//! is tolerated, not on the manual: `host_latency_ms` (part of every reply window) and
//! `silence_ms` (the silence before the not-answering verdict, and how long an
//! unanswered query's answer is taken for late: the key every board has). Driver module docs, docs/keys/tmcpack.md
//! "Timing"; the driver's config and parameter rows from them are the driver's
//! `spec_timing` module's.

use motion_board::keys::{DeviceContext, KeyIssues};

use super::raw::RawDevice;
use crate::TmcpackDeviceKeys;

/// Validates `host_latency_ms` and `silence_ms` into `keys`; `false` on an issue.
pub(crate) fn device_keys(
    v: &mut dyn KeyIssues,
    ctx: &DeviceContext,
    raw: &RawDevice,
    keys: &mut TmcpackDeviceKeys,
) -> bool {
    let mut ok = true;
    if let Some(value) = &raw.host_latency_ms {
        match v.host_latency_ms(value, &ctx.key("host_latency_ms")) {
            Some(ms) => keys.host_latency_ms = Some(ms),
            None => ok = false,
        }
    }
    if let Some(value) = &raw.silence_ms {
        // The same key, range and warning as every board's (`motion_drivers::SILENCE_RANGE_MS`).
        match v.silence_ms(value, &ctx.key("silence_ms")) {
            Some(silence) => keys.silence_ms = Some(silence.as_millis() as u32),
            None => ok = false,
        }
    }
    ok
}
