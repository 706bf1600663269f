//! motionctl end to end against a real `motiond` running `config/sim.toml` under a unique
//! instance name (issue 6's CLI tests). Ignored by default until the server runs the sim
//! config; run them with
//! `cargo build -p motiond && cargo test -p motionctl --test real_server -- --ignored`.
//! The motiond binary is taken from `MOTIOND_BIN`, or from beside the motionctl binary
//! (where `cargo test --workspace` puts it).
//!
//! The tests on a server without devices run by default whenever a motiond binary is found:
//! they check the services, the info history, commands and one CSV row per tick against the
//! real server today.

mod common;

use core::time::Duration;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::Instant;

use common::*;
use motion_client::ipc::Reason;
use motion_client::testing::unique_name;
use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;
use serde_json::Value;

const IGNORED: &str = "needs a motiond that runs config/sim.toml";

/// A motiond child on a copy of `config/sim.toml` with a unique `[server] name`.
struct RealServer {
    name: String,
    child: Option<Child>,
    dir: PathBuf,
    /// One server at a time in this binary: each runs the whole simulated robot (18 axes,
    /// six boards, a tick thread and four I/O threads), and several at once on a 2-core
    /// machine starve each other's ticks until the boards look stale.
    _turn: std::sync::MutexGuard<'static, ()>,
}

static ONE_SERVER_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn motiond_binary() -> Result<PathBuf> {
    if let Some(path) = std::env::var_os("MOTIOND_BIN") {
        return Ok(path.into());
    }
    let beside = PathBuf::from(env!("CARGO_BIN_EXE_motionctl")).with_file_name("motiond");
    if beside.exists() {
        Ok(beside)
    } else {
        Err(format!(
            "no motiond at {}: run `cargo build -p motiond` or set MOTIOND_BIN",
            beside.display()
        )
        .into())
    }
}

fn sim_config() -> Result<String> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../config/sim.toml");
    Ok(std::fs::read_to_string(path)?)
}

/// Axis names in config order, read from the `[[axis]]` tables of the sim config.
fn configured_axes(config: &str) -> Vec<String> {
    let mut names = Vec::new();
    let mut in_axis = false;
    for line in config.lines().map(str::trim) {
        if line.starts_with('[') {
            in_axis = line == "[[axis]]";
        } else if in_axis && let Some(value) = line.strip_prefix("name") {
            let value = value.trim_start().trim_start_matches('=').trim();
            if let Some(name) = value.split('"').nth(1) {
                names.push(name.to_owned());
                in_axis = false;
            }
        }
    }
    names
}

impl RealServer {
    /// motiond on `config/sim.toml`.
    fn start() -> Result<Self> {
        Self::start_with(&sim_config()?)
    }

    /// motiond on `config` (its first `name = "demo"` line becomes a unique name).
    fn start_with(config: &str) -> Result<Self> {
        let turn = ONE_SERVER_AT_A_TIME
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let binary = motiond_binary()?;
        let name = unique_name("real");
        let mut renamed = String::new();
        let mut done = false;
        for line in config.lines() {
            if !done && line.trim_start().starts_with("name = \"demo\"") {
                renamed.push_str(&format!("name = \"{name}\"\n"));
                done = true;
            } else {
                renamed.push_str(line);
                renamed.push('\n');
            }
        }
        let dir = std::env::temp_dir().join(&name);
        std::fs::create_dir_all(&dir)?;
        let config_path = dir.join("sim.toml");
        std::fs::write(&config_path, renamed)?;
        let child = Command::new(binary)
            .arg("--config")
            .arg(&config_path)
            .stdin(Stdio::null())
            .stdout(std::fs::File::create(dir.join("motiond.out"))?)
            .stderr(std::fs::File::create(dir.join("motiond.err"))?)
            .spawn()?;
        let mut server = Self {
            name,
            child: Some(child),
            dir,
            _turn: turn,
        };
        let until = Instant::now() + DEADLINE;
        loop {
            if let Some(status) = server
                .child
                .as_mut()
                .map(Child::try_wait)
                .transpose()?
                .flatten()
            {
                return Err(format!("motiond exited ({status}):\n{}", server.log()).into());
            }
            // Ready = every board answered: no axis stale or faulted (the simulated packs
            // take a second to boot, as real ones do).
            let ready = run(
                &server.name,
                &["--connect-timeout", "500ms", "status", "--json"],
            )?;
            if ready.status.success() {
                let status: Value = serde_json::from_slice(&ready.stdout)?;
                let settled = status["axes"].as_array().is_some_and(|axes| {
                    axes.iter().all(|axis| {
                        axis["flags"].as_array().is_some_and(|flags| {
                            !flags.iter().any(|f| f == "stale" || f == "fault")
                        })
                    })
                });
                if settled {
                    return Ok(server);
                }
            }
            if Instant::now() > until {
                return Err(format!("motiond did not come up: {ready:?}\n{}", server.log()).into());
            }
        }
    }

