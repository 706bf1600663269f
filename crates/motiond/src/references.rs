//! References across a restart of the server (issue 29; docs/ARCHITECTURE.md "References
//! across a server restart", docs/keys/tmcpack.md). For the devices whose driver asks for it
//! ([`Driver::keeps_references`]: a Trinamic pack with `power_down = "restore"`), the server
//! keeps a file, `<state_dir>/<server name>.references.toml`, saying which of their axes it
//! last saw referenced and at rest, and at which position (the board's counts), with what
//! identifies each axis: server name, device name, model, address, link, axis name,
//! channel, and a fingerprint of the device's and the axis's keys. At its next start it
//! reads the file and hands every matching record to the driver
//! ([`Driver::restore_references`]) before the driver's first step; the driver decides
//! from what the board says whether the axis is referenced again.
//!
//! The tick only looks at the frame it just wrote ([`Watch::observe`]: a comparison per
//! watched axis, and a push into a bounded ring when something changed — no allocation, no
//! file, no lock); the main thread drains the ring and writes the file ([`Keeper`]), a
//! temporary file renamed over the old one, so that a reader (the next start) sees the old
//! file or the new one, never half of one.
//!
//! What counts as referenced and at rest is read from a frame only while the axis's device
//! is online and its data fresh: HOMED, not MOVING, no fault, and holding (`hold`, `off`, or
//! arrived at a position target). Any other frame of an online device with fresh data
//! writes the axis as not referenced: a move is written as soon as the command that starts
//! it is taken (the mode changes in that tick's frame), before a byte of it is on the wire.
//! A device that is not online (starting, offline, faulted — as in the pack's own
//! power-down state) leaves the axis's record as it was: it is the state before the board
//! went, which is what the board's own saved positions are compared with.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use motion_boards::AnyDriver;
use motion_drivers::{Driver, SavedReference};
use motion_ipc::{AxisFlags, AxisMode, DeviceState, MotionFrame};
use serde::{Deserialize, Serialize};

use crate::config::ServerConfig;

/// Samples the ring holds between two passes of the main thread (10 ms apart).
const RING: usize = 256;

/// One watched axis's state as the tick last sent it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Sample {
    /// Index into the watched axes.
    pub slot: u16,
    /// Referenced and at rest.
    pub referenced: bool,
    /// Position in the board's counts.
    pub counts: i64,
}

/// The tick's side: the watched axes and what it last sent for each.
#[derive(Debug)]
pub struct Watch {
    /// (axis index, last sample sent).
    axes: Vec<(usize, Option<Sample>)>,
    tx: rtrb::Producer<Sample>,
    /// What start-up handed each driver (device index, reference): the black box journals
    /// it, so that a replay hands its drivers the same.
    restored: Vec<(usize, SavedReference)>,
}

impl Watch {
    /// The references start-up handed the drivers: (device index, reference).
    pub fn restored(&self) -> &[(usize, SavedReference)] {
        &self.restored
    }

    /// Looks at the frame the tick just wrote: a sample for every watched axis whose state
    /// changed (no allocation; a full ring is retried at the next tick).
    pub fn observe(&mut self, frame: &MotionFrame) {
        for (slot, (axis, last)) in self.axes.iter_mut().enumerate() {
            let Some(state) = frame.axes.get(*axis) else {
                continue;
            };
            let flags = AxisFlags(state.flags);
            let online = state.device_state == DeviceState::Online as u8;
            if !online || flags.contains(AxisFlags::STALE) {
                continue;
            }
            let holding = match state.mode().ok() {
                Some(AxisMode::Hold | AxisMode::Off) => true,
                Some(AxisMode::Position | AxisMode::RampPosition) => {
                    flags.contains(AxisFlags::ARRIVED)
                }
                _ => false,
            };
            let referenced = holding
                && flags.contains(AxisFlags::HOMED)
                && !flags.contains(AxisFlags::MOVING)
                && !flags.contains(AxisFlags::FAULT)
                && state.fault == 0;
            let sample = Sample {
                slot: slot as u16,
                referenced,
                counts: state.raw_counts,
            };
            // An unreferenced axis's position does not matter: only a change of either
            // (referenced, or referenced elsewhere) is sent.
            let same = last.is_some_and(|l| {
                l.referenced == referenced && (!referenced || l.counts == sample.counts)
            });
            if !same && self.tx.push(sample).is_ok() {
                *last = Some(sample);
            }
        }
    }
}

/// One axis in the file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Record {
    axis: String,
    device: String,
    model: String,
    address: u32,
    link: String,
    channel: usize,
    /// FNV-1a 64 of the device's and the axis's keys as the driver gets them.
    keys: String,
    referenced: bool,
    counts: i64,
}

