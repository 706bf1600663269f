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

pub mod keys;
pub mod machine;
pub mod standalone;

use core::fmt;
use core::time::Duration;

use motion_drivers::spec::{
    DeviceMachine, Direction, DriverSpec, FromSpec, HomeInput, MachineKeys, Param, SpecError,
};

use crate::keys::{AxisContext, DeviceContext, KeyIssues, KeyTable, Span};
use crate::machine::MachineView;
use motion_drivers::{Driver, Model, PinInfo};
use motion_link::sim::{CanDevice, SpiDevice, StreamDevice};

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

/// What a board that also speaks CAN (a `socketcan` or `sim-can` link) says of its bus: the
/// config validator checks a CAN link's `bitrate` against it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CanFacts {
    /// The bit rates the board can be set to, bits per second.
    pub bitrates: &'static [u32],
    /// The bit rate a CAN link of these boards runs at unless given (the factory setting).
    pub default_bitrate: u32,
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

/// A [`Board`]'s typed parts: its driver's configuration and driver, and its part of the
/// `motion-sim` tool. The registry builds its driver enum (`motion_boards::AnyDriver`, what
/// the server's tick holds: static dispatch, no box) from [`driver`](Self::driver), and
/// every board gets [`BoardParts`] — its parameters, its standalone simulator and help —
/// from these declarations: a board crate declares them, none writes the glue.
pub trait TypedBoard: Board {
    /// The driver's configuration (`<Board>DriverConfig`).
    type Config: FromSpec;

    /// The board's driver.
    type Driver: Driver + 'static;

    /// The driver made of its configuration (`<Board>Driver::new`).
    const NEW_DRIVER: fn(Self::Config) -> Self::Driver;

    /// Its part of `motion-sim --help`.
    const STANDALONE_HELP: StandaloneHelp;

    /// The simulated board the `motion-sim` tool serves alone, from its command-line
    /// options (no config file); an option the board does not have, or a value of one it
    /// cannot take, is refused.
    const SIMULATE_STANDALONE: fn(&StandaloneSim) -> Result<SimBoard, StandaloneError>;

    /// The driver of the device `spec` describes (spec → driver config → driver).
    ///
    /// # Errors
    /// A value of the spec the board cannot take (the config validator refuses such
    /// values first, with file, line and column).
    fn driver(&self, spec: &DriverSpec) -> Result<Self::Driver, SpecError> {
        Ok(Self::NEW_DRIVER(Self::Config::from_spec(spec)?))
    }
}

/// What every board has through its [`TypedBoard`] declarations (a blanket
/// implementation): callable on a `dyn Board`.
pub trait BoardParts {
    /// One [`Param`] per machine parameter of the device `spec` describes and of its axes,
    /// with the value in effect.
    ///
    /// # Errors
    /// As [`TypedBoard::driver`].
    fn params(&self, spec: &DriverSpec) -> Result<Vec<Param>, SpecError>;

    /// The simulated board the `motion-sim` tool serves alone, from its command-line
    /// `options` (no config file).
    ///
    /// # Errors
    /// An option the board does not have, or a value of one it cannot take.
    fn simulate_standalone(&self, options: &StandaloneSim) -> Result<SimBoard, StandaloneError>;

    /// Its part of `motion-sim --help`.
    fn standalone_help(&self) -> StandaloneHelp;
}

impl<B: TypedBoard> BoardParts for B {
    fn params(&self, spec: &DriverSpec) -> Result<Vec<Param>, SpecError> {
        B::Config::from_spec(spec).map(|config| config.params(spec))
    }

    fn simulate_standalone(&self, options: &StandaloneSim) -> Result<SimBoard, StandaloneError> {
        B::SIMULATE_STANDALONE(options)
    }

    fn standalone_help(&self) -> StandaloneHelp {
        B::STANDALONE_HELP
    }
}

/// A value a board's key gives for a general fact, with where it was written (a board key
/// that says the same as a general key: both must agree).
#[derive(Debug, Clone, PartialEq)]
pub struct Given<T> {
    /// The value.
    pub value: T,
    /// Where it was written.
    pub span: Span,
    /// Its key (`axis[0].reference.side`).
    pub key: String,
}

/// What a board's keys say about an axis's reference search, besides the general `home`
/// table (`home.direction`, `home.max_travel`, `home.position`): the server merges both and
/// refuses a disagreement.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct HomeHints {
    /// The search direction (tmcpack `reference.side`, qq2drv `home.positive_end`, qsb
    /// `home_direction`).
    pub direction: Vec<Given<Direction>>,
    /// The search's travel limit, units (qsb `home_max_travel`).
    pub max_travel: Vec<Given<f64>>,
    /// The position at the reference, units (qsb `home_offset`).
    pub position: Vec<Given<f64>>,
    /// The input the axis homes on (qq2drv `home.input`).
    pub input: Option<HomeInput>,
}

