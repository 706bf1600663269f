//! The machine the doctor looks at: files under a root directory (`/`, or a fake tree in
//! tests), the identity and limits of this process as `/proc/self` states them, and the
//! live measurements a file cannot fake (behind [`Probe`]).

use core::time::Duration;
use std::collections::BTreeSet;
use std::os::unix::fs::MetadataExt as _;
use std::path::{Component, Path, PathBuf};

use motion_bench::Summary;

/// Capability numbers (linux/capability.h).
pub const CAP_IPC_LOCK: u32 = 14;
/// Capability numbers (linux/capability.h).
pub const CAP_SYS_NICE: u32 = 23;

/// What only a live system can answer.
pub trait Probe {
    /// Switches a scratch thread to SCHED_FIFO `priority` (pinned to `cpu` when given);
    /// `Err` says why not.
    fn try_fifo(&self, priority: u8, cpu: Option<usize>) -> Result<(), String>;
    /// Sleeps to absolute deadlines every `period` for `duration` at `priority`/`cpu` (the
    /// bench's sleeper) and returns wake − deadline, with a line on the thread's set-up.
    fn wakeup(
        &self,
        period: Duration,
        duration: Duration,
        priority: Option<u8>,
        cpu: Option<usize>,
    ) -> Result<(Summary, String), String>;
    /// Free bytes of the file system holding `path`.
    fn free_bytes(&self, path: &Path) -> Result<u64, String>;
}

/// The live system.
#[derive(Debug, Clone, Copy, Default)]
pub struct LiveProbe;

impl Probe for LiveProbe {
    fn try_fifo(&self, priority: u8, cpu: Option<usize>) -> Result<(), String> {
        std::thread::spawn(move || {
            let setup = motion_bench::rt::set_up_thread(Some(priority), cpu);
            if setup.applied.iter().any(|w| w.starts_with("SCHED_FIFO")) {
                Ok(())
            } else {
                Err(setup.problems.join("; "))
            }
        })
        .join()
        .map_err(|_| "the probe thread panicked".to_owned())?
    }

    fn wakeup(
        &self,
        period: Duration,
        duration: Duration,
        priority: Option<u8>,
        cpu: Option<usize>,
    ) -> Result<(Summary, String), String> {
        // As motiond does: hold /dev/cpu_dma_latency at 0 when we may.
        let dma = motion_bench::rt::DmaLatency::hold();
        let period_ns = u64::try_from(period.as_nanos()).unwrap_or(u64::MAX);
        let run = motion_bench::wakeup::measure(period_ns, duration, priority, cpu)?;
        let mut thread = run.thread;
        thread.push_str(match dma {
            Ok(_) => ", cpu_dma_latency held at 0",
            Err(_) => ", cpu_dma_latency not held",
        });
        Ok((run.latency.summary(), thread))
    }

    fn free_bytes(&self, path: &Path) -> Result<u64, String> {
        let stat =
            nix::sys::statvfs::statvfs(path).map_err(|e| format!("{}: {e}", path.display()))?;
        // Both are u64 here, u32 on a 32-bit Raspberry Pi OS.
        #[allow(clippy::useless_conversion)]
        let (blocks, size) = (
            u64::from(stat.blocks_available()),
            u64::from(stat.fragment_size()),
        );
        Ok(blocks.saturating_mul(size))
    }
}

/// Who this process is, from `/proc/self/status`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Identity {
    /// Effective user id.
    pub uid: u32,
    /// Effective group id.
    pub gid: u32,
    /// Supplementary groups (and the effective group).
    pub groups: BTreeSet<u32>,
    /// Effective capability set.
    pub caps: u64,
}

impl Identity {
    /// Whether the effective set holds capability `cap`.
    pub fn has_cap(&self, cap: u32) -> bool {
        self.caps & (1u64 << cap) != 0
    }

    /// Parses `/proc/<pid>/status` (`Uid:`, `Gid:`, `Groups:`, `CapEff:`).
    pub fn parse(status: &str) -> Result<Self, String> {
        let field = |name: &str| {
            status
                .lines()
                .find_map(|line| line.strip_prefix(name))
                .map(str::trim)
                .ok_or_else(|| format!("no `{name}` line"))
        };
        // Real, effective, saved, file-system: the effective one decides.
        let second = |name: &str| -> Result<u32, String> {
            field(name)?
                .split_whitespace()
                .nth(1)
                .and_then(|v| v.parse().ok())
                .ok_or_else(|| format!("bad `{name}` line"))
        };
        let uid = second("Uid:")?;
        let gid = second("Gid:")?;
        let mut groups: BTreeSet<u32> = field("Groups:")
            .unwrap_or("")
            .split_whitespace()
            .filter_map(|g| g.parse().ok())
            .collect();
        groups.insert(gid);
        let caps = u64::from_str_radix(field("CapEff:")?, 16).map_err(|_| "bad `CapEff:` line")?;
        Ok(Self {
            uid,
            gid,
            groups,
            caps,
        })
    }

