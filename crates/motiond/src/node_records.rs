//! The records iceoryx2 keeps of every node on the service root (`<root>/nodes/`), and the
//! sweep that removes those of dead processes — run by the main thread at every liveness
//! check, never by the tick.
//!
//! iceoryx2 removes a dead node's resources itself (`DeadNodeView::try_remove_stale_resources`)
//! but leaves records behind when a process dies while its node is being created or while
//! it opens a service: a details directory holding only a service or port tag (iceoryx2's
//! last step, removing the then non-empty directory, fails and is retried forever), a
//! directory without a monitor (invisible to `Node::list`), monitor files without the
//! monitor itself. 200 clients SIGKILLed 0–60 ms after start left 96 such records that no
//! process ever removed. The sweep removes them once they are older than
//! [`RESIDUE_AGE`] (a node being created has its directory for microseconds before its
//! details file, and its monitor right after), at most `budget` records per pass.

use core::time::Duration;
use std::collections::{HashMap, HashSet};
use std::fs;
use std::path::{Path, PathBuf};
use std::time::SystemTime;

use iceoryx2::node::{Node, NodeState, NodeView as _};
use iceoryx2::prelude::{CallbackProgression, Config};
use iceoryx2::service::ipc::Service as Ipc;

/// A record younger than this may belong to a node being created: left alone.
pub const RESIDUE_AGE: Duration = Duration::from_secs(1);

/// Records removed by one sweep at most.
pub const SWEEP_BUDGET: usize = 64;

/// What one sweep found and did.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Sweep {
    /// Ids of the dead nodes found (their claims end).
    pub dead: Vec<u128>,
    /// Live nodes other than the one excepted.
    pub live: u32,
    /// Dead nodes' records removed, by iceoryx2 or by this sweep.
    pub cleaned: u32,
}

/// The names iceoryx2 gives a node's records, read from its config.
#[derive(Debug, Clone)]
struct Layout {
    dir: PathBuf,
    prefix: String,
    monitor: String,
}

impl Layout {
    fn of(config: &Config) -> Self {
        let global = &config.global;
        Self {
            dir: PathBuf::from(global.node_dir().as_str()),
            prefix: global.prefix.as_str().to_owned(),
            monitor: global.node.monitor_suffix.as_str().to_owned(),
        }
    }

    /// The node id a record's file name belongs to: `<id>` (the details directory) or
    /// `<prefix><id><monitor suffix>[_context|_owner_lock]` (the monitor's files).
    fn id_of(&self, name: &str) -> Option<u128> {
        if let Ok(id) = name.parse::<u128>() {
            return Some(id);
        }
        let rest = name.strip_prefix(&self.prefix)?;
        let (id, suffix) = rest.split_once('.')?;
        let suffix = format!(".{suffix}");
        if !suffix.starts_with(&self.monitor) {
            return None;
        }
        id.parse().ok()
    }

    fn details_dir(&self, id: u128) -> PathBuf {
        self.dir.join(id.to_string())
    }

    /// Every file of node `id`'s monitor.
    fn monitor_files(&self, id: u128) -> Vec<PathBuf> {
        ["", "_context", "_owner_lock"]
            .iter()
            .map(|tail| {
                self.dir
                    .join(format!("{}{id}{}{tail}", self.prefix, self.monitor))
            })
            .collect()
    }
}

fn older_than(path: &Path, age: Duration) -> bool {
    fs::symlink_metadata(path)
        .and_then(|meta| meta.modified())
        .is_ok_and(|modified| {
            SystemTime::now()
                .duration_since(modified)
                .is_ok_and(|elapsed| elapsed >= age)
        })
}

/// Whether some process holds a lock on `path` (how iceoryx2's monitor tells a live node:
/// its process keeps a POSIX write lock on the monitor file). Unknown counts as locked.
fn locked(path: &Path) -> bool {
    let Ok(file) = fs::OpenOptions::new().read(true).write(true).open(path) else {
        return path.exists();
    };
    let mut lock = libc::flock {
        l_type: libc::F_WRLCK as libc::c_short,
        l_whence: libc::SEEK_SET as libc::c_short,
        l_start: 0,
        l_len: 0,
        l_pid: 0,
    };
    match nix::fcntl::fcntl(&file, nix::fcntl::FcntlArg::F_GETLK(&mut lock)) {
        Ok(_) => lock.l_type != libc::F_UNLCK as libc::c_short,
        Err(_) => true,
    }
}

