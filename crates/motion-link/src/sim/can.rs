//! A simulated CAN bus: device models that speak CAN frames ([`CanDevice`]), several on one
//! bus ([`CanBus`]), and the host's end of the wire behind the [`Link`] trait
//! ([`SimCanLink`]), as a SocketCAN interface presents it: 16-byte records
//! ([`CanRecord`]), one a frame.
//!
//! Wire time: every frame, the host's and the devices', occupies the one bus for its bits
//! at the link's bit rate ([`CanRecord::bits`]: 111 bits for 8 data bytes, without
//! stuffing), one after the other. A frame reaches the devices (a host frame) or the host
//! (a device frame) when its last bit has passed. Frames wait for the bus in the order they
//! were offered (a real bus lets the lowest identifier win when two wait; between one host
//! and packs that answer one request at a time the order is the same). Nobody hears its own
//! frames, as a SocketCAN socket does not by default.
//!
//! Faults ([`SimFaults`]): unplugging makes every call `Disconnected` until replugged and
//! reopened; a dropped "byte" is a whole lost frame here (a frame the bus did not deliver);
//! a reply delay holds every device frame back. Garbage and baud-rate faults have no CAN
//! meaning and are ignored (a CAN controller checks every frame's CRC).

use core::fmt;
use core::time::Duration;
use std::collections::VecDeque;
use std::sync::Arc;

use motion_base::{CAN_RECORD_LEN, CanRecord};

use super::faults::{Direction, Plug, SimFaults, Unplugged};
use super::line::Line;
use crate::can_records::RecordSender;
use crate::error::LinkError;
use crate::link::{Link, LinkKind, LinkStats};

/// How many device events one call follows before giving up (a model whose `next_event`
/// never moves forward must not hang the caller).
const MAX_EVENTS_PER_CALL: usize = 100_000;
/// The fault-noise seed when none is given.
const DEFAULT_SEED: u64 = 0x4d4f_5449_4f4e_4443;
/// Host frames on the wire or waiting for the bus; more are refused (a full transmit
/// queue, as a SocketCAN interface's `txqueuelen`).
pub const TX_QUEUE_FRAMES: usize = 64;
/// Frames the host has not read yet; more are lost (counted as overruns).
pub const RX_QUEUE_FRAMES: usize = 4096;

/// A device model on a CAN bus. Time is the caller's, as for the other device traits.
pub trait CanDevice: Send {
    /// `frame` finished arriving at `now`: every frame on the bus but the device's own.
    fn receive(&mut self, now: Duration, frame: &CanRecord);

    /// Advances the model to `now` and takes the next frame it wants on the bus, with the
    /// instant it became ready (at or before `now`); `None` when nothing is ready.
    fn transmit(&mut self, now: Duration) -> Option<(Duration, CanRecord)>;

    /// The earliest instant at which the model will have a frame ready or its state changes
    /// by itself; `None`: nothing scheduled.
    fn next_event(&self, now: Duration) -> Option<Duration>;
}

/// Several [`CanDevice`]s on one bus. Every host frame reaches all of them; every frame a
/// device sends reaches the host and every other device. Frames ready at the same time go
/// lowest identifier first (CAN arbitration).
pub struct CanBus {
    devices: Vec<Box<dyn CanDevice>>,
    ready: VecDeque<(Duration, CanRecord)>,
}

impl CanBus {
    /// An empty bus.
    pub fn new() -> Self {
        Self {
            devices: Vec::new(),
            ready: VecDeque::new(),
        }
    }

    /// Attaches a device.
    pub fn push(&mut self, device: Box<dyn CanDevice>) {
        self.devices.push(device);
    }

    /// Builder form of [`push`](Self::push).
    #[must_use]
    pub fn with(mut self, device: Box<dyn CanDevice>) -> Self {
        self.push(device);
        self
    }

    /// Number of devices.
    pub fn len(&self) -> usize {
        self.devices.len()
    }

