//! The recorder thread: drains the tick's journal into a ring of the last
//! `blackbox_seconds` of ticks (the start-up records are kept for good) and writes it to an
//! MCAP file on a fault, an e-stop, SIGUSR2, and on a clean exit when `blackbox_on_exit`
//! is set. It is an ordinary thread: it may allocate, block on the disk and log; the tick
//! never waits for it.

use core::time::Duration;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Instant, SystemTime, UNIX_EPOCH};

use rtrb::Consumer;

use motion_config::private_dir::PrivateDir;

use super::directory;
use super::file::{BlackboxFile, SaveError};
use super::record::Trigger;
use super::ring::Ring;

/// How often the recorder drains the journal.
const DRAIN_EVERY: Duration = Duration::from_millis(50);
/// How long after a fault or an e-stop the ring is saved (so that the reaction to it is in
/// the file too).
const AFTER_TRIGGER: Duration = Duration::from_millis(300);

/// Everything the recorder thread needs.
#[derive(Debug)]
pub struct RecorderSetup {
    /// The tick's journal.
    pub queue: Consumer<u8>,
    /// How many ticks the ring keeps.
    pub keep_ticks: usize,
    /// Bytes the ring holds (allocated and touched at start).
    pub ring_bytes: usize,
    /// What a saved file says about the server (name, config, versions).
    pub file: BlackboxFile,
    /// Where files go (`blackbox_dir`: crate::directory).
    pub dir: PathBuf,
    /// Save on a clean exit.
    pub on_exit: bool,
    /// How many of this server's saves `dir` keeps (crate::directory).
    pub keep_files: usize,
    /// The file naming the newest save (`ServerPidFile::blackbox_pointer`).
    pub pointer: PathBuf,
    /// Set by SIGUSR2: save now.
    pub save_now: Arc<AtomicBool>,
    /// Set when the tick loop has ended: drain what is left, save if `on_exit`, end.
    pub stop: Arc<AtomicBool>,
}

/// Why the ring is saved.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SaveReason {
    /// An axis faulted.
    Fault,
    /// The e-stop latched.
    Estop,
    /// SIGUSR2.
    Signal,
    /// A clean exit with `blackbox_on_exit`.
    Exit,
}

impl SaveReason {
    /// Its word in file names and logs.
    pub fn word(self) -> &'static str {
        match self {
            Self::Fault => "fault",
            Self::Estop => "estop",
            Self::Signal => "sigusr2",
            Self::Exit => "exit",
        }
    }
}

/// Runs the recorder until `stop`.
pub fn run(mut setup: RecorderSetup) {
    let mut ring = Ring::new(setup.keep_ticks, setup.ring_bytes);
    // Triggers within the 300 ms wait make one save, named by the first, logged by all.
    let mut pending: Option<(Vec<SaveReason>, Instant)> = None;
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let stopping = setup.stop.load(Ordering::Acquire);
        drain(&mut setup.queue, &mut ring, &mut buf);
        for (why, _axis) in ring.take_triggers() {
            let reason = match why {
                Trigger::Fault => SaveReason::Fault,
                Trigger::Estop => SaveReason::Estop,
            };
            match &mut pending {
                Some((reasons, _)) if !reasons.contains(&reason) => reasons.push(reason),
                Some(_) => {}
                None => pending = Some((vec![reason], Instant::now() + AFTER_TRIGGER)),
            }
        }
        if setup.save_now.swap(false, Ordering::AcqRel) {
            save(&setup, &ring, &[SaveReason::Signal]);
        }
        if let Some((reasons, at)) = &pending
            && (Instant::now() >= *at || stopping)
        {
            save(&setup, &ring, reasons);
            pending = None;
        }
        if stopping {
            if setup.on_exit {
                save(&setup, &ring, &[SaveReason::Exit]);
            }
            // A clean exit leaves nothing in iceoryx2's directory (the pid file goes too);
            // the log named every file saved.
            let _ = std::fs::remove_file(&setup.pointer);
            return;
        }
        std::thread::sleep(DRAIN_EVERY);
    }
}

fn drain(queue: &mut Consumer<u8>, ring: &mut Ring, buf: &mut [u8]) {
    loop {
        let available = queue.slots().min(buf.len());
        if available == 0 {
            return;
        }
        let Ok(chunk) = queue.read_chunk(available) else {
            return;
        };
        let (first, second) = chunk.as_slices();
        let n = first.len() + second.len();
        buf[..first.len()].copy_from_slice(first);
        buf[first.len()..n].copy_from_slice(second);
        chunk.commit_all();
        ring.push(&buf[..n]);
    }
}

/// Writes the ring (the file named by the first of `reasons`); logs where (or why not)
/// with every reason.
fn save(setup: &RecorderSetup, ring: &Ring, reasons: &[SaveReason]) {
    let Some(&first) = reasons.first() else {
        return;
    };
    let words: Vec<&str> = reasons.iter().map(|reason| reason.word()).collect();
    let words = words.join(", ");
    match save_to_dir(setup, ring, first) {
        Ok(path) => tracing::info!(
            "black box saved ({words}): {} ({} ticks)",
            path.display(),
            ring.len()
        ),
        Err(error) => tracing::error!("black box not saved ({words}): {error}"),
    }
}

fn save_to_dir(
    setup: &RecorderSetup,
    ring: &Ring,
    reason: SaveReason,
) -> Result<PathBuf, SaveError> {
    // Opened and checked at every save: one removed meanwhile is made again, and one
    // replaced by another user's (or a link) is refused.
    let dir = PrivateDir::open(&setup.dir, directory::KEY, directory::DIR_MODE)?;
    let millis = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |since| since.as_millis() as u64);
    let server = &setup.file.server_name;
    let (name, file) =
        directory::create(&dir, server, millis, reason.word()).map_err(|source| SaveError::Io {
            path: dir.file_path(&directory::file_name(server, millis, reason.word())),
            source,
        })?;
    let path = dir.file_path(&name);
    if let Err(error) = setup
        .file
        .write_to(file, &path, &ring.ticks(), reason.word())
    {
        let _ = dir.remove(&name);
        return Err(error);
    }
    dir.sync();
    for removed in directory::remove_oldest(&dir, server, setup.keep_files, &name) {
        tracing::info!(
            "black box {} removed (blackbox_keep)",
            dir.file_path(&removed).display()
        );
    }
    point_to(&setup.pointer, &path);
    Ok(path)
}

/// Rewrites the pointer file (`motionctl blackbox save` reads it) to name `saved`: a
/// temporary file made `O_EXCL` (never through a link planted at its name) renamed over
/// it, so a reader sees the old name or the new one.
fn point_to(pointer: &std::path::Path, saved: &std::path::Path) {
    use std::io::Write as _;
    use std::os::unix::fs::OpenOptionsExt as _;
    let absolute = std::path::absolute(saved).unwrap_or_else(|_| saved.to_owned());
    let temporary = pointer.with_extension(format!("blackbox.{}.new", std::process::id()));
    let _ = std::fs::remove_file(&temporary);
    let written = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .custom_flags(libc::O_NOFOLLOW)
        .mode(0o644)
        .open(&temporary)
        .and_then(|mut file| file.write_all(format!("{}\n", absolute.display()).as_bytes()))
        .and_then(|()| std::fs::rename(&temporary, pointer));
    if let Err(error) = written {
        let _ = std::fs::remove_file(&temporary);
        tracing::warn!(
            "black box pointer {} not written: {error}",
            pointer.display()
        );
    }
}
