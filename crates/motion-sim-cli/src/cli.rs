//! Command line: which boards to simulate and where to serve them.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::{ArgMatches, CommandFactory, FromArgMatches, Parser};
use motion_base::LinkKind;
use motion_board::Board;

const AFTER_HELP: &str = "\
--address, --variant, --drive and --seed apply to the --model before them. All serial
boards share one pseudo-terminal (an RS-485 bus: every board hears every byte); all SPI
boards share one socket (one chip select: a board answers its own address, an undriven
MISO reads 0xFF).";

const AFTER_EXAMPLES: &str = "\
The wire runs at --baud until the client sets another rate on its end of the pty (as
motiond does after telling a Trinamic pack $40), then at the client's. A board told to
change its rate (a baud-rate command of its protocol) talks at the new rate: between it and
a wire at another rate the bytes arrive garbled, as on a real line.

Runs until SIGINT or SIGTERM (exit status 0). Logs what it serves on stderr; --trace also
logs every byte with its time.";

/// The text after the options in `--help`: every registered board with its options
/// (`Board::standalone_help`), how boards share a wire, and the boards' examples.
fn after_help() -> String {
    let helps: Vec<(&str, motion_board::StandaloneHelp)> = motion_boards::BOARDS
        .iter()
        .map(|board| (board.model().id(), board.standalone_help()))
        .collect();
    let id_width = helps.iter().map(|(id, _)| id.len()).max().unwrap_or(0);
    let summary_width = helps
        .iter()
        .map(|(_, help)| help.summary.len())
        .max()
        .unwrap_or(0);
    let mut text = String::from("Boards:\n");
    for (id, help) in &helps {
        let line = if help.options.is_empty() {
            format!("  {id:<id_width$}  {}", help.summary)
        } else {
            format!(
                "  {id:<id_width$}  {:<summary_width$}  ({})",
                help.summary, help.options
            )
        };
        text.push_str(line.trim_end());
        text.push('\n');
    }
    text.push('\n');
    text.push_str(AFTER_HELP);
    text.push_str("\n\nExamples:\n");
    for (_, help) in &helps {
        for line in help.examples.lines() {
            text.push_str("  ");
            text.push_str(line);
            text.push('\n');
        }
    }
    text.push('\n');
    text.push_str(AFTER_EXAMPLES);
    text
}

/// A `--model` value: the id of a registered board (`motion_boards::by_id`).
fn parse_model(text: &str) -> Result<&'static dyn Board, String> {
    motion_boards::by_id(text).ok_or_else(|| {
        format!(
            "unknown model `{text}` (one of {})",
            motion_boards::id_list()
        )
    })
}

/// The command with its after-help (built from the registry).
fn command() -> clap::Command {
    Cli::command().after_help(after_help())
}

/// Serve simulated motor-controller boards on a pseudo-terminal or an SPI socket.
#[derive(Debug, Parser)]
#[command(name = "motion-sim", version)]
pub struct Cli {
    /// A board to simulate; repeat for several boards on one bus.
    #[arg(long = "model", value_parser = parse_model, required = true, action = clap::ArgAction::Append)]
    pub models: Vec<&'static dyn Board>,
    /// Bus address of the preceding --model (the boards that have one: see Boards below).
    /// Decimal or 0x-hex.
    #[arg(long, action = clap::ArgAction::Append, value_parser = parse_u8)]
    pub address: Vec<u8>,
    /// Variant of the preceding --model (the boards that have one: see Boards below).
    #[arg(long, action = clap::ArgAction::Append)]
    pub variant: Vec<String>,
    /// Motors on the preceding --model (the boards that have a choice: see Boards below).
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
    /// Pace the pseudo-terminal at this rate, 10 bits a byte (default: the rate the first
    /// serial board listens at, see Boards below).
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
#[derive(Debug, Clone)]
pub struct BoardSpec {
    /// Which board.
    pub board: &'static dyn Board,
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
    let matches = command().try_get_matches_from(args)?;
    let cli = Cli::from_arg_matches(&matches)?;
    let boards = group(&matches, &cli)
        .map_err(|e| command().error(clap::error::ErrorKind::ArgumentConflict, format!("{e:#}")))?;
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
        .map(|&board| BoardSpec {
            board,
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
            bail!("two --address for one --model {}", board.board.model().id());
        }
    }
    for (at, value) in indices("variant").into_iter().zip(&cli.variant) {
        let board = boards.get_mut(owner("variant", at)?).context("variant")?;
        if board.variant.replace(value.clone()).is_some() {
            bail!("two --variant for one --model {}", board.board.model().id());
        }
    }
    for (at, value) in indices("drive").into_iter().zip(&cli.drive) {
        let board = boards.get_mut(owner("drive", at)?).context("drive")?;
        if board.drive.replace(value.clone()).is_some() {
            bail!("two --drive for one --model {}", board.board.model().id());
        }
    }
    for (at, value) in indices("seed").into_iter().zip(&cli.seed) {
        let board = boards.get_mut(owner("seed", at)?).context("seed")?;
        if board.seed.replace(*value).is_some() {
            bail!("two --seed for one --model {}", board.board.model().id());
        }
    }
    let on = |kind: LinkKind| move |board: &dyn Board| board.model().link_kind() == kind;
    let serial = boards.iter().any(|b| on(LinkKind::Stream)(b.board));
    let spi = boards.iter().any(|b| on(LinkKind::Spi)(b.board));
    let serial_ids = || motion_boards::ids(on(LinkKind::Stream), "or");
    let spi_ids = || motion_boards::ids(on(LinkKind::Spi), "or");
    if serial && !cli.pty {
        bail!(
            "serial boards ({}) are served on a pseudo-terminal: add --pty",
            serial_ids()
        );
    }
    if spi && cli.spi_socket.is_none() {
        bail!(
            "SPI boards ({}) are served on a socket: add --spi-socket PATH",
            spi_ids()
        );
    }
    if cli.pty && !serial {
        bail!(
            "--pty given but no serial board ({}) to serve on it",
            serial_ids()
        );
    }
    if cli.spi_socket.is_some() && !spi {
        bail!(
            "--spi-socket given but no SPI board ({}) to serve on it",
            spi_ids()
        );
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

    #[test]
    fn help_names_every_registered_board_and_its_options() {
        let help = command().render_long_help().to_string();
        for board in motion_boards::BOARDS {
            let entry = board.standalone_help();
            let line = help
                .lines()
                .find(|line| line.starts_with(&format!("  {} ", board.model().id())))
                .unwrap_or_else(|| panic!("no line for {}:\n{help}", board.model()));
            assert!(line.contains(entry.summary), "{line}");
            assert!(line.contains(entry.options), "{line}");
        }
    }
}
