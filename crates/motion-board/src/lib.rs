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

pub mod standalone;

use core::fmt;
use core::time::Duration;

use motion_drivers::spec::{DeviceMachine, DriverSpec, Param, SpecError};
use motion_drivers::{Driver, Model, PinInfo};
use motion_link::sim::{SpiDevice, StreamDevice};

pub use standalone::{StandaloneError, StandaloneHelp, StandaloneSim};

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

    /// Channels (motors / encoders) a device of this model has, with its validated
    /// machine keys (which say its variant, where the model comes in several).
    fn channel_count(&self, machine: &DeviceMachine) -> usize;

    /// The device's I/O pins (index = `Pin`), with its validated machine keys.
    fn pins(&self, machine: &DeviceMachine) -> &'static [PinInfo];

    /// The name of the device's product in messages: its variant's where the model comes
    /// in variants with different pins (`qsb-s`), else the model's id.
    fn product_name(&self, machine: &DeviceMachine) -> &'static str {
        let _ = machine;
        self.model().id()
    }

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

    /// The simulated board the `motion-sim` tool serves alone, from its command-line
    /// `options` (no config file).
    ///
    /// # Errors
    /// An option the board does not have, or a value of one it cannot take.
    fn simulate_standalone(&self, options: &StandaloneSim) -> Result<SimBoard, StandaloneError>;

    /// Its part of `motion-sim --help`.
    fn standalone_help(&self) -> StandaloneHelp;
}
