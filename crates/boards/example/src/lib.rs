//! The worked example of a motiond board: the **AS-2**, an (invented) ASCII stepper
//! controller with two channels on a serial link. Its README is its datasheet. This one
//! crate is everything motiond knows of it:
//!
//! | module | holds |
//! |---|---|
//! | [`codec`] | the wire format, sans I/O: requests encoded into a caller's buffer, replies decoded incrementally |
//! | [`driver`] | [`driver::ExampleDriver`], the `motion_drivers::Driver`: start-up, polling, goals, faults |
//! | [`sim`] | [`sim::ExampleSim`], the simulated board on a `type = "sim"` link |
//! | this file | the model's facts and [`ExampleBoard`], the `motion_board::Board` the registry lists |
//!
//! Adding it to the server was one line in the registry's list (`motion_boards`) and one
//! dependency line in that crate's `Cargo.toml` (docs/ARCHITECTURE.md "How to add a
//! board").
//!
//! ```
//! use motion_board::Board;
//! use board_example::ExampleBoard;
//!
//! assert_eq!(ExampleBoard.model().id(), "example");
//! assert_eq!(ExampleBoard.link().default_rate, 115_200);
//! ```
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod codec;
pub mod driver;
pub mod sim;
mod standalone;

use motion_base::{LinkKind, Model, ModelFacts};
use motion_board::{
    Board, LinkFacts, SimBoard, StandaloneError, StandaloneHelp, StandaloneSim, TypedBoard,
};
use motion_drivers::PinInfo;
use motion_drivers::spec::{DeviceMachine, DriverSpec};

use driver::{DEFAULT_BAUD, ExampleDriver, ExampleDriverConfig};
use sim::{ExampleSim, ExampleSimConfig};

/// The AS-2's facts: config id `example`, contract code 5, a byte stream.
pub static FACTS: ModelFacts = ModelFacts {
    id: "example",
    code: 5,
    link_kind: LinkKind::Stream,
    title: "AS-2 ASCII stepper (worked example)",
};

/// The AS-2 as a model.
pub const MODEL: Model = Model::new(&FACTS);

/// The AS-2.
#[derive(Debug, Clone, Copy)]
pub struct ExampleBoard;

impl Board for ExampleBoard {
    fn model(&self) -> Model {
        MODEL
    }

    /// One board on its own RS-232 line (no address, no bus), 115200 baud.
    fn link(&self) -> LinkFacts {
        LinkFacts {
            shared: false,
            default_rate: DEFAULT_BAUD,
            spi_mode: 0,
            host_frame: None,
        }
    }

    fn channel_count(&self, _machine: &DeviceMachine) -> usize {
        codec::CHANNELS
    }

    /// The AS-2 has no I/O pins.
    fn pins(&self, _machine: &DeviceMachine) -> &'static [PinInfo] {
        &[]
    }

    fn cannot_home(&self) -> Option<&'static str> {
        Some("the AS-2 has no reference input (README: no home command), so its axes cannot home")
    }

    fn simulate(&self, _spec: &DriverSpec, seed: u64) -> SimBoard {
        SimBoard::Stream(Box::new(ExampleSim::new(ExampleSimConfig {
            jitter: core::time::Duration::from_micros(100),
            seed,
            ..ExampleSimConfig::default()
        })))
    }
}

impl TypedBoard for ExampleBoard {
    type Config = ExampleDriverConfig;
    type Driver = ExampleDriver;
    const NEW_DRIVER: fn(ExampleDriverConfig) -> ExampleDriver = ExampleDriver::new;
    const STANDALONE_HELP: StandaloneHelp = standalone::HELP;
    const SIMULATE_STANDALONE: fn(&StandaloneSim) -> Result<SimBoard, StandaloneError> =
        standalone::simulate;
}
