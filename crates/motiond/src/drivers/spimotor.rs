//! The SPI_motor driver of a `[[device]]`, configured from its axes and machine keys.

use anyhow::bail;
use motion_drivers::Driver;
use motion_drivers::spimotor::{AxisLimits, SpimotorDrive, SpimotorDriver, SpimotorDriverConfig};
use spimotor::Coils;

use super::{ParamRow, channel_limits, line_rate};
use crate::config::{DeviceMachine, DeviceSpec, Owner, ServerConfig, SpiDrive};

/// The driver configuration of spimotor device `index`: address, drive, its link's clock,
/// the axis limits and (stepper) the drive intensity and coils.
pub(crate) fn driver_config(
    config: &ServerConfig,
    index: usize,
    device: &DeviceSpec,
) -> anyhow::Result<SpimotorDriverConfig> {
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
    if let DeviceMachine::Spimotor(keys) = &device.machine {
        if let Some(intensity) = keys.intensity {
            driver.stepper_intensity = intensity;
        }
        match keys.coils {
            Some(1) => driver.coils = Coils::One,
            Some(_) => driver.coils = Coils::Two,
            None => {}
        }
    }
    Ok(driver)
}

/// The driver of spimotor device `index`.
pub(crate) fn build(
    config: &ServerConfig,
    index: usize,
    device: &DeviceSpec,
) -> anyhow::Result<Box<dyn Driver>> {
    Ok(Box::new(SpimotorDriver::new(driver_config(
        config, index, device,
    )?)))
}

/// The machine parameters of spimotor device `index`, as the driver uses them: a stepper
/// board's `intensity` (port 0x10) and `coils` (port 0x44). A brushed board has none.
pub(crate) fn describe(
    config: &ServerConfig,
    index: usize,
    device: &DeviceSpec,
    out: &mut Vec<ParamRow>,
) {
    if device.drive != SpiDrive::Stepper {
        return;
    }
    let Ok(driver) = driver_config(config, index, device) else {
        return;
    };
    out.push(ParamRow {
        owner: Owner::Device(index),
        key: "intensity".to_owned(),
        value: format!(
            "{} (0x{:02x} of 0xff)",
            driver.stepper_intensity, driver.stepper_intensity
        ),
    });
    out.push(ParamRow {
        owner: Owner::Device(index),
        key: "coils".to_owned(),
        value: match driver.coils {
            Coils::One => "1 (port 0x44 ← 0x00)".to_owned(),
            Coils::Two => "2 (port 0x44 ← 0x01)".to_owned(),
        },
    });
}