/// The file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    server: String,
    #[serde(default)]
    axis: Vec<Record>,
}

/// The main thread's side: the records, the file, the tick's samples.
#[derive(Debug)]
pub struct Keeper {
    path: PathBuf,
    file: File,
    rx: rtrb::Consumer<Sample>,
    /// The last write failed (logged once until one succeeds).
    failing: bool,
}

impl Keeper {
    /// Takes the tick's samples in and writes the file when a record changed.
    pub fn drain(&mut self) {
        let mut changed = false;
        while let Ok(sample) = self.rx.pop() {
            if let Some(record) = self.file.axis.get_mut(usize::from(sample.slot)) {
                let counts = if sample.referenced { sample.counts } else { 0 };
                if record.referenced != sample.referenced || record.counts != counts {
                    record.referenced = sample.referenced;
                    record.counts = counts;
                    changed = true;
                }
            }
        }
        if changed {
            self.write();
        }
    }

    fn write(&mut self) {
        match write_atomically(&self.path, &self.file) {
            Ok(()) => self.failing = false,
            Err(error) => {
                if !self.failing {
                    tracing::warn!(
                        "references: cannot write {}: {error}; the axes will need a new reference after a restart",
                        self.path.display()
                    );
                }
                self.failing = true;
            }
        }
    }
}

/// The file of server `name` in `dir`.
pub fn file_path(dir: &Path, name: &str) -> PathBuf {
    dir.join(format!("{name}.references.toml"))
}

/// FNV-1a 64 of `text`, as 16 hex digits (stable across builds and platforms).
fn fingerprint(text: &str) -> String {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for byte in text.bytes() {
        hash ^= u64::from(byte);
        hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{hash:016x}")
}

/// The records of this config's watched axes, not referenced, in axis order.
fn records(config: &ServerConfig, drivers: &[AnyDriver]) -> Vec<(usize, Record)> {
    let mut out = Vec::new();
    for (index, axis) in config.axes.iter().enumerate() {
        let Some(device) = config.devices.get(axis.device) else {
            continue;
        };
        if !drivers
            .get(axis.device)
            .is_some_and(Driver::keeps_references)
        {
            continue;
        }
        let spec = crate::drivers::driver_spec(config, axis.device, device);
        let Some(driver_axis) = spec.axes.iter().find(|a| a.channel == axis.channel) else {
            continue;
        };
        let mut keys = String::new();
        let _ = write!(
            keys,
            "{} {} {:?} | {:?}",
            device.model.id(),
            device.address,
            device.machine,
            driver_axis
        );
        out.push((
            index,
            Record {
                axis: axis.name.clone(),
                device: device.name.clone(),
                model: device.model.id().to_owned(),
                address: device.address,
                link: config
                    .links
                    .get(device.link)
                    .map_or_else(String::new, |l| l.name.clone()),
                channel: axis.channel,
                keys: fingerprint(&keys),
                referenced: false,
                counts: 0,
            },
        ));
    }
    out
}

/// Why a saved record is not handed to the driver, if it is not.
fn refusal(saved: &Record, now: &Record) -> Option<&'static str> {
    if let Some(why) = identity_refusal(saved, now) {
        Some(why)
    } else if !saved.referenced {
        Some("it was not referenced and at rest when last seen")
    } else {
        None
    }
}

/// Why a saved record is not this config's axis, if it is not.
fn identity_refusal(saved: &Record, now: &Record) -> Option<&'static str> {
    if saved.device != now.device
        || saved.model != now.model
        || saved.address != now.address
        || saved.link != now.link
    {
        Some("it was saved for another device, model, address or link")
    } else if saved.channel != now.channel {
        Some("it was saved for another channel")
    } else if saved.keys != now.keys {
        Some("the device's or the axis's keys changed since it was saved")
    } else {
        None
    }
}

/// Reads `path`: `None` (logged) when missing, unreadable, not a references file or of
/// another server.
fn read(path: &Path, server: &str) -> Option<File> {
    let text = match std::fs::read_to_string(path) {
        Ok(text) => text,
        Err(error) if error.kind() == std::io::ErrorKind::NotFound => {
            tracing::info!(
                "references: no saved references ({} does not exist): every axis needs a reference",
                path.display()
            );
            return None;
        }
        Err(error) => {
            tracing::warn!(
                "references: cannot read {}: {error}; no axis is referenced from it",
                path.display()
            );
            return None;
        }
    };
    let file: File = match toml::from_str(&text) {
        Ok(file) => file,
        Err(error) => {
            tracing::warn!(
                "references: {} is not a references file ({}); no axis is referenced from it",
                path.display(),
                error.message()
            );
            return None;
        }
    };
    if file.server != server {
        tracing::warn!(
            "references: {} belongs to server `{}`, not `{server}`; no axis is referenced from it",
            path.display(),
            file.server
        );
        return None;
    }
    Some(file)
}

