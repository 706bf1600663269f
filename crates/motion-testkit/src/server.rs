//! motiond as a child process, its stderr collected line by line.

use core::marker::PhantomData;
use core::time::Duration;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Instant;

use crate::KitError;

/// Where a [`Server`] type finds the motiond binary: a test crate names its own build
/// (`env!("CARGO_BIN_EXE_motiond")`), so that `Server::start(config)` needs nothing else.
pub trait ServerBinary {
    /// The motiond executable.
    fn path() -> PathBuf;
}

/// The binary is given to every [`Server::spawn`] call.
#[derive(Debug, Clone, Copy)]
pub struct Explicit;

/// A running motiond; killed (SIGKILL) on drop if still running.
#[derive(Debug)]
pub struct Server<B = Explicit> {
    /// The process.
    pub child: Child,
    /// Its stderr, one line at a time (a reader thread feeds it).
    pub stderr: mpsc::Receiver<String>,
    /// The lines collected so far by [`Server::wait_for_log`] and [`Server::drain_log`].
    pub log: Vec<String>,
    binary: PhantomData<B>,
}

impl<B: ServerBinary> Server<B> {
    /// Starts `motiond --config path` from `B`'s binary; panics when it cannot start.
    pub fn start(path: &Path) -> Self {
        Self::spawn_binary(&B::path(), path).unwrap_or_else(|e| panic!("start motiond: {e}"))
    }
}

impl Server<Explicit> {
    /// Starts `bin --config path` (in the caller's working directory, which decides the
    /// iceoryx2 config the server uses: `config/iceoryx2.toml` there, if any).
    pub fn spawn(bin: &Path, path: &Path) -> Result<Self, KitError> {
        Self::spawn_binary(bin, path)
    }
}

impl Server<Explicit> {
    /// Starts `command` (motiond, or a wrapper that ends in motiond: `runuser`, a fake
    /// service manager's environment) with stdin and stdout closed and stderr collected.
    pub fn spawn_command(command: Command) -> Result<Self, KitError> {
        Self::spawn_with(command)
    }
}

impl<B> Server<B> {
    fn spawn_binary(bin: &Path, path: &Path) -> Result<Self, KitError> {
        let mut command = Command::new(bin);
        command.arg("--config").arg(path);
        if std::env::var_os("STATE_DIRECTORY").is_none() {
            // The default state directory (and the black box's under it) of a server the
            // tests start, as systemd's `StateDirectory=` would give it: this run's scratch
            // directory, not the machine's /var/lib/motiond (each test's server has a name
            // of its own, and a server prunes only its own black box files).
            command.env("STATE_DIRECTORY", crate::scratch_dir().join("state"));
        }
        Self::spawn_with(command)
    }

    fn spawn_with(mut command: Command) -> Result<Self, KitError> {
        let program = command.get_program().to_string_lossy().into_owned();
        let mut child = command
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(KitError::io(format!("start {program}")))?;
        let stderr = child
            .stderr
            .take()
            .ok_or_else(|| KitError::Timeout("the child's stderr pipe is missing".to_owned()))?;
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        Ok(Self {
            child,
            stderr: rx,
            log: Vec::new(),
            binary: PhantomData,
        })
    }

    /// The process id.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Collects stderr lines until one contains `needle` or `timeout` passes.
    pub fn wait_for_log(&mut self, needle: &str, timeout: Duration) -> bool {
        let end = Instant::now() + timeout;
        if self.log.iter().any(|l| l.contains(needle)) {
            return true;
        }
        while let Some(left) = end.checked_duration_since(Instant::now()) {
            match self.stderr.recv_timeout(left) {
                Ok(line) => {
                    let hit = line.contains(needle);
                    self.log.push(line);
                    if hit {
                        return true;
                    }
                }
                Err(_) => return false,
            }
        }
        false
    }

    /// Sends `signal` and waits up to `timeout` for the exit status (`None`: still running,
    /// or killed by a signal).
    pub fn signal_and_wait(
        &mut self,
        signal: nix::sys::signal::Signal,
        timeout: Duration,
    ) -> Option<i32> {
        let pid = nix::unistd::Pid::from_raw(self.child.id() as i32);
        let _ = nix::sys::signal::kill(pid, signal);
        self.wait(timeout)
    }

    /// Waits up to `timeout` for the exit status (`None`: still running, or killed by a
    /// signal), then collects the log up to the end of the stderr pipe.
    pub fn wait(&mut self, timeout: Duration) -> Option<i32> {
        let end = Instant::now() + timeout;
        while Instant::now() < end {
            if let Ok(Some(status)) = self.child.try_wait() {
                // The reader thread ends at EOF (the channel disconnects then).
                while let Ok(line) = self.stderr.recv_timeout(Duration::from_millis(200)) {
                    self.log.push(line);
                }
                return status.code();
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        None
    }

    /// The log so far, one string.
    pub fn log_text(&mut self) -> String {
        self.drain_log();
        self.log.join("\n")
    }

    /// Whether the process still runs.
    pub fn is_running(&mut self) -> bool {
        matches!(self.child.try_wait(), Ok(None))
    }

    /// Moves every line received so far into `log`.
    pub fn drain_log(&mut self) {
        while let Ok(line) = self.stderr.try_recv() {
            self.log.push(line);
        }
    }
}

impl<B> Drop for Server<B> {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}
