//! The board models motiond drives: one enum, with every fact about a model that more than
//! one crate needs (its config id, its code in the shared-memory contract, the kind of link
//! it sits on). The per-model code is found from here: see "How to add a board" in
//! docs/ARCHITECTURE.md.

use core::fmt;

use crate::LinkKind;

/// A board model. Travels as its `u32` code in the shared-memory contract
/// (`DeviceInfo::model`, where `motion_ipc` calls it `DeviceModel`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum Model {
    /// QuadQuad2Drv (SPI, 4 DC motors with PID).
    Qq2drv = 1,
    /// Trinamic SIXpack / QUADpack (RS-232 / RS-485 steppers).
    Tmcpack = 2,
    /// SPI_motor (SPI, 2 brushed motors or 1 stepper).
    Spimotor = 3,
    /// US Digital QSB (USB serial encoder interface, stepper on the -M).
    Qsb = 4,
}

impl Model {
    /// Every model, in code order.
    pub const ALL: [Self; 4] = [Self::Qq2drv, Self::Tmcpack, Self::Spimotor, Self::Qsb];

    /// The model id of the config and the CLIs (`model = "tmcpack"`).
    #[must_use]
    pub const fn id(self) -> &'static str {
        match self {
            Self::Qq2drv => "qq2drv",
            Self::Tmcpack => "tmcpack",
            Self::Spimotor => "spimotor",
            Self::Qsb => "qsb",
        }
    }

    /// The model of a config id.
    #[must_use]
    pub fn from_id(id: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|model| model.id() == id)
    }

    /// The ids of every model, for messages (`qq2drv, tmcpack, spimotor, qsb`).
    #[must_use]
    pub const fn id_list() -> &'static str {
        "qq2drv, tmcpack, spimotor, qsb"
    }

    /// Its code in the shared-memory contract.
    #[must_use]
    pub const fn code(self) -> u32 {
        self as u32
    }

    /// The kind of link the board sits on.
    #[must_use]
    pub const fn link_kind(self) -> LinkKind {
        match self {
            Self::Qq2drv | Self::Spimotor => LinkKind::Spi,
            Self::Tmcpack | Self::Qsb => LinkKind::Stream,
        }
    }
}

impl fmt::Display for Model {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.id())
    }
}

/// A `u32` that is no [`Model`] code (a value from a newer writer).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct UnknownModel(pub u32);

impl fmt::Display for UnknownModel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "unknown model code {}", self.0)
    }
}

impl std::error::Error for UnknownModel {}

impl TryFrom<u32> for Model {
    type Error = UnknownModel;
    fn try_from(value: u32) -> Result<Self, Self::Error> {
        Self::ALL
            .into_iter()
            .find(|model| model.code() == value)
            .ok_or(UnknownModel(value))
    }
}

#[cfg(test)]
mod tests {
    use super::{Model, UnknownModel};

    #[test]
    fn ids_and_codes_round_trip() {
        for model in Model::ALL {
            assert_eq!(Model::from_id(model.id()), Some(model));
            assert_eq!(Model::try_from(model.code()), Ok(model));
            assert!(Model::id_list().contains(model.id()));
        }
        assert_eq!(Model::from_id("x"), None);
        assert_eq!(Model::try_from(0), Err(UnknownModel(0)));
        assert_eq!(Model::Tmcpack.to_string(), "tmcpack");
    }
}
