//! A simulated Trinamic pack as its `[[device]]` and axes describe it: each axis's reference
//! switch sits just beyond the soft limit its search runs to (`reference.side` /
//! `home.direction`), wired as `reference.active` says (an opener for "high"), and an axis
//! with a mechanical reference has end stops there.

use motion_sim::tmcpack::{MotorConfig, RefSwitch, TmcpackSim, TmcpackSimConfig};

use crate::config::{DeviceSpec, ServerConfig};
use crate::drivers::tmcpack_driver_config;

/// Width of a simulated reference switch: one unit, at least 64 microsteps (4 full steps).
fn switch_width(counts_per_unit: f64) -> i64 {
    (counts_per_unit.abs().round() as i64).max(64)
}

/// The model of tmcpack device `index`.
pub(crate) fn model(config: &ServerConfig, index: usize, device: &DeviceSpec) -> TmcpackSim {
    let driver = tmcpack_driver_config(config, index, device);
    let mut motors = [MotorConfig::default(); 6];
    for axis in config.axes.iter().filter(|a| a.device == index) {
        let (Some(slot), Some(Some(channel))) = (
            motors.get_mut(axis.channel),
            driver.channels.get(axis.channel),
        ) else {
            continue;
        };
        let cpu = axis.counts_per_unit;
        let (lo, hi) = {
            let (a, b) = (axis.min * cpu, axis.max * cpu);
            (a.min(b).round() as i64, a.max(b).round() as i64)
        };
        let width = switch_width(cpu);
        // The rotor starts at physical 0 = position 0; the search runs towards decreasing
        // microsteps with NullLeft (manual 8.3 $15).
        let toward_lower = channel.searches_toward_lower();
        let (from, to) = if toward_lower {
            (lo - width, lo - 1)
        } else {
            (hi + 1, hi + width)
        };
        slot.ref_switch = Some(RefSwitch {
            from,
            to,
            opener: channel.switch_active_high(),
        });
        if channel.mechanical_reference() {
            slot.travel = Some((lo - width, hi + width));
        }
    }
    TmcpackSim::new(TmcpackSimConfig {
        address: device.address as u8,
        variant: driver.variant,
        seed: device.sim_seed,
        motors,
        ..TmcpackSimConfig::default()
    })
}
