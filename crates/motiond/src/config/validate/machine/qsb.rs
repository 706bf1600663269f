//! qsb machine keys (README "Config"): validated here, turned into the driver's config in
//! `crate::drivers::qsb`.

use super::DeviceContext;
use crate::config::ServerConfig;
use crate::config::raw::{RawConfig, RawDevice};
use crate::config::validate::Validator;

/// The qsb keys of one `[[device]]`; `None` fields were not set (the driver's default
/// applies).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct QsbDeviceKeys {}

/// Validates the qsb keys of a `[[device]]` table.
pub(in crate::config) fn device_keys(
    v: &mut Validator<'_, '_>,
    ctx: &DeviceContext,
    raw: &RawDevice,
) -> Option<QsbDeviceKeys> {
    let _ = (v, ctx, raw);
    Some(QsbDeviceKeys::default())
}

/// Checks across tables for qsb devices (after everything else was validated).
pub(in crate::config) fn cross_check(
    v: &mut Validator<'_, '_>,
    config: &ServerConfig,
    raw: &RawConfig,
) {
    let _ = (v, config, raw);
}
