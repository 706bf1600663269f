//! Device models of the four boards motiond drives (work in progress).
//!
//! Each model implements [`motion_link::sim::StreamDevice`] (serial boards) or
//! [`motion_link::sim::SpiDevice`] (SPI boards), is deterministic under the time it is
//! given, and is built on its board's protocol crate.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod qsb;
pub mod rng;
