//! The server's pid file: which process a client may signal (SIGUSR1, the e-stop of last
//! resort) without trusting anything another process chooses freely, such as an iceoryx2
//! node name.
//!
//! `motiond` writes `<iceoryx2 root>/motiond-<name>.pid` once its services exist (so it is
//! the one process serving `<name>`) and removes it on a clean exit. The file holds three
//! lines:
//!
//! ```text
//! pid 4242
//! start 1234567
//! node 1234567890123456789
//! ```
//!
//! `start` is the process's start time in clock ticks since boot (field 22 of
//! `/proc/<pid>/stat`), so that a pid recycled after a crash is never taken for the server;
//! `node` is the server's iceoryx2 node id, which a client can check among the live nodes.
//!
//! [`ServerPidFile::read_verified`] trusts the file only when it is a regular file (not a
//! symbolic link) that neither its group nor others may write, in a directory that others
//! may not write (or that has the sticky bit), owned by the same user as the process it
//! names, and that process is alive with the recorded start time. iceoryx2 creates its root
//! directory writable by its owner alone, so another user cannot plant a pid file there.
//!
//! This module reads `/proc` and writes one file: it is used by the server's main thread
//! and by clients, never on a real-time path.

use std::fs::{self, OpenOptions};
use std::io::Write as _;
use std::os::unix::fs::{MetadataExt as _, OpenOptionsExt as _, PermissionsExt as _};
use std::path::{Path, PathBuf};

use iceoryx2::prelude::Config;

/// Why the pid file could not be written or was not trusted.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PidFileError {
    /// There is no pid file: no server of that name runs (or it has not finished starting).
    #[error("no pid file {path}: no motiond of that name has started")]
    Missing {
        /// The file's path.
        path: String,
    },
    /// The file could not be read, written, renamed or inspected.
    #[error("{what} {path}: {detail}")]
    Io {
        /// What was being done.
        what: &'static str,
        /// The file's path.
        path: String,
        /// The system's error.
        detail: String,
    },
    /// The file or its directory is not one only the server's user could have written.
    #[error("pid file {path} is not trusted: {why}")]
    Untrusted {
        /// The file's path.
        path: String,
        /// Which check failed.
        why: String,
    },
    /// The file's content is not `pid …`, `start …`, `node …`.
    #[error("pid file {path} is malformed: {why}")]
    Malformed {
        /// The file's path.
        path: String,
        /// What is wrong.
        why: String,
    },
    /// The process the file names is gone or is another process now (a recycled pid).
    #[error("pid file {path} names process {pid}, which {why}")]
    Stale {
        /// The file's path.
        path: String,
        /// The process id in the file.
        pid: u32,
        /// What was found instead.
        why: String,
    },
}

/// What a trusted pid file says of the running server.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ServerProcess {
    /// The server's process id.
    pub pid: u32,
    /// Its start time in clock ticks since boot (`/proc/<pid>/stat` field 22).
    pub start_ticks: u64,
    /// Its iceoryx2 node id.
    pub node: u128,
    /// The user owning both the file and the process.
    pub uid: u32,
}

/// The pid file of the instance `name`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ServerPidFile {
    path: PathBuf,
}

impl ServerPidFile {
    /// The pid file of instance `name` under iceoryx2's root directory (the global config's
    /// `root-path`, `/tmp/iceoryx2/` by default).
    pub fn of(name: &str) -> Self {
        let root = Config::global_config()
            .global
            .root_path()
            .as_str()
            .to_owned();
        Self::in_dir(Path::new(&root), name)
    }

    /// The file naming instance `name`'s newest black box (`motiond`'s recorder rewrites
    /// it after each save: the saved file's path and a newline), beside its pid file.
    pub fn blackbox_pointer(name: &str) -> PathBuf {
        Self::of(name)
            .path
            .with_file_name(format!("motiond-{name}.blackbox"))
    }

    /// The pid file of instance `name` in `dir` (tests).
    pub fn in_dir(dir: &Path, name: &str) -> Self {
        Self {
            path: dir.join(format!("motiond-{name}.pid")),
        }
    }

    /// Where the file is.
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn shown(&self) -> String {
        self.path.display().to_string()
    }

