//! What the board simulators share: [`rng::SimRng`], the deterministic random number
//! generator of their noise and fault injection. Each board's simulator lives in its board
//! crate (`crates/boards/<board>/src/sim/`): it implements
//! `motion_link::sim::StreamDevice` (serial boards) or `motion_link::sim::SpiDevice` (SPI
//! boards), is deterministic under the time it is given, and is built on its board's
//! protocol crate. The `motion-sim` tool that serves them is the package `motion-sim-cli`.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod rng;
