//! The simulated boards behind `type = "sim"` links, built from the config.

use motion_drivers::Model;
use motion_link::sim::{SimLink, SpiBus, StreamBus};
use motion_sim::qq2drv::{Qq2drvSim, Qq2drvSimConfig};
use motion_sim::qsb::{QsbSim, QsbSimConfig};
use motion_sim::spimotor::{Drive, SpimotorSim, SpimotorSimConfig};
use motion_sim::tmcpack::{TmcpackSim, TmcpackSimConfig};

use crate::config::{DeviceSpec, PackVariant, SpiDrive};

/// A simulated link carrying the models of `devices` (all on this link), at `rate` (baud
/// for serial boards, SPI clock for SPI boards).
pub fn sim_link(name: &str, rate: u32, devices: &[&DeviceSpec]) -> SimLink {
    let spi = devices
        .first()
        .is_some_and(|d| matches!(d.model, Model::Qq2drv | Model::Spimotor));
    if spi {
        let mut bus = SpiBus::new();
        for device in devices {
            match device.model {
                Model::Qq2drv => bus.push(Box::new(Qq2drvSim::new(Qq2drvSimConfig {
                    seed: device.sim_seed,
                    ..Qq2drvSimConfig::default()
                }))),
                Model::Spimotor => bus.push(Box::new(SpimotorSim::new(SpimotorSimConfig {
                    address: device.address as u8,
                    drive: match device.drive {
                        SpiDrive::Stepper => Drive::Stepper,
                        SpiDrive::Brushed => Drive::Brushed,
                    },
                    seed: device.sim_seed,
                    ..SpimotorSimConfig::default()
                }))),
                Model::Tmcpack | Model::Qsb => {}
            }
        }
        SimLink::spi(name, rate, Box::new(bus))
    } else {
        let mut bus = StreamBus::new();
        for device in devices {
            match device.model {
                Model::Tmcpack => bus.push(Box::new(TmcpackSim::new(TmcpackSimConfig {
                    address: device.address as u8,
                    variant: match device.variant {
                        PackVariant::Sixpack => tmcpack::Variant::SixPack,
                        PackVariant::Quadpack => tmcpack::Variant::QuadPack,
                    },
                    seed: device.sim_seed,
                    ..TmcpackSimConfig::default()
                }))),
                Model::Qsb => bus.push(Box::new(QsbSim::new(QsbSimConfig {
                    seed: device.sim_seed,
                    ..QsbSimConfig::default()
                }))),
                Model::Qq2drv | Model::Spimotor => {}
            }
        }
        SimLink::stream(name, rate, Box::new(bus))
    }
}
