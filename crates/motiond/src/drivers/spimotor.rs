//! The SPI_motor driver of a `[[device]]`, configured from its axes and machine keys.

use anyhow::bail;
use motion_drivers::Driver;
use motion_drivers::spimotor::{AxisLimits, SpimotorDrive, SpimotorDriver, SpimotorDriverConfig};

use super::{ParamRow, channel_limits, line_rate};
use crate::config::{DeviceSpec, ServerConfig, SpiDrive};

/// The driver of spimotor device `index`.
pub(super) fn build(
    config: &ServerConfig,
    index: usize,
    device: &DeviceSpec,
) -> anyhow::Result<Box<dyn Driver>> {
    let Ok(address) = spimotor::Address::new(device.address as u8) else {
        bail!(
            "device `{}`: {} is not an SPI_motor address",
            device.name,
            device.address
        );
    };
    let mut driver = SpimotorDriverConfig {
        address,
        drive: match device.drive {
            SpiDrive::Stepper => SpimotorDrive::Stepper,
            SpiDrive::Brushed => SpimotorDrive::Brushed,
        },
        ..SpimotorDriverConfig::default()
    };
    if let Some(speed) = line_rate(config, device) {
        driver.speed_hz = speed;
    }
    for (channel, limits) in driver.limits.iter_mut().enumerate() {
        if let Some((max_velocity, max_accel)) = channel_limits(config, index, channel) {
            *limits = AxisLimits {
                max_velocity,
                max_accel,
            };
        }
    }
    Ok(Box::new(SpimotorDriver::new(driver)))
}

/// The machine parameters of spimotor device `index` and its axes, as the driver uses them.
pub(super) fn describe(
    config: &ServerConfig,
    index: usize,
    device: &DeviceSpec,
    out: &mut Vec<ParamRow>,
) {
    let _ = (config, index, device, out);
}
