//! The real thing: a motiond child on the simulated robot (`config/sim.toml` under a unique
//! name), a `motion-bridge` child in front of it, and `motionctl --remote` runs — on this
//! host over loopback, or across two network namespaces joined by a veth pair.

use core::time::Duration;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::Instant;

use motion_client::testing::unique_name;
use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;
use serde_json::Value;

use crate::{DEADLINE, Result, free_port, scratch};

/// The bridge's rules in these tests: `operator` may do anything, `viewer` only stop and
/// e-stop.
pub const RULES: &str = r#"
[[remote]]
identity = "operator"
allow = ["all"]

[[remote]]
identity = "viewer"
allow = ["stop", "estop"]
"#;

/// The processes these tests run, from this build of the workspace.
#[derive(Debug, Clone)]
pub struct Binaries {
    pub motiond: PathBuf,
    pub motionctl: PathBuf,
    pub bridge: PathBuf,
}

/// A binary of the workspace: `$env` if set, else in the directory cargo builds the
/// workspace's binaries into (the parent of this test's `deps/`). `cargo test --workspace`
/// builds a member's binaries there because the member has integration tests of its own
/// (motion-bridge's `tests/binary.rs` is there for that too).
pub fn binary(name: &str, env: &str) -> Option<PathBuf> {
    if let Some(path) = std::env::var_os(env) {
        return Some(path.into());
    }
    let exe = std::env::current_exe().ok()?;
    let path = exe.parent()?.parent()?.join(name);
    path.exists().then_some(path)
}

/// motiond, motionctl and motion-bridge, or `None` with a note on stderr when this run did
/// not build them (`cargo test -p motion-bridge-tests` alone; `./scripts/test` builds them).
pub fn binaries() -> Option<Binaries> {
    match (
        binary("motiond", "MOTIOND_BIN"),
        binary("motionctl", "MOTIONCTL_BIN"),
        binary("motion-bridge", "MOTION_BRIDGE_BIN"),
    ) {
        (Some(motiond), Some(motionctl), Some(bridge)) => Some(Binaries {
            motiond,
            motionctl,
            bridge,
        }),
        _ => {
            eprintln!(
                "SKIPPED: no motiond, motionctl or motion-bridge beside this test: run `cargo \
                 build -p motiond -p motionctl -p motion-bridge` first (./scripts/test builds \
                 them), or set MOTIOND_BIN, MOTIONCTL_BIN and MOTION_BRIDGE_BIN"
            );
            None
        }
    }
}