    /// `true` without devices.
    pub fn is_empty(&self) -> bool {
        self.devices.is_empty()
    }
}

impl Default for CanBus {
    fn default() -> Self {
        Self::new()
    }
}

impl fmt::Debug for CanBus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("CanBus")
            .field("devices", &self.devices.len())
            .field("ready", &self.ready.len())
            .finish()
    }
}

impl CanDevice for CanBus {
    fn receive(&mut self, now: Duration, frame: &CanRecord) {
        for device in &mut self.devices {
            device.receive(now, frame);
        }
    }

    fn transmit(&mut self, now: Duration) -> Option<(Duration, CanRecord)> {
        for i in 0..self.devices.len() {
            while let Some(sent) = self.devices.get_mut(i).and_then(|d| d.transmit(now)) {
                for (j, other) in self.devices.iter_mut().enumerate() {
                    if j != i {
                        other.receive(now, &sent.1);
                    }
                }
                self.ready.push_back(sent);
            }
        }
        // Earliest ready first; among equals the lowest identifier wins the arbitration.
        let best = self
            .ready
            .iter()
            .enumerate()
            .min_by_key(|(_, (at, frame))| (*at, frame.can_id & 0x1FFF_FFFF))
            .map(|(i, _)| i)?;
        self.ready.remove(best)
    }

    fn next_event(&self, now: Duration) -> Option<Duration> {
        let queued = (!self.ready.is_empty()).then_some(now);
        self.devices
            .iter()
            .filter_map(|d| d.next_event(now))
            .chain(queued)
            .min()
    }
}

/// The host's end of a simulated CAN bus to a [`CanDevice`] (or a [`CanBus`]) behind the
/// [`Link`] trait, reading and writing 16-byte [`CanRecord`]s like
/// [`SocketCanLink`](crate::socketcan::SocketCanLink). Its kind is
/// [`LinkKind::Stream`]. Time comes only from `now`; see the module docs for the wire.
pub struct SimCanLink {
    name: Arc<str>,
    device: Box<dyn CanDevice>,
    bitrate: u32,
    bus: Line,
    faults: SimFaults,
    /// Host frames on their way to the device: (arrival, frame).
    to_device: VecDeque<(Duration, CanRecord)>,
    /// Device frames on their way to the host or not read yet: (arrival, frame).
    to_host: VecDeque<(Duration, CanRecord)>,
    device_time: Duration,
    /// Connected, or why not.
    plug: Plug,
    tx: [u8; CAN_RECORD_LEN],
    tx_len: usize,
    rx: [u8; CAN_RECORD_LEN],
    rx_from: usize,
    rx_to: usize,
    overruns: u64,
    frames: (u64, u64),
    stats: LinkStats,
}

impl fmt::Debug for SimCanLink {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SimCanLink")
            .field("name", &self.name)
            .field("to_device", &self.to_device.len())
            .field("to_host", &self.to_host.len())
            .field("connected", &self.plug.connected())
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

impl SimCanLink {
    /// A CAN bus at `bitrate` bits per second to `device`.
    pub fn new(name: &str, bitrate: u32, device: Box<dyn CanDevice>) -> Self {
        let bitrate = bitrate.max(1);
        Self {
            name: format!("sim {name} CAN @ {bitrate} bit/s").into(),
            device,
            bitrate,
            bus: Line::new(u64::from(bitrate)),
            faults: SimFaults::new(DEFAULT_SEED),
            to_device: VecDeque::new(),
            to_host: VecDeque::new(),
            device_time: Duration::ZERO,
            plug: Plug::OPEN,
            tx: [0; CAN_RECORD_LEN],
            tx_len: 0,
            rx: [0; CAN_RECORD_LEN],
            rx_from: 0,
            rx_to: 0,
            overruns: 0,
            frames: (0, 0),
            stats: LinkStats::default(),
        }
    }

