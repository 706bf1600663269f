//! The directories whose files the server trusts — `[server] state_dir` (the references
//! file and the server's key) and `[server] blackbox_dir` — and the files it makes in them
//! (docs/ARCHITECTURE.md "Files the server trusts").
//!
//! A directory is used only when it is the server's own, the checks the pid file gets
//! (`motion_ipc::pid_file`): not a symbolic link, a directory, owned by the server's
//! effective user, writable by neither its group nor others, in a parent that others may
//! not write unless it has the sticky bit (`/tmp`). A missing one is created with the mode
//! asked for (its missing parents 0700); one that fails a check is refused with what was
//! found and what to do ([`PrivateDirError::Untrusted`]).
//!
//! Every operation goes through the directory's file descriptor (`openat`, `renameat`,
//! `linkat`, `unlinkat`, `fstatat` on it): a directory swapped for another after the check
//! is not the one written to. New files are created `O_CREAT | O_EXCL | O_NOFOLLOW` with
//! an explicit mode: never through a symbolic link planted at the name, never into a file
//! someone else made. A file is read only when it is a regular file of the server's user
//! that its group and others may not write (nor read, for a secret).
//!
//! Used by the main thread and the black box's recorder thread, never on the tick.

use std::ffi::OsString;
use std::fs::{DirBuilder, File, Permissions};
use std::io::{self, Read as _, Write as _};
use std::os::fd::{AsRawFd as _, OwnedFd};
use std::os::unix::fs::{DirBuilderExt as _, MetadataExt as _, PermissionsExt as _};
use std::path::{Path, PathBuf};

use nix::errno::Errno;
use nix::fcntl::{AtFlags, OFlag};
use nix::sys::stat::{FileStat, Mode, SFlag};
use nix::unistd::UnlinkatFlags;

/// Why a directory or a file in it is not used.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PrivateDirError {
    /// The system refused an operation.
    #[error("{key} {}: cannot {what}: {detail}", path.display())]
    Io {
        /// The config key naming the directory (`server.state_dir`, `server.blackbox_dir`).
        key: &'static str,
        /// The directory or file.
        path: PathBuf,
        /// What was being done.
        what: &'static str,
        /// The system's error.
        detail: String,
    },
    /// The directory or file is not one only the server's user could have made.
    #[error("{key} {} is not the server's own: {why}; {fix}", path.display())]
    Untrusted {
        /// The config key naming the directory.
        key: &'static str,
        /// The directory or file.
        path: PathBuf,
        /// What was found.
        why: String,
        /// What to do.
        fix: String,
    },
}

/// How private a file read back must be.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Privacy {
    /// Its group and others may not write it (the references file).
    Unwritable,
    /// Its group and others may neither read nor write it (the server's key).
    Secret,
}

/// A directory that passed the checks, held by its file descriptor.
#[derive(Debug)]
pub struct PrivateDir {
    key: &'static str,
    path: PathBuf,
    fd: OwnedFd,
    euid: u32,
}

/// Whether `error` is "no such file or directory".
fn missing(error: Errno) -> bool {
    error == Errno::ENOENT
}

