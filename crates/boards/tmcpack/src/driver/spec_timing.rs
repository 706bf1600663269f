//! The driver config and the parameter rows of the pack's line timing that depend on the
//! host and on the tolerated silence (the `keys::timing` module's keys): `host_latency_ms`
//! and `silence_ms`. Every row's value fits `MachineParam`'s 40 bytes.

use core::time::Duration;

use motion_drivers::spec::ParamOwner;

use super::TmcpackDriverConfig;
use crate::TmcpackDeviceKeys;

/// The driver config's `host_latency` and `not_answering` from the keys.
pub(super) fn config(keys: &TmcpackDeviceKeys, driver: &mut TmcpackDriverConfig) {
    if let Some(ms) = keys.host_latency_ms {
        driver.host_latency = Duration::from_secs_f64(ms / 1000.0);
    }
    if let Some(ms) = keys.silence_ms {
        driver.not_answering = Duration::from_millis(u64::from(ms));
    }
}

/// The parameter rows of both keys (each value within `MachineParam`'s 40 bytes).
pub(super) fn rows(
    config: &TmcpackDriverConfig,
    row: &mut dyn FnMut(ParamOwner, &'static str, String),
) {
    let ms = |d: Duration| {
        let text = format!("{:.3}", d.as_secs_f64() * 1000.0);
        text.trim_end_matches('0').trim_end_matches('.').to_owned()
    };
    row(
        ParamOwner::Device,
        "host_latency_ms",
        format!("{} ms (in every reply window)", ms(config.host_latency)),
    );
    row(
        ParamOwner::Device,
        "silence_ms",
        format!(
            "{} ms (silence before the verdict)",
            ms(config.not_answering)
        ),
    );
}
