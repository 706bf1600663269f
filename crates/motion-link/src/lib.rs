//! Byte transports for motiond behind one trait, [`Link`].
//!
//! | module | transport |
//! |---|---|
//! | [`serial`] | a tty through `serialport` (RS-232, RS-485 adapters, USB CDC), 8N1 |
//! | [`spidev`] | a Linux spidev device, full-duplex transactions |
//! | [`spi_socket`] | SPI transactions over a Unix socket (DESIGN.md "SPI socket contract") |
//! | [`sim`] | an in-process wire to a device model, with wire time and fault injection |
//!
//! Links know no protocol: they move bytes, report honest fault kinds ([`LinkErrorKind`])
//! and never block the caller except in [`Link::flush`] (and spidev transfers, which
//! belong on their own I/O thread).
#![forbid(unsafe_code)]

mod error;
mod link;
pub mod serial;
pub mod sim;
pub mod spi_socket;
pub mod spidev;

pub use error::{LinkError, LinkErrorKind};
pub use link::{Link, LinkKind, LinkStats};
