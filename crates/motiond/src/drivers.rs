//! One driver per configured device, configured from its axes.

use anyhow::bail;
use motion_drivers::qq2drv::{HomeInput, Qq2drvDriver, Qq2drvDriverConfig};
use motion_drivers::qsb::{QsbDriver, QsbDriverConfig};
use motion_drivers::spimotor::{AxisLimits, SpimotorDrive, SpimotorDriver, SpimotorDriverConfig};
use motion_drivers::tmcpack::{TmcpackChannel, TmcpackDriver, TmcpackDriverConfig};
use motion_drivers::{Driver, Model};

use crate::config::{DeviceSpec, HomeInputKind, PackVariant, ServerConfig, SpiDrive, Transport};

/// Velocity and acceleration limits of `device`'s channel `channel` in counts, from the axis
/// that drives it.
fn channel_limits(config: &ServerConfig, device: usize, channel: usize) -> Option<(f64, f64)> {
    config
        .axes
        .iter()
        .find(|axis| axis.device == device && axis.channel == channel)
        .map(|axis| {
            let scale = axis.counts_per_unit.abs();
            (axis.max_velocity * scale, axis.max_accel * scale)
        })
}

/// The line rate of `device`'s link (baud or SPI clock), when the config gives one.
fn line_rate(config: &ServerConfig, device: &DeviceSpec) -> Option<u32> {
    match &config.links.get(device.link)?.transport {
        Transport::Serial { baud, .. } => Some(*baud),
        Transport::Spidev { speed_hz, .. } => Some(*speed_hz),
        Transport::Sim { rate } => Some(*rate),
        Transport::SpiSocket { .. } => None,
    }
}

fn tmcpack(config: &ServerConfig, index: usize, device: &DeviceSpec) -> Box<dyn Driver> {
    let mut driver = TmcpackDriverConfig {
        address: device.address as u8,
        variant: match device.variant {
            PackVariant::Sixpack => tmcpack::Variant::SixPack,
            PackVariant::Quadpack => tmcpack::Variant::QuadPack,
        },
        ..TmcpackDriverConfig::default()
    };
    if let Some(baud) = line_rate(config, device) {
        driver.baud = baud;
    }
    // Every pack on the link shares its polling budget.
    driver.bus_motors = config
        .axes
        .iter()
        .filter(|axis| config.devices[axis.device].link == device.link)
        .count()
        .min(usize::from(u8::MAX)) as u8;
    for (channel, slot) in driver.channels.iter_mut().enumerate() {
        if let Some((max_velocity, max_accel)) = channel_limits(config, index, channel) {
            *slot = Some(TmcpackChannel {
                max_velocity,
                max_accel,
                ..TmcpackChannel::default()
            });
        }
    }
    Box::new(TmcpackDriver::new(driver))
}

fn spimotor(
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

fn qq2drv(config: &ServerConfig, index: usize, device: &DeviceSpec) -> Box<dyn Driver> {
    let mut driver = Qq2drvDriverConfig::default();
    if let Some(speed) = line_rate(config, device) {
        driver.speed_hz = speed;
    }
    for (channel, slot) in driver.channels.iter_mut().enumerate() {
        match channel_limits(config, index, channel) {
            Some((max_velocity, max_accel)) => {
                slot.enabled = true;
                slot.limits.max_velocity = max_velocity;
                slot.limits.max_accel = max_accel;
            }
            None => slot.enabled = false,
        }
        let home = config
            .axes
            .iter()
            .zip(&config.homes)
            .find(|(axis, _)| axis.device == index && axis.channel == channel)
            .and_then(|(axis, home)| home.map(|home| (axis.counts_per_unit, home)));
        slot.home = home.map(|(counts_per_unit, home)| HomeInput {
            mode: match home.input {
                HomeInputKind::Home => qq2drv::InputMode::Home,
                HomeInputKind::Index => qq2drv::InputMode::Index,
                HomeInputKind::Edge => qq2drv::InputMode::Edge,
            },
            active_high: home.active_high,
            positive_end: home.positive_end == (counts_per_unit > 0.0),
            position: (home.position * counts_per_unit).round() as i32,
        });
    }
    Box::new(Qq2drvDriver::new(driver))
}

fn qsb(config: &ServerConfig, index: usize, device: &DeviceSpec) -> Box<dyn Driver> {
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

/// Builds the drivers of `config`'s devices, in config order.
pub fn build(config: &ServerConfig) -> anyhow::Result<Vec<Box<dyn Driver>>> {
    let mut drivers: Vec<Box<dyn Driver>> = Vec::with_capacity(config.devices.len());
    for (index, device) in config.devices.iter().enumerate() {
        drivers.push(match device.model {
            Model::Tmcpack => tmcpack(config, index, device),
            Model::Spimotor => spimotor(config, index, device)?,
            Model::Qq2drv => qq2drv(config, index, device),
            Model::Qsb => qsb(config, index, device),
        });
    }
    Ok(drivers)
}
