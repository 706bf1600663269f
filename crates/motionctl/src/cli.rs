//! The command line (docs/ARCHITECTURE.md "Contracts").

use core::time::Duration;
use std::path::PathBuf;

use clap::{Parser, Subcommand};
use motion_base::parse_duration;

/// Exit statuses, documented in `--help`.
pub mod exit {
    /// Success.
    pub const OK: u8 = 0;
    /// Any other failure (iceoryx2, terminal, file).
    pub const FAILURE: u8 = 1;
    /// Bad command line (clap's own status).
    pub const USAGE: u8 = 2;
    /// No server of that name runs, or it could not be reached (its port slots are taken).
    pub const NO_SERVER: u8 = 3;
    /// The server refused the command (the reason is printed), or no such axis or signal.
    pub const REFUSED: u8 = 4;
    /// A wait ran out of time, the axis could not get there (stopped, faulted), a device
    /// was not ready, or the server went silent.
    pub const TIMEOUT: u8 = 5;
    /// Interrupted by Ctrl-C / SIGTERM while waiting (not for jog, watch, scope, claim).
    pub const INTERRUPTED: u8 = 130;
}

const AFTER_HELP: &str = "\
Exit status:
  0    success
  1    other failure (iceoryx2, terminal, file; the server restarted under the command)
  2    bad command line
  3    no motiond server of that name is running (or none of its ports is free)
  4    the server refused the command (its reason is printed), or no such axis or signal
  5    timed out, or the axis stopped or faulted before reaching its goal, or a device
       was not ready, or the server went silent
  130  interrupted by Ctrl-C or SIGTERM while waiting

