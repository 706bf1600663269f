//! Command line: which boards to simulate and where to serve them.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::{ArgMatches, CommandFactory, FromArgMatches, Parser};
use motion_base::{LinkKind, Model};

const AFTER_HELP: &str = "\
Boards:
  qsb       US Digital QSB-S/-D/-M, ASCII over USB serial, 230400 baud   (--variant s|d|m)
  tmcpack   Trinamic SIXpack/QUADpack, 9-byte frames, 19200 baud          (--address, --variant sixpack|quadpack)
  qq2drv    QuadQuad2Drv, SPI mode 1, 500 kHz                             (SPI socket)
  spimotor  SPI_motor, SPI, default address 0x90                          (--address, --drive stepper|brushed)

--address, --variant, --drive and --seed apply to the --model before them. All serial
boards share one pseudo-terminal (an RS-485 bus: every board hears every byte); all SPI
boards share one socket (one chip select: a board answers its own address, an undriven
MISO reads 0xFF).

Examples:
  motion-sim --model qsb --pty --link /tmp/qsb
      prints the pty path (first line of stdout) and links /tmp/qsb to it. Talk to it:
        screen /tmp/qsb 230400          (type R14 then Enter; Ctrl-A k quits)
        python3 -c \"import os,time; f=os.open('/tmp/qsb',os.O_RDWR); os.write(f,b'R14\\r\\n'); time.sleep(0.1); print(os.read(f,64))\"
  motion-sim --model tmcpack --address 1 --model tmcpack --address 2 --variant quadpack --pty
      two packs on one RS-485 bus. Unit info ($43) of pack 1, 9-byte request:
        python3 -c \"import os,time,sys; f=os.open(sys.argv[1],os.O_RDWR); os.write(f,bytes([1,0x43,0xFE,0,0,0,0,0,0])); time.sleep(0.1); print(os.read(f,64).hex())\" /dev/pts/N
  motion-sim --model qq2drv --spi-socket /tmp/qq2drv.sock
      one transaction = u16 little-endian length + MOSI bytes; the answer is as many MISO
      bytes. Version request (packet 1) then filler to clock the reply out:
        python3 -c \"import socket; s=socket.socket(socket.AF_UNIX); s.connect('/tmp/qq2drv.sock'); s.send(bytes([4,0,2,4,1,249])); print(s.recv(4).hex()); s.send(bytes([16,0])+bytes(16)); print(s.recv(16).hex())\"
  motion-sim --model spimotor --address 0x90 --model spimotor --address 0x92 --drive brushed --spi-socket /tmp/motors.sock

A board told to change its rate (tmcpack $40, QSB COMMAND baud selection) then talks
at the new rate while the pty stays at --baud: its bytes arrive garbled, as on a real line.

Runs until SIGINT or SIGTERM (exit status 0). Logs what it serves on stderr; --trace also
logs every byte with its time.";

/// A `--model` value: the id of one of the models this simulator has (`Model::BUILT_IN`).
fn parse_model(text: &str) -> Result<Model, String> {
    Model::BUILT_IN
        .into_iter()
        .find(|model| model.id() == text)
        .ok_or_else(|| {
            let ids: Vec<&str> = Model::BUILT_IN.iter().map(|model| model.id()).collect();
            format!("unknown model `{text}` (one of {})", ids.join(", "))
        })
}

