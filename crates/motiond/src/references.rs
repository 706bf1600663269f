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
//! The file is the server's own (docs/ARCHITECTURE.md "Files the server trusts"): the state
//! directory must pass [`PrivateDir`]'s checks (the server refuses to start otherwise), the
//! file is read only when it is a regular file of the server's user that no one else may
//! write, and written through a temporary file created `O_EXCL | O_NOFOLLOW`, mode 0600.
//! Each record carries a MAC (HMAC-SHA256 with the server's key, crate::secret) of the
//! server's name and every field: a record edited or planted by anyone without the key is
//! refused, with the reason in the log, and its axis needs a reference.
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

use crate::secret::ServerKey;
use motion_config::ServerConfig;
use motion_config::private_dir::{Privacy, PrivateDir, PrivateDirError};

/// The state directory's mode when the server makes it.
pub const STATE_DIR_MODE: u32 = 0o700;

/// The references file's mode.
const FILE_MODE: u32 = 0o600;

/// The largest references file read (1024 axes' records are ~400 KiB).
const MAX_FILE_BYTES: u64 = 1 << 20;

/// The config key naming the state directory, for messages.
const KEY: &str = "[server] state_dir";

/// What each record's MAC starts with (a tag made for one purpose is never taken for
/// another's).
const DOMAIN: &[u8] = b"motiond references record v1";

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
    /// HMAC-SHA256 of the server's name and the fields above, with the server's key
    /// (crate::secret), in hex; empty in a file written before records were authenticated.
    #[serde(default)]
    mac: String,
}

impl Record {
    /// Hands `f` the record's fields, framed for its MAC: the domain, server `server`, then
    /// every field but the MAC.
    fn with_parts<T>(&self, server: &str, f: impl FnOnce(&[&[u8]]) -> T) -> T {
        let address = self.address.to_le_bytes();
        let channel = (self.channel as u64).to_le_bytes();
        let referenced = [u8::from(self.referenced)];
        let counts = self.counts.to_le_bytes();
        f(&[
            DOMAIN,
            server.as_bytes(),
            self.axis.as_bytes(),
            self.device.as_bytes(),
            self.model.as_bytes(),
            &address,
            self.link.as_bytes(),
            &channel,
            self.keys.as_bytes(),
            &referenced,
            &counts,
        ])
    }

    /// Sets the record's MAC (server `server`, key `key`).
    fn sign(&mut self, server: &str, key: &ServerKey) {
        self.mac = self.with_parts(server, |parts| key.sign(parts));
    }

    /// Whether the record's MAC is server `server`'s with `key`.
    fn authentic(&self, server: &str, key: &ServerKey) -> bool {
        self.with_parts(server, |parts| key.verify(parts, &self.mac))
    }
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
    /// The state directory (opened and checked again at every write: one made again after
    /// a clean-up is checked as the first was).
    dir: PathBuf,
    /// The file's name in it.
    name: String,
    key: ServerKey,
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
        let server = self.file.server.clone();
        for record in &mut self.file.axis {
            record.sign(&server, &self.key);
        }
        let written = PrivateDir::open(&self.dir, KEY, STATE_DIR_MODE)
            .map_err(|error| error.to_string())
            .and_then(|dir| {
                write_atomically(&dir, &self.name, &self.file).map_err(|error| {
                    format!(
                        "cannot write {}: {error}",
                        dir.file_path(&self.name).display()
                    )
                })
            });
        match written {
            Ok(()) => self.failing = false,
            Err(error) => {
                if !self.failing {
                    tracing::warn!(
                        "references: {error}; the axes will need a new reference after a restart"
                    );
                }
                self.failing = true;
            }
        }
    }
}

/// The file of server `name` in `dir`.
pub fn file_path(dir: &Path, name: &str) -> PathBuf {
    dir.join(file_name(name))
}

/// The file's name for server `name`.
fn file_name(name: &str) -> String {
    format!("{name}.references.toml")
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
        let spec = motion_config::boards::driver_spec(config, axis.device, device);
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
                mac: String::new(),
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

/// Reads file `name` of `dir`: `None` (logged) when missing, not the server's own (see the
/// module docs), unreadable, not a references file or of another server.
fn read(dir: &PrivateDir, name: &str, server: &str) -> Option<File> {
    let path = dir.file_path(name);
    let bytes = match dir.read_own(name, Privacy::Unwritable, MAX_FILE_BYTES) {
        Ok(Some(bytes)) => bytes,
        Ok(None) => {
            tracing::info!(
                "references: no saved references ({} does not exist): every axis needs a reference",
                path.display()
            );
            return None;
        }
        Err(error) => {
            tracing::warn!("references: {error}; no axis is referenced from it");
            return None;
        }
    };
    let Ok(text) = String::from_utf8(bytes) else {
        tracing::warn!(
            "references: {} is not a references file (not UTF-8); no axis is referenced from it",
            path.display()
        );
        return None;
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

/// Start-up: checks the state directory (refused: the server does not start), reads the
/// saved references of `config`'s server, hands each authentic and matching one to its
/// driver ([`Driver::restore_references`]), and returns the tick's watch and the main
/// thread's keeper (`None` when no driver keeps references: no file is touched).
pub fn start(
    config: &ServerConfig,
    drivers: &mut [AnyDriver],
) -> Result<Option<(Watch, Keeper)>, PrivateDirError> {
    let now = records(config, drivers);
    if now.is_empty() {
        return Ok(None);
    }
    let server = &config.server.name;
    let dir = PrivateDir::open(&config.server.state_dir, KEY, STATE_DIR_MODE)?;
    let key = ServerKey::load_or_create(&dir)?;
    let name = file_name(server);
    let path = dir.file_path(&name);
    let saved = read(&dir, &name, server);
    let mut given: Vec<Vec<SavedReference>> = vec![Vec::new(); drivers.len()];
    let mut now = now;
    for (index, record) in &mut now {
        let Some(old) = saved
            .as_ref()
            .and_then(|f| f.axis.iter().find(|r| r.axis == record.axis))
        else {
            continue;
        };
        if !old.authentic(server, &key) {
            tracing::warn!(
                "references: axis `{}` is not referenced from {}: its record is not \
                 authenticated by the server's key ({}: edited, planted, or saved with another \
                 key); it needs a reference",
                record.axis,
                path.display(),
                dir.file_path(crate::secret::KEY_FILE).display()
            );
            continue;
        }
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
        server: server.clone(),
        axis: now.into_iter().map(|(_, record)| record).collect(),
    };
    let keeper = Keeper {
        dir: config.server.state_dir.clone(),
        name,
        key,
        file,
        rx,
        failing: false,
    };
    Ok(Some((watch, keeper)))
}

/// Writes `file` as file `name` of `dir` ([`PrivateDir::replace`]: a temporary file made
/// `O_EXCL | O_NOFOLLOW`, mode 0600, synced, renamed over the old one).
fn write_atomically(dir: &PrivateDir, name: &str, file: &File) -> std::io::Result<()> {
    let text = toml::to_string(file).map_err(std::io::Error::other)?;
    let mut bytes =
        b"# motiond: axes referenced and at rest (docs/keys/tmcpack.md); written by the server, \
each record authenticated with its key (motiond.key): an edited record is refused\n"
            .to_vec();
    bytes.extend_from_slice(text.as_bytes());
    dir.replace(name, &bytes, FILE_MODE)
}

#[cfg(test)]
mod tests;
