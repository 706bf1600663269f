//! `motion-bridge`: serves one motiond instance's frames, state and commands on zenoh
//! (crates/motion-bridge/README.md).
#![forbid(unsafe_code)]

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;

use clap::Parser;
use motion_bridge::Bridge;
use motion_bridge::config::{BridgeConfig, Overrides};

const AFTER_HELP: &str = "\
Commands are refused unless the config file allows them ([[remote]] identity, allow, rate).
Without --config the bridge publishes frames and state and refuses every command.
An allow-list wider than stop and e-stop needs zenoh authentication (--zenoh-config with
users and passwords or TLS client certificates), or --insecure on a network you trust.

Example:
  motion-bridge --server demo --listen tcp/0.0.0.0:7447 --config bridge.toml --zenoh-config zenoh.json5
  motionctl --remote tcp/HOST:7447 --identity panel list

Logging: RUST_LOG=debug (default info; zenoh's own at warn).
Exit status: 0 after SIGINT/SIGTERM, 1 when it could not start, 2 bad command line.";

/// Bridges a motiond instance onto zenoh, across hosts.
#[derive(Debug, Parser)]
#[command(name = "motion-bridge", version, about, after_help = AFTER_HELP)]
struct Cli {
    /// Instance name of the server (`[server] name` of its config); default `demo`.
    #[arg(long, value_name = "NAME")]
    server: Option<String>,
    /// zenoh endpoint to listen on (repeatable); default tcp/0.0.0.0:7447.
    #[arg(long, value_name = "ENDPOINT")]
    listen: Vec<String>,
    /// zenoh endpoint to connect to (a router or another peer; repeatable).
    #[arg(long, value_name = "ENDPOINT")]
    connect: Vec<String>,
    /// The bridge's TOML config: remotes' allow-lists and rate limits, rates, endpoints.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Frames per second published (server ticks decimated); default 100.
    #[arg(long, value_name = "HZ")]
    frame_rate: Option<f64>,
    /// JSON states per second on motiond/<name>/state/json; default 10.
    #[arg(long, value_name = "HZ")]
    json_rate: Option<f64>,
    /// zenoh's own config file (JSON5): TLS, user/password authentication, access control.
    #[arg(long, value_name = "FILE")]
    zenoh_config: Option<PathBuf>,
    /// Start although the config lets remotes do more than stop and e-stop and zenoh
    /// authenticates nobody (a network you trust; anyone reaching it may claim any identity).
    #[arg(long)]
    insecure: bool,
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(error) => {
            let _ = error.print();
            return ExitCode::from(if error.use_stderr() { 2 } else { 0 });
        }
    };
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info,zenoh=warn"));
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .init();
    iceoryx2::prelude::set_log_level(iceoryx2::prelude::LogLevel::Error);
    let overrides = Overrides {
        server: cli.server,
        listen: cli.listen,
        connect: cli.connect,
        frame_rate: cli.frame_rate,
        json_rate: cli.json_rate,
        zenoh_config: cli.zenoh_config,
        insecure: cli.insecure,
    };
    let config = match BridgeConfig::load(cli.config.as_deref(), overrides) {
        Ok(config) => config,
        Err(error) => {
            eprintln!("motion-bridge: {error}");
            return ExitCode::from(1);
        }
    };
    if config.remotes.is_empty() {
        tracing::warn!("no [[remote]] in the config: every command is refused (read-only bridge)");
    }
    let mut bridge = match Bridge::start(config) {
        Ok(bridge) => bridge,
        Err(error) => {
            eprintln!("motion-bridge: {error}");
            return ExitCode::from(1);
        }
    };
    bridge.run(&AtomicBool::new(false));
    ExitCode::SUCCESS
}
