//! Command line of the latency bench (shared with the smoke test in `tests/`): the server's
//! name and the suite's options from the `motion-bench` crate, which `motionctl bench` uses
//! as well.

use clap::Parser;
use motion_bench::BenchArgs;

/// End-to-end latency of a live motiond, each figure beside a baseline measured in the
/// same run (plain iceoryx2 or a bare `clock_nanosleep` loop), with the ratio.
///
/// Phases (each runs for DURATION, one after the other): tick wake-up baseline, frames
/// (WaitSet, busy-poll), command round trip against motiond; the Python client (`python
/// -m motiond.bench`, frames then round trip, when an interpreter with the package is
/// found); then the same three against a plain iceoryx2 peer process; then request-response
/// against a busy-polling peer; then command to wire, on a motiond the bench starts with a
/// pty-served simulated QSB.
/// Absolute times drift on a shared machine: read the ratios.
#[derive(Debug, Parser)]
#[command(name = "latency", version, about, long_about)]
pub struct Cli {
    /// Instance name of the running motiond (`[server] name`).
    #[arg(long, default_value = "demo")]
    pub server: String,
    /// The suite's options.
    #[command(flatten)]
    pub bench: BenchArgs,
    /// `cargo bench` passes `--bench` to every bench binary; accepted and ignored.
    #[arg(long = "bench", hide = true)]
    pub cargo_bench: bool,
}
