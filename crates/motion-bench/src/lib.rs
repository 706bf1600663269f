//! The end-to-end latency suite of a live motiond: every figure beside a baseline measured
//! in the same run, with the ratio (docs/PERFORMANCE.md explains each figure). Two programs
//! run it: `cargo bench --bench latency` (the workspace's bench, `benches/latency/`) and
//! `motionctl bench` on a deployed machine.
//!
//! Everything goes through plain iceoryx2 and the motion-ipc types, opening the server's
//! services as any client would. Baselines: a bare `clock_nanosleep` loop (wake-up), and a
//! plain peer process that ticks, publishes a frame-sized sample and answers requests like
//! motiond minus its engine. The peer is the running program re-executed with
//! [`peer::PEER_FLAG`]: every program that calls [`run`] must call
//! [`peer::run_if_requested`] first thing in its `main`, which also serves the bare poller
//! ([`poller`]: the I/O phase's idle link traffic and nothing else, the baseline of motiond's
//! CPU on those links, [`io_poller`]). Command to wire is timed on a
//! motiond the bench starts itself, its four links to boards the bench simulates: a QSB and
//! a SIXpack on ptys, a QuadQuad2Drv and an SPI_motor on SPI sockets ([`wire`],
//! [`wire_board`], [`pty`], [`spi_board`]). The Python client's figures come from `python -m motiond.bench`
//! (the pip package in `python/`) run as a child process ([`python`]). Coordinated motion
//! (trajectory tracking, arrival skew, streaming) is measured on a motiond the bench starts
//! on `config/sim.toml` ([`groups`], [`stream`]). The Trinamic pack's refresh at the factory
//! and a faster line rate is measured on a motiond the bench starts with two SIXpacks
//! ([`link_rate`]).
//!
//! ```no_run
//! use clap::Parser;
//!
//! #[derive(Parser)]
//! struct Cli {
//!     #[arg(long, default_value = "demo")]
//!     server: String,
//!     #[command(flatten)]
//!     bench: motion_bench::BenchArgs,
//! }
//!
//! fn main() -> std::process::ExitCode {
//!     if let Some(status) = motion_bench::peer::run_if_requested() {
//!         return status; // this process is a baseline peer
//!     }
//!     let cli = Cli::parse();
//!     match motion_bench::run(&cli.server, &cli.bench) {
//!         Ok(report) => {
//!             print!("{}", report.table());
//!             std::process::ExitCode::SUCCESS
//!         }
//!         Err(error) => {
//!             eprintln!("{error}");
//!             std::process::ExitCode::FAILURE
//!         }
//!     }
//! }
//! ```
#![warn(missing_docs)]
#![deny(unsafe_code)] // one exception: pty.rs (the FIONREAD ioctl), with a SAFETY note

pub mod args;
pub mod arrival;
pub mod cpu;
pub mod delivery;
pub mod dist;
pub mod group_client;
pub mod groups;
pub mod io_links;
pub mod io_phase;
pub mod io_poller;
pub mod ipc;
pub mod link_rate;
pub mod peer;
mod peer_services;
pub mod plots;
pub mod poller;
pub mod poller_boards;
pub mod pty;
pub mod python;
pub mod python_stream;
pub mod report;
pub mod roundtrip;
pub mod rt;
mod run;
pub mod sim_boards;
pub mod spi_board;
pub mod stream;
pub mod stream_wire;
pub mod svg;
pub mod sweep;
pub mod wakeup;
pub mod wire;
pub mod wire_board;

pub use args::{BenchArgs, CommandProbe, PeerMode, parse_duration};
pub use dist::{Dist, Summary, format_ns};
pub use report::Report;
pub use run::run;

/// Why the bench could not run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BenchError {
    /// No server of that name answers (its frame service could not be opened, or it does
    /// not tick).
    NoServer(String),
    /// Anything else (a peer, a thread, a file), in words.
    Failed(String),
}

impl core::fmt::Display for BenchError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NoServer(text) | Self::Failed(text) => f.write_str(text),
        }
    }
}

impl std::error::Error for BenchError {}

impl From<String> for BenchError {
    fn from(text: String) -> Self {
        Self::Failed(text)
    }
}