/// Start-up: reads the saved references of `config`'s server, hands each matching one to
/// its driver ([`Driver::restore_references`]), and returns the tick's watch and the main
/// thread's keeper (`None` when no driver keeps references: no file is touched).
pub fn start(config: &ServerConfig, drivers: &mut [AnyDriver]) -> Option<(Watch, Keeper)> {
    let now = records(config, drivers);
    if now.is_empty() {
        return None;
    }
    let path = file_path(&config.server.state_dir, &config.server.name);
    let saved = read(&path, &config.server.name);
    let mut given: Vec<Vec<SavedReference>> = vec![Vec::new(); drivers.len()];
    let mut now = now;
    for (index, record) in &mut now {
        let Some(old) = saved
            .as_ref()
            .and_then(|f| f.axis.iter().find(|r| r.axis == record.axis))
        else {
            continue;
        };
        if identity_refusal(old, record).is_none() {
            // Kept as it was until the axis is seen again (its device online): a device
            // that does not come back in this run keeps its record for the next.
            record.referenced = old.referenced;
            record.counts = old.counts;
        }
        if let Some(why) = refusal(old, record) {
            tracing::info!(
                "references: axis `{}` is not referenced from {}: {why}",
                record.axis,
                path.display()
            );
            continue;
        }
        let device = config.axes[*index].device;
        tracing::info!(
            "references: axis `{}` was referenced and at rest at {} counts; it is referenced again if device `{}` confirms that position",
            record.axis,
            old.counts,
            record.device
        );
        given[device].push(SavedReference {
            channel: record.channel,
            counts: old.counts,
        });
    }
    for (driver, saved) in drivers.iter_mut().zip(&given) {
        if !saved.is_empty() {
            driver.restore_references(saved);
        }
    }
    let (tx, rx) = rtrb::RingBuffer::new(RING);
    let watch = Watch {
        axes: now.iter().map(|(index, _)| (*index, None)).collect(),
        tx,
        restored: given
            .iter()
            .enumerate()
            .flat_map(|(device, saved)| saved.iter().map(move |r| (device, *r)))
            .collect(),
    };
    let file = File {
        server: config.server.name.clone(),
        axis: now.into_iter().map(|(_, record)| record).collect(),
    };
    let keeper = Keeper {
        path,
        file,
        rx,
        failing: false,
    };
    Some((watch, keeper))
}

