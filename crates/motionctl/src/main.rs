//! `motionctl`: the command-line client of motiond (docs/ARCHITECTURE.md "Contracts").
//!
//! Every subcommand connects to the instance given by `--server` (default `demo`) over
//! iceoryx2 shared memory through `motion-client`. Errors are one line naming what failed
//! and, for refused commands, the reason the server gave; the exit status says which kind
//! of failure it was (see `motionctl --help`).
#![forbid(unsafe_code)]

/// `println!` that returns the write error instead of panicking (a closed pipe, as in
/// `motionctl watch --json | head`, ends the command quietly: see `main`).
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*)?
    }};
}

mod act;
mod bench;
mod blackbox;
mod cli;
mod commission;
mod describe;
mod doctor;
mod group;
mod group_csv;
mod group_report;
mod io;
mod joint_state_cdr;
mod machine;
mod record;
mod record_csv;
mod record_mcap;
mod record_output;
mod record_plot;
mod scope;
mod terminal;
mod watch;

use std::process::ExitCode;

use clap::Parser;
use iceoryx2::prelude::{LogLevel, ipc, set_log_level};
use motion_client::{Client, ClientBuilder, ClientError, ConnectError, EstopError};

use crate::cli::{Cli, Command, exit};

/// The service type of a real server.
pub type Service = ipc::Service;

fn main() -> ExitCode {
    // `motionctl bench` re-executes motionctl as its baseline peer process.
    if let Some(status) = motion_bench::peer::run_if_requested() {
        return status;
    }
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(error) => {
            let _ = error.print();
            // --help and --version are not errors.
            return ExitCode::from(if error.use_stderr() {
                exit::USAGE
            } else {
                exit::OK
            });
        }
    };
    // iceoryx2 logs its own warnings (e.g. "no config file") on stderr; keep one-line errors.
    set_log_level(LogLevel::Error);
    match run(&cli) {
        Ok(()) => ExitCode::from(exit::OK),
        Err(error) if closed_pipe(&error) => ExitCode::from(exit::OK),
        Err(error) => {
            eprintln!("motionctl: {error:#}");
            ExitCode::from(exit_status(&error))
        }
    }
}

fn connect(cli: &Cli) -> anyhow::Result<Client<Service>> {
    let mut builder = ClientBuilder::new(&cli.server)
        .node_name("motionctl")
        .connect_timeout(cli.connect_timeout);
    if let Some(endpoint) = &cli.remote {
        builder = builder.remote(endpoint);
        if let Some(identity) = &cli.identity {
            builder = builder.identity(identity);
        }
        if let Some(path) = &cli.zenoh_config {
            builder = builder.zenoh_config(path);
        }
    }
    Ok(builder.connect()?)
}

/// Commands that must not wait for anything: the e-stop (which needs no client port even)
/// and the stop of every axis (the command service alone). `None` for the others.
fn run_unconnected(cli: &Cli) -> Option<anyhow::Result<()>> {
    if cli.remote.is_some() {
        // Through a bridge every command needs the connection (see `run`).
        return None;
    }
    match &cli.command {
        Command::Estop => Some(estop(cli)),
        Command::Bench(args) => Some(bench::run(&cli.server, args)),
        Command::Doctor(args) => Some(doctor::run(args)),
        Command::Stop { axes } if axes.is_empty() => Some(
            motion_client::stop_all::<Service>(&cli.server, cli.connect_timeout)
                .map_err(anyhow::Error::new)
                .and_then(|accepted| {
                    out!("all axes stopping (tick {})", accepted.tick);
                    Ok(())
                }),
        ),
        _ => None,
    }
}

fn estop(cli: &Cli) -> anyhow::Result<()> {
    let estop = motion_client::estop::<Service>(&cli.server, cli.connect_timeout)?;
    out!(
        "e-stop latched via {estop}: every axis stops with its e-stop category; \
         `motionctl reset` clears it"
    );
    Ok(())
}

