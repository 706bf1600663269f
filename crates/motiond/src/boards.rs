//! The model registry: what motiond does with each board model, in one table, and the
//! three things done through it: [`build`] the drivers, [`describe`] their machine
//! parameters, serve a `type = "sim"` link with simulated boards ([`sim_link`]). The
//! model's own facts (config id, contract code, link kind) are `motion_base::Model`; its
//! machine keys are validated in `config/validate/machine/<model>.rs` (the key table of
//! `machine/mod.rs` says which model has which key) into `motion_drivers::spec`, whose
//! `DriverSpec` (filled in `drivers.rs`) each board's driver config is built from; its
//! channel count and pin table are `config::channel_count` and `DeviceSpec::pins`.

use motion_drivers::qq2drv::{Qq2drvDriver, Qq2drvDriverConfig};
use motion_drivers::qsb::{QsbDriver, QsbDriverConfig};
use motion_drivers::spec::{DriverSpec, Param, SpecError};
use motion_drivers::spimotor::{SpimotorDriver, SpimotorDriverConfig};
use motion_drivers::tmcpack::{TmcpackDriver, TmcpackDriverConfig};
use motion_drivers::{Driver, LinkKind, Model};
use motion_link::sim::{SimLink, SpiBus, SpiDevice, StreamBus, StreamDevice};

use crate::config::{DeviceSpec, ServerConfig, Transport};
use crate::drivers::{self, ParamRow};
use crate::sim_models;

/// A simulated board on a `type = "sim"` link.
pub enum SimBoard {
    /// A board on a byte stream.
    Stream(Box<dyn StreamDevice>),
    /// A board on an SPI bus.
    Spi(Box<dyn SpiDevice>),
}

impl core::fmt::Debug for SimBoard {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::Stream(_) => "SimBoard::Stream",
            Self::Spi(_) => "SimBoard::Spi",
        })
    }
}

/// What the server does with one board model.
#[derive(Debug, Clone, Copy)]
pub struct Board {
    /// The model.
    pub model: Model,
    /// The driver of the device a spec describes (spec → driver config → driver).
    pub build: fn(&DriverSpec) -> Result<Box<dyn Driver>, SpecError>,
    /// One [`Param`] per machine parameter of the device a spec describes and its axes.
    pub describe: fn(&DriverSpec) -> Result<Vec<Param>, SpecError>,
    /// The simulated board of device `index`, configured like the machine.
    pub simulate: fn(&ServerConfig, usize, &DeviceSpec) -> SimBoard,
    /// How the board's bytes reach the host on a simulated link: `Some(frame)` for a
    /// board behind USB (handed over at the end of each bus frame), `None` as each byte's
    /// wire time passes.
    pub host_frame: Option<core::time::Duration>,
}

/// A full-speed USB device is polled once per 1 ms frame.
const USB_FRAME: core::time::Duration = core::time::Duration::from_millis(1);

const QQ2DRV: Board = Board {
    model: Model::Qq2drv,
    build: |spec| {
        Ok(Box::new(Qq2drvDriver::new(Qq2drvDriverConfig::from_spec(
            spec,
        )?)))
    },
    describe: |spec| Qq2drvDriverConfig::from_spec(spec).map(|config| config.params(spec)),
    simulate: |config, index, device| {
        SimBoard::Spi(Box::new(sim_models::qq2drv::model(config, index, device)))
    },
    host_frame: None,
};

const TMCPACK: Board = Board {
    model: Model::Tmcpack,
    build: |spec| {
        Ok(Box::new(TmcpackDriver::new(
            TmcpackDriverConfig::from_spec(spec)?,
        )))
    },
    describe: |spec| TmcpackDriverConfig::from_spec(spec).map(|config| config.params(spec)),
    simulate: |config, index, device| {
        SimBoard::Stream(Box::new(sim_models::tmcpack::model(config, index, device)))
    },
    // RS-232 or RS-485 (manual 2): a UART, whatever adapter the host uses.
    host_frame: None,
};

const SPIMOTOR: Board = Board {
    model: Model::Spimotor,
    build: |spec| {
        Ok(Box::new(SpimotorDriver::new(
            SpimotorDriverConfig::from_spec(spec)?,
        )))
    },
    describe: |spec| SpimotorDriverConfig::from_spec(spec).map(|config| config.params(spec)),
    simulate: |config, index, device| {
        SimBoard::Spi(Box::new(sim_models::spimotor::model(config, index, device)))
    },
    host_frame: None,
};

const QSB: Board = Board {
    model: Model::Qsb,
    build: |spec| Ok(Box::new(QsbDriver::new(QsbDriverConfig::from_spec(spec)?))),
    describe: |spec| QsbDriverConfig::from_spec(spec).map(|config| config.params(spec)),
    simulate: |config, index, device| {
        SimBoard::Stream(Box::new(sim_models::qsb::model(config, index, device)))
    },
    // "The commands and responses are sent in RS-232 format over a virtual COM port
    // connection through the USB" (QSB command list, Communications).
    host_frame: Some(USB_FRAME),
};

/// The registry entry of `model`.
#[must_use]
pub const fn board(model: Model) -> &'static Board {
    match model {
        Model::Qq2drv => &QQ2DRV,
        Model::Tmcpack => &TMCPACK,
        Model::Spimotor => &SPIMOTOR,
        Model::Qsb => &QSB,
    }
}

/// Builds the drivers of `config`'s devices, in config order.
pub fn build(config: &ServerConfig) -> anyhow::Result<Vec<Box<dyn Driver>>> {
    let mut drivers: Vec<Box<dyn Driver>> = Vec::with_capacity(config.devices.len());
    for (index, device) in config.devices.iter().enumerate() {
        let spec = drivers::driver_spec(config, index, device);
        let driver = (board(device.model).build)(&spec)
            .map_err(|error| drivers::spec_error(config, index, &error))?;
        drivers.push(driver);
    }
    Ok(drivers)
}

/// Every machine parameter of every device and axis, with the value in effect.
pub fn describe(config: &ServerConfig) -> Vec<ParamRow> {
    let mut rows = Vec::new();
    for (index, device) in config.devices.iter().enumerate() {
        let spec = drivers::driver_spec(config, index, device);
        // A device whose spec the driver refuses has no driver and so no parameters.
        if let Ok(params) = (board(device.model).describe)(&spec) {
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
    let devices: Vec<(usize, &DeviceSpec)> = config
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
        let link = SimLink::stream(name, rate, Box::new(stream_bus));
        // Devices behind USB share its frames (a link mixes no others in practice).
        let frame = devices
            .iter()
            .filter_map(|(_, d)| board(d.model).host_frame)
            .max();
        match frame {
            Some(frame) => link.with_host_frames(frame),
            None => link,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::board;
    use motion_drivers::Model;

    #[test]
    fn every_model_has_its_own_entry() {
        for model in Model::ALL {
            assert_eq!(board(model).model, model);
        }
    }
}
