//! `motion-sim`: serves simulated motor-controller boards on a pseudo-terminal (serial
//! boards) or a Unix socket (SPI boards), so that motiond, `screen` or a script can talk to
//! them as to real hardware. See `motion-sim --help`.
#![forbid(unsafe_code)]

mod boards;
mod cli;
mod faults;
mod pty;
mod socket;
mod trace;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use anyhow::{Context, Result, bail};
use motion_board::SimBoard;
use nix::sys::signal::{SigSet, Signal};

use crate::trace::Trace;

fn main() -> ExitCode {
    let options = match cli::parse(std::env::args_os()) {
        Ok(options) => options,
        Err(e) => e.exit(),
    };
    match run(&options) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("motion-sim: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(options: &cli::Options) -> Result<()> {
    // SIGINT and SIGTERM are blocked in every thread and taken by one waiting thread, which
    // asks the servers to stop; they then clean up and the process exits 0.
    let mut signals = SigSet::empty();
    signals.add(Signal::SIGINT);
    signals.add(Signal::SIGTERM);
    signals.thread_block().context("blocking SIGINT/SIGTERM")?;
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    std::thread::spawn(move || {
        if let Ok(signal) = signals.wait() {
            eprintln!("motion-sim: {signal}, stopping");
            flag.store(true, Ordering::SeqCst);
        }
    });

    let cli = &options.cli;
    let mut serial = Vec::new();
    let mut spi = Vec::new();
    let mut serial_names = Vec::new();
    let mut spi_names = Vec::new();
    let mut first_serial_rate = None;
    for spec in &options.boards {
        match boards::build(spec, cli.baud, cli.spi_hz)? {
            SimBoard::Stream(device) => {
                first_serial_rate.get_or_insert(spec.board.link().default_rate);
                serial.push(device);
                serial_names.push(boards::describe(spec));
            }
            SimBoard::Spi(device) => {
                spi.push(device);
                spi_names.push(boards::describe(spec));
            }
        }
    }

    let mut stdout = std::io::stdout().lock();
    let pty_endpoint = if serial.is_empty() {
        None
    } else {
        // The wire runs at --baud, else at the rate the boards listen at after power-up,
        // else at the first serial board's line rate.
        let baud = cli
            .baud
            .or_else(|| serial.iter().find_map(|d| d.baud()))
            .or(first_serial_rate)
            .context("a serial board without a line rate")?;
        for (device, name) in serial.iter().zip(&serial_names) {
            if let Some(own) = device.baud().filter(|&own| own != baud) {
                eprintln!(
                    "motion-sim: warning: {name} listens at {own} baud, the pty runs at {baud}: \
                     its bytes will be garbled, as on a real line"
                );
            }
        }
        let pty = pty::Pty::open(baud)?;
        // The link exists before the path is printed: a client may use either at once.
        let link = match &cli.link {
            Some(path) => Some(Symlink::create(path, pty.path())?),
            None => None,
        };
        writeln!(stdout, "{}", pty.path().display())?;
        stdout.flush()?;
        let shown = link
            .as_ref()
            .map(|l| format!(" (also {})", l.path.display()))
            .unwrap_or_default();
        eprintln!(
            "motion-sim: serving {} on {}{shown} at {baud} baud 8N1",
            serial_names.join(", "),
            pty.path().display()
        );
        let wire = boards::stream_link(serial, baud);
        Some((pty, link, wire))
    };
    let socket_endpoint = match &cli.spi_socket {
        Some(path) if !spi.is_empty() => {
            let socket = socket::SpiSocket::bind(path)?;
            writeln!(stdout, "{}", socket.path().display())?;
            stdout.flush()?;
            eprintln!(
                "motion-sim: serving {} on SPI socket {} at {} Hz",
                spi_names.join(", "),
                socket.path().display(),
                cli.spi_hz
            );
            Some((socket, boards::spi_link(spi, cli.spi_hz)))
        }
        _ => None,
    };
    drop(stdout);
    let plan = faults::FaultPlan::new(
        cli.drop_rate,
        Duration::from_millis(cli.noise_every),
        Duration::from_millis(cli.reply_delay),
    );
    if plan.is_active() {
        eprintln!("motion-sim: {}", plan.describe());
    }

    std::thread::scope(|scope| -> Result<()> {
        let mut workers = Vec::new();
        if let Some((pty, symlink, mut wire)) = pty_endpoint {
            let stop = &stop;
            workers.push(scope.spawn(move || {
                // The symlink lives as long as the server: it is removed when this ends.
                let _symlink = symlink;
                let mut trace = Trace::new("pty", cli.trace);
                let mut plan = plan;
                plan.apply(&wire.faults());
                let outcome = pty::serve(&pty, &mut wire, stop, &mut trace, &mut plan);
                stop.store(true, Ordering::SeqCst);
                outcome
            }));
        }
        if let Some((socket, mut wire)) = socket_endpoint {
            let stop = &stop;
            workers.push(scope.spawn(move || {
                let mut trace = Trace::new("spi", cli.trace);
                let mut plan = plan;
                plan.apply(&wire.faults());
                let outcome = socket::serve(&socket, &mut wire, stop, &mut trace, &mut plan);
                stop.store(true, Ordering::SeqCst);
                outcome
            }));
        }
        let mut first_error = None;
        for worker in workers {
            let outcome = match worker.join() {
                Ok(outcome) => outcome,
                Err(_) => Err(anyhow::anyhow!("a server thread panicked")),
            };
            if let Err(e) = outcome {
                first_error.get_or_insert(e);
            }
        }
        first_error.map_or(Ok(()), Err)
    })
}

/// A symbolic link to the pty, removed on exit if it still points there.
struct Symlink {
    path: PathBuf,
    target: PathBuf,
}

impl Symlink {
    fn create(path: &Path, target: &Path) -> Result<Self> {
        if let Ok(meta) = std::fs::symlink_metadata(path) {
            if !meta.file_type().is_symlink() {
                bail!(
                    "--link {}: exists and is not a symbolic link",
                    path.display()
                );
            }
            std::fs::remove_file(path)
                .with_context(|| format!("replacing the old link {}", path.display()))?;
        }
        std::os::unix::fs::symlink(target, path)
            .with_context(|| format!("--link {}", path.display()))?;
        Ok(Self {
            path: path.to_owned(),
            target: target.to_owned(),
        })
    }
}

impl Drop for Symlink {
    fn drop(&mut self) {
        if std::fs::read_link(&self.path).is_ok_and(|t| t == self.target) {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}
