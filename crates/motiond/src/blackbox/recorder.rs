//! The recorder thread: drains the tick's journal into a ring of the last
//! `blackbox_seconds` of ticks (the start-up records are kept for good) and writes it to an
//! MCAP file on a fault, an e-stop, SIGUSR2, and on a clean exit when `blackbox_on_exit`
//! is set. It is an ordinary thread: it may allocate, block on the disk and log; the tick
//! never waits for it.

use core::time::Duration;
use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Instant, SystemTime, UNIX_EPOCH};

use rtrb::Consumer;

use super::file::{BlackboxFile, SaveError, Ticks};
use super::record::{HEADER_LEN, Kind, Trigger, records};

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
    /// What a saved file says about the server (name, config, versions).
    pub file: BlackboxFile,
    /// Where files go.
    pub dir: PathBuf,
    /// Save on a clean exit.
    pub on_exit: bool,
    /// How many `.mcap` files `dir` keeps.
    pub keep_files: usize,
    /// The file naming the newest save (`ServerPidFile::blackbox_pointer`).
    pub pointer: PathBuf,
    /// Set by SIGUSR2: save now.
    pub save_now: Arc<AtomicBool>,
    /// Set when the tick loop has ended: drain what is left, save if `on_exit`, end.
    pub stop: Arc<AtomicBool>,
}

/// One tick's records.
#[derive(Debug, Default)]
struct TickRecords {
    tick: u64,
    bytes: Vec<u8>,
}

/// The ring and the bytes not yet split into records.
#[derive(Debug, Default)]
pub struct Ring {
    /// Records before the first tick (the start).
    head: Vec<u8>,
    ticks: VecDeque<TickRecords>,
    keep: usize,
    /// Drained bytes that do not make a whole record yet.
    partial: Vec<u8>,
    /// Emptied buffers, reused.
    spare: Vec<Vec<u8>>,
    /// Triggers seen since the last take.
    triggers: Vec<(Trigger, u32)>,
    /// Ticks dropped from the front (the ring wrapped).
    pub dropped: u64,
}

impl Ring {
    /// A ring keeping `keep` ticks.
    pub fn new(keep: usize) -> Self {
        Self {
            keep: keep.max(1),
            ..Self::default()
        }
    }

    /// Takes in drained journal bytes.
    pub fn push(&mut self, bytes: &[u8]) {
        self.partial.extend_from_slice(bytes);
        let mut used = 0;
        while let Some(header) = self.partial.get(used..used + HEADER_LEN) {
            let len = u32::from_le_bytes([header[2], header[3], header[4], header[5]]) as usize;
            let end = used + HEADER_LEN + len;
            if end > self.partial.len() {
                break;
            }
            let kind = Kind::from_u8(header[0]);
            if kind == Some(Kind::Tick) {
                let tick = records(&self.partial[used..end])
                    .next()
                    .and_then(Result::ok)
                    .map_or(0, |record| record.u64_at(8));
                let mut bytes = self.spare.pop().unwrap_or_default();
                bytes.clear();
                self.ticks.push_back(TickRecords { tick, bytes });
                while self.ticks.len() > self.keep {
                    if let Some(old) = self.ticks.pop_front() {
                        self.spare.push(old.bytes);
                        self.dropped += 1;
                    }
                }
            }
            if kind == Some(Kind::Trigger) {
                let payload = &self.partial[used + HEADER_LEN..end];
                let why = match payload.first() {
                    Some(2) => Trigger::Estop,
                    _ => Trigger::Fault,
                };
                let axis = payload
                    .get(1..5)
                    .map_or(u32::MAX, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
                self.triggers.push((why, axis));
            }
            let record = &self.partial[used..end];
            match self.ticks.back_mut() {
                Some(current) => current.bytes.extend_from_slice(record),
                None => self.head.extend_from_slice(record),
            }
            used = end;
        }
        self.partial.drain(..used);
    }

    /// The triggers seen since the last call.
    pub fn take_triggers(&mut self) -> Vec<(Trigger, u32)> {
        std::mem::take(&mut self.triggers)
    }

    /// The ring as the file writes it.
    pub fn ticks(&self) -> Ticks<'_> {
        Ticks {
            head: &self.head,
            ticks: self
                .ticks
                .iter()
                .map(|t| (t.tick, t.bytes.as_slice()))
                .collect(),
            dropped: self.dropped,
        }
    }
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
    let mut ring = Ring::new(setup.keep_ticks);
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
            ring.ticks.len()
        ),
        Err(error) => tracing::error!("black box not saved ({words}): {error}"),
    }
}

