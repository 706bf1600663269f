//! qq2drv machine keys (README "Config"): validated here, turned into the driver's config in
//! `crate::drivers::qq2drv`.

use super::AxisContext;
use crate::config::ServerConfig;
use crate::config::raw::{RawAxis, RawConfig};
use crate::config::validate::Validator;

/// The qq2drv keys of one `[[axis]]`; `None` fields were not set (the driver's default
/// applies).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Qq2drvAxisKeys {}

/// Validates the qq2drv keys of an `[[axis]]` table.
pub(in crate::config) fn axis_keys(
    v: &mut Validator<'_, '_>,
    ctx: &AxisContext<'_>,
    raw: &RawAxis,
) -> Option<Qq2drvAxisKeys> {
    let _ = (v, ctx, raw);
    Some(Qq2drvAxisKeys::default())
}

/// Checks across tables for qq2drv devices (after everything else was validated).
pub(in crate::config) fn cross_check(
    v: &mut Validator<'_, '_>,
    config: &ServerConfig,
    raw: &RawConfig,
) {
    let _ = (v, config, raw);
}
