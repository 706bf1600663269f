//! A simulated Trinamic pack as its `[[device]]` and axes describe it: each axis's reference
//! switch sits just beyond the soft limit its search runs to (`reference.side` /
//! `home.direction`), wired as `reference.active` says (an opener for "high"), and an axis
//! with a mechanical reference has end stops there.

use super::{MotorConfig, RefSwitch, TmcpackSim, TmcpackSimConfig};
use crate::driver::TmcpackDriverConfig;
use motion_drivers::spec::DriverSpec;
use motion_drivers::spec::FromSpec as _;

/// Width of a simulated reference switch: one unit, at least 64 microsteps (4 full steps).
fn switch_width(counts_per_unit: f64) -> i64 {
    (counts_per_unit.abs().round() as i64).max(64)
}

/// The simulated pack of the device `spec` describes. (Validation refuses every value
/// `from_spec` refuses; should one slip through, the pack gets the driver's defaults.)
pub(crate) fn model(spec: &DriverSpec, seed: u64) -> TmcpackSim {
    let driver = TmcpackDriverConfig::from_spec(spec).unwrap_or_default();
    let mut motors = [MotorConfig::default(); 6];
    for axis in &spec.axes {
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
        address: spec.address as u8,
        variant: driver.variant,
        seed,
        motors,
        // The firmware the machine's keys say it has.
        amax_divisor: driver.amax_divisor,
        options_layout: driver.options_layout,
        ..TmcpackSimConfig::default()
    })
}
