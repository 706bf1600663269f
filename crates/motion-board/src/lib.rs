//! The plug-in interface of a board: [`Board`].
//!
//! motiond, its config validator and its simulated links know a board model only through
//! this trait and the registry's list (crate `motion-boards`): its facts (model, whether
//! boards share a link, the line rate and SPI mode it starts at, how its bytes reach the
//! host), its channels and pins, how its driver is built from the neutral
//! [`DriverSpec`], what the driver made of the machine keys ([`Param`]s, for
//! `motionctl list` and the published parameters), and its simulated board on a
//! `type = "sim"` link. One crate per board implements it (`crates/boards/<board>/`);
//! docs/ARCHITECTURE.md "How to add a board" walks through one.
//!
//! Nothing here runs per tick: a [`Board`] is consulted at start-up. The driver it builds
//! is what the tick calls.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

use core::fmt;
use core::time::Duration;

use motion_drivers::spec::{DriverSpec, PackVariant, Param, QsbVariant, SpecError, SpiDrive};
use motion_drivers::{Driver, Model, PinInfo};
use motion_link::sim::{SpiDevice, StreamDevice};

/// A simulated board, on the kind of wire its model uses.
pub enum SimBoard {
    /// A board on a byte stream.
    Stream(Box<dyn StreamDevice>),
    /// A board on an SPI bus.
    Spi(Box<dyn SpiDevice>),
}

impl fmt::Debug for SimBoard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Stream(_) => "SimBoard::Stream",
            Self::Spi(_) => "SimBoard::Spi",
        })
    }
}

/// The general variant keys of a `[[device]]` (`variant`, `drive`), as validated: what a
/// board's channel count and pin table depend on. A model reads the one that is its own
/// and ignores the others.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Variants {
    /// Trinamic pack variant (SIXpack, QUADpack).
    pub pack: PackVariant,
    /// QSB product variant.
    pub qsb: QsbVariant,
    /// SPI_motor drive.
    pub drive: SpiDrive,
}

impl Variants {
    /// The variants a [`DriverSpec`] was filled with.
    #[must_use]
    pub fn of(spec: &DriverSpec) -> Self {
        Self {
            pack: spec.pack_variant,
            qsb: spec.qsb_variant,
            drive: spec.drive,
        }
    }
}

/// How a board's link is laid out: the facts the config validator checks links against.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LinkFacts {
    /// Several boards of this model may share one link (an RS-485 bus, SPI chip selects);
    /// they are told apart by their `address`.
    pub shared: bool,
    /// The line rate a `type = "sim"` link runs at unless given: the board's factory baud
    /// on a serial link, the SPI clock on an SPI link.
    pub default_rate: u32,
    /// The SPI mode (0..=3) a spidev link uses unless given; 0 for a serial board.
    pub spi_mode: u8,
    /// How a simulated link hands the board's bytes to the host: `Some(frame)` for a
    /// board behind USB (everything received within a bus frame at its end), `None` as
    /// each byte's wire time passes.
    pub host_frame: Option<Duration>,
}

/// One board model, as the server knows it. Implemented once per board crate; the
/// registry (`motion_boards::BOARDS`) lists every implementation.
pub trait Board: Sync + fmt::Debug {
    /// The model (its id, contract code and link kind).
    fn model(&self) -> Model;

    /// How its link is laid out.
    fn link(&self) -> LinkFacts;

    /// Channels (motors / encoders) a device of this model has, in `variants`.
    fn channel_count(&self, variants: Variants) -> usize;

    /// The device's I/O pins in `variants` (index = `Pin`).
    fn pins(&self, variants: Variants) -> &'static [PinInfo];

    /// The driver of the device `spec` describes (spec → driver config → driver).
    ///
    /// # Errors
    /// A value of the spec the board cannot take (the config validator refuses such
    /// values first, with file, line and column).
    fn build(&self, spec: &DriverSpec) -> Result<Box<dyn Driver>, SpecError>;

    /// One [`Param`] per machine parameter of the device `spec` describes and of its axes,
    /// with the value in effect.
    ///
    /// # Errors
    /// As [`build`](Self::build).
    fn params(&self, spec: &DriverSpec) -> Result<Vec<Param>, SpecError>;

    /// The simulated board of the device `spec` describes, configured like the machine
    /// (switches where its axes search, the variant, the address), seeded with `seed`.
    fn simulate(&self, spec: &DriverSpec, seed: u64) -> SimBoard;
}