    fn io(&self, what: &'static str) -> impl Fn(std::io::Error) -> PidFileError + '_ {
        move |error| PidFileError::Io {
            what,
            path: self.shown(),
            detail: error.to_string(),
        }
    }

    /// Writes the file for this process (the server, once its services exist) and node
    /// `node`: a new file beside it, then renamed over any old one, so a reader never sees
    /// half a file. Mode 0644. Fails when the directory does not exist or the old file
    /// cannot be replaced (another user's file in a sticky directory).
    pub fn write_for_this_process(&self, node: u128) -> Result<ServerProcess, PidFileError> {
        let pid = std::process::id();
        let start_ticks = process_start_ticks(pid).map_err(|why| PidFileError::Stale {
            path: self.shown(),
            pid,
            why,
        })?;
        let text = format!("pid {pid}\nstart {start_ticks}\nnode {node}\n");
        let temporary = self.path.with_extension(format!("pid.{pid}.new"));
        let _ = fs::remove_file(&temporary);
        let mut file = OpenOptions::new()
            .write(true)
            .create_new(true)
            // create_new is O_EXCL: never through a symbolic link planted at that name.
            .mode(0o644)
            .open(&temporary)
            .map_err(self.io("cannot create"))?;
        // The umask may have taken bits off; it never adds any, but say so explicitly.
        file.set_permissions(fs::Permissions::from_mode(0o644))
            .map_err(self.io("cannot set the mode of"))?;
        let written = file
            .write_all(text.as_bytes())
            .and_then(|()| file.sync_all());
        drop(file);
        if let Err(error) = written.and_then(|()| fs::rename(&temporary, &self.path)) {
            let _ = fs::remove_file(&temporary);
            return Err(self.io("cannot write")(error));
        }
        let uid = fs::metadata(&self.path)
            .map_err(self.io("cannot inspect"))?
            .uid();
        Ok(ServerProcess {
            pid,
            start_ticks,
            node,
            uid,
        })
    }

    /// Removes the file if it still names this process (a clean exit); a file another
    /// server wrote meanwhile stays.
    pub fn remove_if_this_process(&self) {
        if let Ok(text) = fs::read_to_string(&self.path)
            && parse(&text).is_ok_and(|(pid, _, _)| pid == std::process::id())
        {
            let _ = fs::remove_file(&self.path);
        }
    }

    /// Reads the file and checks that it can be trusted and names a live process (see the
    /// module docs).
    pub fn read_verified(&self) -> Result<ServerProcess, PidFileError> {
        let untrusted = |why: String| PidFileError::Untrusted {
            path: self.shown(),
            why,
        };
        let meta = match fs::symlink_metadata(&self.path) {
            Ok(meta) => meta,
            Err(error) if error.kind() == std::io::ErrorKind::NotFound => {
                return Err(PidFileError::Missing { path: self.shown() });
            }
            Err(error) => return Err(self.io("cannot inspect")(error)),
        };
        if !meta.file_type().is_file() {
            return Err(untrusted("not a regular file".into()));
        }
        if meta.mode() & 0o022 != 0 {
            return Err(untrusted(format!(
                "its group or others may write it (mode {:o})",
                meta.mode() & 0o7777
            )));
        }
        if let Some(dir) = self.path.parent() {
            let dir_meta = fs::metadata(dir).map_err(self.io("cannot inspect the directory of"))?;
            let others_write = dir_meta.mode() & 0o002 != 0;
            let sticky = dir_meta.mode() & 0o1000 != 0;
            if others_write && !sticky {
                return Err(untrusted(format!(
                    "anyone may replace files in {} (mode {:o}, no sticky bit)",
                    dir.display(),
                    dir_meta.mode() & 0o7777
                )));
            }
        }
        let text = fs::read_to_string(&self.path).map_err(self.io("cannot read"))?;
        let (pid, start_ticks, node) = parse(&text).map_err(|why| PidFileError::Malformed {
            path: self.shown(),
            why,
        })?;
        let stale = |why: String| PidFileError::Stale {
            path: self.shown(),
            pid,
            why,
        };
        let started = process_start_ticks(pid).map_err(stale)?;
        if started != start_ticks {
            return Err(stale(format!(
                "started at tick {started}, not {start_ticks}: another process has that pid now"
            )));
        }
        let owner = process_uid(pid).map_err(stale)?;
        if owner != meta.uid() {
            return Err(untrusted(format!(
                "it belongs to uid {}, the process it names to uid {owner}",
                meta.uid()
            )));
        }
        Ok(ServerProcess {
            pid,
            start_ticks,
            node,
            uid: owner,
        })
    }
}

fn parse(text: &str) -> Result<(u32, u64, u128), String> {
    let mut pid = None;
    let mut start = None;
    let mut node = None;
    for line in text.lines() {
        let (key, value) = line
            .split_once(' ')
            .ok_or_else(|| format!("line `{line}` is not `key value`"))?;
        let bad = |_| format!("`{key}` has a bad value `{value}`");
        match key {
            "pid" => pid = Some(value.parse::<u32>().map_err(bad)?),
            "start" => start = Some(value.parse::<u64>().map_err(bad)?),
            "node" => node = Some(value.parse::<u128>().map_err(bad)?),
            other => return Err(format!("unknown key `{other}`")),
        }
    }
    match (pid, start, node) {
        (Some(0), _, _) => Err("pid 0".into()),
        (Some(pid), Some(start), Some(node)) => Ok((pid, start, node)),
        _ => Err("`pid`, `start` and `node` are required".into()),
    }
}

/// Field 22 of `/proc/<pid>/stat`: the process's start time in clock ticks since boot.
pub fn process_start_ticks(pid: u32) -> Result<u64, String> {
    let stat = fs::read_to_string(format!("/proc/{pid}/stat"))
        .map_err(|error| format!("is not running ({error})"))?;
    // The command name (field 2) is in parentheses and may hold spaces or parentheses: the
    // fields after it start after the last ')'.
    let after = stat
        .rfind(')')
        .map(|at| &stat[at + 1..])
        .ok_or("has an unreadable /proc stat")?;
    // After the name: state is field 3, so start time (22) is the 20th field here.
    after
        .split_whitespace()
        .nth(19)
        .and_then(|field| field.parse().ok())
        .ok_or_else(|| "has an unreadable /proc stat".to_owned())
}

/// The effective user id of process `pid` (`Uid:` of `/proc/<pid>/status`).
pub fn process_uid(pid: u32) -> Result<u32, String> {
    let status = fs::read_to_string(format!("/proc/{pid}/status"))
        .map_err(|error| format!("is not running ({error})"))?;
    status
        .lines()
        .find_map(|line| line.strip_prefix("Uid:"))
        .and_then(|ids| ids.split_whitespace().nth(1))
        .and_then(|euid| euid.parse().ok())
        .ok_or_else(|| "has an unreadable /proc status".to_owned())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("motion-ipc-pid-{tag}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        fs::set_permissions(&dir, fs::Permissions::from_mode(0o755)).unwrap();
        dir
    }

    #[test]
    fn a_file_this_process_wrote_is_trusted_and_names_it() {
        let dir = scratch("own");
        let file = ServerPidFile::in_dir(&dir, "demo");
        let written = file.write_for_this_process(77).unwrap();
        let read = file.read_verified().unwrap();
        assert_eq!(read, written);
        assert_eq!(read.pid, std::process::id());
        assert_eq!(read.node, 77);
        assert_eq!(fs::metadata(file.path()).unwrap().mode() & 0o777, 0o644);
        file.remove_if_this_process();
        assert!(matches!(
            file.read_verified(),
            Err(PidFileError::Missing { .. })
        ));
        fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn writable_files_links_recycled_pids_and_garbage_are_refused() {
        let dir = scratch("bad");
        let file = ServerPidFile::in_dir(&dir, "demo");
        file.write_for_this_process(1).unwrap();

        fs::set_permissions(file.path(), fs::Permissions::from_mode(0o666)).unwrap();
        let error = file.read_verified().unwrap_err();
        assert!(matches!(error, PidFileError::Untrusted { .. }), "{error}");
        fs::set_permissions(file.path(), fs::Permissions::from_mode(0o644)).unwrap();

        fs::set_permissions(&dir, fs::Permissions::from_mode(0o777)).unwrap();
        let error = file.read_verified().unwrap_err();
        assert!(error.to_string().contains("no sticky bit"), "{error}");
        fs::set_permissions(&dir, fs::Permissions::from_mode(0o1777)).unwrap();
        file.read_verified().unwrap();
        fs::set_permissions(&dir, fs::Permissions::from_mode(0o755)).unwrap();

        // This process's pid with another start time: a recycled pid.
        let pid = std::process::id();
        fs::write(file.path(), format!("pid {pid}\nstart 1\nnode 1\n")).unwrap();
        let error = file.read_verified().unwrap_err();
        assert!(matches!(error, PidFileError::Stale { .. }), "{error}");

        for garbage in [
            "",
            "pid x\n",
            "pid 0\nstart 1\nnode 1\n",
            "who 1\n",
            "pid 1",
        ] {
            fs::write(file.path(), garbage).unwrap();
            let error = file.read_verified().unwrap_err();
            assert!(
                matches!(error, PidFileError::Malformed { .. }),
                "{garbage:?}: {error}"
            );
        }

        let target = dir.join("elsewhere");
        fs::write(&target, format!("pid {pid}\n")).unwrap();
        fs::remove_file(file.path()).unwrap();
        std::os::unix::fs::symlink(&target, file.path()).unwrap();
        let error = file.read_verified().unwrap_err();
        assert!(error.to_string().contains("not a regular file"), "{error}");
        fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn a_process_that_is_gone_is_stale() {
        let dir = scratch("gone");
        let file = ServerPidFile::in_dir(&dir, "demo");
        // pid_max is at most 2^22 on Linux: this pid cannot exist.
        fs::write(file.path(), "pid 4194305\nstart 1\nnode 1\n").unwrap();
        let error = file.read_verified().unwrap_err();
        assert!(error.to_string().contains("is not running"), "{error}");
        fs::remove_dir_all(dir).unwrap();
    }
}