/// Serve simulated motor-controller boards on a pseudo-terminal or an SPI socket.
#[derive(Debug, Parser)]
#[command(name = "motion-sim", version, after_help = AFTER_HELP)]
pub struct Cli {
    /// A board to simulate; repeat for several boards on one bus.
    #[arg(long = "model", value_parser = parse_model, required = true, action = clap::ArgAction::Append)]
    pub models: Vec<Model>,
    /// Bus address of the preceding --model (tmcpack: 0..=255, default 1; spimotor: even
    /// byte, default 0x90). Decimal or 0x-hex.
    #[arg(long, action = clap::ArgAction::Append, value_parser = parse_u8)]
    pub address: Vec<u8>,
    /// Variant of the preceding --model (tmcpack: sixpack|quadpack; qsb: s|d|m).
    #[arg(long, action = clap::ArgAction::Append)]
    pub variant: Vec<String>,
    /// Motors on the preceding spimotor: stepper|brushed.
    #[arg(long, action = clap::ArgAction::Append)]
    pub drive: Vec<String>,
    /// Seed of the preceding --model's random effects (default: the model's own).
    #[arg(long, action = clap::ArgAction::Append)]
    pub seed: Vec<u64>,
    /// Serve the serial boards on a new pseudo-terminal; its path is the first line on
    /// stdout.
    #[arg(long)]
    pub pty: bool,
    /// Also make PATH a symbolic link to the pseudo-terminal (removed on exit).
    #[arg(long, value_name = "PATH", requires = "pty")]
    pub link: Option<PathBuf>,
    /// Pace the pseudo-terminal at this rate, 10 bits a byte (default: the board's own
    /// rate, 230400 for qsb, 19200 for tmcpack).
    #[arg(long)]
    pub baud: Option<u32>,
    /// Serve the SPI boards on a Unix socket at PATH (docs/ARCHITECTURE.md SPI socket contract).
    #[arg(long, value_name = "PATH")]
    pub spi_socket: Option<PathBuf>,
    /// SPI clock used for wire time on the socket (default 500000).
    #[arg(long, value_name = "HZ", default_value_t = 500_000)]
    pub spi_hz: u32,
    /// Fault injection: probability that a byte is lost, each way (0 to 1).
    #[arg(long, value_name = "P", default_value_t = 0.0)]
    pub drop_rate: f64,
    /// Fault injection: put one random byte on the wire to the client every MS
    /// milliseconds (SPI: corrupt one MISO byte as often).
    #[arg(long, value_name = "MS", default_value_t = 0)]
    pub noise_every: u64,
    /// Fault injection: hold every reply back by MS milliseconds.
    #[arg(long, value_name = "MS", default_value_t = 0)]
    pub reply_delay: u64,
    /// Log every byte in and out on stderr, with its time.
    #[arg(long)]
    pub trace: bool,
}

/// One board and its options.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BoardSpec {
    /// Which board.
    pub model: Model,
    /// `--address`, if given.
    pub address: Option<u8>,
    /// `--variant`, if given.
    pub variant: Option<String>,
    /// `--drive`, if given.
    pub drive: Option<String>,
    /// `--seed`, if given (else the model's default).
    pub seed: Option<u64>,
}

/// The parsed command line.
#[derive(Debug)]
pub struct Options {
    /// The flags.
    pub cli: Cli,
    /// The boards, in command-line order, with their own options.
    pub boards: Vec<BoardSpec>,
}

fn parse_u8(s: &str) -> Result<u8, String> {
    let parsed = match s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        Some(hex) => u8::from_str_radix(hex, 16),
        None => s.parse(),
    };
    parsed.map_err(|_| format!("`{s}` is not a byte (0..=255 or 0x00..=0xff)"))
}

/// Parses `args` (program name first).
pub fn parse<I, T>(args: I) -> Result<Options, clap::Error>
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    let matches = Cli::command().try_get_matches_from(args)?;
    let cli = Cli::from_arg_matches(&matches)?;
    let boards = group(&matches, &cli).map_err(|e| {
        Cli::command().error(clap::error::ErrorKind::ArgumentConflict, format!("{e:#}"))
    })?;
    Ok(Options { cli, boards })
}