/// Waits for `child` up to `within`, killing it if it does not end; its output.
pub fn finish(mut child: Child, within: Duration) -> Result<Output> {
    // The output is read while the child runs: one that writes more than a pipe holds
    // (`list --json` of the simulated robot is above 64 KiB) would block on its write.
    fn drain(mut pipe: impl std::io::Read + Send + 'static) -> std::thread::JoinHandle<Vec<u8>> {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            let _ = pipe.read_to_end(&mut bytes);
            bytes
        })
    }
    let out = child.stdout.take().map(drain);
    let err = child.stderr.take().map(drain);
    let join = |reader: Option<std::thread::JoinHandle<Vec<u8>>>| {
        reader.and_then(|r| r.join().ok()).unwrap_or_default()
    };
    let until = Instant::now() + within;
    let status = loop {
        if let Some(status) = child.try_wait()? {
            break status;
        }
        if Instant::now() > until {
            let _ = child.kill();
            let status = child.wait()?;
            let output = Output {
                status,
                stdout: join(out),
                stderr: join(err),
            };
            return Err(format!("did not end within {within:?}: {output:?}").into());
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    Ok(Output {
        status,
        stdout: join(out),
        stderr: join(err),
    })
}

/// Two network namespaces joined by a veth pair: `server` (10.250.K.1) for motiond and
/// the bridge, `remote` (10.250.K.2) for the remote client. Deleted when dropped.
#[derive(Debug)]
pub struct Netns {
    pub server: String,
    pub remote: String,
    pub server_addr: String,
    remote_link: String,
}

fn ip(args: &[&str]) -> Result {
    let output = Command::new("ip").args(args).output()?;
    if output.status.success() {
        Ok(())
    } else {
        Err(format!(
            "ip {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&output.stderr).trim()
        )
        .into())
    }
}

impl Netns {
    /// Creates the pair; `Err` says why it could not be made here.
    pub fn create() -> Result<Self> {
        let tag = std::process::id() % 100_000;
        let subnet = std::process::id() % 250;
        let this = Self {
            server: format!("mb{tag}s"),
            remote: format!("mb{tag}r"),
            server_addr: format!("10.250.{subnet}.1"),
            remote_link: format!("mb{tag}r0"),
        };
        let server_link = format!("mb{tag}s0");
        ip(&["netns", "add", &this.server])?;
        ip(&["netns", "add", &this.remote])?;
        ip(&[
            "link",
            "add",
            &server_link,
            "type",
            "veth",
            "peer",
            "name",
            &this.remote_link,
        ])?;
        ip(&["link", "set", &server_link, "netns", &this.server])?;
        ip(&["link", "set", &this.remote_link, "netns", &this.remote])?;
        let remote_addr = format!("10.250.{subnet}.2/30");
        let server_cidr = format!("{}/30", this.server_addr);
        ip(&[
            "-n",
            &this.server,
            "addr",
            "add",
            &server_cidr,
            "dev",
            &server_link,
        ])?;
        ip(&[
            "-n",
            &this.remote,
            "addr",
            "add",
            &remote_addr,
            "dev",
            &this.remote_link,
        ])?;
        for (ns, link) in [
            (&this.server, &server_link),
            (&this.remote, &this.remote_link),
        ] {
            ip(&["-n", ns, "link", "set", "lo", "up"])?;
            ip(&["-n", ns, "link", "set", link, "up"])?;
        }
        Ok(this)
    }

    /// Takes the remote's end of the link down (`up = false`) or up again: the network
    /// drops without either side closing anything.
    pub fn set_remote_link(&self, up: bool) -> Result {
        ip(&[
            "-n",
            &self.remote,
            "link",
            "set",
            &self.remote_link,
            if up { "up" } else { "down" },
        ])
    }
}

impl Drop for Netns {
    fn drop(&mut self) {
        let _ = ip(&["netns", "del", &self.remote]);
        let _ = ip(&["netns", "del", &self.server]);
    }
}

/// `program args` as a command, run inside `netns` when given.
fn in_ns(netns: Option<&str>, program: &Path, args: &[&str]) -> Command {
    match netns {
        Some(ns) => {
            let mut command = Command::new("ip");
            command.args(["netns", "exec", ns]).arg(program).args(args);
            command
        }
        None => {
            let mut command = Command::new(program);
            command.args(args);
            command
        }
    }
}

/// One rig at a time in a test binary: each runs the whole simulated robot, and two at once
/// on a 2-core machine starve each other's ticks.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// motiond and a bridge in front of it, and how a remote reaches them.
#[derive(Debug)]
pub struct Rig {
    pub name: String,
    pub endpoint: String,
    motionctl: PathBuf,
    dir: PathBuf,
    remote_ns: Option<String>,
    motiond: Option<Child>,
    bridge: Option<Child>,
    _turn: std::sync::MutexGuard<'static, ()>,
}

impl Rig {
    /// Starts motiond on the simulated robot and a bridge with [`RULES`]: both in
    /// `netns.server` when given (the remote then reaches the bridge across the veth pair),
    /// else on this host, listening on loopback.
    pub fn start(binaries: &Binaries, netns: Option<&Netns>) -> Result<Self> {
        Self::start_with(binaries, netns, RULES, "operator")
    }

    /// [`Rig::start`] with the bridge's `rules` (a `bridge.toml`); `identity` is one the
    /// rules let read and list (the rig waits until it can).
    pub fn start_with(
        binaries: &Binaries,
        netns: Option<&Netns>,
        rules: &str,
        identity: &str,
    ) -> Result<Self> {
        let turn = ONE_AT_A_TIME
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let name = unique_name("bridge");
        let dir = scratch("bridge-rig")?;
        let sim = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../config/sim.toml"
        ))?;
        let config = sim.replacen("name = \"demo\"", &format!("name = \"{name}\""), 1);
        std::fs::write(dir.join("sim.toml"), config)?;
        std::fs::write(dir.join("bridge.toml"), rules)?;
        let server_ns = netns.map(|ns| ns.server.as_str());
        let logs = dir.clone();
        let log = move |file: &str| -> Result<Stdio> {
            Ok(Stdio::from(std::fs::File::create(logs.join(file))?))
        };
        let sim_path = dir.join("sim.toml").display().to_string();
        let motiond_child = in_ns(server_ns, &binaries.motiond, &["--config", &sim_path])
            .stdin(Stdio::null())
            .stdout(log("motiond.out")?)
            .stderr(log("motiond.err")?)
            .spawn()?;
        let address = netns.map_or("127.0.0.1".to_owned(), |ns| ns.server_addr.clone());
        let port = free_port()?;
        let endpoint = format!("tcp/{address}:{port}");
        let mut rig = Self {
            name,
            endpoint,
            motionctl: binaries.motionctl.clone(),
            dir,
            remote_ns: netns.map(|ns| ns.remote.clone()),
            motiond: Some(motiond_child),
            bridge: None,
            _turn: turn,
        };
        rig.wait_settled()?;
        let bridge_config = rig.dir.join("bridge.toml").display().to_string();
        let listen = rig.endpoint.clone();
        let bridge = in_ns(
            server_ns,
            &binaries.bridge,
            &[
                "--server",
                &rig.name,
                "--listen",
                &listen,
                "--config",
                &bridge_config,
                // The test's rules let `operator` do anything, without zenoh users.
                "--insecure",
            ],
        )
        .stdin(Stdio::null())
        .stdout(log("bridge.out")?)
        .stderr(log("bridge.err")?)
        .spawn()?;
        rig.bridge = Some(bridge);
        let until = Instant::now() + DEADLINE;
        loop {
            let output = rig.remote(identity, &["list", "--json"])?;
            if output.status.success() {
                break;
            }
            if Instant::now() > until {
                return Err(
                    format!("the bridge never answered: {output:?}\n{}", rig.logs()).into(),
                );
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        Ok(rig)
    }

    /// `motionctl` on this host, through shared memory: what the server itself says.
    pub fn local(&self, args: &[&str]) -> Result<Output> {
        let child = Command::new(&self.motionctl)
            .arg("--server")
            .arg(&self.name)
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()?;
        finish(child, DEADLINE)
    }

    /// `motionctl --remote` as `identity`, in the remote namespace when there is one.
    pub fn remote_command(&self, identity: &str, args: &[&str]) -> Command {
        let mut all = vec![
            "--server",
            self.name.as_str(),
            "--remote",
            self.endpoint.as_str(),
            "--identity",
            identity,
            "--connect-timeout",
            "5s",
        ];
        all.extend_from_slice(args);
        let mut command = in_ns(self.remote_ns.as_deref(), &self.motionctl, &all);
        command
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        command
    }

    /// Runs [`Rig::remote_command`] to its end.
    pub fn remote(&self, identity: &str, args: &[&str]) -> Result<Output> {
        finish(self.remote_command(identity, args).spawn()?, DEADLINE)
    }

    /// `status --json` of the server, read locally.
    pub fn status(&self) -> Result<Value> {
        let output = self.local(&["status", "--json"])?;
        if !output.status.success() {
            return Err(format!("status failed: {output:?}").into());
        }
        Ok(serde_json::from_slice(&output.stdout)?)
    }

    /// The state of axis `name` in a `status --json`.
    pub fn axis(status: &Value, name: &str) -> Result<Value> {
        status["axes"]
            .as_array()
            .and_then(|axes| axes.iter().find(|axis| axis["name"] == name))
            .cloned()
            .ok_or_else(|| format!("no axis {name} in {status}").into())
    }

    fn wait_settled(&mut self) -> Result {
        let until = Instant::now() + DEADLINE;
        loop {
            if let Some(child) = self.motiond.as_mut()
                && let Some(status) = child.try_wait()?
            {
                return Err(format!("motiond exited ({status}):\n{}", self.logs()).into());
            }
            if let Ok(status) = self.status() {
                let axes = status["axes"].as_array().cloned().unwrap_or_default();
                let flagged = |flag: &str| {
                    axes.iter().any(|axis| {
                        axis["flags"]
                            .as_array()
                            .is_some_and(|flags| flags.iter().any(|f| f == flag))
                    })
                };
                if !axes.is_empty() && !flagged("stale") && !flagged("fault") {
                    return Ok(());
                }
                if !axes.is_empty() && !flagged("stale") {
                    // A loaded test machine can overrun ticks at start-up, which latches
                    // `overrun` faults only a reset clears: not what these tests are about.
                    let only_overruns = axes
                        .iter()
                        .all(|axis| axis["fault"].is_null() || axis["fault"] == "overrun");
                    if only_overruns {
                        self.local(&["reset"])?;
                    }
                }
            }
            if Instant::now() > until {
                return Err(format!("motiond did not settle:\n{}", self.logs()).into());
            }
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// Everything motiond and the bridge wrote.
    pub fn logs(&self) -> String {
        ["motiond.out", "motiond.err", "bridge.out", "bridge.err"]
            .iter()
            .map(|file| {
                format!(
                    "--- {file}\n{}",
                    std::fs::read_to_string(self.dir.join(file)).unwrap_or_default()
                )
            })
            .collect::<Vec<_>>()
            .join("\n")
    }
}

fn stop(child: Option<Child>, what: &str) {
    if let Some(child) = child {
        if let Ok(pid) = i32::try_from(child.id()) {
            let _ = kill(Pid::from_raw(pid), Signal::SIGTERM);
        }
        if let Err(error) = finish(child, Duration::from_secs(10)) {
            eprintln!("{what} did not stop on SIGTERM: {error}");
        }
    }
}

impl Drop for Rig {
    fn drop(&mut self) {
        stop(self.bridge.take(), "motion-bridge");
        stop(self.motiond.take(), "motiond");
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}