impl PrivateDir {
    /// Opens directory `path` (named by config key `key`), creating it with `mode` when
    /// missing, and checks that it is the server's own (see the module docs).
    pub fn open(path: &Path, key: &'static str, mode: u32) -> Result<Self, PrivateDirError> {
        let euid = nix::unistd::geteuid().as_raw();
        let io = |what: &'static str, detail: String| PrivateDirError::Io {
            key,
            path: path.to_owned(),
            what,
            detail,
        };
        let untrusted = |why: String, fix: String| PrivateDirError::Untrusted {
            key,
            path: path.to_owned(),
            why,
            fix,
        };
        if path.as_os_str().is_empty() {
            return Err(io("use an empty path", "give a directory".into()));
        }
        match std::fs::symlink_metadata(path) {
            Ok(_) => {}
            Err(error) if error.kind() == io::ErrorKind::NotFound => {
                if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
                    DirBuilder::new()
                        .recursive(true)
                        .mode(0o700)
                        .create(parent)
                        .map_err(|e| io("create its parent directories", e.to_string()))?;
                }
                match DirBuilder::new().mode(mode).create(path) {
                    Ok(()) => {}
                    // Made meanwhile by someone else: the checks below decide.
                    Err(error) if error.kind() == io::ErrorKind::AlreadyExists => {}
                    Err(error) => return Err(io("create it", error.to_string())),
                }
            }
            Err(error) => return Err(io("inspect it", error.to_string())),
        }
        let link = std::fs::symlink_metadata(path).map_err(|e| io("inspect it", e.to_string()))?;
        if link.file_type().is_symlink() {
            let target = std::fs::read_link(path)
                .map_or_else(|_| "?".to_owned(), |t| t.display().to_string());
            return Err(untrusted(
                format!("it is a symbolic link (to {target})"),
                format!("give `{key}` the directory itself, one of uid {euid}'s"),
            ));
        }
        if !link.is_dir() {
            return Err(untrusted(
                "it is not a directory".into(),
                format!("remove it, or give `{key}` a directory of uid {euid}'s"),
            ));
        }
        // O_NOFOLLOW | O_DIRECTORY: what was just looked at, not a link put there since.
        let flags = OFlag::O_RDONLY | OFlag::O_DIRECTORY | OFlag::O_NOFOLLOW | OFlag::O_CLOEXEC;
        let fd = match nix::fcntl::open(path, flags, Mode::empty()) {
            Ok(fd) => fd,
            Err(error @ (Errno::ELOOP | Errno::ENOTDIR)) => {
                return Err(untrusted(
                    format!("it was replaced while it was checked ({})", error.desc()),
                    format!(
                        "find out who replaces it, or give `{key}` a directory of uid {euid}'s"
                    ),
                ));
            }
            Err(error) => return Err(io("open it", error.to_string())),
        };
        let stat = nix::sys::stat::fstat(&fd).map_err(|e| io("inspect it", e.to_string()))?;
        let found = format!("uid {}, mode {:o}", stat.st_uid, stat.st_mode & 0o7777);
        if stat.st_uid != euid {
            return Err(untrusted(
                format!("it belongs to another user ({found}) and this server runs as uid {euid}"),
                format!(
                    "remove it if nobody needs it, or give `{key}` a directory of uid {euid}'s \
                     (e.g. `install -d -m 0700 DIR` as that user)"
                ),
            ));
        }
        if stat.st_mode & 0o022 != 0 {
            return Err(untrusted(
                format!("its group or others may write it ({found})"),
                format!("`chmod go-w {}`", path.display()),
            ));
        }
        if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
            let meta = std::fs::metadata(parent)
                .map_err(|e| io("inspect its parent directory", e.to_string()))?;
            if meta.mode() & 0o002 != 0 && meta.mode() & 0o1000 == 0 {
                return Err(untrusted(
                    format!(
                        "anyone may rename it away in {} (mode {:o}, no sticky bit)",
                        parent.display(),
                        meta.mode() & 0o7777
                    ),
                    "move it under a directory others may not write".to_owned(),
                ));
            }
        }
        Ok(Self {
            key,
            path: path.to_owned(),
            fd,
            euid,
        })
    }

    /// The directory's path (as given).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The path of file `name` in the directory (for messages).
    pub fn file_path(&self, name: &str) -> PathBuf {
        self.path.join(name)
    }

    fn io(&self, name: &str, what: &'static str) -> impl Fn(Errno) -> PrivateDirError + '_ {
        let path = self.file_path(name);
        move |error| PrivateDirError::Io {
            key: self.key,
            path: path.clone(),
            what,
            detail: error.desc().to_owned(),
        }
    }

    /// Creates file `name` for writing, `O_CREAT | O_EXCL | O_NOFOLLOW`, with exactly
    /// `mode` (whatever the umask): fails when anything (a file, a symbolic link) is there.
    pub fn create_new(&self, name: &str, mode: u32) -> io::Result<File> {
        let flags =
            OFlag::O_WRONLY | OFlag::O_CREAT | OFlag::O_EXCL | OFlag::O_NOFOLLOW | OFlag::O_CLOEXEC;
        let fd = nix::fcntl::openat(&self.fd, name, flags, Mode::from_bits_truncate(mode))?;
        let file = File::from(fd);
        file.set_permissions(Permissions::from_mode(mode))?;
        Ok(file)
    }

    /// Removes what is at `name` (a file or a link, never followed); nothing there is no
    /// error.
    pub fn remove(&self, name: &str) -> io::Result<()> {
        match nix::unistd::unlinkat(&self.fd, name, UnlinkatFlags::NoRemoveDir) {
            Ok(()) => Ok(()),
            Err(error) if missing(error) => Ok(()),
            Err(error) => Err(error.into()),
        }
    }

    /// Writes `bytes` as file `name` with `mode`: through `<name>.tmp` (whatever was there
    /// removed, never followed; created `O_EXCL | O_NOFOLLOW`), synced, renamed over
    /// `name`, the directory synced; a reader sees the old file or the new one.
    pub fn replace(&self, name: &str, bytes: &[u8], mode: u32) -> io::Result<()> {
        let temporary = format!("{name}.tmp");
        self.remove(&temporary)?;
        let written = self.create_new(&temporary, mode).and_then(|mut file| {
            file.write_all(bytes)?;
            file.sync_all()
        });
        let renamed = written.and_then(|()| {
            nix::fcntl::renameat(&self.fd, temporary.as_str(), &self.fd, name)
                .map_err(io::Error::from)
        });
        if let Err(error) = renamed {
            let _ = self.remove(&temporary);
            return Err(error);
        }
        self.sync();
        Ok(())
    }

    /// Makes file `name` with `bytes` and `mode` unless it exists (then `false`): written
    /// whole under a temporary name first and linked to `name` (`linkat`, which never
    /// replaces), so no reader ever sees it half written.
    pub fn create_whole(&self, name: &str, bytes: &[u8], mode: u32) -> io::Result<bool> {
        let temporary = format!("{name}.{}.new", std::process::id());
        self.remove(&temporary)?;
        let written = self.create_new(&temporary, mode).and_then(|mut file| {
            file.write_all(bytes)?;
            file.sync_all()
        });
        let linked = written.and_then(|()| {
            match nix::unistd::linkat(
                &self.fd,
                temporary.as_str(),
                &self.fd,
                name,
                AtFlags::empty(),
            ) {
                Ok(()) => Ok(true),
                Err(Errno::EEXIST) => Ok(false),
                Err(error) => Err(error.into()),
            }
        });
        let _ = self.remove(&temporary);
        if linked.as_ref().is_ok_and(|made| *made) {
            self.sync();
        }
        linked
    }

    /// Reads file `name` when it is a regular file of the server's user that `privacy`
    /// allows (`None` when there is none), at most `limit` bytes.
    pub fn read_own(
        &self,
        name: &str,
        privacy: Privacy,
        limit: u64,
    ) -> Result<Option<Vec<u8>>, PrivateDirError> {
        let path = self.file_path(name);
        let untrusted = |why: String, fix: String| PrivateDirError::Untrusted {
            key: self.key,
            path: path.clone(),
            why,
            fix,
        };
        // O_NONBLOCK: a FIFO planted at the name does not hang the open.
        let flags = OFlag::O_RDONLY | OFlag::O_NOFOLLOW | OFlag::O_NONBLOCK | OFlag::O_CLOEXEC;
        let fd = match nix::fcntl::openat(&self.fd, name, flags, Mode::empty()) {
            Ok(fd) => fd,
            Err(error) if missing(error) => return Ok(None),
            Err(Errno::ELOOP) => {
                return Err(untrusted(
                    "it is a symbolic link".into(),
                    format!("remove it (`rm {}`)", path.display()),
                ));
            }
            Err(error) => return Err(self.io(name, "open")(error)),
        };
        let stat = nix::sys::stat::fstat(&fd).map_err(self.io(name, "inspect"))?;
        let found = format!("uid {}, mode {:o}", stat.st_uid, stat.st_mode & 0o7777);
        if !is_regular(&stat) {
            return Err(untrusted(
                "it is not a regular file".into(),
                format!("remove it (`rm {}`)", path.display()),
            ));
        }
        if stat.st_uid != self.euid {
            return Err(untrusted(
                format!(
                    "it belongs to another user ({found}) and this server runs as uid {}",
                    self.euid
                ),
                format!("remove it (`rm {}`)", path.display()),
            ));
        }
        let (forbidden, may) = match privacy {
            Privacy::Unwritable => (0o022, "write"),
            Privacy::Secret => (0o077, "read or write"),
        };
        if stat.st_mode & forbidden != 0 {
            return Err(untrusted(
                format!("its group or others may {may} it ({found})"),
                format!(
                    "remove it (`rm {}`): the server makes it again, mode 600",
                    path.display()
                ),
            ));
        }
        let mut bytes = Vec::new();
        File::from(fd)
            .take(limit + 1)
            .read_to_end(&mut bytes)
            .map_err(|e| PrivateDirError::Io {
                key: self.key,
                path: path.clone(),
                what: "read",
                detail: e.to_string(),
            })?;
        if bytes.len() as u64 > limit {
            return Err(untrusted(
                format!("it is larger than {limit} bytes"),
                format!("remove it (`rm {}`)", path.display()),
            ));
        }
        Ok(Some(bytes))
    }

    /// The regular files of the server's user in the directory, with what `fstatat` says
    /// of each (never following a link).
    pub fn own_files(&self) -> io::Result<Vec<(String, FileStat)>> {
        // The directory the descriptor holds, not whatever is at the path now.
        let listing = std::fs::read_dir(format!("/proc/self/fd/{}", self.fd.as_raw_fd()))?;
        let mut out = Vec::new();
        for entry in listing.filter_map(Result::ok) {
            let Ok(name) = entry.file_name().into_string() else {
                continue;
            };
            let Ok(stat) =
                nix::sys::stat::fstatat(&self.fd, name.as_str(), AtFlags::AT_SYMLINK_NOFOLLOW)
            else {
                continue;
            };
            if is_regular(&stat) && stat.st_uid == self.euid {
                out.push((name, stat));
            }
        }
        Ok(out)
    }

    /// Syncs the directory (a rename or a new name in it reaches the disk).
    pub fn sync(&self) {
        let _ = nix::unistd::fsync(&self.fd);
    }
}