fn run(cli: &Cli) -> anyhow::Result<()> {
    if let Some(result) = run_unconnected(cli) {
        return result;
    }
    let client = connect(cli)?;
    let client = &client;
    match &cli.command {
        Command::List { json } => describe::list(client, *json),
        Command::Status { axes, json } => describe::status(client, axes, *json),
        Command::Watch { json, interval } => watch::run(client, *json, *interval),
        Command::Move {
            axis,
            position,
            velocity,
            accel,
            wait,
            timeout,
        } => act::move_axis(
            client,
            axis,
            *position,
            *velocity,
            *accel,
            wait.then_some(*timeout),
        ),
        Command::Jog {
            axis,
            velocity,
            accel,
        } => act::jog(client, axis, *velocity, *accel),
        Command::Power { axis, power } => act::power(client, axis, *power),
        Command::Stop { axes } if axes.is_empty() && client.is_remote() => {
            let accepted = client.stop_all()?;
            out!("all axes stopping (tick {})", accepted.tick);
            Ok(())
        }
        Command::Stop { axes } => act::stop(client, axes),
        Command::Off { axes, all } => act::off(client, axes, *all),
        Command::Estop if client.is_remote() => {
            let accepted = client.estop()?;
            out!(
                "e-stop latched in tick {} through the bridge: every axis stops with its \
                 e-stop category; `motionctl reset` clears it",
                accepted.tick
            );
            Ok(())
        }
        Command::Estop => estop(cli),
        Command::Bench(args) => bench::run(&cli.server, args),
        Command::Doctor(args) => doctor::run(args),
        Command::WaitReady { axes, timeout } => act::wait_ready(client, axes, *timeout),
        Command::Io { command } => io::run(client, command),
        Command::Group { command } => group::run(client, command),
        Command::Reset => {
            client.reset()?;
            out!("reset: e-stop and faults cleared");
            Ok(())
        }
        Command::Home {
            axis,
            velocity,
            wait,
            timeout,
        } => act::home(client, axis, *velocity, wait.then_some(*timeout)),
        Command::Hold { axis } => {
            let accepted = client.axis(axis)?.hold()?;
            out!(
                "{axis}: held (tick {}); `motionctl resume {axis}` continues",
                accepted.tick
            );
            Ok(())
        }
        Command::Resume { axis } => {
            let accepted = client.axis(axis)?.resume()?;
            out!("{axis}: resumed (tick {})", accepted.tick);
            Ok(())
        }
        Command::SetPosition { axis, position } => {
            let handle = client.axis(axis)?;
            handle.set_position(*position)?;
            out!(
                "{axis}: position set to {position} {}",
                handle.info().unit()
            );
            Ok(())
        }
        Command::Commission {
            device,
            address,
            baud,
            factory_reset,
            yes,
            timeout,
            json,
        } => commission::run(
            client,
            &commission::Request {
                device,
                change: commission::change(*address, *baud, *factory_reset, *yes)?,
                timeout: *timeout,
                json: *json,
            },
        ),
        Command::Claim { axes, duration } => act::claim(client, axes, *duration),
        Command::Release { axes } => act::release(client, axes),
        Command::Scope { axes, window } => scope::run(client, axes, *window),
        Command::Blackbox {
            command: cli::BlackboxCommand::Save { out },
        } => blackbox::save(client, out.as_deref()),
        Command::Record {
            duration,
            out,
            format,
            plot,
            axes,
        } => record::run(
            client,
            &record::RecordRequest {
                duration: *duration,
                outs: out,
                format: *format,
                plot: plot.as_deref(),
                axes,
            },
        ),
    }
}

/// Whether the error is stdout being closed by its reader.
fn closed_pipe(error: &anyhow::Error) -> bool {
    error.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

fn connect_status(error: &ConnectError) -> u8 {
    match error {
        ConnectError::NoServer { .. }
        | ConnectError::NoInfo { .. }
        | ConnectError::NoBridge { .. }
        | ConnectError::PortsExhausted { .. } => exit::NO_SERVER,
        _ => exit::FAILURE,
    }
}

/// The documented exit status of an error.
fn exit_status(error: &anyhow::Error) -> u8 {
    for cause in error.chain() {
        if let Some(connect) = cause.downcast_ref::<ConnectError>() {
            return connect_status(connect);
        }
        if let Some(motion_bench::BenchError::NoServer(_)) = cause.downcast_ref() {
            return exit::NO_SERVER;
        }
        if let Some(estop) = cause.downcast_ref::<EstopError>() {
            return if estop.unconfirmed.is_some() {
                // Sent, but the server never showed it latched: as a silent server.
                exit::TIMEOUT
            } else if estop.server_found {
                exit::FAILURE
            } else {
                exit::NO_SERVER
            };
        }
        if cause.downcast_ref::<group::BadArguments>().is_some() {
            return exit::USAGE;
        }
        if let Some(client) = cause.downcast_ref::<ClientError>() {
            return match client {
                ClientError::Refused { .. }
                | ClientError::GroupRefused(_)
                | ClientError::BridgeRefused { .. }
                | ClientError::UnknownAxis(_)
                | ClientError::UnknownDevice(_)
                | ClientError::UnknownGroup { .. }
                | ClientError::UnknownSignal(_) => exit::REFUSED,
                ClientError::Trajectory(_) => exit::USAGE,
                ClientError::NoServer { .. } => exit::NO_SERVER,
                ClientError::Connect(connect) => connect_status(connect),
                ClientError::NoReply { .. }
                | ClientError::NoFrame(_)
                | ClientError::EstopNotSeen { .. }
                | ClientError::WaitTimeout { .. }
                | ClientError::WaitAborted { .. }
                | ClientError::AxisFaulted { .. }
                | ClientError::NotReady { .. }
                | ClientError::SignalTimeout { .. }
                | ClientError::GroupAborted(_)
                | ClientError::GroupTimeout { .. }
                | ClientError::GroupWaitAborted { .. } => exit::TIMEOUT,
                ClientError::Interrupted => exit::INTERRUPTED,
                ClientError::ServerRestarted(_)
                | ClientError::NotPublished { .. }
                | ClientError::Network { .. }
                | ClientError::Remote(_)
                | ClientError::PathNotSent { .. }
                | ClientError::LocalOnly { .. }
                | ClientError::UnknownValue { .. }
                | ClientError::Ipc { .. } => exit::FAILURE,
            };
        }
    }
    exit::FAILURE
}
