//! The simulated boards behind `type = "sim"` links, built from the config (one module per
//! board model).

pub(crate) mod qq2drv;
pub(crate) mod qsb;
pub(crate) mod spimotor;
pub(crate) mod tmcpack;

use motion_drivers::LinkKind;
use motion_link::sim::{SimLink, SpiBus, StreamBus};

use crate::boards::{SimBoard, board};
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
        .is_some_and(|(_, d)| d.model.link_kind() == LinkKind::Spi);
    let mut spi_bus = SpiBus::new();
    let mut stream_bus = StreamBus::new();
    for &(index, device) in &devices {
        // Validation keeps SPI and stream models apart; a model of the other kind is left out.
        match (board(device.model).simulate)(config, index, device) {
            SimBoard::Spi(model) if spi => spi_bus.push(model),
            SimBoard::Stream(model) if !spi => stream_bus.push(model),
            SimBoard::Spi(_) | SimBoard::Stream(_) => {}
        }
    }
    if spi {
        SimLink::spi(name, rate, Box::new(spi_bus))
    } else {
        SimLink::stream(name, rate, Box::new(stream_bus))
    }
}
