//! tmcpack machine keys (README "Config"): validated here, turned into the driver's config in
//! `crate::drivers::tmcpack`.

use super::{AxisContext, DeviceContext};
use crate::config::ServerConfig;
use crate::config::raw::{RawAxis, RawConfig, RawDevice};
use crate::config::validate::Validator;

/// The tmcpack keys of one `[[device]]`; `None` fields were not set (the driver's default
/// applies).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TmcpackDeviceKeys {}

/// Validates the tmcpack keys of a `[[device]]` table.
pub(in crate::config) fn device_keys(
    v: &mut Validator<'_, '_>,
    ctx: &DeviceContext,
    raw: &RawDevice,
) -> Option<TmcpackDeviceKeys> {
    let _ = (v, ctx, raw);
    Some(TmcpackDeviceKeys::default())
}

/// The tmcpack keys of one `[[axis]]`; `None` fields were not set (the driver's default
/// applies).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TmcpackAxisKeys {}

/// Validates the tmcpack keys of an `[[axis]]` table.
pub(in crate::config) fn axis_keys(
    v: &mut Validator<'_, '_>,
    ctx: &AxisContext<'_>,
    raw: &RawAxis,
) -> Option<TmcpackAxisKeys> {
    let _ = (v, ctx, raw);
    Some(TmcpackAxisKeys::default())
}

/// Checks across tables for tmcpack devices (after everything else was validated).
pub(in crate::config) fn cross_check(
    v: &mut Validator<'_, '_>,
    config: &ServerConfig,
    raw: &RawConfig,
) {
    let _ = (v, config, raw);
}