/// Gives each per-board option to the `--model` that precedes it.
fn group(matches: &ArgMatches, cli: &Cli) -> Result<Vec<BoardSpec>> {
    let model_at: Vec<usize> = matches
        .indices_of("models")
        .map(Iterator::collect)
        .unwrap_or_default();
    let mut boards: Vec<BoardSpec> = cli
        .models
        .iter()
        .map(|&model| BoardSpec {
            model,
            address: None,
            variant: None,
            drive: None,
            seed: None,
        })
        .collect();
    let owner = |flag: &str, at: usize| -> Result<usize> {
        model_at
            .iter()
            .rposition(|&m| m < at)
            .with_context(|| format!("--{flag} must follow the --model it applies to"))
    };
    let indices = |id: &str| -> Vec<usize> {
        matches
            .indices_of(id)
            .map(Iterator::collect)
            .unwrap_or_default()
    };
    for (at, value) in indices("address").into_iter().zip(&cli.address) {
        let board = boards.get_mut(owner("address", at)?).context("address")?;
        if board.address.replace(*value).is_some() {
            bail!("two --address for one --model {}", board.model.id());
        }
    }
    for (at, value) in indices("variant").into_iter().zip(&cli.variant) {
        let board = boards.get_mut(owner("variant", at)?).context("variant")?;
        if board.variant.replace(value.clone()).is_some() {
            bail!("two --variant for one --model {}", board.model.id());
        }
    }
    for (at, value) in indices("drive").into_iter().zip(&cli.drive) {
        let board = boards.get_mut(owner("drive", at)?).context("drive")?;
        if board.drive.replace(value.clone()).is_some() {
            bail!("two --drive for one --model {}", board.model.id());
        }
    }
    for (at, value) in indices("seed").into_iter().zip(&cli.seed) {
        let board = boards.get_mut(owner("seed", at)?).context("seed")?;
        if board.seed.replace(*value).is_some() {
            bail!("two --seed for one --model {}", board.model.id());
        }
    }
    let serial = boards
        .iter()
        .any(|b| b.model.link_kind() == LinkKind::Stream);
    let spi = boards.iter().any(|b| b.model.link_kind() == LinkKind::Spi);
    if serial && !cli.pty {
        bail!("serial boards (qsb, tmcpack) are served on a pseudo-terminal: add --pty");
    }
    if spi && cli.spi_socket.is_none() {
        bail!("SPI boards (qq2drv, spimotor) are served on a socket: add --spi-socket PATH");
    }
    if cli.pty && !serial {
        bail!("--pty given but no serial board (qsb, tmcpack) to serve on it");
    }
    if cli.spi_socket.is_some() && !spi {
        bail!("--spi-socket given but no SPI board (qq2drv, spimotor) to serve on it");
    }
    if !(0.0..=1.0).contains(&cli.drop_rate) {
        bail!(
            "--drop-rate {} is not a probability (0 to 1)",
            cli.drop_rate
        );
    }
    if cli.baud == Some(0) || cli.spi_hz == 0 {
        bail!("--baud and --spi-hz must be positive");
    }
    Ok(boards)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn boards(args: &str) -> Result<Vec<BoardSpec>, String> {
        parse(std::iter::once("motion-sim").chain(args.split_whitespace()))
            .map(|o| o.boards)
            .map_err(|e| e.to_string())
    }

    #[test]
    fn options_belong_to_the_preceding_model() {
        let got = boards(
            "--model tmcpack --address 1 --model tmcpack --address 0x02 --variant quadpack \
             --seed 7 --pty",
        )
        .unwrap();
        assert_eq!(got.len(), 2);
        assert_eq!((got[0].address, got[0].variant.as_deref()), (Some(1), None));
        assert_eq!(got[1].address, Some(2));
        assert_eq!(got[1].variant.as_deref(), Some("quadpack"));
        assert_eq!((got[0].seed, got[1].seed), (None, Some(7)));
        let got = boards("--model spimotor --drive brushed --spi-socket /tmp/s").unwrap();
        assert_eq!(got[0].drive.as_deref(), Some("brushed"));
    }

    #[test]
    fn mistakes_are_refused_with_a_reason() {
        for (args, why) in [
            ("--address 1 --model tmcpack --pty", "must follow"),
            (
                "--model tmcpack --address 1 --address 2 --pty",
                "two --address",
            ),
            ("--model qsb", "add --pty"),
            ("--model qq2drv --pty", "add --spi-socket"),
            ("--model qsb --pty --spi-socket /tmp/x", "no SPI board"),
            ("--model tmcpack --address 300 --pty", "not a byte"),
            ("--model nosuch --pty", "nosuch"),
            ("--model qsb --link /tmp/x", "--pty"),
            ("--model qsb --pty --drop-rate 2", "probability"),
        ] {
            let err = boards(args).unwrap_err();
            assert!(err.contains(why), "{args}: {err}");
        }
    }
}
