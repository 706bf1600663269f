//! The bench's options, shared by `cargo bench --bench latency` and `motionctl bench`
//! (each adds its own `--server`: motionctl's is global to every subcommand).

use core::time::Duration;
use std::path::PathBuf;

use clap::{Args, ValueEnum};

/// Every option of the latency suite except the server's name.
#[derive(Debug, Clone, Args)]
pub struct BenchArgs {
    /// How long each phase runs: `10s`, `500ms`, `2m`.
    #[arg(long, default_value = "10s", value_parser = parse_duration)]
    pub duration: Duration,
    /// Print the results as one JSON document instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Write every distribution measured here as `value_ns percentile total_count` lines,
    /// one file per distribution, into DIR (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Draw one SVG histogram per figure, its same-run baselines overlaid (log counts,
    /// p50/p99/p99.9 marked), and `DIR/index.html` with the table and the pictures
    /// (created if missing). The distribution files go there too unless --out is given.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// SCHED_FIFO priority for the baseline sleeper, the baseline peer's tick thread and the
    /// WaitSet clients (never for busy-polling threads). Give the server's `rt_priority`.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u8).range(1..=99))]
    pub rt_priority: Option<u8>,
    /// Pin the baseline sleeper and the baseline peer's tick thread to this core. Give the
    /// server's `cpu`.
    #[arg(long, value_name = "N")]
    pub cpu: Option<usize>,
    /// The harmless command timed in the round trip.
    #[arg(long, value_enum, default_value_t = CommandProbe::UnknownAxis)]
    pub command: CommandProbe,
    /// Also measure tick work versus axis count: start motiond on generated configs with
    /// 4, 16, 64 and 128 simulated axes (each for DURATION).
    #[arg(long)]
    pub axes_sweep: bool,
    /// Measure "command to wire": start a motiond of the bench's own on a generated config
    /// whose serial link is a pty served by a simulated QSB in this bench, and time request →
    /// first byte of the board command at the pty (DURATION, plus a third of it for the
    /// baseline). On by default; `--command-to-wire=false` skips it.
    #[arg(long, value_name = "BOOL", default_value_t = true, num_args = 0..=1,
          default_missing_value = "true", action = clap::ArgAction::Set)]
    pub command_to_wire: bool,
    /// Measure the I/O phase: a motiond of the bench's own with four idle external links (two
    /// ptys, two SPI sockets served by simulated boards in this bench) for its CPU beside a
    /// plain peer's (DURATION each), and how long a reply's bytes wait in the tty before
    /// its I/O thread reads them beside a plain poll + read thread (half of DURATION each).
    /// On by default; `--io-phase=false` skips it.
    #[arg(long, value_name = "BOOL", default_value_t = true, num_args = 0..=1,
          default_missing_value = "true", action = clap::ArgAction::Set)]
    pub io_phase: bool,
    /// Measure coordinated motion: start a motiond of the bench's own on `config/sim.toml`
    /// (the simulated robot) and run trajectories on its groups `gantry` and `base`
    /// (tracking error and lag per board beside its refresh), three gantry lines (arrival
    /// skew beside single-axis ramps) and a velocity stream to `base` (setpoints in their
    /// tick, frame → setpoint beside a plain peer pair); about 3 × DURATION (at least 10 s).
    /// Never moves the server under test. On by default; `--groups=false` skips it.
    #[arg(long, value_name = "BOOL", default_value_t = true, num_args = 0..=1,
          default_missing_value = "true", action = clap::ArgAction::Set)]
    pub groups: bool,
    /// Measure the Trinamic pack's line rate: start a motiond of the bench's own with two
    /// simulated SIXpacks, one at the factory 19200 baud and one switched to 115200 (its
    /// `baud` key), and sample the refresh age of their axes (DURATION). On by default;
    /// `--link-rate=false` skips it.
    #[arg(long, value_name = "BOOL", default_value_t = true, num_args = 0..=1,
          default_missing_value = "true", action = clap::ArgAction::Set)]
    pub link_rate: bool,
    /// Also run the I/O phase's CPU measurement with this motiond binary (an older build:
    /// a before/after on the same machine in the same run).
    #[arg(long, value_name = "PATH")]
    pub io_before: Option<PathBuf>,
    /// The motiond binary the sweep and the command-to-wire phase start (default: `motiond`
    /// beside this program or in the target directory above it, else on PATH).
    #[arg(long, value_name = "PATH")]
    pub motiond: Option<PathBuf>,
    /// The Python interpreter that has the `motiond` package (`python/`): the "Python
    /// client" phase runs `PATH -m motiond.bench` against the server (default:
    /// `py-venv/bin/python` in the target directory of this program, which `./scripts/test`
    /// creates; without one the phase is skipped with a note).
    #[arg(long, value_name = "PATH")]
    pub python: Option<PathBuf>,
    /// Processes spinning `while True: pass` beside the Python streaming client of the
    /// coordinated-motion phase (its runs with lead 1 and with the default lead), to measure
    /// the share of ticks it meets on a loaded machine. 0 by default.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub busy_loops: u32,
}

/// The command whose round trip is timed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum CommandProbe {
    /// `Stop` on the first axis index past the last one: answered `UnknownAxis`, touches no
    /// axis, works on a server without devices.
    UnknownAxis,
    /// `Claim` then `Release` of axis 0, alternating: no motion, but the axis is claimed
    /// for a moment, so other clients may see `ClaimedByOther`. Needs an axis.
    ClaimRelease,
}

/// What the re-executed peer process does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PeerMode {
    /// motiond's skeleton without the engine: absolute-deadline tick, answer requests,
    /// publish a frame-sized sample, notify the tick event.
    Ticking,
    /// Answer requests as fast as possible (busy-polling server).
    BusyRr,
    /// `Ticking`, plus a `setpoints` service as motiond's, drained at the start of each
    /// tick (the baseline of a client streaming setpoints).
    Streaming,
}

impl PeerMode {
    /// The word on the peer's command line.
    pub fn word(self) -> &'static str {
        match self {
            Self::Ticking => "ticking",
            Self::BusyRr => "busy-rr",
            Self::Streaming => "streaming",
        }
    }

    /// Parses [`PeerMode::word`].
    pub fn from_word(word: &str) -> Option<Self> {
        match word {
            "ticking" => Some(Self::Ticking),
            "busy-rr" => Some(Self::BusyRr),
            "streaming" => Some(Self::Streaming),
            _ => None,
        }
    }
}

/// `10s`, `250ms`, `2m`, `1.5s`, `500us`; a bare number is seconds
/// ([`motion_base::parse_duration`]); a bench run lasts more than 0 and at most a day.
pub fn parse_duration(text: &str) -> Result<Duration, String> {
    let duration = motion_base::parse_duration(text)?;
    if duration.is_zero() || duration > Duration::from_secs(86_400) {
        return Err(format!(
            "`{}`: must be more than 0 and at most a day",
            text.trim()
        ));
    }
    Ok(duration)
}