    /// Whether this identity may read and write a file of `mode` owned by `uid`:`gid`
    /// (root may; otherwise the owner, group or other bits that apply).
    pub fn can_read_write(&self, mode: u32, uid: u32, gid: u32) -> bool {
        self.allowed(mode, uid, gid, 0o6)
    }

    /// Whether this identity may create entries in a directory (write and search).
    pub fn can_create_in(&self, mode: u32, uid: u32, gid: u32) -> bool {
        self.allowed(mode, uid, gid, 0o3)
    }

    fn allowed(&self, mode: u32, uid: u32, gid: u32, bits: u32) -> bool {
        if self.uid == 0 {
            return true;
        }
        let granted = if self.uid == uid {
            (mode >> 6) & 0o7
        } else if self.groups.contains(&gid) {
            (mode >> 3) & 0o7
        } else {
            mode & 0o7
        };
        granted & bits == bits
    }
}

/// One resource limit of `/proc/self/limits`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Limit {
    /// `unlimited`.
    Unlimited,
    /// A number (bytes for memory, a priority for rtprio).
    Value(u64),
}

impl core::fmt::Display for Limit {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Unlimited => f.write_str("unlimited"),
            Self::Value(v) => write!(f, "{v}"),
        }
    }
}

/// The soft limit named `name` ("Max realtime priority") in `/proc/self/limits` text.
pub fn soft_limit(limits: &str, name: &str) -> Option<Limit> {
    let line = limits.lines().find(|l| l.starts_with(name))?;
    let soft = line.get(name.len()..)?.split_whitespace().next()?;
    if soft == "unlimited" {
        Some(Limit::Unlimited)
    } else {
        soft.parse().ok().map(Limit::Value)
    }
}

/// A file's mode, owner and group.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Owner {
    /// Permission bits (with the sticky bit).
    pub mode: u32,
    /// Owner.
    pub uid: u32,
    /// Group.
    pub gid: u32,
}

impl Owner {
    /// `0660 root:dialout` style, names from the root's /etc/passwd and /etc/group.
    pub fn describe(&self, host: &Host<'_>) -> String {
        format!(
            "{:04o} {}:{}",
            self.mode & 0o7777,
            host.user_name(self.uid),
            host.group_name(self.gid)
        )
    }
}

/// The machine under a root directory.
pub struct Host<'a> {
    /// `/`, or a fake tree.
    pub root: PathBuf,
    /// The live measurements.
    pub probe: &'a dyn Probe,
}

impl core::fmt::Debug for Host<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Host").field("root", &self.root).finish()
    }
}