fn is_regular(stat: &FileStat) -> bool {
    SFlag::from_bits_truncate(stat.st_mode & SFlag::S_IFMT.bits()) == SFlag::S_IFREG
}

/// Where `[server] state_dir` is when the config does not say (docs/ARCHITECTURE.md
/// "Files the server trusts"), from the environment of the process:
/// 1. `$STATE_DIRECTORY` (systemd's, for a unit with `StateDirectory=motiond`; the first
///    of several), when absolute;
/// 2. `/var/lib/motiond` for root, or for a user who owns it (deploy/tmpfiles.d makes it
///    `motion`'s for a run without systemd);
/// 3. `$XDG_STATE_HOME/motiond` (absolute), else `~/.local/state/motiond` when `$HOME` is
///    a directory of this user's;
/// 4. else `/tmp/motiond-state-<uid>`, used only when it is this user's (as any state
///    directory: [`PrivateDir::open`]).
pub fn default_state_dir() -> PathBuf {
    let euid = nix::unistd::geteuid().as_raw();
    let owner = |path: &str| std::fs::metadata(path).ok().map(|meta| meta.uid());
    let home = std::env::var_os("HOME");
    let home_owner = home.as_ref().and_then(|home| {
        std::fs::metadata(home)
            .ok()
            .filter(std::fs::Metadata::is_dir)
            .map(|meta| meta.uid())
    });
    state_dir_from(&StateEnv {
        state_directory: std::env::var_os("STATE_DIRECTORY"),
        euid,
        var_lib_owner: owner(VAR_LIB),
        xdg_state_home: std::env::var_os("XDG_STATE_HOME"),
        home,
        home_owner,
    })
}

