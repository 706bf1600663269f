//! The QSB driver of a `[[device]]`, configured from its axis and machine keys.

use motion_drivers::Driver;
use motion_drivers::qsb::{QsbDriver, QsbDriverConfig};

use super::{ParamRow, channel_limits, line_rate};
use crate::config::{DeviceSpec, ServerConfig};

/// The driver of qsb device `index`.
pub(super) fn build(config: &ServerConfig, index: usize, device: &DeviceSpec) -> Box<dyn Driver> {
    let mut driver = QsbDriverConfig::default();
    if let Some(baud) = line_rate(config, device) {
        driver.baud = baud;
    }
    if let Some((max_velocity, max_accel)) = channel_limits(config, index, 0) {
        driver.max_velocity = max_velocity;
        driver.max_accel = max_accel;
    }
    Box::new(QsbDriver::new(driver))
}

/// The machine parameters of qsb device `index` and its axes, as the driver uses them.
pub(super) fn describe(
    config: &ServerConfig,
    index: usize,
    device: &DeviceSpec,
    out: &mut Vec<ParamRow>,
) {
    let _ = (config, index, device, out);
}
