//! A real `motiond` child on a copy of a config with a unique `[server] name`.

use core::time::Duration;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::Instant;

use motion_client::testing::unique_name;
use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;
use serde_json::Value;

use super::{DEADLINE, Result, finish, run};

/// A motiond child on a copy of a config with a unique `[server] name`.
pub struct RealServer {
    pub name: String,
    child: Option<Child>,
    dir: PathBuf,
    /// One server at a time in a test binary: each runs the whole simulated robot (18 axes,
    /// six boards, a tick thread and four I/O threads), and several at once on a 2-core
    /// machine starve each other's ticks until the boards look stale.
    _turn: std::sync::MutexGuard<'static, ()>,
}

static ONE_SERVER_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

pub fn motiond_binary() -> Result<PathBuf> {
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

pub fn sim_config() -> Result<String> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../config/sim.toml");
    Ok(std::fs::read_to_string(path)?)
}

/// The `name` values of the `[[table]]` tables of `config`, in order.
pub fn configured(config: &str, table: &str) -> Vec<String> {
    let header = format!("[[{table}]]");
    let mut names = Vec::new();
    let mut inside = false;
    for line in config.lines().map(str::trim) {
        if line.starts_with('[') {
            inside = line == header;
        } else if inside && let Some(value) = line.strip_prefix("name") {
            let value = value.trim_start().trim_start_matches('=').trim();
            if let Some(name) = value.split('"').nth(1) {
                names.push(name.to_owned());
                inside = false;
            }
        }
    }
    names
}

/// Axis names in config order, read from the `[[axis]]` tables of the sim config.
pub fn configured_axes(config: &str) -> Vec<String> {
    configured(config, "axis")
}

/// Whether every device of a `status --json` is online (it answered, was configured and
/// stopped) and every axis is fresh and unfaulted. A board's axes can be fresh before its
/// start-up is complete (seen on the simulated packs: `x` fresh at 0.75 s, `pack_xyz` online
/// at 1.25 s).
pub fn settled(status: &Value) -> bool {
    let online = status["devices"]
        .as_array()
        .is_some_and(|devices| devices.iter().all(|device| device["state"] == "online"));
    online
        && status["axes"].as_array().is_some_and(|axes| {
            axes.iter().all(|axis| {
                axis["flags"]
                    .as_array()
                    .is_some_and(|flags| !flags.iter().any(|f| f == "stale" || f == "fault"))
            })
        })
}

/// Whether the only faults of a `status --json` are tick overruns.
fn only_overruns(status: &Value) -> bool {
    let faults: Vec<&Value> = status["axes"]
        .as_array()
        .map(|axes| {
            axes.iter()
                .map(|axis| &axis["fault"])
                .filter(|f| !f.is_null())
                .collect()
        })
        .unwrap_or_default();
    !faults.is_empty() && faults.iter().all(|fault| *fault == "overrun")
}

impl RealServer {
    /// motiond on `config/sim.toml`, once every board answered.
    pub fn start() -> Result<Self> {
        Self::start_with(&sim_config()?)
    }

    /// motiond on `config` (its first `name = "demo"` line becomes a unique name), once
    /// every board answered.
    pub fn start_with(config: &str) -> Result<Self> {
        let mut server = Self::spawn(config)?;
        server.wait_settled()?;
        Ok(server)
    }

    /// motiond on `config/sim.toml`, returned as soon as the process runs (services may not
    /// exist yet, boards not answer yet).
    pub fn spawn_sim() -> Result<Self> {
        Self::spawn(&sim_config()?)
    }

    fn spawn(config: &str) -> Result<Self> {
        let turn = ONE_SERVER_AT_A_TIME
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
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
        std::fs::write(dir.join("sim.toml"), renamed)?;
        let mut server = Self {
            name,
            child: None,
            dir,
            _turn: turn,
        };
        server.child = Some(server.launch()?);
        Ok(server)
    }

    fn launch(&self) -> Result<Child> {
        Ok(Command::new(motiond_binary()?)
            .arg("--config")
            .arg(self.dir.join("sim.toml"))
            // Its state directory and black box in this server's directory (removed with
            // it), as systemd's StateDirectory= would give it: not the machine's.
            .env("STATE_DIRECTORY", self.dir.join("state"))
            .stdin(Stdio::null())
            .stdout(
                std::fs::File::options()
                    .create(true)
                    .append(true)
                    .open(self.dir.join("motiond.out"))?,
            )
            .stderr(
                std::fs::File::options()
                    .create(true)
                    .append(true)
                    .open(self.dir.join("motiond.err"))?,
            )
            .spawn()?)
    }

    /// The server's process id.
    pub fn pid(&self) -> Result<u32> {
        self.child
            .as_ref()
            .map(Child::id)
            .ok_or_else(|| "not running".into())
    }

    /// Waits until every board answered: no axis stale or faulted (the simulated packs take
    /// a second to boot, as real ones do).
    pub fn wait_settled(&mut self) -> Result {
        let until = Instant::now() + DEADLINE;
        loop {
            let Some(child) = self.child.as_mut() else {
                return Err("motiond is not running".into());
            };
            if let Some(status) = child.try_wait()? {
                return Err(format!("motiond exited ({status}):\n{}", self.log()).into());
            }
            let ready = run(
                &self.name,
                &["--connect-timeout", "500ms", "status", "--json"],
            )?;
            if ready.status.success() {
                let status: Value = serde_json::from_slice(&ready.stdout)?;
                if settled(&status) {
                    return Ok(());
                }
                if only_overruns(&status) {
                    // A loaded 2-core test machine can overrun the tick at start-up; that
                    // latches `overrun` faults which only a reset clears. Not what these
                    // tests are about.
                    run(&self.name, &["reset"])?;
                }
            }
            if Instant::now() > until {
                return Err(format!("motiond did not come up: {ready:?}\n{}", self.log()).into());
            }
        }
    }

    /// Kills the server with SIGKILL (no clean-up, as a crash) and starts a new one on the
    /// same config and name; returns once it settled.
    pub fn crash_and_restart(&mut self) -> Result {
        if let Some(mut child) = self.child.take() {
            child.kill()?;
            child.wait()?;
        }
        self.child = Some(self.launch()?);
        self.wait_settled()
    }

    pub fn log(&self) -> String {
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