    /// Seeds the fault noise (random frame losses).
    #[must_use]
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.faults = SimFaults::new(seed);
        self.plug = Plug::OPEN;
        self
    }

    /// The fault-injection handle (a clone shares the same bus).
    pub fn faults(&self) -> SimFaults {
        self.faults.clone()
    }

    /// The bit rate.
    pub fn bitrate(&self) -> u32 {
        self.bitrate
    }

    /// Device frames lost because the host did not read in time.
    pub fn overruns(&self) -> u64 {
        self.overruns
    }

    /// Frames the host read and wrote so far.
    pub fn frames(&self) -> (u64, u64) {
        self.frames
    }

    fn check_plug(&mut self, now: Duration) -> Result<(), LinkError> {
        let Err((why, was_connected)) = self.plug.check(&self.faults) else {
            return Ok(());
        };
        if was_connected {
            self.drop_in_flight(now);
        }
        self.stats.errors += 1;
        Err(LinkError::Disconnected {
            link: self.name.clone(),
            detail: match why {
                Unplugged::Now => "the simulated CAN bus is unplugged",
                Unplugged::Since => {
                    "the simulated CAN bus was unplugged since the link was opened; reopen it"
                }
            },
        })
    }

    fn drop_in_flight(&mut self, now: Duration) {
        self.to_device.clear();
        self.to_host.clear();
        self.tx_len = 0;
        self.rx_from = 0;
        self.rx_to = 0;
        self.bus.reset(now);
    }

    /// Runs the device and the bus up to `now`, event by event.
    fn pump(&mut self, now: Duration) {
        for _ in 0..MAX_EVENTS_PER_CALL {
            let arrival = self.to_device.front().map(|f| f.0).filter(|t| *t <= now);
            let scheduled = self
                .device
                .next_event(self.device_time)
                .filter(|t| *t <= now)
                .map(|t| t.max(self.device_time));
            let t = match (arrival, scheduled) {
                (Some(a), Some(s)) => a.min(s),
                (Some(a), None) => a,
                (None, Some(s)) => s,
                (None, None) => break,
            };
            let before = self.device_time;
            let mut delivered = false;
            while let Some((at, frame)) = self.to_device.front().copied().filter(|f| f.0 <= t) {
                self.to_device.pop_front();
                self.device_time = self.device_time.max(at);
                self.device.receive(self.device_time, &frame);
                delivered = true;
            }
            self.device_time = self.device_time.max(t);
            let sent = self.poll_device(self.device_time);
            if !delivered && sent == 0 && self.device_time == before {
                break;
            }
        }
        self.device_time = self.device_time.max(now);
        self.poll_device(self.device_time);
    }

    /// Puts what the device sends at `t` on the bus towards the host.
    fn poll_device(&mut self, t: Duration) -> usize {
        let mut sent = 0;
        while let Some((ready, frame)) = self.device.transmit(t) {
            sent += 1;
            let (delay, lost) = {
                let mut faults = self.faults.lock();
                (faults.reply_delay, faults.drops(Direction::ToHost))
            };
            let (_, end) = self
                .bus
                .send(ready.min(t).saturating_add(delay), frame.bits());
            if lost {
                continue;
            }
            if self.to_host.len() >= RX_QUEUE_FRAMES {
                self.overruns += 1;
            } else {
                self.to_host.push_back((end, frame));
            }
        }
        sent
    }

    /// Puts the assembled host record on the bus; `Ok(false)` when the queue is full.
    fn send_record(&mut self, now: Duration) -> Result<bool, LinkError> {
        let Some(frame) = CanRecord::from_bytes(&self.tx) else {
            self.tx_len = 0;
            self.stats.errors += 1;
            return Err(LinkError::Unsupported {
                link: self.name.clone(),
                what: "a CAN record with a length byte above 8 (CAN 2.0 carries 0..=8 bytes); \
                       the record was dropped",
            });
        };
        if self.to_device.len() >= TX_QUEUE_FRAMES {
            return Ok(false);
        }
        let (_, end) = self.bus.send(now, frame.bits());
        if !self.faults.lock().drops(Direction::ToDevice) {
            self.to_device.push_back((end, frame));
        }
        self.tx_len = 0;
        self.frames.1 += 1;
        Ok(true)
    }
}

