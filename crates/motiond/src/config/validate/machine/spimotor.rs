//! spimotor machine keys (README "Config"): validated here, turned into the driver's config in
//! `crate::drivers::spimotor`.

use super::DeviceContext;
use crate::config::ServerConfig;
use crate::config::raw::{RawConfig, RawDevice};
use crate::config::validate::Validator;

/// The spimotor keys of one `[[device]]`; `None` fields were not set (the driver's default
/// applies).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SpimotorDeviceKeys {}

/// Validates the spimotor keys of a `[[device]]` table.
pub(in crate::config) fn device_keys(
    v: &mut Validator<'_, '_>,
    ctx: &DeviceContext,
    raw: &RawDevice,
) -> Option<SpimotorDeviceKeys> {
    let _ = (v, ctx, raw);
    Some(SpimotorDeviceKeys::default())
}

/// Checks across tables for spimotor devices (after everything else was validated).
pub(in crate::config) fn cross_check(
    v: &mut Validator<'_, '_>,
    config: &ServerConfig,
    raw: &RawConfig,
) {
    let _ = (v, config, raw);
}