/// Writes `file` to `path` through a temporary file in the same directory (created if
/// missing), synced, then renamed over `path`.
fn write_atomically(path: &Path, file: &File) -> std::io::Result<()> {
    use std::io::Write as _;
    let dir = path.parent().unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir)?;
    let text = toml::to_string(file).map_err(std::io::Error::other)?;
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    {
        let mut out = std::fs::File::create(&tmp)?;
        out.write_all(b"# motiond: axes referenced and at rest (docs/keys/tmcpack.md); written by the server\n")?;
        out.write_all(text.as_bytes())?;
        out.sync_all()?;
    }
    std::fs::rename(&tmp, path)?;
    if let Ok(dir) = std::fs::File::open(dir) {
        let _ = dir.sync_all();
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(axis: &str) -> Record {
        Record {
            axis: axis.into(),
            device: "pack".into(),
            model: "tmcpack".into(),
            address: 1,
            link: "rs485".into(),
            channel: 0,
            keys: fingerprint("x"),
            referenced: true,
            counts: 1234,
        }
    }

    #[test]
    fn a_record_is_refused_for_any_identity_change_or_when_not_referenced() {
        let now = record("x");
        assert_eq!(refusal(&record("x"), &now), None);
        for change in [
            |r: &mut Record| r.device = "other".into(),
            |r: &mut Record| r.address = 2,
            |r: &mut Record| r.model = "qsb".into(),
            |r: &mut Record| r.link = "bus".into(),
            |r: &mut Record| r.channel = 1,
            |r: &mut Record| r.keys = fingerprint("y"),
            |r: &mut Record| r.referenced = false,
        ] {
            let mut saved = record("x");
            change(&mut saved);
            assert!(refusal(&saved, &now).is_some(), "{saved:?}");
        }
    }

    #[test]
    fn the_file_is_written_atomically_and_read_back() {
        let dir = std::env::temp_dir().join(format!("motiond-refs-{}", std::process::id()));
        let path = file_path(&dir, "demo");
        let file = File {
            server: "demo".into(),
            axis: vec![record("x")],
        };
        write_atomically(&path, &file).expect("written");
        assert_eq!(read(&path, "demo"), Some(file));
        assert_eq!(read(&path, "other"), None, "another server's file");
        std::fs::write(&path, "server = \"demo\"\n[[axis]]\naxis = 3\n").expect("garbage");
        assert_eq!(read(&path, "demo"), None, "a corrupt file");
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(read(&path, "demo"), None, "no file");
    }

    /// A frame whose axis 1 is `mode` with `flags`, online, at `counts`.
    fn frame(mode: AxisMode, flags: AxisFlags, counts: i64) -> Box<MotionFrame> {
        let mut frame = Box::new(MotionFrame::EMPTY);
        let axis = &mut frame.axes[1];
        axis.mode = mode as u8;
        axis.flags = flags.0;
        axis.raw_counts = counts;
        axis.device_state = DeviceState::Online as u8;
        frame
    }

    /// What the tick sends for a watched axis (index 1): referenced only while HOMED, not
    /// MOVING, no fault, holding (or arrived); nothing while the device is not online or
    /// the data stale; a change of position while referenced; a full ring retried.
    #[test]
    fn the_watch_sends_referenced_only_at_rest_and_only_changes() {
        let (tx, mut rx) = rtrb::RingBuffer::new(2);
        let mut watch = Watch {
            axes: vec![(1, None)],
            tx,
            restored: Vec::new(),
        };
        let mut seen = |watch: &mut Watch, frame: &MotionFrame| {
            watch.observe(frame);
            let mut out = Vec::new();
            while let Ok(s) = rx.pop() {
                out.push((s.referenced, s.counts));
            }
            out
        };
        let homed = AxisFlags::HOMED;
        let rest = frame(AxisMode::Hold, homed, 2000);
        assert_eq!(seen(&mut watch, &rest), [(true, 2000)]);
        assert_eq!(seen(&mut watch, &rest), [], "no change, nothing sent");
        // A move taken: the mode changes before the board reports motion.
        let taken = frame(AxisMode::RampPosition, homed, 2000);
        assert_eq!(seen(&mut watch, &taken), [(false, 2000)]);
        let moving = frame(
            AxisMode::RampPosition,
            homed.with(AxisFlags::MOVING, true),
            2300,
        );
        assert_eq!(seen(&mut watch, &moving), [], "still not referenced");
        let arrived = frame(
            AxisMode::RampPosition,
            homed.with(AxisFlags::ARRIVED, true),
            2500,
        );
        assert_eq!(seen(&mut watch, &arrived), [(true, 2500)]);
        // Moving in hold (pushed, a board's own motion), a fault, no reference: not.
        for flags in [
            homed.with(AxisFlags::MOVING, true),
            homed.with(AxisFlags::FAULT, true),
            AxisFlags::default(),
        ] {
            assert_eq!(
                seen(&mut watch, &frame(AxisMode::Hold, flags, 2500)),
                [(false, 2500)]
            );
            assert_eq!(seen(&mut watch, &arrived), [(true, 2500)]);
        }
        // Stopping, homing: not at rest.
        for mode in [AxisMode::Stopping, AxisMode::Homing, AxisMode::Velocity] {
            assert_eq!(seen(&mut watch, &frame(mode, homed, 2500)), [(false, 2500)]);
            assert_eq!(seen(&mut watch, &arrived), [(true, 2500)]);
        }
        // The device not online, or the data stale: the record stays as it was.
        let mut offline = frame(AxisMode::Stopping, AxisFlags::default(), 0);
        offline.axes[1].device_state = DeviceState::Faulted as u8;
        assert_eq!(seen(&mut watch, &offline), []);
        let stale = frame(AxisMode::Off, AxisFlags::STALE, 0);
        assert_eq!(seen(&mut watch, &stale), []);
        // Referenced elsewhere (a set-position): sent.
        assert_eq!(
            seen(&mut watch, &frame(AxisMode::Hold, homed, 100)),
            [(true, 100)]
        );
        // A full ring: the change is sent at the next frame that finds room.
        let mut full = Watch {
            axes: vec![(1, None)],
            tx: rtrb::RingBuffer::new(1).0,
            restored: Vec::new(),
        };
        full.observe(&rest);
        full.observe(&taken);
        assert_eq!(
            full.axes[0].1.map(|s| s.referenced),
            Some(true),
            "not sent: not taken"
        );
    }

    #[test]
    fn fingerprints_are_fnv1a_64() {
        // FNV-1a 64 of "" and "a" (the published test vectors).
        assert_eq!(fingerprint(""), "cbf29ce484222325");
        assert_eq!(fingerprint("a"), "af63dc4c8601ec8c");
    }
}