impl RecordSender for SimCanLink {
    fn pending(&mut self) -> (&mut [u8; CAN_RECORD_LEN], &mut usize) {
        (&mut self.tx, &mut self.tx_len)
    }
    fn send_pending(&mut self, now: Duration) -> Result<bool, LinkError> {
        self.send_record(now)
    }
    fn count_out(&mut self, bytes: usize) {
        self.stats.bytes_out += bytes as u64;
    }
}

impl Link for SimCanLink {
    fn kind(&self) -> LinkKind {
        LinkKind::Stream
    }

    fn name(&self) -> &str {
        &self.name
    }

    /// Takes bytes up to whole records, each one frame on the bus (a record may come in
    /// parts over several calls); stops at a full transmit queue.
    fn write(&mut self, now: Duration, bytes: &[u8]) -> Result<usize, LinkError> {
        self.check_plug(now)?;
        self.pump(now);
        crate::can_records::write_records(self, now, bytes)
    }

    fn write_parts(&mut self, now: Duration, parts: &[&[u8]]) -> Result<usize, LinkError> {
        crate::link::write_in_turn(self, now, parts)
    }

    /// The records of the frames whose last bit arrived at or before `now`.
    fn read(&mut self, now: Duration, buf: &mut [u8]) -> Result<usize, LinkError> {
        self.check_plug(now)?;
        self.pump(now);
        let mut n = 0;
        while n < buf.len() {
            if self.rx_from == self.rx_to {
                if buf.len() - n < CAN_RECORD_LEN && n > 0 {
                    break;
                }
                let Some((_, frame)) = self.to_host.front().copied().filter(|f| f.0 <= now) else {
                    break;
                };
                self.to_host.pop_front();
                self.rx = frame.to_bytes();
                self.rx_from = 0;
                self.rx_to = CAN_RECORD_LEN;
                self.frames.0 += 1;
            }
            let chunk = (self.rx_to - self.rx_from).min(buf.len() - n);
            if let (Some(dst), Some(src)) = (
                buf.get_mut(n..n + chunk),
                self.rx.get(self.rx_from..self.rx_from + chunk),
            ) {
                dst.copy_from_slice(src);
            }
            self.rx_from += chunk;
            n += chunk;
        }
        self.stats.bytes_in += n as u64;
        Ok(n)
    }

    fn flush(&mut self, now: Duration) -> Result<(), LinkError> {
        self.check_plug(now)?;
        self.pump(now);
        Ok(())
    }

    fn reopen(&mut self, now: Duration) -> Result<(), LinkError> {
        if self.plug.reconnect(&self.faults).is_err() {
            self.stats.errors += 1;
            return Err(LinkError::Disconnected {
                link: self.name.clone(),
                detail: "the simulated CAN bus is still unplugged; replug it first",
            });
        }
        self.drop_in_flight(now);
        self.stats.reconnects += 1;
        Ok(())
    }

    fn next_event(&self, now: Duration) -> Option<Duration> {
        let plug_changed = {
            let state = self.faults.lock();
            self.plug.changed(&state)
        };
        if plug_changed || self.rx_from != self.rx_to {
            return Some(now);
        }
        [
            self.to_host.front().map(|f| f.0),
            self.to_device.front().map(|f| f.0),
            self.device.next_event(self.device_time.max(now)),
        ]
        .into_iter()
        .flatten()
        .min()
        .map(|t| t.max(now))
    }

    fn stats(&self) -> LinkStats {
        self.stats
    }
}