/// A table's validated board keys: a device's ([`DeviceKeys`]) or an axis's
/// ([`AxisKeys`]).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BoardKeys {
    /// The machine keys its driver is built from.
    pub machine: MachineKeys,
    /// What they say about reference searches: of the device's axes, or of the axis.
    pub home: HomeHints,
}

/// A device's validated board keys.
pub type DeviceKeys = BoardKeys;

/// An axis's validated board keys.
pub type AxisKeys = BoardKeys;

impl BoardKeys {
    /// A board's validated keys `keys` of a device or an axis, and what they say about the
    /// reference searches.
    pub fn new<T: core::any::Any + fmt::Debug + PartialEq + Send + Sync>(
        keys: T,
        home: HomeHints,
    ) -> Self {
        Self {
            machine: MachineKeys::new(keys),
            home,
        }
    }
}

/// A model's `address` key: the default, and the check of a value written.
#[derive(Debug, Clone, Copy)]
pub struct AddressKey {
    /// The address when none is written.
    pub default: u32,
    /// The address a written value gives, or what is wrong with it and what is allowed.
    pub check: fn(i128) -> Result<u32, String>,
}

/// One board model, as the server knows it. Implemented once per board crate; the
/// registry (`motion_boards::BOARDS`) lists every implementation.
pub trait Board: BoardParts + Sync + fmt::Debug {
    /// The model (its id, contract code and link kind).
    fn model(&self) -> Model;

    /// How its link is laid out.
    fn link(&self) -> LinkFacts;

    /// Whether the board also speaks CAN, and at which bit rates; `None` (the default):
    /// a CAN link refuses it. A board that says so builds its driver for CAN frames when
    /// its spec's `framing` is `LinkFraming::Can`, and simulates with
    /// [`simulate_can`](Self::simulate_can).
    fn can(&self) -> Option<CanFacts> {
        None
    }

    /// The simulated board on a `type = "sim-can"` link (see
    /// [`simulate`](Self::simulate)); `None` for a board without CAN.
    fn simulate_can(&self, spec: &DriverSpec, seed: u64) -> Option<Box<dyn CanDevice>> {
        let _ = (spec, seed);
        None
    }

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

    /// The simulated board of the device `spec` describes, configured like the machine
    /// (switches where its axes search, the variant, the address), seeded with `seed`.
    fn simulate(&self, spec: &DriverSpec, seed: u64) -> SimBoard;

    /// The keys a `[[device]]` of this model may have besides the general ones (`name`,
    /// `link`, `model`, `address`, `sim`). The server refuses any other with a message
    /// naming the models that have it.
    fn device_key_names(&self) -> &'static [&'static str] {
        &[]
    }

    /// The keys an `[[axis]]` on this model may have besides the general ones; a key of the
    /// axis's `home` table is named `home.<key>`.
    fn axis_key_names(&self) -> &'static [&'static str] {
        &[]
    }

    /// The model's `address` key; `None`: the model has none (it never shares a link).
    fn address(&self) -> Option<AddressKey> {
        None
    }

    /// Why an axis of this model cannot home (a `home` table is refused with it); `None`:
    /// its axes home.
    fn cannot_home(&self) -> Option<&'static str> {
        None
    }

    /// Validates a `[[device]]`'s board keys (`keys` holds only names of
    /// [`device_key_names`](Self::device_key_names)); `None` after an issue.
    fn device_keys(
        &self,
        keys: &KeyTable<'_>,
        ctx: &DeviceContext,
        issues: &mut dyn KeyIssues,
    ) -> Option<DeviceKeys> {
        let _ = (keys, ctx, issues);
        Some(DeviceKeys::default())
    }

    /// Validates an `[[axis]]`'s board keys, on a device with `device` keys; `None` after
    /// an issue.
    fn axis_keys(
        &self,
        keys: &KeyTable<'_>,
        device: &MachineKeys,
        ctx: &AxisContext<'_>,
        issues: &mut dyn KeyIssues,
    ) -> Option<AxisKeys> {
        let _ = (keys, device, ctx, issues);
        Some(AxisKeys::default())
    }

    /// Checks across tables (keys that must agree between axes of one device, addresses
    /// against other devices, pins against the machine keys), after everything else was
    /// validated. Called once per model present.
    fn cross_check(&self, machine: &MachineView<'_>, issues: &mut dyn KeyIssues) {
        let _ = (machine, issues);
    }
}
