//! The board model of a device: [`Model`], a handle on the model's [`ModelFacts`] (config
//! id, code in the shared-memory contract, the kind of link it sits on). The set of models
//! is open: a board crate declares its own facts (`static FACTS: ModelFacts`) and the
//! server learns every model from its registry (crate `motion-boards`, docs/ARCHITECTURE.md
//! "How to add a board"). The four built-in boards keep their facts here
//! ([`Model::QQ2DRV`], [`Model::TMCPACK`], [`Model::SPIMOTOR`], [`Model::QSB`]; their drivers
//! are in their own board crates, `crates/boards/<board>`, which name these constants): their
//! codes are the shared-memory contract's `MOTIOND_DEVICE_MODEL_*`, which a client names
//! without the registry ([`Model::BUILT_IN`]); any other board, like the worked example,
//! declares its facts in its crate.

use core::fmt;

use crate::LinkKind;

/// What every crate may know of a board model without depending on the board's crate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ModelFacts {
    /// The model id of the config and the CLIs (`model = "tmcpack"`): lower case, unique, at
    /// most 16 bytes of printable ASCII (it travels in the shared-memory contract's
    /// `DeviceInfo::model_id`, where clients read the model's name).
    pub id: &'static str,
    /// Its code in the shared-memory contract (`DeviceInfo::model`): nonzero, unique.
    pub code: u32,
    /// The kind of link the board sits on.
    pub link_kind: LinkKind,
    /// The product's name as its documents spell it (`"Trinamic SIXpack / QUADpack"`).
    pub title: &'static str,
}

/// A board model: a copyable handle on its [`ModelFacts`]. Two models are equal when their
/// facts are (codes are unique across a registry: its tests check it).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Model(&'static ModelFacts);

impl Model {
    /// QuadQuad2Drv (SPI, 4 DC motors with PID).
    pub const QQ2DRV: Self = Self(&ModelFacts {
        id: "qq2drv",
        code: 1,
        link_kind: LinkKind::Spi,
        title: "QuadQuad2Drv",
    });
    /// Trinamic SIXpack / QUADpack (RS-232 / RS-485 steppers).
    pub const TMCPACK: Self = Self(&ModelFacts {
        id: "tmcpack",
        code: 2,
        link_kind: LinkKind::Stream,
        title: "Trinamic SIXpack / QUADpack",
    });
    /// SPI_motor (SPI, 2 brushed motors or 1 stepper).
    pub const SPIMOTOR: Self = Self(&ModelFacts {
        id: "spimotor",
        code: 3,
        link_kind: LinkKind::Spi,
        title: "SPI_motor",
    });
    /// US Digital QSB (USB serial encoder interface, stepper on the -M).
    pub const QSB: Self = Self(&ModelFacts {
        id: "qsb",
        code: 4,
        link_kind: LinkKind::Stream,
        title: "US Digital QSB",
    });

    /// The models whose facts live here, for readers of the shared-memory contract that
    /// name a device's model from its code without the board registry (the clients); a
    /// code outside this list is an [`UnknownModel`] to them, shown by its number.
    pub const BUILT_IN: [Self; 4] = [Self::QQ2DRV, Self::TMCPACK, Self::SPIMOTOR, Self::QSB];

    /// The model `facts` describe.
    #[must_use]
    pub const fn new(facts: &'static ModelFacts) -> Self {
        Self(facts)
    }

    /// Its facts.
    #[must_use]
    pub const fn facts(self) -> &'static ModelFacts {
        self.0
    }

    /// The model id of the config and the CLIs (`model = "tmcpack"`).
    #[must_use]
    pub const fn id(self) -> &'static str {
        self.0.id
    }

    /// Its code in the shared-memory contract.
    #[must_use]
    pub const fn code(self) -> u32 {
        self.0.code
    }

    /// The kind of link the board sits on.
    #[must_use]
    pub const fn link_kind(self) -> LinkKind {
        self.0.link_kind
    }

    /// The product's name.
    #[must_use]
    pub const fn title(self) -> &'static str {
        self.0.title
    }
}

impl fmt::Debug for Model {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Model({})", self.id())
    }
}

impl fmt::Display for Model {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.id())
    }
}

/// A `u32` that is no known model's code (a model the reader was not built with).
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
    /// One of the [`BUILT_IN`](Model::BUILT_IN) models by its code.
    fn try_from(code: u32) -> Result<Self, Self::Error> {
        Self::BUILT_IN
            .into_iter()
            .find(|model| model.code() == code)
            .ok_or(UnknownModel(code))
    }
}

#[cfg(test)]
mod tests {
    use super::{LinkKind, Model, ModelFacts};

    #[test]
    fn a_model_is_its_facts() {
        static OTHER: ModelFacts = ModelFacts {
            id: "example",
            code: 99,
            link_kind: LinkKind::Stream,
            title: "Example",
        };
        let other = Model::new(&OTHER);
        assert_eq!(other.id(), "example");
        assert_eq!(other.code(), 99);
        assert_ne!(other, Model::TMCPACK);
        assert_eq!(Model::TMCPACK, Model::TMCPACK);
        assert_eq!(Model::TMCPACK.to_string(), "tmcpack");
        assert_eq!(format!("{:?}", Model::QSB), "Model(qsb)");
        assert_eq!(Model::QQ2DRV.link_kind(), LinkKind::Spi);
        for model in Model::BUILT_IN {
            assert_eq!(Model::try_from(model.code()), Ok(model));
        }
        assert_eq!(Model::try_from(99), Err(super::UnknownModel(99)));
    }
}
