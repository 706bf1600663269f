//! Simulated wires to in-process device models.

mod device;

pub use device::{SpiDevice, StreamDevice};