/// Removes node `id`'s details directory and its monitor files; whether anything was
/// removed.
fn remove_residue(layout: &Layout, id: u128) -> bool {
    let mut removed = false;
    let dir = layout.details_dir(id);
    if let Ok(entries) = fs::read_dir(&dir) {
        for entry in entries.flatten() {
            removed |= fs::remove_file(entry.path()).is_ok();
        }
        removed |= fs::remove_dir(&dir).is_ok();
    }
    for file in layout.monitor_files(id) {
        removed |= fs::remove_file(file).is_ok();
    }
    removed
}

/// Sweeps the node records of one iceoryx2 root, remembering across passes which dead
/// nodes iceoryx2 failed to clean.
#[derive(Debug)]
pub struct Sweeper {
    config: Config,
    layout: Layout,
    /// Dead nodes whose clean-up failed, with the passes that saw it fail.
    failed: HashMap<u128, u32>,
    /// What the last full sweep found when every node it listed was alive and nothing
    /// was left to clean: while nothing changes, a sweep only checks that it still holds.
    quiet: Option<Quiet>,
}

/// How often a sweep lists every node even though nothing seemed to change (a node's state
/// can change inside its own details directory, which the quick check does not watch).
pub const FULL_SWEEP_EVERY: Duration = Duration::from_secs(1);

/// A node directory in which only live nodes were found.
#[derive(Debug, Clone)]
struct Quiet {
    /// The node directory's modification time before that listing.
    modified: SystemTime,
    /// The live nodes' monitors (the server's own excluded: checking a lock this process
    /// holds would release it).
    monitors: Vec<PathBuf>,
    /// The live nodes counted.
    live: u32,
    /// When that listing was made.
    at: std::time::Instant,
}

/// The modification time of `dir` (changed by every node record made or removed in it).
fn modified(dir: &Path) -> Option<SystemTime> {
    fs::metadata(dir).and_then(|meta| meta.modified()).ok()
}

impl Quiet {
    /// Nothing changed since: no record made or removed, every live node still holds its
    /// monitor's lock (a node that dies releases it). A few system calls a node, against
    /// iceoryx2's listing, which reads and parses every node's details.
    fn holds(&self, dir: &Path) -> bool {
        self.at.elapsed() < FULL_SWEEP_EVERY
            && modified(dir) == Some(self.modified)
            && self.monitors.iter().all(|monitor| locked(monitor))
    }
}

impl Default for Sweeper {
    fn default() -> Self {
        Self::new(Config::global_config().clone())
    }
}

impl Sweeper {
    /// A sweeper of `config`'s root.
    pub fn new(config: Config) -> Self {
        let layout = Layout::of(&config);
        Self {
            config,
            layout,
            failed: HashMap::new(),
            quiet: None,
        }
    }

    /// Dead nodes and live ones (see [`Sweeper::full_sweep`]), listed only when something
    /// may have changed since the last listing found nothing but live nodes, and at least
    /// every [`FULL_SWEEP_EVERY`].
    pub fn sweep(&mut self, except: u128, residue_age: Duration, budget: usize) -> Sweep {
        if let Some(quiet) = &self.quiet
            && quiet.holds(&self.layout.dir)
        {
            return Sweep {
                dead: Vec::new(),
                live: quiet.live,
                cleaned: 0,
            };
        }
        // Taken before the listing: a change during it makes the next check fail.
        let before = modified(&self.layout.dir);
        let (sweep, alive) = self.full_sweep(except, residue_age, budget);
        self.quiet = match (before, alive) {
            (Some(modified), Some(alive)) if sweep.dead.is_empty() && sweep.cleaned == 0 => {
                Some(Quiet {
                    modified,
                    monitors: alive
                        .into_iter()
                        .filter(|&id| id != except)
                        .map(|id| self.layout.monitor_files(id).swap_remove(0))
                        .collect(),
                    live: sweep.live,
                    at: std::time::Instant::now(),
                })
            }
            _ => None,
        };
        sweep
    }

