//! The simulated boards behind `type = "sim"` links, built from the config (one module per
//! board model).

mod qq2drv;
mod qsb;
mod spimotor;
mod tmcpack;

use motion_drivers::Model;
use motion_link::sim::{SimLink, SpiBus, StreamBus};

use crate::config::{ServerConfig, Transport};

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
        for &(index, device) in &devices {
            match device.model {
                Model::Qq2drv => bus.push(Box::new(qq2drv::model(config, index, device))),
                Model::Spimotor => bus.push(Box::new(spimotor::model(config, index, device))),
                Model::Tmcpack | Model::Qsb => {}
            }
        }
        SimLink::spi(name, rate, Box::new(bus))
    } else {
        let mut bus = StreamBus::new();
        for &(index, device) in &devices {
            match device.model {
                Model::Tmcpack => bus.push(Box::new(tmcpack::model(config, index, device))),
                Model::Qsb => bus.push(Box::new(qsb::model(config, index, device))),
                Model::Qq2drv | Model::Spimotor => {}
            }
        }
        SimLink::stream(name, rate, Box::new(bus))
    }
}