fn save_to_dir(
    setup: &RecorderSetup,
    ring: &Ring,
    reason: SaveReason,
) -> Result<PathBuf, SaveError> {
    std::fs::create_dir_all(&setup.dir).map_err(|source| SaveError::Io {
        path: setup.dir.clone(),
        source,
    })?;
    let millis = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |since| since.as_millis());
    let path = setup.dir.join(format!(
        "{}-{millis}-{}.mcap",
        setup.file.server_name,
        reason.word()
    ));
    setup.file.write(&path, &ring.ticks(), reason.word())?;
    remove_oldest(&setup.dir, setup.keep_files);
    point_to(&setup.pointer, &path);
    Ok(path)
}

/// Rewrites the pointer file (`motionctl blackbox save` reads it) to name `saved`: a
/// temporary file renamed over it, so a reader sees the old name or the new one.
fn point_to(pointer: &std::path::Path, saved: &std::path::Path) {
    let absolute = std::path::absolute(saved).unwrap_or_else(|_| saved.to_owned());
    let temporary = pointer.with_extension("blackbox.new");
    let written = std::fs::write(&temporary, format!("{}\n", absolute.display()))
        .and_then(|()| std::fs::rename(&temporary, pointer));
    if let Err(error) = written {
        tracing::warn!(
            "black box pointer {} not written: {error}",
            pointer.display()
        );
    }
}

/// Removes the oldest `.mcap` files of `dir` beyond the newest `keep` (a file another
/// process removed meanwhile is no error).
fn remove_oldest(dir: &std::path::Path, keep: usize) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut files: Vec<(SystemTime, PathBuf)> = entries
        .filter_map(Result::ok)
        .map(|entry| entry.path())
        .filter(|path| path.extension().is_some_and(|ext| ext == "mcap"))
        .filter_map(|path| Some((path.metadata().ok()?.modified().ok()?, path)))
        .collect();
    files.sort();
    let excess = files.len().saturating_sub(keep);
    for (_, path) in files.into_iter().take(excess) {
        if std::fs::remove_file(&path).is_ok() {
            tracing::info!("black box {} removed (blackbox_keep)", path.display());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(kind: Kind, payload: &[u8]) -> Vec<u8> {
        let mut bytes = vec![kind as u8, 0];
        bytes.extend_from_slice(&(payload.len() as u32).to_le_bytes());
        bytes.extend_from_slice(payload);
        bytes
    }

    fn tick(n: u64) -> Vec<u8> {
        let mut payload = (n * 1_000_000).to_le_bytes().to_vec();
        payload.extend_from_slice(&n.to_le_bytes());
        record(Kind::Tick, &payload)
    }

    #[test]
    fn the_ring_keeps_the_start_and_the_last_ticks_from_bytes_split_anywhere() {
        let mut journal = record(Kind::Start, &[0; 16]);
        for n in 0..10 {
            journal.extend(tick(n));
            journal.extend(record(Kind::LinkRx, &[1, 2, 3]));
        }
        journal.extend(record(Kind::Trigger, &[2, 4, 0, 0, 0]));
        let mut ring = Ring::new(4);
        // Fed in pieces of 7 bytes: records cut in the middle wait for their rest.
        for piece in journal.chunks(7) {
            ring.push(piece);
        }
        let ticks = ring.ticks();
        assert_eq!(ticks.head, record(Kind::Start, &[0; 16]).as_slice());
        let kept: Vec<u64> = ticks.ticks.iter().map(|(tick, _)| *tick).collect();
        assert_eq!(kept, [6, 7, 8, 9]);
        assert_eq!(ticks.dropped, 6);
        let mut last = tick(9);
        last.extend(record(Kind::LinkRx, &[1, 2, 3]));
        last.extend(record(Kind::Trigger, &[2, 4, 0, 0, 0]));
        assert_eq!(ticks.ticks[3].1, last.as_slice());
        assert_eq!(ring.take_triggers(), [(Trigger::Estop, 4)]);
        assert!(ring.take_triggers().is_empty());
    }
}
