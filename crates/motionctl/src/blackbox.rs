//! `motionctl blackbox save [FILE.mcap]`: asks the server to save its black box now (the
//! signal `motiond` takes for it, SIGUSR2, sent to the pid its description names), waits
//! for the file, copies it to FILE and says where both are.

use core::time::Duration;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context as _, bail};
use motion_client::Client;
use motion_client::ipc::ServerPidFile;
use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;

use crate::Service;

/// How long the server may take to write its ring (10 s of `config/sim.toml`: about 18 MiB).
const SAVE_TIMEOUT: Duration = Duration::from_secs(10);

/// The path the pointer file names, if any.
fn pointed(pointer: &Path) -> Option<PathBuf> {
    let text = std::fs::read_to_string(pointer).ok()?;
    let line = text.lines().next()?.trim();
    (!line.is_empty()).then(|| PathBuf::from(line))
}

/// Saves the black box of the server `client` talks to; copies it to `out` when given.
pub fn save(client: &Client<Service>, out: Option<&Path>) -> anyhow::Result<()> {
    if client.is_remote() {
        bail!("the black box is saved on the server's host: run motionctl there");
    }
    let info = client.info()?;
    let name = info.name().to_owned();
    let pid = i32::try_from(info.server_pid).context("the server's pid")?;
    let pointer = ServerPidFile::blackbox_pointer(&name);
    let before = pointed(&pointer);
    kill(Pid::from_raw(pid), Signal::SIGUSR2).with_context(|| {
        format!(
            "signal motiond \"{name}\" (pid {pid}, SIGUSR2): run motionctl as the server's \
             user or root"
        )
    })?;
    let end = Instant::now() + SAVE_TIMEOUT;
    let saved = loop {
        if let Some(path) = pointed(&pointer)
            && Some(&path) != before.as_ref()
            && path.to_string_lossy().ends_with("-sigusr2.mcap")
        {
            break path;
        }
        if Instant::now() >= end {
            bail!(
                "motiond \"{name}\" saved no black box within {SAVE_TIMEOUT:?} (its log says \
                 why; [server] blackbox_seconds = 0 turns the black box off)"
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    match out {
        Some(out) => {
            let bytes = std::fs::copy(&saved, out)
                .with_context(|| format!("copy {} to {}", saved.display(), out.display()))?;
            out!(
                "black box saved: {} ({bytes} bytes; the server's copy: {})",
                out.display(),
                saved.display()
            );
        }
        None => out!("black box saved: {}", saved.display()),
    }
    out!(
        "replay it: motiond --replay {}",
        out.unwrap_or(&saved).display()
    );
    Ok(())
}
