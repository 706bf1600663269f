//! Simulated wires to in-process device models.
//!
//! A device model implements [`StreamDevice`] or [`SpiDevice`]; [`StreamBus`] and
//! [`SpiBus`] put several on one wire; [`SimLink`] connects a device or bus to the host
//! side behind the [`Link`](crate::Link) trait, charging wire time and injecting faults
//! through [`SimFaults`].

mod bus;
mod device;
mod faults;
mod line;
mod link;

pub use bus::{SpiBus, StreamBus};
pub use device::{SpiDevice, StreamDevice};
pub use faults::{Direction, SimFaults};
pub use link::{Duplex, SimLimits, SimLink, SimWire};
