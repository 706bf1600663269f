//! Sans-I/O drivers for the boards motiond drives.
//!
//! One driver per board model implements [`Driver`]: goals in counts ([`Goal`]), received
//! bytes and `now` in; bytes to send and [`ChannelState`] out. Drivers never read a clock
//! and never touch a file descriptor. A [`LinkBus`] puts several drivers on one link and
//! enforces what no single driver sees: one request in flight on a shared serial bus,
//! commands before polls, MISO bytes back to the transaction's owner.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod bus;
mod driver;
mod goal;
mod pin;
pub mod qq2drv;
pub mod qsb;
mod state;

pub mod spimotor;
pub mod tmcpack;

pub use bus::{LinkBus, MAX_SENDS_PER_STEP, SPI_PENDING_CAPACITY};
pub use driver::{Driver, Model, Priority, Transmit};
pub use goal::{Goal, GoalError, GoalKind, GoalKinds};
/// Whether a link carries a byte stream or SPI transactions (one enum with `motion_link`).
pub use motion_base::LinkKind;
pub use pin::{Pin, PinInfo, PinReading, SignalKind, SignalKinds, find_pin};
pub use state::{ChannelState, DeviceFault, DeviceStatus, FIRMWARE_LEN};