impl Host<'_> {
    /// `path` (absolute, as on the machine) under the root.
    pub fn path(&self, path: &str) -> PathBuf {
        under(&self.root, Path::new(path))
    }

    /// The text of a file, trimmed; `None` when it cannot be read.
    pub fn read(&self, path: &str) -> Option<String> {
        self.read_path(&self.path(path))
    }

    /// The text of a file already under the root, trimmed.
    pub fn read_path(&self, path: &Path) -> Option<String> {
        std::fs::read_to_string(path)
            .ok()
            .map(|text| text.trim().to_owned())
    }

    /// Mode, owner and group of a path under the root (following links within the root).
    pub fn owner(&self, path: &Path) -> Option<Owner> {
        let meta = std::fs::metadata(self.resolve(path)?).ok()?;
        Some(Owner {
            mode: meta.mode(),
            uid: meta.uid(),
            gid: meta.gid(),
        })
    }

    /// This process's identity.
    pub fn identity(&self) -> Result<Identity, String> {
        let text = self
            .read("/proc/self/status")
            .ok_or("cannot read /proc/self/status")?;
        Identity::parse(&text).map_err(|e| format!("/proc/self/status: {e}"))
    }

    /// This process's limits text.
    pub fn limits(&self) -> Option<String> {
        self.read("/proc/self/limits")
    }

    /// A user's name from /etc/passwd (the number when unknown).
    pub fn user_name(&self, uid: u32) -> String {
        self.id_name("/etc/passwd", uid)
    }

    /// A group's name from /etc/group (the number when unknown).
    pub fn group_name(&self, gid: u32) -> String {
        self.id_name("/etc/group", gid)
    }

    fn id_name(&self, file: &str, id: u32) -> String {
        self.read(file)
            .and_then(|text| {
                text.lines().find_map(|line| {
                    let mut fields = line.split(':');
                    let name = fields.next()?;
                    let number: u32 = fields.nth(1)?.parse().ok()?;
                    (number == id).then(|| name.to_owned())
                })
            })
            .unwrap_or_else(|| id.to_string())
    }

    /// The online CPUs (`/sys/devices/system/cpu/online`).
    pub fn online_cpus(&self) -> Option<BTreeSet<usize>> {
        self.read("/sys/devices/system/cpu/online")
            .and_then(|text| parse_cpu_list(&text))
    }

    /// `path` under the root with every symbolic link followed inside the root (an absolute
    /// target is taken relative to the root). `None` when a component is missing or the
    /// links loop.
    pub fn resolve(&self, path: &Path) -> Option<PathBuf> {
        let mut rest: Vec<std::ffi::OsString> = components(path);
        rest.reverse();
        let mut current = PathBuf::from("/");
        let mut hops = 0;
        while let Some(part) = rest.pop() {
            if part == ".." {
                current.pop();
                continue;
            }
            let next = current.join(&part);
            let real = under(&self.root, &next);
            match std::fs::symlink_metadata(&real) {
                Ok(meta) if meta.file_type().is_symlink() => {
                    hops += 1;
                    if hops > 40 {
                        return None;
                    }
                    let target = std::fs::read_link(&real).ok()?;
                    if target.is_absolute() {
                        current = PathBuf::from("/");
                    }
                    let mut more = components(&target);
                    more.reverse();
                    rest.extend(more);
                }
                Ok(_) => current = next,
                Err(_) => return None,
            }
        }
        Some(under(&self.root, &current))
    }

    /// The path as the machine names it, from a path under the root.
    pub fn unroot(&self, path: &Path) -> PathBuf {
        path.strip_prefix(&self.root)
            .map_or_else(|_| path.to_path_buf(), |p| Path::new("/").join(p))
    }
}

fn components(path: &Path) -> Vec<std::ffi::OsString> {
    path.components()
        .filter_map(|c| match c {
            Component::Normal(name) => Some(name.to_owned()),
            Component::ParentDir => Some("..".into()),
            _ => None,
        })
        .collect()
}

/// `path` (absolute) under `root`.
pub fn under(root: &Path, path: &Path) -> PathBuf {
    let relative = path.strip_prefix("/").unwrap_or(path);
    root.join(relative)
}

/// A kernel CPU list (`0-3,5,7-8`; `isolcpus` flags such as `domain,managed_irq` are
/// skipped); `None` when a part is not a CPU number or range.
pub fn parse_cpu_list(text: &str) -> Option<BTreeSet<usize>> {
    let mut cpus = BTreeSet::new();
    for part in text.trim().split(',').filter(|p| !p.is_empty()) {
        if part.chars().all(|c| c.is_ascii_alphabetic() || c == '_') {
            continue; // isolcpus=domain,managed_irq,2-3
        }
        // `2-7:2/4` (groups) is rare; the range before the colon is what it covers.
        let range = part.split(':').next().unwrap_or(part);
        match range.split_once('-') {
            Some((a, b)) => {
                let (a, b): (usize, usize) = (a.parse().ok()?, b.parse().ok()?);
                if b < a || b - a > 4096 {
                    return None;
                }
                cpus.extend(a..=b);
            }
            None => {
                cpus.insert(range.parse().ok()?);
            }
        }
    }
    Some(cpus)
}

/// `0-1,3` for a set of CPUs.
pub fn format_cpu_list(cpus: &BTreeSet<usize>) -> String {
    let mut parts: Vec<String> = Vec::new();
    let mut iter = cpus.iter().copied().peekable();
    while let Some(start) = iter.next() {
        let mut end = start;
        while iter.peek() == Some(&(end + 1)) {
            end += 1;
            iter.next();
        }
        parts.push(if end == start {
            start.to_string()
        } else {
            format!("{start}-{end}")
        });
    }
    if parts.is_empty() {
        "none".to_owned()
    } else {
        parts.join(",")
    }
}

