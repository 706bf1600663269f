//! Byte transports for motiond behind one trait, [`Link`].
//!
//! | module | transport |
//! |---|---|
//! | [`serial`] | a tty through `serialport` (RS-232, RS-485 adapters, USB CDC), 8N1 |
//! | [`spidev`] | a Linux spidev device, full-duplex transactions |
//! | [`spi_socket`] | SPI transactions over a Unix socket (docs/ARCHITECTURE.md "SPI socket contract") |
//! | [`socketcan`] | a Linux SocketCAN interface (raw `AF_CAN` socket), CAN frames as 16-byte records |
//! | [`sim`] | an in-process wire to a device model, with wire time and fault injection (a serial line, an SPI bus, or a CAN bus: [`sim::SimCanLink`]) |
//!
//! Links know no protocol: they move bytes, report honest fault kinds ([`LinkErrorKind`])
//! and never block the caller except in [`Link::flush`] (and spidev transfers, which
//! belong on their own I/O thread).
//!
//! Every byte transport passes one conformance suite (`tests/conformance.rs`): serial over
//! a pseudo-terminal pair, spi-socket against a test listener, and sim. The CAN links move
//! 16-byte frame records instead of free bytes and have their own tests: `tests/can_link.rs`
//! (the simulated bus) and `tests/vcan.rs` (SocketCAN on a virtual interface, where the
//! kernel has one).
//!
//! # Example: a simulated 19200-baud wire charges real wire time
//!
//! ```
//! use core::time::Duration;
//! use motion_link::sim::{SimLink, StreamDevice};
//! use motion_link::{Link, LinkErrorKind};
//!
//! /// Echoes every byte back.
//! #[derive(Default)]
//! struct Echo(Vec<u8>);
//!
//! impl StreamDevice for Echo {
//!     fn receive(&mut self, _now: Duration, bytes: &[u8]) {
//!         self.0.extend_from_slice(bytes);
//!     }
//!     fn transmit(&mut self, _now: Duration, out: &mut [u8]) -> usize {
//!         let n = out.len().min(self.0.len());
//!         out[..n].copy_from_slice(&self.0[..n]);
//!         self.0.drain(..n);
//!         n
//!     }
//!     fn next_event(&self, now: Duration) -> Option<Duration> {
//!         (!self.0.is_empty()).then_some(now)
//!     }
//! }
//!
//! let mut link = SimLink::stream("echo", 19_200, Box::new(Echo::default()));
//! let faults = link.faults();
//! let t0 = Duration::from_secs(1);
//! link.write(t0, b"hello")?;
//! let mut buf = [0u8; 16];
//! // Full duplex, 10 bits a byte: each byte echoes as soon as it has arrived, so the
//! // last echo ends 6 byte times (3.125 ms, rounded up to the ns) after the first start bit.
//! assert_eq!(link.read(t0 + Duration::from_micros(3_124), &mut buf)?, 4);
//! assert_eq!(link.read(t0 + Duration::from_micros(3_126), &mut buf)?, 1);
//! faults.unplug();
//! let err = link.read(t0 + Duration::from_millis(6), &mut buf).unwrap_err();
//! assert_eq!(err.kind(), LinkErrorKind::Disconnected);
//! # Ok::<(), motion_link::LinkError>(())
//! ```
#![warn(missing_docs)]
// Three exceptions, each with a SAFETY note: SerialLink::poll_fd (a BorrowedFd of the port's
// own descriptor), socketcan's bind(2) (nix has no sockaddr_can) and serial::tty_speed (one
// ioctl).
#![deny(unsafe_code)]

mod can_records;
mod config;
mod error;
mod link;
pub mod serial;
pub mod sim;
pub mod socketcan;
pub mod spi_socket;
pub mod spidev;

pub use config::LinkConfig;
pub use error::{LinkError, LinkErrorKind};
pub use link::{Link, LinkKind, LinkStats};