/// The system's state directory for motiond (`StateDirectory=motiond`).
pub const VAR_LIB: &str = "/var/lib/motiond";

/// What [`default_state_dir`] looks at.
#[derive(Debug, Clone, Default)]
pub struct StateEnv {
    /// `$STATE_DIRECTORY`.
    pub state_directory: Option<OsString>,
    /// The effective user id.
    pub euid: u32,
    /// The owner of `/var/lib/motiond`, if it exists.
    pub var_lib_owner: Option<u32>,
    /// `$XDG_STATE_HOME`.
    pub xdg_state_home: Option<OsString>,
    /// `$HOME`.
    pub home: Option<OsString>,
    /// The owner of `$HOME`, if it is a directory.
    pub home_owner: Option<u32>,
}

/// [`default_state_dir`] from `env`.
pub fn state_dir_from(env: &StateEnv) -> PathBuf {
    let absolute = |value: &OsString| {
        let path = PathBuf::from(value);
        (path.is_absolute() && path != Path::new("/")).then_some(path)
    };
    if let Some(dir) = env.state_directory.as_ref().and_then(|value| {
        let first = value.to_str().map_or_else(
            || value.clone(),
            |text| OsString::from(text.split(':').next().unwrap_or(text)),
        );
        absolute(&first)
    }) {
        return dir;
    }
    if env.euid == 0 || env.var_lib_owner == Some(env.euid) {
        return PathBuf::from(VAR_LIB);
    }
    if let Some(dir) = env.xdg_state_home.as_ref().and_then(absolute) {
        return dir.join("motiond");
    }
    if let Some(home) = env.home.as_ref().and_then(absolute)
        && env.home_owner == Some(env.euid)
    {
        return home.join(".local/state/motiond");
    }
    PathBuf::from(format!("/tmp/motiond-state-{}", env.euid))
}

#[cfg(test)]
mod tests;
