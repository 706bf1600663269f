//! Simulated wires to in-process device models.

mod bus;
mod device;

pub use bus::{SpiBus, StreamBus};
pub use device::{SpiDevice, StreamDevice};