    fn log(&self) -> String {
        let read = |file: &str| std::fs::read_to_string(self.dir.join(file)).unwrap_or_default();
        format!("{}{}", read("motiond.out"), read("motiond.err"))
    }
}

impl Drop for RealServer {
    fn drop(&mut self) {
        if let Some(child) = self.child.take() {
            if let Ok(pid) = i32::try_from(child.id()) {
                let _ = kill(Pid::from_raw(pid), Signal::SIGTERM);
            }
            if finish(child, Duration::from_secs(10)).is_err() {
                eprintln!("motiond did not stop on SIGTERM:\n{}", self.log());
            }
        }
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

fn axis_index(status: &Value, name: &str) -> Result<usize> {
    status["axes"]
        .as_array()
        .and_then(|axes| axes.iter().position(|axis| axis["name"] == name))
        .ok_or_else(|| format!("no axis {name} in {status}").into())
}

fn position(server: &str, axis: &str) -> Result<f64> {
    let status = status_json(server)?;
    let index = axis_index(&status, axis)?;
    axis_field(&status, index, "position")
        .as_f64()
        .ok_or_else(|| "position is not a number".into())
}

#[test]
fn real_list_json_shows_every_configured_axis() -> Result {
    let server = RealServer::start()?;
    let output = run(&server.name, &["list", "--json"])?;
    assert!(output.status.success(), "{output:?}");
    let list: Value = serde_json::from_slice(&output.stdout)?;
    let names: Vec<String> = list["axes"]
        .as_array()
        .ok_or("axes")?
        .iter()
        .filter_map(|axis| axis["name"].as_str().map(str::to_owned))
        .collect();
    assert_eq!(names, configured_axes(&sim_config()?), "{IGNORED}");
    Ok(())
}

#[test]
fn real_move_wait_ends_at_the_target() -> Result {
    let server = RealServer::start()?;
    let output = run(
        &server.name,
        &["move", "x", "10", "--wait", "--timeout", "30s"],
    )?;
    assert!(output.status.success(), "{output:?}\n{}", server.log());
    let status = status_json(&server.name)?;
    let x = axis_index(&status, "x")?;
    let reached = axis_field(&status, x, "position")
        .as_f64()
        .ok_or("position")?;
    assert!((reached - 10.0).abs() < 0.1, "x at {reached}");
    let flags = axis_field(&status, x, "flags");
    assert!(
        flags.as_array().ok_or("flags")?.contains(&"arrived".into()),
        "{flags}"
    );
    Ok(())
}

#[test]
fn real_out_of_limit_move_is_refused_and_nothing_moves() -> Result {
    let server = RealServer::start()?;
    let before = position(&server.name, "x")?;
    let output = run(&server.name, &["move", "x", "1000"])?;
    assert_eq!(output.status.code(), Some(4), "{output:?}");
    assert!(
        stderr(&output).contains(Reason::OutOfRange.message()),
        "{output:?}"
    );
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(position(&server.name, "x")?, before);
    Ok(())
}

#[test]
fn real_estop_refuses_moves_until_reset() -> Result {
    let server = RealServer::start()?;
    assert!(run(&server.name, &["estop"])?.status.success());
    let refused = run(&server.name, &["move", "y", "5"])?;
    assert_eq!(refused.status.code(), Some(4), "{refused:?}");
    assert!(stderr(&refused).contains(Reason::EstopLatched.message()));
    assert!(run(&server.name, &["reset"])?.status.success());
    let moved = run(
        &server.name,
        &["move", "y", "5", "--wait", "--timeout", "30s"],
    )?;
    assert!(moved.status.success(), "{moved:?}");
    Ok(())
}

#[test]
fn real_record_writes_one_row_per_tick() -> Result {
    let server = RealServer::start()?;
    let out = std::env::temp_dir().join(format!("{}.csv", unique_name("real-record")));
    let out_arg = out.to_str().ok_or("path")?;
    let output = run(
        &server.name,
        &["record", "--duration", "1s", "--out", out_arg],
    )?;
    assert!(output.status.success(), "{output:?}");
    let csv = std::fs::read_to_string(&out)?;
    std::fs::remove_file(&out)?;
    let ticks: Vec<u64> = csv
        .lines()
        .skip(1)
        .map(|line| line.split(',').next().unwrap_or("").parse())
        .collect::<core::result::Result<_, _>>()?;
    let first = *ticks.first().ok_or("no rows")?;
    assert!(
        ticks
            .iter()
            .all(|tick| (first..first + 1000).contains(tick)),
        "1 s at 1 kHz"
    );
    let missed = 1000 - ticks.len();
    assert!(
        missed == 0 || stderr(&output).contains(&format!("{missed} ticks were missed")),
        "{output:?}"
    );
    Ok(())
}

#[test]
fn real_claim_refuses_the_other_client() -> Result {
    let server = RealServer::start()?;
    let holder = command(&server.name, &["claim", "y", "--duration", "20s"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()?;
    let until = Instant::now() + DEADLINE;
    loop {
        let status = status_json(&server.name)?;
        let flags = axis_field(&status, axis_index(&status, "y")?, "flags");
        if flags
            .as_array()
            .is_some_and(|f| f.contains(&"claimed".into()))
        {
            break;
        }
        assert!(Instant::now() < until, "never claimed");
        std::thread::sleep(Duration::from_millis(50));
    }
    let refused = run(&server.name, &["move", "y", "1"])?;
    assert_eq!(refused.status.code(), Some(4), "{refused:?}");
    assert!(stderr(&refused).contains(Reason::ClaimedByOther.message()));
    kill(Pid::from_raw(i32::try_from(holder.id())?), Signal::SIGINT)?;
    assert!(finish(holder, DEADLINE)?.status.success());
    Ok(())
}

/// Polls until `axis` no longer moves; returns how long that took.
fn wait_stopped(server: &str, axis: &str, within: Duration) -> Result<Duration> {
    let started = Instant::now();
    loop {
        let status = status_json(server)?;
        let index = axis_index(&status, axis)?;
        let mode = axis_field(&status, index, "mode");
        if mode != "ramp-velocity" && mode != "velocity" {
            return Ok(started.elapsed());
        }
        if started.elapsed() > within {
            return Err(format!("{axis} still jogging after {within:?}: {status}").into());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn real_jog_stops_on_ctrl_c_and_when_the_client_is_killed() -> Result {
    let server = RealServer::start()?;
    for signal in [Signal::SIGINT, Signal::SIGKILL] {
        let child = command(&server.name, &["jog", "conveyor", "50"])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()?;
        // Longer than the 250 ms deadman: the guard renews it.
        std::thread::sleep(Duration::from_millis(800));
        let status = status_json(&server.name)?;
        let conveyor = axis_index(&status, "conveyor")?;
        assert_eq!(
            axis_field(&status, conveyor, "mode"),
            "ramp-velocity",
            "{status}"
        );
        kill(Pid::from_raw(i32::try_from(child.id())?), signal)?;
        let output = finish(child, DEADLINE)?;
        if signal == Signal::SIGINT {
            assert!(output.status.success(), "{output:?}");
        }
        // Deadman (250 ms) plus the server's liveness check bound a killed client's jog.
        wait_stopped(&server.name, "conveyor", Duration::from_secs(3))?;
    }
    Ok(())
}

/// The smallest server motiond accepts (a config needs a board and an axis or a signal):
/// one simulated SPI_motor stepper, axis `a`.
const EMPTY_CONFIG: &str = "[server]\nname = \"demo\"\ntick_hz = 1000\ncommand_timeout_ms = 250\n\n[[link]]\nname = \"spi\"\ntype = \"sim\"\n\n[[device]]\nname = \"m\"\nlink = \"spi\"\nmodel = \"spimotor\"\n\n[[axis]]\nname = \"a\"\ndevice = \"m\"\nchannel = 0\nunit = \"step\"\ncounts_per_unit = 1.0\nmin = -100.0\nmax = 100.0\nmax_velocity = 100.0\nmax_accel = 1000.0\n";

/// `Some(server)` when a motiond binary exists; `None` (with a note) when this run did not
/// build one (`cargo test -p motionctl` alone; `cargo test --workspace` builds it).
fn empty_server() -> Result<Option<RealServer>> {
    if motiond_binary().is_err() {
        eprintln!("skipped: no motiond binary (build it, or run cargo test --workspace)");
        return Ok(None);
    }
    RealServer::start_with(EMPTY_CONFIG).map(Some)
}

#[test]
fn real_server_without_devices_answers_list_status_and_commands() -> Result {
    let Some(server) = empty_server()? else {
        return Ok(());
    };
    let output = run(&server.name, &["list", "--json"])?;
    assert!(output.status.success(), "{output:?}");
    let list: Value = serde_json::from_slice(&output.stdout)?;
    assert_eq!(list["server"], server.name.as_str());
    assert_eq!(list["tick_hz"], 1000);
    assert_eq!(list["axes"].as_array().map(Vec::len), Some(1));
    let status = status_json(&server.name)?;
    assert!(status["tick"].as_u64().ok_or("tick")? > 0, "{status}");
    assert!(run(&server.name, &["estop"])?.status.success());
    assert_eq!(status_json(&server.name)?["estop"], true);
    assert!(run(&server.name, &["reset"])?.status.success());
    assert_eq!(status_json(&server.name)?["estop"], false);
    let unknown = run(&server.name, &["move", "x", "1"])?;
    assert_eq!(unknown.status.code(), Some(4), "{unknown:?}");
    Ok(())
}

#[test]
fn real_server_without_devices_records_one_row_per_tick() -> Result {
    let Some(server) = empty_server()? else {
        return Ok(());
    };
    let out = std::env::temp_dir().join(format!("{}.csv", unique_name("real-empty")));
    let out_arg = out.to_str().ok_or("path")?;
    let output = run(
        &server.name,
        &["record", "--duration", "500ms", "--out", out_arg],
    )?;
    assert!(output.status.success(), "{output:?}");
    let csv = std::fs::read_to_string(&out)?;
    std::fs::remove_file(&out)?;
    let ticks: Vec<u64> = csv
        .lines()
        .skip(1)
        .map(|line| line.split(',').next().unwrap_or("").parse())
        .collect::<core::result::Result<_, _>>()?;
    let first = *ticks.first().ok_or("no rows")?;
    assert!(
        ticks.iter().all(|tick| (first..first + 500).contains(tick)),
        "{ticks:?}"
    );
    assert!(ticks.windows(2).all(|pair| pair[1] > pair[0]));
    // Ticks the client was too slow for (the server keeps 2 frames) are reported, not faked.
    let missed = 500 - ticks.len();
    assert!(
        missed == 0 || stderr(&output).contains(&format!("{missed} ticks were missed")),
        "{output:?}"
    );
    Ok(())
}
