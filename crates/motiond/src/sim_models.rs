//! The simulated boards behind `type = "sim"` links, built from the config.

use motion_drivers::Model;
use motion_link::sim::{SimLink, SpiBus, StreamBus};
use motion_sim::qq2drv::{InputPin, InputSource, Qq2drvSim, Qq2drvSimConfig};
use motion_sim::qsb::{QsbSim, QsbSimConfig};
use motion_sim::spimotor::{Drive, SpimotorSim, SpimotorSimConfig};
use motion_sim::tmcpack::{TmcpackSim, TmcpackSimConfig};

use crate::config::{HomeInputKind, PackVariant, ServerConfig, SpiDrive, Transport};

/// The IN pins of a simulated QuadQuad2Drv, wired as its axes' `home` tables say: an
/// encoder index once per revolution, or a switch at the end of travel the search runs to.
fn qq2drv_inputs(config: &ServerConfig, device: usize) -> [InputPin; 4] {
    let mut inputs = [InputPin::default(); 4];
    for (axis, home) in config.axes.iter().zip(&config.homes) {
        let (Some(home), true) = (home, axis.device == device) else {
            continue;
        };
        let Some(pin) = inputs.get_mut(axis.channel) else {
            continue;
        };
        let end = if home.positive_end {
            axis.max
        } else {
            axis.min
        };
        pin.actuated_high = home.active_high;
        pin.source = match home.input {
            HomeInputKind::Index => InputSource::Index {
                offset: 0.0,
                width: 4.0,
            },
            HomeInputKind::Home | HomeInputKind::Edge => InputSource::EndStop {
                position: end * axis.counts_per_unit,
                positive_end: home.positive_end == (axis.counts_per_unit > 0.0),
            },
        };
    }
    inputs
}

/// The simulated link `link` of `config` (a `type = "sim"` link) with the models of its
/// devices, at its rate (baud for serial boards, SPI clock for SPI boards).
pub fn sim_link(config: &ServerConfig, link: usize) -> SimLink {
    let spec = &config.links[link];
    let name = spec.name.as_str();
    let rate = match spec.transport {
        Transport::Sim { rate } => rate,
        _ => 1_000_000,
    };
    let devices: Vec<(usize, &crate::config::DeviceSpec)> = config
        .devices
        .iter()
        .enumerate()
        .filter(|(_, d)| d.link == link)
        .collect();
    let spi = devices
        .first()
        .is_some_and(|(_, d)| matches!(d.model, Model::Qq2drv | Model::Spimotor));
    if spi {
        let mut bus = SpiBus::new();
        for (index, device) in &devices {
            match device.model {
                Model::Qq2drv => bus.push(Box::new(Qq2drvSim::new(Qq2drvSimConfig {
                    seed: device.sim_seed,
                    inputs: qq2drv_inputs(config, *index),
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
        for (_, device) in &devices {
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
