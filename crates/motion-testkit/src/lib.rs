//! The process-level harness of motiond's tests and of the reliability campaigns
//! (`crates/motion-reliability`): a motiond child process with its log ([`Server`]), a plain
//! iceoryx2 client of one instance ([`RawClient`]), and simulated boards served by a thread of
//! the calling process on a pseudo-terminal ([`pty_board::PtyBoard`], with line noise on
//! demand) or on an SPI socket ([`socket_board::SocketBoard`]), each logging every byte the
//! server sent.
//!
//! Set-up failures are typed ([`KitError`]) in the `try_` functions; the plain ones panic
//! with the same message, which is what a test wants.
#![deny(unsafe_code)] // two exceptions with SAFETY notes: counting_alloc (a GlobalAlloc), board_priority (libc)

pub mod board_priority;
pub mod client;
pub mod counting_alloc;
pub mod pty_board;
pub mod server;
pub mod socket_board;

use std::path::PathBuf;

pub use client::{RawClient, next_frame, open_frames};
pub use server::{Explicit, Server, ServerBinary};

/// Why the harness could not set something up.
#[derive(Debug, thiserror::Error)]
pub enum KitError {
    /// A file, pty, socket or process operation failed.
    #[error("{what}: {source}")]
    Io {
        /// What was being done.
        what: String,
        /// The OS error.
        source: std::io::Error,
    },
    /// A system call through nix failed.
    #[error("{what}: {source}")]
    Sys {
        /// What was being done.
        what: String,
        /// The errno.
        source: nix::errno::Errno,
    },
    /// An iceoryx2 operation failed (its error in words).
    #[error("iceoryx2: {0}")]
    Ipc(String),
    /// Nothing happened within the time allowed.
    #[error("timed out: {0}")]
    Timeout(String),
}

impl KitError {
    pub(crate) fn io(what: impl Into<String>) -> impl FnOnce(std::io::Error) -> Self {
        let what = what.into();
        move |source| Self::Io { what, source }
    }

    pub(crate) fn sys(what: impl Into<String>) -> impl FnOnce(nix::errno::Errno) -> Self {
        let what = what.into();
        move |source| Self::Sys { what, source }
    }
}

/// A unique instance name for one test.
pub fn unique_name(test: &str) -> String {
    format!("t{}-{test}", std::process::id())
}

/// This test process's scratch directory, `<tmp>/motiond-e2e-<pid>`: the configs it
/// writes, and the state directory of the servers it starts.
pub fn scratch_dir() -> PathBuf {
    std::env::temp_dir().join(format!("motiond-e2e-{}", std::process::id()))
}

/// Writes `text` to a temp config file `<tmp>/motiond-e2e-<pid>/<name>.toml`.
pub fn try_write_config(name: &str, text: &str) -> Result<PathBuf, KitError> {
    let dir = scratch_dir();
    std::fs::create_dir_all(&dir).map_err(KitError::io(format!("create {}", dir.display())))?;
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).map_err(KitError::io(format!("write {}", path.display())))?;
    Ok(path)
}

/// [`try_write_config`], panicking on failure.
pub fn write_config(name: &str, text: &str) -> PathBuf {
    try_write_config(name, text).unwrap_or_else(|e| panic!("write config: {e}"))
}