    /// One pass over every node: dead nodes' resources removed by iceoryx2; what it cannot
    /// remove removed here once every record of the node is older than `residue_age` and
    /// no process holds its monitor (at most `budget` nodes a pass); live nodes other than
    /// `except` counted. Returns the ids of the live nodes when the listing was complete,
    /// every node in it alive and no residue seen (`None` otherwise).
    ///
    /// A dead node iceoryx2 cannot clean, or one whose monitor it cannot read, because its
    /// monitor's owner lock file is gone (a cleaner or the node itself died half-way) gets
    /// that file back once, so that iceoryx2's own clean-up — which also takes the node
    /// out of every service it had joined — runs at the next pass; a node that still fails
    /// then, or that no listing shows at all (it died before its monitor was complete), has
    /// its files removed.
    fn full_sweep(
        &mut self,
        except: u128,
        residue_age: Duration,
        budget: usize,
    ) -> (Sweep, Option<Vec<u128>>) {
        let layout = &self.layout;
        let mut sweep = Sweep::default();
        let mut listed = HashSet::new();
        let mut stuck = Vec::new();
        let mut alive = Vec::new();
        let mut only_alive = true;
        let complete = Node::<Ipc>::list(&self.config, |state| {
            listed.insert(state.node_id().value());
            if let NodeState::Alive(view) = &state {
                alive.push(view.id().value());
            } else {
                only_alive = false;
            }
            match state {
                NodeState::Dead(view) => {
                    let id = view.id().value();
                    sweep.dead.push(id);
                    match view.try_remove_stale_resources() {
                        Ok(()) => sweep.cleaned += 1,
                        Err(_) => stuck.push(id),
                    }
                }
                NodeState::Alive(view) if view.id().value() != except => sweep.live += 1,
                // A monitor iceoryx2 cannot read (its context file half-written, or its
                // owner lock gone while its state file stays: "corrupted"): iceoryx2
                // neither shows it dead nor ever removes it. Handled as a dead node whose
                // clean-up failed: same age and lock checks, same owner-lock repair, then
                // removal.
                NodeState::Undefined(id) => stuck.push(id.value()),
                _ => {}
            }
            CallbackProgression::Continue
        })
        .is_ok();
        self.failed.retain(|id, _| stuck.contains(id));
        let mut budget = budget;
        let old_and_unlocked = |id: u128| {
            let monitor = &layout.monitor_files(id)[0];
            core::iter::once(layout.details_dir(id))
                .chain(layout.monitor_files(id))
                .filter(|path| path.exists())
                .all(|path| older_than(&path, residue_age))
                && !locked(monitor)
        };
        for id in stuck {
            if budget == 0 {
                return (sweep, None);
            }
            if !old_and_unlocked(id) {
                continue;
            }
            let passes = self.failed.entry(id).or_insert(0);
            *passes += 1;
            let owner_lock = &layout.monitor_files(id)[2];
            if *passes == 1 && !owner_lock.exists() {
                // iceoryx2's cleaner needs the owner lock file to take the node over.
                let _ = fs::File::create(owner_lock);
                continue;
            }
            if *passes >= 2 && remove_residue(layout, id) {
                sweep.cleaned += 1;
                budget -= 1;
            }
        }
        // Records no listing shows: a node that died before its monitor was complete
        // (iceoryx2 takes it for one still starting, forever), a details directory without
        // a monitor, monitor files without the monitor. Only after a complete listing:
        // a record missing from a failed one may be a live node's.
        if !complete {
            return (sweep, None);
        }
        let Ok(entries) = fs::read_dir(&layout.dir) else {
            return (sweep, None);
        };
        let mut orphans = HashSet::new();
        for entry in entries.flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            if let Some(id) = layout.id_of(&name)
                && !listed.contains(&id)
                && id != except
            {
                orphans.insert(id);
            }
        }
        if !orphans.is_empty() {
            only_alive = false;
        }
        for id in orphans {
            if budget == 0 {
                break;
            }
            // A node created since the listing is younger than `residue_age`; one being
            // created has its monitor a few microseconds after its details directory.
            if old_and_unlocked(id) && remove_residue(layout, id) {
                sweep.cleaned += 1;
                budget -= 1;
            }
        }
        (sweep, only_alive.then_some(alive))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch_config(tag: &str) -> (Config, PathBuf) {
        let root = std::env::temp_dir().join(format!("motiond-nodes-{tag}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&root);
        fs::create_dir_all(root.join("nodes")).unwrap();
        let mut config = Config::default();
        let text = format!("{}/", root.display());
        config
            .global
            .set_root_path(&iceoryx2::prelude::Path::new_normalized(text.as_bytes()).unwrap());
        (config, root)
    }

    /// Another process that takes the POSIX write lock iceoryx2's live nodes hold on
    /// `monitor`, and holds it until killed.
    fn hold_lock(monitor: &Path) -> std::process::Child {
        let mut holder = std::process::Command::new("python3")
            .args([
                "-c",
                "import fcntl,sys,time\nf=open(sys.argv[1],'r+')\nfcntl.lockf(f,fcntl.LOCK_EX)\nprint('held',flush=True)\ntime.sleep(60)",
            ])
            .arg(monitor)
            .stdout(std::process::Stdio::piped())
            .spawn()
            .expect("python3 (scripts/test installs it)");
        let mut line = String::new();
        std::io::BufRead::read_line(
            &mut std::io::BufReader::new(holder.stdout.take().unwrap()),
            &mut line,
        )
        .unwrap();
        assert_eq!(line.trim(), "held");
        holder
    }

    #[test]
    fn record_names_map_to_node_ids() {
        let layout = Layout::of(&Config::default());
        assert_eq!(layout.id_of("1302643"), Some(1_302_643));
        assert_eq!(layout.id_of("iox2_77.node_monitor"), Some(77));
        assert_eq!(layout.id_of("iox2_77.node_monitor_context"), Some(77));
        assert_eq!(layout.id_of("iox2_77.node_monitor_owner_lock"), Some(77));
        assert_eq!(layout.id_of("iox2_77.service_tag"), None);
        assert_eq!(layout.id_of("motiond-demo.pid"), None);
        assert_eq!(layout.id_of("iox2_x.node_monitor"), None);
    }

    #[test]
    fn orphaned_records_older_than_the_age_go_and_young_ones_stay() {
        let (config, root) = scratch_config("orphans");
        let nodes = root.join("nodes");
        let mut sweeper = Sweeper::new(config);
        // A directory with a tag only, no monitor (iceoryx2's failed last step).
        fs::create_dir(nodes.join("11")).unwrap();
        fs::write(nodes.join("11/iox2_abc.service_tag"), b"").unwrap();
        // Monitor files without the monitor.
        fs::write(nodes.join("iox2_12.node_monitor_context"), b"x").unwrap();
        // Details and a monitor no listing shows (died while its monitor was made).
        fs::create_dir(nodes.join("13")).unwrap();
        fs::write(nodes.join("13/iox2_node.details"), b"").unwrap();
        fs::write(nodes.join("iox2_13.node_monitor"), b"").unwrap();

        // Too young: nothing goes.
        let swept = sweeper.sweep(0, Duration::from_secs(3600), SWEEP_BUDGET);
        assert_eq!(swept.cleaned, 0);
        assert!(nodes.join("11").exists() && nodes.join("iox2_12.node_monitor_context").exists());
        assert!(nodes.join("13/iox2_node.details").exists());

        // Old enough: the orphans go; the budget bounds a pass.
        let swept = sweeper.sweep(0, Duration::ZERO, 2);
        assert_eq!(swept.cleaned, 2);
        let swept = sweeper.sweep(0, Duration::ZERO, SWEEP_BUDGET);
        assert_eq!(swept.cleaned, 1);
        assert_eq!(fs::read_dir(&nodes).unwrap().count(), 0);
        let swept = sweeper.sweep(0, Duration::ZERO, SWEEP_BUDGET);
        assert_eq!(swept, Sweep::default());
        fs::remove_dir_all(root).unwrap();
    }

    #[test]
    fn a_node_iceoryx2_cannot_read_is_repaired_or_removed() {
        let (config, root) = scratch_config("undefined");
        let nodes = root.join("nodes");
        // A monitor whose context file exists but holds no process id (the process died
        // while writing it) and no owner lock: iceoryx2 lists the node as `Undefined`.
        fs::write(nodes.join("iox2_41.node_monitor"), b"").unwrap();
        fs::write(nodes.join("iox2_41.node_monitor_context"), b"").unwrap();
        fs::create_dir(nodes.join("41")).unwrap();
        fs::write(nodes.join("41/iox2_node.details"), b"").unwrap();
        let mut undefined = 0;
        Node::<Ipc>::list(&config, |state| {
            undefined += usize::from(matches!(state, NodeState::Undefined(_)));
            CallbackProgression::Continue
        })
        .unwrap();
        assert_eq!(undefined, 1, "the fixture is what iceoryx2 calls undefined");

        let mut sweeper = Sweeper::new(config);
        // Too young: left alone.
        let swept = sweeper.sweep(0, Duration::from_secs(3600), SWEEP_BUDGET);
        assert_eq!(swept.cleaned, 0);
        assert!(nodes.join("iox2_41.node_monitor").exists());
        // First pass: the owner lock is given back for iceoryx2's own clean-up; second:
        // still unreadable, the records go.
        let swept = sweeper.sweep(0, Duration::ZERO, SWEEP_BUDGET);
        assert_eq!(swept.cleaned, 0);
        assert!(nodes.join("iox2_41.node_monitor_owner_lock").exists());
        let swept = sweeper.sweep(0, Duration::ZERO, SWEEP_BUDGET);
        assert_eq!(swept.cleaned, 1);
        assert_eq!(fs::read_dir(&nodes).unwrap().count(), 0);
        fs::remove_dir_all(root).unwrap();
    }

    #[test]
    fn a_monitor_another_process_holds_is_never_removed() {
        let (config, root) = scratch_config("locked");
        let nodes = root.join("nodes");
        let monitor = nodes.join("iox2_21.node_monitor");
        fs::write(&monitor, b"").unwrap();
        // Another process takes the POSIX write lock iceoryx2's live nodes hold.
        let mut holder = hold_lock(&monitor);
        assert!(locked(&monitor));
        let mut sweeper = Sweeper::new(config);
        let swept = sweeper.sweep(0, Duration::ZERO, SWEEP_BUDGET);
        assert_eq!(swept.cleaned, 0);
        assert!(monitor.exists());
        holder.kill().unwrap();
        holder.wait().unwrap();
        assert!(!locked(&monitor));
        let swept = sweeper.sweep(0, Duration::ZERO, SWEEP_BUDGET);
        assert_eq!(swept.cleaned, 1);
        assert!(!monitor.exists());
        fs::remove_dir_all(root).unwrap();
    }

    #[test]
    fn a_quiet_directory_holds_until_a_record_changes_or_a_live_node_lets_go() {
        let (_config, root) = scratch_config("quiet");
        let nodes = root.join("nodes");
        let monitor = nodes.join("iox2_31.node_monitor");
        fs::write(&monitor, b"").unwrap();
        let mut holder = hold_lock(&monitor);
        let quiet = |at| Quiet {
            modified: modified(&nodes).expect("a directory"),
            monitors: vec![monitor.clone()],
            live: 1,
            at,
        };
        assert!(quiet(std::time::Instant::now()).holds(&nodes));
        // Too old: list again.
        let long_ago = std::time::Instant::now() - FULL_SWEEP_EVERY;
        assert!(!quiet(long_ago).holds(&nodes));
        // A record made in the directory.
        let before = quiet(std::time::Instant::now());
        std::thread::sleep(Duration::from_millis(10));
        fs::write(nodes.join("iox2_32.node_monitor"), b"").unwrap();
        assert!(!before.holds(&nodes));
        // The live node dies: its lock goes.
        let after = quiet(std::time::Instant::now());
        assert!(after.holds(&nodes));
        holder.kill().unwrap();
        holder.wait().unwrap();
        assert!(!after.holds(&nodes));
        fs::remove_dir_all(root).unwrap();
    }
}
