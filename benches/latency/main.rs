//! End-to-end latency of a live motiond, every figure beside a baseline measured in the same
//! run, with the ratio (issue 7; STYLE.md habit 12). Run it against a server:
//!
//! ```text
//! cargo run --release &                      # motiond on config/sim.toml, instance `demo`
//! cargo bench --bench latency -- --server demo --duration 10s [--json] [--out DIR]
//! ```
//!
//! The suite lives in the `motion-bench` crate (`crates/motion-bench`), which `motionctl
//! bench` runs on a deployed machine; this is its thin command-line wrapper.
//! docs/PERFORMANCE.md explains every figure.

mod cli;

use std::process::ExitCode;

use clap::Parser;

use crate::cli::Cli;

fn main() -> ExitCode {
    // The baseline peer is this binary re-executed: serve as one when asked to.
    if let Some(status) = motion_bench::peer::run_if_requested() {
        return status;
    }
    iceoryx2::prelude::set_log_level_from_env_or(iceoryx2::prelude::LogLevel::Error);
    let cli = Cli::parse();
    match motion_bench::run(&cli.server, &cli.bench) {
        Ok(report) => {
            if cli.bench.json {
                println!("{:#}", report.json());
            } else {
                print!("{}", report.table());
            }
            ExitCode::SUCCESS
        }
        Err(error) => {
            eprintln!("latency bench: {error}");
            ExitCode::from(1)
        }
    }
}
