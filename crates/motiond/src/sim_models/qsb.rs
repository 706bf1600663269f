//! A simulated QSB as its `[[device]]` and axis describe it: the variant, the encoder's
//! counts per motor step, and the external stepper driver's enable line where
//! `enable_output` says it is wired. (The index is the encoder's, once per revolution of
//! the model's 500-cycle encoder: a home search finds it within 2000 counts.)

use motion_drivers::qsb::QsbDriverConfig;
use motion_sim::qsb::{DriveEnable, QsbSim, QsbSimConfig, Variant};

use crate::config::{DeviceMachine, DeviceSpec, QsbVariant, ServerConfig};

/// The model of qsb device `index`.
pub(crate) fn model(config: &ServerConfig, index: usize, device: &DeviceSpec) -> QsbSim {
    let _ = (config, index);
    let (counts_per_step, drive_enable) = match &device.machine {
        DeviceMachine::Qsb(keys) => (
            keys.counts_per_step,
            keys.enable_output.map(|bit| DriveEnable {
                bit,
                active_high: keys.enable_active_high.unwrap_or(false),
            }),
        ),
        _ => (None, None),
    };
    let counts_per_step =
        counts_per_step.unwrap_or_else(|| QsbDriverConfig::default().counts_per_step);
    QsbSim::new(QsbSimConfig {
        variant: match device.qsb_variant {
            QsbVariant::M => Variant::M,
            QsbVariant::S => Variant::S,
            QsbVariant::D => Variant::D,
        },
        seed: device.sim_seed,
        drive_enable,
        ..QsbSimConfig::default().with_counts_per_step(counts_per_step)
    })
}