Durations take a unit: 500ms, 10s, 2m (a bare number is seconds).
Examples:
  motionctl list
  motionctl watch
  motionctl wait-ready
  motionctl move x 10 --velocity 5 --wait
  motionctl jog y -2.5          (Ctrl-C stops the axis)
  motionctl io set lamp on
  motionctl io events probe --count 1   (each capture or trigger pulse as it comes)
  motionctl hold feeder         (a position move to rest; resume feeder continues it)
  motionctl group move gantry x=200 feeder=100 lift=150 --wait
  motionctl group follow arm arm.csv --wait --json
  motionctl group feed arm 50%  (also hold, resume, cancel, stop, claim, list)
  motionctl estop               (gets through even when the server's ports are taken)
  motionctl record --duration 5s --out run.csv
  motionctl record --duration 5s --out run.mcap --plot run.svg x y
  motionctl bench --duration 5s --json
  motionctl bench --duration 2s --plot target/latency-plots
  motionctl doctor --config /etc/motiond/motiond.toml
  motionctl commission pack_aux --address 5      (also --baud 115200, --factory-reset --yes)
  motionctl --remote tcp/cell4:7447 --identity panel status   (through motion-bridge)";

/// Command-line client of motiond.
#[derive(Debug, Parser)]
#[command(name = "motionctl", version, about, after_help = AFTER_HELP)]
pub struct Cli {
    /// Instance name of the server (`[server] name` in its config).
    #[arg(long, global = true, default_value = "demo", value_name = "NAME")]
    pub server: String,

    /// How long to wait for the server to appear.
    #[arg(long, global = true, default_value = "2s", value_parser = parse_duration, value_name = "DURATION")]
    pub connect_timeout: Duration,

    /// Talk to the server through the motion-bridge at this zenoh endpoint
    /// (`tcp/HOST:7447`) instead of shared memory.
    #[arg(long, global = true, value_name = "ENDPOINT")]
    pub remote: Option<String>,

    /// With --remote: the identity to send commands as (the bridge's allow-list is per
    /// identity).
    #[arg(long, global = true, value_name = "NAME", requires = "remote")]
    pub identity: Option<String>,

    /// With --remote: zenoh's own config file (JSON5): TLS certificates, user/password.
    #[arg(long, global = true, value_name = "FILE", requires = "remote")]
    pub zenoh_config: Option<PathBuf>,

    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// List the server's axes (units, limits, supervision), devices (state, firmware),
    /// signals, and every machine parameter in effect (from the config or the default).
    List {
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// Show the devices, every axis (or the ones named) with its fault in words, and the
    /// signals, from the newest frame.
    Status {
        /// Axes to show (default: all).
        axes: Vec<String>,
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// Live table of every axis, group and signal and the server's tick statistics; q or Ctrl-C
    /// exits.
    Watch {
        /// Print one JSON object per frame sampled, every --interval, instead of a table.
        #[arg(long)]
        json: bool,
        /// Refresh interval.
        #[arg(long, default_value = "100ms", value_parser = parse_duration)]
        interval: Duration,
    },
    /// Move an axis to a position along a velocity- and acceleration-limited ramp.
    Move {
        /// Axis name.
        axis: String,
        /// Target position, axis units.
        #[arg(allow_negative_numbers = true)]
        position: f64,
        /// Ramp velocity, units/s (default: the axis's maximum).
        #[arg(long)]
        velocity: Option<f64>,
        /// Ramp acceleration, units/s² (default: the axis's maximum).
        #[arg(long)]
        accel: Option<f64>,
        /// Wait until the axis's device is ready, then until the axis has arrived.
        #[arg(long)]
        wait: bool,
        /// Longest wait with --wait (readiness included).
        #[arg(long, default_value = "60s", value_parser = parse_duration)]
        timeout: Duration,
    },
    /// Run an axis at a velocity until Ctrl-C, then stop it.
    Jog {
        /// Axis name.
        axis: String,
        /// Velocity, units/s (negative: backwards).
        #[arg(allow_negative_numbers = true)]
        velocity: f64,
        /// Acceleration, units/s² (default: the axis's maximum).
        #[arg(long)]
        accel: Option<f64>,
    },
    /// Open-loop power (−1.0..1.0 of full scale) until Ctrl-C, then stop.
    Power {
        /// Axis name.
        axis: String,
        /// Power, −1.0..1.0.
        #[arg(allow_negative_numbers = true)]
        power: f64,
    },
    /// Stop the named axes (all axes when none is named: sent before anything else is
    /// read).
    Stop {
        /// Axes to stop.
        axes: Vec<String>,
    },
    /// De-energise the named axes, or every axis with --all (they coast, no holding
    /// torque). Each refusal is reported for its axis.
    Off {
        /// Axes to de-energise.
        #[arg(required_unless_present = "all", conflicts_with = "all")]
        axes: Vec<String>,
        /// Every axis.
        #[arg(long)]
        all: bool,
    },
    /// Emergency stop: every axis stops with its e-stop category; latched until `reset`.
    /// Tries the command service, then the estop event, then SIGUSR1 to the process the
    /// server's pid file names, and says which path delivered it; exits 0 only when the
    /// server showed the latch (a frame, or the command's reply), 5 when it was sent but
    /// not seen.
    Estop,
    /// Wait until every device (or the devices of the axes named) is online.
    WaitReady {
        /// Axes whose devices to wait for (default: every device).
        axes: Vec<String>,
        /// Longest wait.
        #[arg(long, default_value = "10s", value_parser = parse_duration)]
        timeout: Duration,
    },
    /// Axis groups: coordinated lines and trajectories, feed hold and override.
    Group {
        /// What to do.
        #[command(subcommand)]
        command: GroupCommand,
    },
    /// Board I/O signals: list, get, set, watch.
    Io {
        /// What to do.
        #[command(subcommand)]
        command: IoCommand,
    },
    /// Clear a latched e-stop and faults.
    Reset,
    /// Reference search.
    Home {
        /// Axis name.
        axis: String,
        /// Search velocity, units/s (default: the server's).
        #[arg(long)]
        velocity: Option<f64>,
        /// Wait until the axis's device is ready, then until the axis is homed.
        #[arg(long)]
        wait: bool,
        /// Longest wait with --wait (readiness included).
        #[arg(long, default_value = "120s", value_parser = parse_duration)]
        timeout: Duration,
    },
    /// Bring the axis's position move (`move`, a position goal) to rest and keep it; `resume`
    /// continues it to its target. A QSB-M pauses its own move (COMMAND 6); any other board
    /// stops at the move's acceleration. A jog is stopped, not held.
    Hold {
        /// Axis name.
        axis: String,
    },
    /// Continue the move `hold` brought to rest (COMMAND 7 on a QSB-M; on any other board
    /// the same move again, from where the axis stands).
    Resume {
        /// Axis name.
        axis: String,
    },
    /// Declare the axis's current position to be POS (no motion).
    SetPosition {
        /// Axis name.
        axis: String,
        /// The position the axis is at now, units.
        #[arg(allow_negative_numbers = true)]
        position: f64,
    },
    /// Change a device's own settings on the running server: its bus address (Trinamic
    /// `$42`, SPI_motor 0xf1/0xf2/0xf0), its line rate (Trinamic `$40`, the link follows)
    /// or its factory settings (Trinamic `$CC`, with --yes). Claims every axis and signal
    /// of the device meanwhile (refused while another client holds one, or while one of
    /// its axes moves); the server tells the board, finds it again where it now answers,
    /// and this prints what to put in the config.
    #[command(group(clap::ArgGroup::new("change").required(true).args(["address", "baud", "factory_reset"])))]
    Commission {
        /// Device name (`[[device]] name`).
        device: String,
        /// The new bus address: 0..=255 for a Trinamic pack, an even byte (0x92) for an
        /// SPI_motor.
        #[arg(long, value_parser = parse_address, value_name = "N")]
        address: Option<u32>,
        /// The new line rate, baud (a Trinamic pack: a rate its `$40` divisor reaches).
        #[arg(long, value_name = "N")]
        baud: Option<u32>,
        /// Reset the pack to its factory settings (`$CC`: every parameter, the address from
        /// its rotary switches, 19200 baud); the server configures it again from its config.
        #[arg(long)]
        factory_reset: bool,
        /// Confirm --factory-reset.
        #[arg(long, requires = "factory_reset")]
        yes: bool,
        /// How long to wait for the board to answer again.
        #[arg(long, default_value = "5s", value_parser = parse_duration)]
        timeout: Duration,
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// Claim axes for this process until Ctrl-C (or --duration), then release them.
    /// Claims die with the process that made them: other clients are refused meanwhile.
    Claim {
        /// Axes to claim.
        #[arg(required = true)]
        axes: Vec<String>,
        /// Release after this long instead of waiting for Ctrl-C.
        #[arg(long, value_parser = parse_duration)]
        duration: Option<Duration>,
    },
    /// Release claims held by this process. A claim belongs to the process that made it, so
    /// from a new process this only reports who holds the axis; end the claiming process
    /// (Ctrl-C) to release.
    Release {
        /// Axes to release.
        #[arg(required = true)]
        axes: Vec<String>,
    },
    /// Live plot of position and velocity of the named axes; q or Ctrl-C exits.
    Scope {
        /// Axes to plot.
        #[arg(required = true)]
        axes: Vec<String>,
        /// Time window shown.
        #[arg(long, default_value = "10s", value_parser = parse_duration)]
        window: Duration,
    },
    /// Measure end-to-end latency against the running server, each figure beside a baseline
    /// measured in the same run (plain iceoryx2, a bare clock_nanosleep loop), with the
    /// ratio: the `cargo bench --bench latency` suite (docs/PERFORMANCE.md). Takes about
    /// 9 × DURATION, 11 × with the Python client's rows (when a venv with the `motiond`
    /// package is found or given with --python).
    Bench(motion_bench::BenchArgs),
    /// Check this machine for real-time operation: kernel, cores, interrupts, limits,
    /// devices, shared memory, and a wake-up measurement; each check passes, warns or fails
    /// with the value found and the fix. Exits 1 when any check fails.
    Doctor(crate::doctor::DoctorArgs),
    /// The server's black box (flight recorder): `save [FILE.mcap]`.
    Blackbox {
        /// What to do.
        #[command(subcommand)]
        command: BlackboxCommand,
    },
    /// Record every frame, one row or message per tick, for a duration: to CSV (the axes,
    /// all when none is named, and every signal), to MCAP (ROS 2 JointState and JSON
    /// channels, for Foxglove and PlotJuggler), and/or to an SVG plot of desired and
    /// measured position and velocity per axis. Every output holds the same ticks.
    Record {
        /// How long to record (server time).
        #[arg(long, value_parser = parse_duration)]
        duration: Duration,
        /// The file to write, its format from the extension (`.csv`, `.mcap`); repeat it
        /// to write the same ticks to several files.
        #[arg(long, value_name = "FILE")]
        out: Vec<PathBuf>,
        /// The format of every --out file, whatever its extension.
        #[arg(long, value_enum)]
        format: Option<crate::record_output::RecordFormat>,
        /// Also plot desired and measured position and velocity per axis into this SVG.
        #[arg(long, value_name = "FILE.svg")]
        plot: Option<PathBuf>,
        /// Axes to record (default: all).
        axes: Vec<String>,
    },
}

/// `motionctl blackbox …`.
#[derive(Debug, Subcommand)]
pub enum BlackboxCommand {
    /// Save the server's black box now (the last [server] blackbox_seconds of its link
    /// bytes, commands and frames) and say where the file is; with FILE, copy it there.
    /// Replay it with `motiond --replay FILE`.
    Save {
        /// Where to copy the file (default: only the server's own copy, in its blackbox_dir).
        out: Option<PathBuf>,
    },
}

/// `motionctl io …`.
#[derive(Debug, Subcommand)]
pub enum IoCommand {
    /// Every signal: name, device, pin, kind, unit, value, flags.
    List {
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// One signal's value and flags.
    Get {
        /// Signal name.
        name: String,
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// Set a digital output on or off.
    Set {
        /// Signal name.
        name: String,
        /// `on` or `off` (also 1/0, true/false, high/low).
        #[arg(value_parser = parse_on_off, action = clap::ArgAction::Set, value_name = "on|off")]
        value: bool,
    },
    /// Set a trigger's compare position (kind "trigger"), in its unit (the axis's by
    /// default): the board pulses its output when the count matches it.
    Compare {
        /// Signal name.
        name: String,
        /// The compare position.
        #[arg(allow_negative_numbers = true)]
        position: f64,
    },
    /// Print every capture or trigger pulse of a signal as it comes (its value, sequence,
    /// tick and how many were missed) until Ctrl-C, --count events or --timeout.
    Events {
        /// Signal name (kind "capture" or "trigger").
        name: String,
        /// Stop after this many events.
        #[arg(long)]
        count: Option<u32>,
        /// Give up (exit 5) when no event came for this long.
        #[arg(long, value_parser = parse_duration)]
        timeout: Option<Duration>,
        /// One JSON object per event.
        #[arg(long)]
        json: bool,
    },
    /// Live table of every signal; q or Ctrl-C exits.
    Watch {
        /// Print one JSON object per --interval instead of a table.
        #[arg(long)]
        json: bool,
        /// Refresh interval.
        #[arg(long, default_value = "100ms", value_parser = parse_duration)]
        interval: Duration,
    },
}

/// `motionctl group …`.
#[derive(Debug, Subcommand)]
pub enum GroupCommand {
    /// Every group: its axes in order, their path and goal tolerances, the goal time.
    List {
        /// Print JSON.
        #[arg(long)]
        json: bool,
    },
    /// Move every axis of a group along one synchronized line (they start and arrive
    /// together): `group move gantry x=200 feeder=100 lift=150`.
    Move {
        /// Group name.
        group: String,
        /// AXIS=POSITION for every axis of the group, each once.
        #[arg(required = true, value_parser = parse_target, value_name = "AXIS=POS")]
        targets: Vec<(String, f64)>,
        /// Fraction (0, 1] of every axis's max velocity.
        #[arg(long, value_name = "F")]
        velocity_scale: Option<f64>,
        /// Fraction (0, 1] of every axis's max acceleration.
        #[arg(long, value_name = "F")]
        accel_scale: Option<f64>,
        /// Wait until the devices are ready, then until the motion ends (exit 5 when it is
        /// aborted); prints per axis when it arrived and its largest path error.
        #[arg(long)]
        wait: bool,
        /// Print JSON (with --wait: one object with the outcome).
        #[arg(long)]
        json: bool,
        /// Longest wait with --wait (readiness included).
        #[arg(long, default_value = "120s", value_parser = parse_duration)]
        timeout: Duration,
    },
    /// Follow a trajectory from a CSV file: header `time,<axis>,…` (optional `<axis>:vel`,
    /// `<axis>:acc` columns), one row per point, time in seconds from the start.
    Follow {
        /// Group name.
        group: String,
        /// The CSV file.
        file: PathBuf,
        /// Wait until the devices are ready, then until the motion ends (exit 5 when it is
        /// aborted); prints per axis when it arrived and its largest path error.
        #[arg(long)]
        wait: bool,
        /// Print JSON (with --wait: one object with the outcome).
        #[arg(long)]
        json: bool,
        /// Longest wait with --wait (readiness included).
        #[arg(long, default_value = "600s", value_parser = parse_duration)]
        timeout: Duration,
    },
    /// Feed hold: bring the group to rest along its path (`resume` continues).
    Hold {
        /// Group name.
        group: String,
    },
    /// Continue a held path.
    Resume {
        /// Group name.
        group: String,
    },
    /// Bring the group to rest along its path and end its motion.
    Cancel {
        /// Group name.
        group: String,
    },
    /// Stop every axis of the group (ends its motion).
    Stop {
        /// Group name.
        group: String,
    },
    /// Set the feed override: `50%` or `0.5`, 0–150 %.
    Feed {
        /// Group name.
        group: String,
        /// The feed: a percentage (`80%`) or a fraction (`0.8`), 0–150 %.
        #[arg(value_parser = parse_feed, value_name = "FEED")]
        feed: f64,
    },
    /// Claim every axis of the group (all or none) until Ctrl-C (or --duration), then
    /// release them.
    Claim {
        /// Group name.
        group: String,
        /// Release after this long instead of waiting for Ctrl-C.
        #[arg(long, value_parser = parse_duration)]
        duration: Option<Duration>,
    },
}

/// An address in decimal or `0x` hex.
pub fn parse_address(text: &str) -> Result<u32, String> {
    let text = text.trim();
    let parsed = match text.strip_prefix("0x").or_else(|| text.strip_prefix("0X")) {
        Some(hex) => u32::from_str_radix(hex, 16),
        None => text.parse(),
    };
    parsed.map_err(|_| format!("`{text}` is not an address (decimal, or hex as 0x92)"))
}

/// `AXIS=POSITION`.
pub fn parse_target(text: &str) -> Result<(String, f64), String> {
    let (axis, position) = text
        .split_once('=')
        .ok_or_else(|| format!("`{text}` is not AXIS=POSITION"))?;
    let axis = axis.trim();
    if axis.is_empty() {
        return Err(format!("`{text}` names no axis"));
    }
    let position: f64 = position
        .trim()
        .parse()
        .map_err(|_| format!("`{position}` is not a position (in `{text}`)"))?;
    if !position.is_finite() {
        return Err(format!("`{text}`: the position is not finite"));
    }
    Ok((axis.to_owned(), position))
}

/// A feed: `50%` (a percentage) or `0.5` (a fraction), 0–150 %.
pub fn parse_feed(text: &str) -> Result<f64, String> {
    let text = text.trim();
    let (number, percent) = match text.strip_suffix('%') {
        Some(number) => (number.trim(), true),
        None => (text, false),
    };
    let value: f64 = number
        .parse()
        .map_err(|_| format!("`{text}` is not a feed (write 80% or 0.8)"))?;
    let feed = if percent { value / 100.0 } else { value };
    if !feed.is_finite() || !(0.0..=1.5).contains(&feed) {
        let hint = if !percent && (1.5..=150.0).contains(&value) {
            format!(" (a fraction; for a percentage write {value}%)")
        } else {
            String::new()
        };
        return Err(format!("`{text}` is outside 0–150 %{hint}"));
    }
    Ok(feed)
}

/// `on`/`off` and their usual spellings.
pub fn parse_on_off(text: &str) -> Result<bool, String> {
    match text.trim().to_ascii_lowercase().as_str() {
        "on" | "1" | "true" | "high" => Ok(true),
        "off" | "0" | "false" | "low" => Ok(false),
        other => Err(format!("`{other}` is not on or off")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_parse_with_units() {
        assert_eq!(parse_duration("500ms"), Ok(Duration::from_millis(500)));
        assert_eq!(parse_duration("10s"), Ok(Duration::from_secs(10)));
        assert_eq!(parse_duration("1.5"), Ok(Duration::from_millis(1500)));
        assert_eq!(parse_duration("2m"), Ok(Duration::from_secs(120)));
        assert!(parse_duration("soon").is_err());
        assert!(parse_duration("5 parsecs").is_err());
    }

    #[test]
    fn command_line_is_consistent() {
        use clap::CommandFactory;
        Cli::command().debug_assert();
        let cli = Cli::try_parse_from(["motionctl", "jog", "x", "-2.5"]).map_err(|e| e.to_string());
        assert!(
            matches!(cli, Ok(Cli { command: Command::Jog { velocity, .. }, .. }) if velocity == -2.5)
        );
        let cli = Cli::try_parse_from(["motionctl", "move", "x", "-30", "--velocity", "5"]);
        assert!(
            matches!(cli, Ok(Cli { command: Command::Move { position, .. }, .. }) if position == -30.0),
            "{cli:?}"
        );
        let cli = Cli::try_parse_from(["motionctl", "io", "set", "lamp", "off"]);
        assert!(
            matches!(
                cli,
                Ok(Cli {
                    command: Command::Io {
                        command: IoCommand::Set { value: false, .. }
                    },
                    ..
                })
            ),
            "{cli:?}"
        );
        assert!(
            Cli::try_parse_from(["motionctl", "off"]).is_err(),
            "axes or --all"
        );
        assert!(Cli::try_parse_from(["motionctl", "off", "x", "--all"]).is_err());
        assert!(Cli::try_parse_from(["motionctl", "io", "set", "lamp", "maybe"]).is_err());
        let cli = Cli::try_parse_from([
            "motionctl",
            "group",
            "move",
            "gantry",
            "x=200",
            "feeder=-100",
            "lift=1.5e2",
            "--wait",
            "--velocity-scale",
            "0.5",
        ]);
        assert!(
            matches!(
                &cli,
                Ok(Cli {
                    command: Command::Group {
                        command: GroupCommand::Move { targets, wait: true, velocity_scale: Some(0.5), .. }
                    },
                    ..
                }) if targets == &[("x".to_owned(), 200.0), ("feeder".to_owned(), -100.0), ("lift".to_owned(), 150.0)]
            ),
            "{cli:?}"
        );
        assert!(Cli::try_parse_from(["motionctl", "group", "move", "gantry"]).is_err());
        assert!(Cli::try_parse_from(["motionctl", "group", "move", "gantry", "x:200"]).is_err());
        let cli = Cli::try_parse_from(["motionctl", "group", "feed", "arm", "50%"]);
        assert!(
            matches!(cli, Ok(Cli { command: Command::Group { command: GroupCommand::Feed { feed, .. } }, .. }) if feed == 0.5),
            "{cli:?}"
        );
        assert!(Cli::try_parse_from(["motionctl", "group", "feed", "arm", "151%"]).is_err());
    }

    #[test]
    fn feeds_parse_as_percentages_or_fractions() {
        assert_eq!(parse_feed("50%"), Ok(0.5));
        assert_eq!(parse_feed(" 150 % "), Ok(1.5));
        assert_eq!(parse_feed("0%"), Ok(0.0));
        assert_eq!(parse_feed("0.5"), Ok(0.5));
        assert_eq!(parse_feed("1.5"), Ok(1.5));
        assert_eq!(parse_feed("12.5%"), Ok(0.125));
        let error = parse_feed("50").unwrap_err();
        assert!(
            error.contains("outside 0–150 %") && error.contains("write 50%"),
            "{error}"
        );
        assert!(parse_feed("151%").unwrap_err().contains("outside"));
        assert!(parse_feed("-10%").is_err());
        assert!(parse_feed("1.6").is_err());
        assert!(parse_feed("NaN%").is_err());
        assert!(parse_feed("fast").unwrap_err().contains("not a feed"));
        assert!(parse_feed("%").is_err());
    }

    #[test]
    fn targets_parse_as_axis_equals_position() {
        assert_eq!(parse_target("x=200"), Ok(("x".to_owned(), 200.0)));
        assert_eq!(parse_target("lift = -1.5"), Ok(("lift".to_owned(), -1.5)));
        assert!(parse_target("x").unwrap_err().contains("AXIS=POSITION"));
        assert!(parse_target("=3").unwrap_err().contains("names no axis"));
        assert!(
            parse_target("x=far")
                .unwrap_err()
                .contains("not a position")
        );
        assert!(parse_target("x=inf").is_err());
    }
}
