//! The model registry: what motiond does with each board model, in one table. The model's
//! own facts (config id, contract code, link kind) are `motion_base::Model`; its machine
//! keys are validated in `config/validate/machine/<model>.rs` (the key table of
//! `machine/mod.rs` says which model has which key). Everything else a model needs from
//! the server is a [`Board`] entry here.

use motion_drivers::{Driver, Model, PinInfo};
use motion_link::sim::{SpiDevice, StreamDevice};

use crate::config::{DeviceSpec, PackVariant, QsbVariant, ServerConfig};
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
    /// The driver of device `index` (config → driver config → driver).
    pub build: fn(&ServerConfig, usize, &DeviceSpec) -> anyhow::Result<Box<dyn Driver>>,
    /// One [`ParamRow`] per machine parameter of device `index` and its axes.
    pub describe: fn(&ServerConfig, usize, &DeviceSpec, &mut Vec<ParamRow>),
    /// The simulated board of device `index`, configured like the machine.
    pub simulate: fn(&ServerConfig, usize, &DeviceSpec) -> SimBoard,
    /// The device's I/O pins (the model's pin table for its variant).
    pub pins: fn(&DeviceSpec) -> &'static [PinInfo],
}

const QQ2DRV: Board = Board {
    model: Model::Qq2drv,
    build: |config, index, device| Ok(drivers::qq2drv::build(config, index, device)),
    describe: drivers::qq2drv::describe,
    simulate: |config, index, device| {
        SimBoard::Spi(Box::new(sim_models::qq2drv::model(config, index, device)))
    },
    pins: |_| motion_drivers::qq2drv::PINS,
};

const TMCPACK: Board = Board {
    model: Model::Tmcpack,
    build: |config, index, device| Ok(drivers::tmcpack::build(config, index, device)),
    describe: drivers::tmcpack::describe,
    simulate: |config, index, device| {
        SimBoard::Stream(Box::new(sim_models::tmcpack::model(config, index, device)))
    },
    pins: |device| {
        motion_drivers::tmcpack::pins(match device.variant {
            PackVariant::Sixpack => tmcpack::Variant::SixPack,
            PackVariant::Quadpack => tmcpack::Variant::QuadPack,
        })
    },
};

const SPIMOTOR: Board = Board {
    model: Model::Spimotor,
    build: drivers::spimotor::build,
    describe: drivers::spimotor::describe,
    simulate: |config, index, device| {
        SimBoard::Spi(Box::new(sim_models::spimotor::model(config, index, device)))
    },
    pins: |_| motion_drivers::spimotor::PINS,
};

const QSB: Board = Board {
    model: Model::Qsb,
    build: |config, index, device| Ok(drivers::qsb::build(config, index, device)),
    describe: drivers::qsb::describe,
    simulate: |config, index, device| {
        SimBoard::Stream(Box::new(sim_models::qsb::model(config, index, device)))
    },
    pins: |device| {
        motion_drivers::qsb::pins(match device.qsb_variant {
            QsbVariant::M => qsb::ProductType::M,
            QsbVariant::S => qsb::ProductType::S,
            QsbVariant::D => qsb::ProductType::D,
        })
    },
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
