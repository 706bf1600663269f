//! `reliability`: the reliability campaigns of docs/RELIABILITY.md against a release
//! motiond on simulated boards, one table row per campaign (`--json` for the rows as JSON).
//! `--quick` is the short version `./scripts/test` runs: it asserts the invariants (0 axes
//! left moving, 0 out-of-limit bytes, 0 stale shared-memory files, the server alive, every
//! refusal with a reason, …) and reports timing without judging it. Exit status: 0 when
//! every invariant held, 1 otherwise, 2 on a usage error.
//!
//! `scripts/reliability` builds the release binaries and runs this.
#![forbid(unsafe_code)]

mod boards;
mod c1_dead_clients;
mod c2_crash;
mod c3_links;
mod c3_noise;
mod c4_bad_input;
mod c5_consumers;
mod c6_config;
mod c7_soak;
mod c8_decoders;
mod harness;
mod jogger;
mod report;

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use clap::{Parser, Subcommand};

use crate::harness::Harness;
use crate::report::Row;

/// Reliability campaigns against motiond on simulated boards.
#[derive(Debug, Parser)]
#[command(version, about, long_about = None)]
struct Cli {
    /// The short version (CI): a few runs of each campaign, invariants only.
    #[arg(long)]
    quick: bool,
    /// Print the rows as JSON instead of the table.
    #[arg(long)]
    json: bool,
    /// Only these campaigns (numbers, comma-separated: `--only 1,4`).
    #[arg(long, value_delimiter = ',')]
    only: Vec<u32>,
    /// The motiond binary (default: `motiond` beside this binary).
    #[arg(long, value_name = "PATH")]
    motiond: Option<PathBuf>,
    /// The simulated robot's config (default: config/sim.toml of the source tree).
    #[arg(long, value_name = "FILE")]
    sim_config: Option<PathBuf>,
    /// Working directory for configs, ptys, sockets and the isolated iceoryx2 root
    /// (default: a new directory under the temp dir, removed afterwards).
    #[arg(long, value_name = "DIR")]
    dir: Option<PathBuf>,
    /// Seed of every random choice.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Campaign 8: seconds of fuzzing per cargo-fuzz target (`scripts/fuzz`); 0 skips it.
    /// Full runs only.
    #[arg(long, default_value_t = 60)]
    fuzz_seconds: u64,
    #[command(subcommand)]
    role: Option<Role>,
}

/// Child processes of the campaigns (this binary run again).
#[derive(Debug, Subcommand)]
enum Role {
    /// Campaign 1's client: jog an axis with motion-client and read frames until killed.
    #[command(hide = true)]
    Jogger {
        #[arg(long)]
        server: String,
        #[arg(long)]
        axis: String,
        #[arg(long, allow_hyphen_values = true)]
        velocity: f64,
    },
}

fn main() -> ExitCode {
    iceoryx2::prelude::set_log_level_from_env_or(iceoryx2::prelude::LogLevel::Fatal);
    let cli = Cli::parse();
    if let Some(Role::Jogger {
        server,
        axis,
        velocity,
    }) = &cli.role
    {
        return match jogger::run(server, axis, *velocity) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("jogger: {e:#}");
                ExitCode::FAILURE
            }
        };
    }
    match run(&cli) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("reliability: {e:#}");
            ExitCode::FAILURE
        }
    }
}

type Campaign = fn(&Harness) -> anyhow::Result<Row>;

fn campaigns() -> Vec<(u32, &'static str, Campaign)> {
    vec![
        (1, "1 dead clients", c1_dead_clients::run),
        (2, "2 server crash", c2_crash::run),
        (3, "3a links: unplug/replug", c3_links::run),
        (3, "3b links: line noise", c3_noise::run),
        (4, "4 bad input", c4_bad_input::run),
        (5, "5 slow and many consumers", c5_consumers::run),
        (6, "6 malformed configs", c6_config::run),
        (7, "7 soak", c7_soak::run),
        (8, "8 decoders", c8_decoders::run),
    ]
}

fn run(cli: &Cli) -> anyhow::Result<bool> {
    let exe = std::env::current_exe()?;
    let motiond = cli
        .motiond
        .clone()
        .unwrap_or_else(|| exe.with_file_name("motiond"));
    let source = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let sim_config = cli
        .sim_config
        .clone()
        .unwrap_or_else(|| source.join("config/sim.toml"));
    let (dir, remove) = match &cli.dir {
        Some(dir) => (dir.clone(), false),
        None => (
            std::env::temp_dir().join(format!("motion-reliability-{}", std::process::id())),
            true,
        ),
    };
    let mut harness = Harness::new(&dir, &motiond, &sim_config, cli.quick, cli.seed)?;
    harness.source = std::fs::canonicalize(&source).unwrap_or(source);
    harness.fuzz_seconds = cli.fuzz_seconds;
    let started = Instant::now();
    let mut rows = Vec::new();
    for (number, label, campaign) in campaigns() {
        if !cli.only.is_empty() && !cli.only.contains(&number) {
            continue;
        }
        eprintln!("== campaign {label}");
        let began = Instant::now();
        let mut row = campaign(&harness).unwrap_or_else(|e| Row::failed(label, &e));
        row.seconds = began.elapsed().as_secs_f64();
        eprintln!(
            "   {} in {:.0} s",
            if row.passed() { "passed" } else { "FAILED" },
            row.seconds
        );
        rows.push(row);
    }
    let passed = rows.iter().all(Row::passed);
    if cli.json {
        let json = serde_json::json!({
            "quick": cli.quick,
            "seed": cli.seed,
            "seconds": started.elapsed().as_secs(),
            "passed": passed,
            "campaigns": rows.iter().map(Row::json).collect::<Vec<_>>(),
        });
        println!("{}", serde_json::to_string_pretty(&json)?);
    } else {
        print!("{}", report::table(&rows));
        println!(
            "{} in {:.0} s ({})",
            if passed { "PASSED" } else { "FAILED" },
            started.elapsed().as_secs_f64(),
            if cli.quick { "--quick" } else { "full run" }
        );
    }
    harness.remove_iox_root();
    if remove {
        let _ = std::env::set_current_dir(std::env::temp_dir());
        let _ = std::fs::remove_dir_all(&dir);
    }
    Ok(passed)
}
