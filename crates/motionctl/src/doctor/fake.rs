//! Tests only: a fake root directory (`/proc`, `/sys`, `/etc`, `/dev` as plain files and
//! relative links) and a fake probe, so every branch of every check runs on any machine.

use core::cell::RefCell;
use core::time::Duration;
use std::os::unix::fs::PermissionsExt as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};

use motion_bench::Summary;

use super::check::{Check, Context};
use super::config::DoctorConfig;
use super::host::{Host, Probe, under};

/// The fake process's user and group (nobody on the machine has them).
pub const UID: u32 = 4242;

/// What the fake probe answers.
#[derive(Debug)]
pub struct FakeProbe {
    /// `try_fifo`'s answer.
    pub fifo: RefCell<Result<(), String>>,
    /// `wakeup`'s answer.
    pub wakeup: RefCell<Result<(Summary, String), String>>,
    /// `free_bytes`' answer.
    pub free: RefCell<u64>,
    /// The priorities `try_fifo` was asked for.
    pub fifo_asked: RefCell<Vec<u8>>,
}

impl Probe for FakeProbe {
    fn try_fifo(&self, priority: u8, _cpu: Option<usize>) -> Result<(), String> {
        self.fifo_asked.borrow_mut().push(priority);
        self.fifo.borrow().clone()
    }

    fn wakeup(
        &self,
        _period: Duration,
        _duration: Duration,
        _priority: Option<u8>,
        _cpu: Option<usize>,
    ) -> Result<(Summary, String), String> {
        self.wakeup.borrow().clone()
    }

    fn free_bytes(&self, _path: &Path) -> Result<u64, String> {
        Ok(*self.free.borrow())
    }
}

/// A temporary root directory, removed on drop.
#[derive(Debug)]
pub struct FakeRoot {
    /// Its path.
    pub dir: PathBuf,
    /// The probe every check gets.
    pub probe: FakeProbe,
    config: RefCell<DoctorConfig>,
}

impl FakeRoot {
    /// An empty root with this process's status (uid and gid [`UID`], no capabilities).
    pub fn new() -> Self {
        static NEXT: AtomicU32 = AtomicU32::new(0);
        let dir = std::env::temp_dir().join(format!(
            "motionctl-doctor-{}-{}",
            std::process::id(),
            NEXT.fetch_add(1, Ordering::Relaxed)
        ));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("create the fake root");
        let fake = Self {
            dir,
            probe: FakeProbe {
                fifo: RefCell::new(Ok(())),
                wakeup: RefCell::new(Err("not set".to_owned())),
                free: RefCell::new(1 << 30),
                fifo_asked: RefCell::new(Vec::new()),
            },
            config: RefCell::new(DoctorConfig::default()),
        };
        fake.identity(UID, &[], 0);
        fake
    }

    /// Writes `/proc/self/status` for `uid` (its group is the same number) with extra
    /// `groups` and effective capabilities `caps`.
    pub fn identity(&self, uid: u32, groups: &[u32], caps: u64) {
        let groups: Vec<String> = groups.iter().map(u32::to_string).collect();
        self.file(
            "/proc/self/status",
            &format!(
                "Name:\tmotionctl\nUid:\t{uid}\t{uid}\t{uid}\t{uid}\nGid:\t{uid}\t{uid}\t{uid}\t{uid}\nGroups:\t{}\nCapEff:\t{caps:016x}\n",
                groups.join(" ")
            ),
        );
    }

    /// The group of the files this test creates (to grant access through it).
    pub fn file_gid(&self) -> u32 {
        use std::os::unix::fs::MetadataExt as _;
        std::fs::metadata(&self.dir).map_or(0, |m| m.gid())
    }

    /// The real path of machine path `path`.
    pub fn at(&self, path: &str) -> PathBuf {
        under(&self.dir, Path::new(path))
    }

    /// Writes a file (and its directories).
    pub fn file(&self, path: &str, text: &str) {
        let real = self.at(path);
        if let Some(parent) = real.parent() {
            std::fs::create_dir_all(parent).expect("fake dirs");
        }
        std::fs::write(&real, text).expect("fake file");
    }

    /// Creates a directory (and its parents).
    pub fn dir(&self, path: &str) {
        std::fs::create_dir_all(self.at(path)).expect("fake dir");
    }

    /// Sets a path's permission bits.
    pub fn chmod(&self, path: &str, mode: u32) {
        std::fs::set_permissions(self.at(path), std::fs::Permissions::from_mode(mode))
            .expect("chmod");
    }

    /// A symbolic link at `path` pointing at `target` (as the link's text).
    pub fn symlink(&self, path: &str, target: &str) {
        let real = self.at(path);
        if let Some(parent) = real.parent() {
            std::fs::create_dir_all(parent).expect("fake dirs");
        }
        let _ = std::fs::remove_file(&real);
        std::os::unix::fs::symlink(target, &real).expect("symlink");
    }

    /// Removes a file or a directory tree.
    pub fn remove(&self, path: &str) {
        let real = self.at(path);
        let _ = std::fs::remove_file(&real).or_else(|_| std::fs::remove_dir_all(&real));
    }

    /// Uses this config from now on.
    pub fn set_config(&self, text: &str) {
        *self.config.borrow_mut() = DoctorConfig::parse(text).expect("test config");
    }

    /// Runs one check against this root.
    pub fn check(&self, check: fn(&Context<'_>) -> Check) -> Check {
        let host = Host {
            root: self.dir.clone(),
            probe: &self.probe,
        };
        let identity = host.identity();
        let cx = Context {
            host,
            config: self.config.borrow().clone(),
            config_path: None,
            identity,
            wakeup: Duration::from_secs(1),
        };
        check(&cx)
    }
}

impl Drop for FakeRoot {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}
