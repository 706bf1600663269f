//! Simulated wires to in-process device models.
//!
//! A device model implements [`StreamDevice`] or [`SpiDevice`]; [`StreamBus`] and
//! [`SpiBus`] put several on one wire; [`SimLink`] connects a device or bus to the host
//! side behind the [`Link`](crate::Link) trait, charging wire time and injecting faults
//! through [`SimFaults`].
//!
//! What the host reads, and when, is what a real host would: an SPI transaction's MISO
//! bytes together once its last clock has passed (a spidev transfer returns whole); a
//! serial device's bytes as each stop bit passes (a UART), or, behind USB
//! ([`SimLink::with_host_frames`]), together at the end of each bus frame.
//!
//! A CAN bus is simulated apart ([`SimCanLink`], [`CanDevice`], [`CanBus`]): its devices
//! speak frames, not bytes, and its host end reads and writes 16-byte CAN records like a
//! SocketCAN interface.

mod bus;
mod can;
mod device;
mod faults;
mod line;
mod link;

pub use bus::{SpiBus, StreamBus};
pub use can::{CanBus, CanDevice, RX_QUEUE_FRAMES, SimCanLink, TX_QUEUE_FRAMES};
pub use device::{SpiDevice, StreamDevice};
pub use faults::{Direction, SimFaults};
pub use line::garble;
pub use link::{Duplex, SimLimits, SimLink, SimWire};