/// `16 MiB` style.
pub fn format_bytes(bytes: u64) -> String {
    const MIB: u64 = 1 << 20;
    if bytes >= 10 * 1024 * MIB {
        format!("{} GiB", bytes / (1024 * MIB))
    } else if bytes >= MIB {
        format!("{} MiB", bytes / MIB)
    } else {
        format!("{} KiB", bytes / 1024)
    }
}

#[cfg(test)]
mod tests {
    use super::super::fake::FakeRoot;
    use super::*;

    #[test]
    fn cpu_lists_parse_and_print() {
        let parse = |t: &str| parse_cpu_list(t).map(|s| s.into_iter().collect::<Vec<_>>());
        assert_eq!(parse("0-3,5,7-8"), Some(vec![0, 1, 2, 3, 5, 7, 8]));
        assert_eq!(parse("domain,managed_irq,2-3"), Some(vec![2, 3]));
        assert_eq!(parse("1\n"), Some(vec![1]));
        assert_eq!(parse(""), Some(vec![]));
        assert_eq!(parse("3-1"), None);
        assert_eq!(parse("x1"), None);
        let set: BTreeSet<usize> = [0, 1, 3, 5, 6, 7].into();
        assert_eq!(format_cpu_list(&set), "0-1,3,5-7");
        assert_eq!(format_cpu_list(&BTreeSet::new()), "none");
    }

    #[test]
    fn identity_from_proc_status() {
        let id = Identity::parse(
            "Name:\tx\nUid:\t1000\t998\t998\t998\nGid:\t1000\t997\t997\t997\nGroups:\t20 44\nCapEff:\t0000000000804000\n",
        )
        .expect("parses");
        assert_eq!((id.uid, id.gid), (998, 997));
        assert_eq!(id.groups, BTreeSet::from([20, 44, 997]));
        assert!(id.has_cap(CAP_SYS_NICE) && id.has_cap(CAP_IPC_LOCK));
        assert!(!id.has_cap(0));
        // Owner, group, other bits, and root.
        assert!(id.can_read_write(0o600, 998, 0));
        assert!(
            !id.can_read_write(0o060, 998, 44),
            "the owner bits apply to the owner"
        );
        assert!(id.can_read_write(0o660, 0, 44));
        assert!(!id.can_read_write(0o660, 0, 45));
        assert!(id.can_read_write(0o666, 0, 45));
        assert!(id.can_create_in(0o1777, 0, 0));
        assert!(!id.can_create_in(0o750, 0, 0));
        let root = Identity { uid: 0, ..id };
        assert!(root.can_read_write(0o000, 5, 5));
        assert!(Identity::parse("Uid: x\n").is_err());
    }

    #[test]
    fn limits_parse() {
        let text = "Limit                     Soft Limit           Hard Limit           Units     \n\
                    Max locked memory         8388608              8388608              bytes     \n\
                    Max realtime priority     unlimited            unlimited                      \n";
        assert_eq!(
            soft_limit(text, "Max locked memory"),
            Some(Limit::Value(8 << 20))
        );
        assert_eq!(
            soft_limit(text, "Max realtime priority"),
            Some(Limit::Unlimited)
        );
        assert_eq!(soft_limit(text, "Max open files"), None);
    }

    #[test]
    fn links_resolve_inside_the_root() {
        let fake = FakeRoot::new();
        let probe = LiveProbe;
        let host = Host {
            root: fake.dir.clone(),
            probe: &probe,
        };
        fake.file("/dev/ttyUSB0", "");
        fake.symlink("/dev/serial/by-id/usb-x", "../../ttyUSB0");
        // An absolute target is the root's, not the machine's.
        fake.symlink("/dev/rs485", "/dev/serial/by-id/usb-x");
        assert_eq!(
            host.resolve(Path::new("/dev/rs485")),
            Some(fake.at("/dev/ttyUSB0"))
        );
        fake.symlink("/dev/loop-a", "loop-b");
        fake.symlink("/dev/loop-b", "loop-a");
        assert_eq!(host.resolve(Path::new("/dev/loop-a")), None);
        assert_eq!(host.resolve(Path::new("/dev/nothing")), None);
        assert_eq!(
            host.unroot(&fake.at("/dev/ttyUSB0")),
            Path::new("/dev/ttyUSB0")
        );
    }
}
