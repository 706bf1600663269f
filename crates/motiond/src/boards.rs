//! What motiond does with the boards of its config, through the board registry
//! (`motion_boards`): [`build`] the drivers, [`describe`] their machine parameters, serve a
//! `type = "sim"` link with simulated boards ([`sim_link`]), a `type = "sim-can"` link
//! ([`sim_can_link`]). motiond names no board here:
//! each model's facts, driver, parameters and simulator are its board crate's
//! (`crates/boards/<board>/`, trait `motion_board::Board`), its machine keys too (read
//! and validated by the board through `config/validate/machine/`); each board's driver is
//! built from the `DriverSpec` filled in `drivers.rs`.

pub use motion_boards::AnyDriver;
use motion_boards::{Board, SimBoard};
use motion_link::sim::{CanBus, SimCanLink, SimLink, SpiBus, StreamBus};

use crate::config::{DeviceSpec, ServerConfig, Transport};
use crate::drivers::{self, ParamRow};

/// A device whose driver cannot be built from its validated config: the key and why.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("device `{device}`: {key}: {message}")]
pub struct BuildError {
    /// The device's name.
    pub device: String,
    /// The config key the board refused (`device[0].switchover_ms`, `axis[3].current.peak`).
    pub key: String,
    /// What is wrong with its value.
    pub message: String,
}

/// The board of `device`.
#[must_use]
pub fn board_of(device: &DeviceSpec) -> &'static dyn Board {
    motion_boards::board(device.model)
}

/// Builds the drivers of `config`'s devices, in config order, as the registry's enum the
/// tick holds (`AnyDriver`: static dispatch, each driver inline in its link's bus).
///
/// # Errors
/// The first device whose board refuses its spec.
pub fn build(config: &ServerConfig) -> Result<Vec<AnyDriver>, BuildError> {
    let mut built = Vec::with_capacity(config.devices.len());
    for (index, device) in config.devices.iter().enumerate() {
        let spec = drivers::driver_spec(config, index, device);
        let driver =
            AnyDriver::build(&spec).map_err(|error| drivers::spec_error(config, index, &error))?;
        built.push(driver);
    }
    Ok(built)
}

/// Every machine parameter of every device and axis, with the value in effect.
pub fn describe(config: &ServerConfig) -> Vec<ParamRow> {
    let mut rows = Vec::new();
    for (index, device) in config.devices.iter().enumerate() {
        let spec = drivers::driver_spec(config, index, device);
        // A device whose spec the driver refuses has no driver and so no parameters.
        if let Ok(params) = board_of(device).params(&spec) {
            rows.extend(drivers::param_rows(config, index, params));
        }
    }
    rows
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
    let mut spi_bus = SpiBus::new();
    let mut stream_bus = StreamBus::new();
    let mut host_frame = None;
    for (index, device) in config.devices.iter().enumerate() {
        if device.link != link {
            continue;
        }
        let board = board_of(device);
        let model = board.simulate(
            &drivers::driver_spec(config, index, device),
            device.sim_seed,
        );
        // Validation keeps SPI and stream models apart; a model of the other kind is left out.
        match (model, spec.kind) {
            (SimBoard::Spi(model), motion_drivers::LinkKind::Spi) => spi_bus.push(model),
            (SimBoard::Stream(model), motion_drivers::LinkKind::Stream) => {
                stream_bus.push(model);
            }
            (SimBoard::Spi(_) | SimBoard::Stream(_), _) => {}
        }
        // Devices behind USB share its frames (a link mixes no others in practice).
        host_frame = host_frame.max(board.link().host_frame);
    }
    match spec.kind {
        motion_drivers::LinkKind::Spi => SimLink::spi(name, rate, Box::new(spi_bus)),
        motion_drivers::LinkKind::Stream => {
            let link = SimLink::stream(name, rate, Box::new(stream_bus));
            match host_frame {
                Some(frame) => link.with_host_frames(frame),
                None => link,
            }
        }
    }
}

/// The simulated CAN bus `link` of `config` (a `type = "sim-can"` link) with the CAN
/// models of its devices, at its bit rate. A board without CAN is left off (validation
/// refuses it on a CAN link).
pub fn sim_can_link(config: &ServerConfig, link: usize) -> SimCanLink {
    let spec = &config.links[link];
    let bitrate = match spec.transport {
        Transport::SimCan { bitrate } | Transport::SocketCan { bitrate, .. } => bitrate,
        _ => 250_000,
    };
    let mut bus = CanBus::new();
    for (index, device) in config.devices.iter().enumerate() {
        if device.link != link {
            continue;
        }
        if let Some(model) = board_of(device).simulate_can(
            &drivers::driver_spec(config, index, device),
            device.sim_seed,
        ) {
            bus.push(model);
        }
    }
    SimCanLink::new(&spec.name, bitrate, Box::new(bus))
}

#[cfg(test)]
mod tests {
    use motion_ipc::{DeviceInfo, write_text};

    /// The engine writes each model's id into `DeviceInfo::model_id`, where clients read
    /// the model's name: every registered id fits whole and reads back as itself.
    #[test]
    fn every_model_id_travels_whole_in_the_device_info() {
        for board in motion_boards::BOARDS {
            let id = board.model().id();
            let mut device = DeviceInfo::EMPTY;
            assert!(write_text(&mut device.model_id, id), "{id} is cut");
            assert_eq!(device.model_name(), id);
        }
    }
}
