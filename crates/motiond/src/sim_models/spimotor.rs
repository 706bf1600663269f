//! A simulated SPI_motor as its `[[device]]` describes it.

use motion_sim::spimotor::{Drive, SpimotorSim, SpimotorSimConfig};

use crate::config::{DeviceSpec, ServerConfig, SpiDrive};

/// The model of spimotor device `index`.
pub(crate) fn model(config: &ServerConfig, index: usize, device: &DeviceSpec) -> SpimotorSim {
    let _ = (config, index);
    SpimotorSim::new(SpimotorSimConfig {
        address: device.address as u8,
        drive: match device.drive {
            SpiDrive::Stepper => Drive::Stepper,
            SpiDrive::Brushed => Drive::Brushed,
        },
        seed: device.sim_seed,
        ..SpimotorSimConfig::default()
    })
}
