//! `motiond`, the real-time motion server.
#![forbid(unsafe_code)]

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use motion_config::ServerConfig;
use motion_config::locate::{Places, locate};

/// The motiond real-time motion server.
///
/// Exit status: 0 on success (and after a clean shutdown), 1 when the config is invalid,
/// 2 on a usage error.
#[derive(Debug, Parser)]
#[command(version, about, long_about = None)]
struct Cli {
    /// The config file to run. Without it: $MOTIOND_CONFIG, then /etc/motiond/motiond.toml,
    /// then config/sim.toml when run from the source tree's root.
    #[arg(long, value_name = "FILE")]
    config: Option<PathBuf>,
    /// Only validate FILE: print a summary or every error with file:line:column, and exit.
    #[arg(long, value_name = "FILE", conflicts_with = "config")]
    check_config: Option<PathBuf>,
    /// Replay a black box FILE.mcap (saved on a fault, an e-stop, SIGUSR2 or exit) through
    /// the drivers and the engine of its recorded config (or --config), compare every
    /// frame, and exit: 0 when every frame is identical, 1 at the first difference.
    #[arg(long, value_name = "FILE.mcap", conflicts_with = "check_config")]
    replay: Option<PathBuf>,
    /// Refuse to run without real-time privileges (SCHED_FIFO, locked memory) instead of
    /// warning and continuing.
    #[arg(long)]
    require_rt: bool,
}

fn main() -> ExitCode {
    iceoryx2::prelude::set_log_level_from_env_or(iceoryx2::prelude::LogLevel::Error);
    let cli = Cli::parse();
    if let Some(file) = &cli.replay {
        return replay(file, cli.config.as_deref());
    }
    let named = cli.check_config.clone().or(cli.config.clone());
    let (path, source) = match locate(&Places::of_process(named)) {
        Ok(found) => found,
        Err(none) => {
            eprintln!("{none}");
            return ExitCode::from(2);
        }
    };
    if cli.check_config.is_none() {
        init_logging();
        tracing::info!("config {} ({source})", path.display());
    }
    let path = &path;
    let config = match ServerConfig::load(path) {
        Ok(config) => config,
        Err(error) => {
            eprintln!("{error}");
            eprintln!(
                "motiond: {} is not a usable config; nothing was opened",
                path.display()
            );
            return ExitCode::from(1);
        }
    };
    for warning in &config.warnings {
        eprintln!("{}", warning.warning_line(&config.path));
    }
    if cli.check_config.is_some() {
        print_summary(&config);
        println!("config ok");
        return ExitCode::SUCCESS;
    }
    match motiond::app::run(
        config,
        motiond::app::RunOptions {
            require_rt: cli.require_rt,
        },
    ) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            // Every layer's words, down to iceoryx2's or the system's.
            eprintln!("motiond: {:#}", anyhow::Error::from(error));
            ExitCode::from(1)
        }
    }
}

/// `motiond --replay FILE.mcap [--config FILE]`.
fn replay(file: &std::path::Path, config: Option<&std::path::Path>) -> ExitCode {
    let recording = match motion_blackbox::read(file) {
        Ok(recording) => recording,
        Err(error) => {
            eprintln!("motiond: {error}");
            return ExitCode::from(1);
        }
    };
    let loaded = match config {
        Some(path) => ServerConfig::load(path),
        None if recording.config_text().is_empty() => {
            eprintln!(
                "motiond: {} holds no config text: pass the config it was recorded with \
                 (--config FILE)",
                file.display()
            );
            return ExitCode::from(1);
        }
        None => {
            let recorded = recording
                .metadata
                .get("config_path")
                .map_or_else(|| file.to_path_buf(), PathBuf::from);
            ServerConfig::parse(&recorded, recording.config_text())
        }
    };
    let config = match loaded {
        Ok(config) => config,
        Err(error) => {
            eprintln!("{error}");
            eprintln!("motiond: the replay's config is not usable");
            return ExitCode::from(1);
        }
    };
    match motion_blackbox::replay(&config, &recording) {
        Ok(done) if done.first > 0 => {
            println!(
                "replayed {} ticks from the state snapshot at tick {} (the ring had wrapped): \
                 frames identical",
                done.ticks, done.first
            );
            ExitCode::SUCCESS
        }
        Ok(done) => {
            println!("replayed {} ticks: frames identical", done.ticks);
            ExitCode::SUCCESS
        }
        Err(error) => {
            println!("replay: {error}");
            ExitCode::from(1)
        }
    }
}

fn init_logging() {
    let filter = tracing_subscriber::EnvFilter::try_from_env("MOTIOND_LOG")
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info"));
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_target(false)
        .init();
}

fn print_summary(config: &ServerConfig) {
    let server = &config.server;
    println!(
        "{}: instance `{}`, {} Hz, deadman {} ms, {} links, {} devices, {} axes",
        config.path.display(),
        server.name,
        server.tick_hz,
        server.command_timeout.as_millis(),
        config.links.len(),
        config.devices.len(),
        config.axes.len()
    );
    for (index, link) in config.links.iter().enumerate() {
        println!("  link {:<10} {:?}", link.name, link.transport);
        for device in config.devices.iter().filter(|d| d.link == index) {
            println!(
                "    device {:<12} {} @ {}",
                device.name, device.model, device.address
            );
            for (axis_index, axis) in config.axes.iter().enumerate() {
                if config.devices[axis.device].name == device.name {
                    println!(
                        "      axis #{axis_index:<3} {:<12} ch {} [{} .. {}] {} (≤ {} {}/s)",
                        axis.name,
                        axis.channel,
                        axis.min,
                        axis.max,
                        axis.unit,
                        axis.max_velocity,
                        axis.unit
                    );
                }
            }
        }
    }
    for group in &config.groups {
        let axes: Vec<&str> = group
            .axes
            .iter()
            .map(|&axis| config.axes[axis].name.as_str())
            .collect();
        println!("  group {:<10} {}", group.name, axes.join(" "));
    }
}
