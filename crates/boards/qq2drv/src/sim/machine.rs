//! A simulated QuadQuad2Drv as its `[[device]]` and axes describe it.

use super::{InputPin, InputSource, Qq2drvSim, Qq2drvSimConfig};
use motion_drivers::spec::{Direction, DriverSpec, HomeInputKind};

/// The IN pins of a simulated QuadQuad2Drv, wired as its axes' `home` tables say: an
/// encoder index once per revolution, a switch at the end of travel the search runs to, or
/// (with `home.spacing`: two end-stops on one input) a switch at each end of travel.
fn inputs(spec: &DriverSpec) -> [InputPin; 4] {
    let mut inputs = [InputPin::default(); 4];
    for axis in &spec.axes {
        let Some(input) = axis.home.input else {
            continue;
        };
        let Some(pin) = inputs.get_mut(axis.channel) else {
            continue;
        };
        let positive = axis.home.direction == Direction::Positive;
        let end = if positive { axis.max } else { axis.min };
        pin.actuated_high = input.active_high;
        pin.source = match input.kind {
            HomeInputKind::Index => InputSource::Index {
                offset: 0.0,
                width: 4.0,
            },
            HomeInputKind::Home | HomeInputKind::Edge if input.spacing.is_some() => {
                let (a, b) = (
                    axis.min * axis.counts_per_unit,
                    axis.max * axis.counts_per_unit,
                );
                InputSource::TwoEndStops {
                    negative: a.min(b),
                    positive: a.max(b),
                }
            }
            HomeInputKind::Home | HomeInputKind::Edge => InputSource::EndStop {
                position: end * axis.counts_per_unit,
                positive_end: positive == (axis.counts_per_unit > 0.0),
            },
        };
    }
    inputs
}

/// The simulated board of the device `spec` describes.
pub(crate) fn model(spec: &DriverSpec, seed: u64) -> Qq2drvSim {
    Qq2drvSim::new(Qq2drvSimConfig {
        seed,
        inputs: inputs(spec),
        // The firmware the device's `velocity_ramp` says it has.
        velocity_ramp: spec
            .machine
            .get_or_default::<crate::Qq2drvDeviceKeys>()
            .velocity_ramp
            .unwrap_or_default(),
        ..Qq2drvSimConfig::default()
    })
}
