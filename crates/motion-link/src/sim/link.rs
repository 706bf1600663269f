//! [`SimLink`]: an in-process wire to a device model, with wire time and fault injection.

use core::fmt;
use core::time::Duration;
use std::collections::VecDeque;
use std::sync::Arc;

use super::device::{SpiDevice, StreamDevice};
use super::faults::{Direction, Plug, SimFaults, Unplugged};
use super::line::{Line, Received, resample};
use crate::error::LinkError;
use crate::link::{Link, LinkKind, LinkStats};

/// Bits on the wire per byte: 8N1 (start, 8 data, stop).
const BITS_8N1: u64 = 10;
/// How many device events one call follows before giving up (a model whose
/// `next_event` never moves forward must not hang the caller).
const MAX_EVENTS_PER_CALL: usize = 100_000;
/// The fault-noise seed when none is given.
const DEFAULT_SEED: u64 = 0x4d4f_5449_4f4e_4421;

/// The two wires a [`SimLink`] can be.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SimWire {
    /// A serial line, 8N1 at `baud`.
    Serial {
        /// Line rate of the host side.
        baud: u32,
        /// Full duplex (RS-232, USB CDC) or half duplex (two-wire RS-485, where a reply
        /// and a request share the one pair and occupy it in turn).
        duplex: Duplex,
    },
    /// An SPI bus clocked at `speed_hz`, 8 clocks a byte.
    Spi {
        /// Clock rate in Hz.
        speed_hz: u32,
    },
}

/// Whether both directions of a serial line can carry bytes at once.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Duplex {
    /// Separate transmit and receive lines.
    Full,
    /// One shared pair: the host's bytes and the devices' replies take turns on it. The
    /// host does not hear its own bytes (its receiver is off while it transmits, as on
    /// USB RS-485 adapters with automatic direction control).
    Half,
}

/// The sizes of a [`SimLink`]'s queues (bounded: a full queue refuses or drops, it never
/// grows).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SimLimits {
    /// Bytes written and still on the wire to the device (stream links); a write accepts
    /// only what fits, as an OS transmit buffer would.
    pub to_device: usize,
    /// Bytes on the wire to the host or received and not yet read; a stream device's
    /// excess is lost (an overrun, counted), an SPI write that would overflow fails.
    pub to_host: usize,
    /// Longest SPI transaction.
    pub max_transaction: usize,
}

impl Default for SimLimits {
    fn default() -> Self {
        Self {
            to_device: 4096,
            to_host: 64 * 1024,
            max_transaction: 4096,
        }
    }
}

enum Model {
    Stream {
        device: Box<dyn StreamDevice>,
        baud: u32,
        /// Host to device; on a half-duplex pair also device to host.
        out_line: Line,
        /// Device to host (full duplex only).
        in_line: Line,
        duplex: Duplex,
        to_device: VecDeque<Received>,
    },
    Spi {
        device: Box<dyn SpiDevice>,
        line: Line,
        mosi: Vec<u8>,
        miso: Vec<u8>,
    },
}

/// An in-process wire to a [`StreamDevice`] or [`SpiDevice`] (or a bus of them) behind the
/// [`Link`] trait.
///
/// Time comes only from `now`. A byte written at `now` reaches the device when its last
/// bit has crossed the wire; a byte the device transmits becomes readable when its last
/// bit has arrived (10 bit times a byte on a serial line, 8 clocks on SPI), and a
/// transmission occupies its line so later bytes queue behind it. The device is advanced
/// event by event (its [`next_event`](StreamDevice::next_event)), so a coarse caller still
/// sees exact timing. Faults are injected through [`SimFaults`] ([`faults`](Self::faults)).
pub struct SimLink {
    name: Arc<str>,
    model: Model,
    faults: SimFaults,
    limits: SimLimits,
    /// Bytes on their way to the host or waiting to be read, in arrival order.
    to_host: VecDeque<Received>,
    /// The latest instant handed to the device: its clock never goes back.
    device_time: Duration,
    /// Connected, or why not.
    plug: Plug,
    scratch: Vec<u8>,
    overruns: u64,
    stats: LinkStats,
    /// [`SimLink::with_host_frames`].
    host_frame: Option<Duration>,
    /// The rate a stream link was made with, which [`Link::reopen`] goes back to.
    opening_baud: u32,
}

impl fmt::Debug for SimLink {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SimLink")
            .field("name", &self.name)
            .field("kind", &self.kind())
            .field("to_host", &self.to_host.len())
            .field("device_time", &self.device_time)
            .field("connected", &self.plug.connected())
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

impl SimLink {
    /// A full-duplex serial wire at `baud` to a stream device (RS-232, USB CDC).
    pub fn stream(name: &str, baud: u32, device: Box<dyn StreamDevice>) -> Self {
        Self::stream_with(name, baud, Duplex::Full, device)
    }

    /// A serial wire with the duplex given (use [`Duplex::Half`] for an RS-485 pair).
    pub fn stream_with(
        name: &str,
        baud: u32,
        duplex: Duplex,
        device: Box<dyn StreamDevice>,
    ) -> Self {
        let baud = baud.max(1);
        let line = Line::new(u64::from(baud));
        let mut device = device;
        device.line_rate(baud);
        let model = Model::Stream {
            device,
            baud,
            out_line: line,
            in_line: line,
            duplex,
            to_device: VecDeque::new(),
        };
        let mut link = Self::with_model(format!("sim {name} @ {baud} 8N1"), model);
        link.opening_baud = baud;
        link
    }

    /// An SPI wire clocked at `speed_hz` to an SPI device.
    pub fn spi(name: &str, speed_hz: u32, device: Box<dyn SpiDevice>) -> Self {
        let speed_hz = speed_hz.max(1);
        let model = Model::Spi {
            device,
            line: Line::new(u64::from(speed_hz)),
            mosi: Vec::new(),
            miso: Vec::new(),
        };
        Self::with_model(format!("sim {name} SPI @ {speed_hz} Hz"), model)
    }

    fn with_model(name: String, model: Model) -> Self {
        Self {
            name: name.into(),
            model,
            faults: SimFaults::new(DEFAULT_SEED),
            limits: SimLimits::default(),
            to_host: VecDeque::new(),
            device_time: Duration::ZERO,
            plug: Plug::OPEN,
            scratch: vec![0; 256],
            overruns: 0,
            stats: LinkStats::default(),
            host_frame: None,
            opening_baud: 0,
        }
    }

    /// Seeds the fault noise (dropped-byte draws, [`SimFaults::inject_noise`]).
    #[must_use]
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.faults = SimFaults::new(seed);
        self.plug = Plug::OPEN;
        self
    }

    /// Hands the device's bytes to the host at the end of each `frame` (a multiple of it
    /// since the link's time origin) instead of as each byte's wire time passes: a board
    /// behind USB (a virtual COM port) is polled once per bus frame, 1 ms at full speed,
    /// and its bytes reach the host's tty together. A zero `frame` keeps per-byte delivery.
    #[must_use]
    pub fn with_host_frames(mut self, frame: Duration) -> Self {
        self.host_frame = (!frame.is_zero()).then_some(frame);
        self
    }

    /// Sets the queue sizes.
    #[must_use]
    pub fn with_limits(mut self, limits: SimLimits) -> Self {
        self.limits = limits;
        self
    }

    /// The fault-injection handle of this link (a clone shares the same wire).
    pub fn faults(&self) -> SimFaults {
        self.faults.clone()
    }

    /// The wire this link models.
    pub fn wire(&self) -> SimWire {
        match &self.model {
            Model::Stream { baud, duplex, .. } => SimWire::Serial {
                baud: *baud,
                duplex: *duplex,
            },
            Model::Spi { line, .. } => SimWire::Spi {
                speed_hz: u32::try_from(line.rate()).unwrap_or(u32::MAX),
            },
        }
    }

    /// Moves the host's side of a stream wire to `baud` (after the line fell silent:
    /// bytes in flight keep their timing), and tells the device ([`StreamDevice::line_rate`]).
    fn retime(&mut self, baud: u32) {
        let baud = baud.max(1);
        let Model::Stream {
            device,
            baud: rate,
            out_line,
            in_line,
            ..
        } = &mut self.model
        else {
            return;
        };
        *rate = baud;
        out_line.retime(u64::from(baud));
        in_line.retime(u64::from(baud));
        device.line_rate(baud);
        let old = self.name.to_string();
        let base = old
            .rsplit_once(" @ ")
            .map_or(old.as_str(), |(base, _)| base);
        self.name = format!("{base} @ {baud} 8N1").into();
    }

    /// Device bytes lost because the host did not read in time.
    pub fn overruns(&self) -> u64 {
        self.overruns
    }

    /// Fails with `Disconnected` when the plug is out or was out since the last open.
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
                Unplugged::Now => "the simulated device is unplugged",
                Unplugged::Since => {
                    "the simulated device was unplugged since the link was opened; reopen it"
                }
            },
        })
    }

    fn drop_in_flight(&mut self, now: Duration) {
        self.to_host.clear();
        match &mut self.model {
            Model::Stream {
                out_line,
                in_line,
                to_device,
                ..
            } => {
                to_device.clear();
                out_line.reset(now);
                in_line.reset(now);
            }
            Model::Spi { line, .. } => line.reset(now),
        }
    }

    /// Queues a byte for the host, or counts an overrun when the host is too far behind.
    fn push_to_host(&mut self, mut received: Received) {
        received.at = self.faults.lock().held(received.at);
        if let Some(frame) = self.host_frame {
            let frame_ns = frame.as_nanos().max(1);
            let at_ns = received.at.as_nanos();
            let end_ns = at_ns.div_ceil(frame_ns).saturating_mul(frame_ns);
            received.at = Duration::from_nanos(u64::try_from(end_ns).unwrap_or(u64::MAX));
        }
        if self.to_host.len() >= self.limits.to_host {
            self.overruns += 1;
        } else {
            self.to_host.push_back(received);
        }
    }

    /// Runs the stream device and the wire up to `now`, event by event.
    fn pump(&mut self, now: Duration) {
        if let Model::Spi { device, .. } = &mut self.model {
            self.device_time = self.device_time.max(now);
            device.advance(self.device_time);
            return;
        }
        for _ in 0..MAX_EVENTS_PER_CALL {
            let Model::Stream {
                device, to_device, ..
            } = &mut self.model
            else {
                return;
            };
            let arrival = to_device.front().map(|r| r.at).filter(|t| *t <= now);
            let scheduled = device
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
            while let Some(r) = to_device.front().copied().filter(|r| r.at <= t) {
                to_device.pop_front();
                self.device_time = self.device_time.max(r.at);
                device.receive(self.device_time, &[r.byte]);
                delivered = true;
            }
            self.device_time = self.device_time.max(t);
            let sent = self.poll_stream_device(self.device_time);
            if !delivered && sent == 0 && self.device_time == before {
                // The model asked to be polled now but had nothing: do not spin.
                break;
            }
        }
        self.device_time = self.device_time.max(now);
        self.poll_stream_device(self.device_time);
        self.send_garbage(now);
    }

    /// Takes what the stream device transmits at `t` and puts it on the wire to the host.
    fn poll_stream_device(&mut self, t: Duration) -> usize {
        let mut total = 0;
        loop {
            let Model::Stream { device, .. } = &mut self.model else {
                return total;
            };
            let n = device
                .transmit(t, &mut self.scratch)
                .min(self.scratch.len());
            if n == 0 {
                return total;
            }
            total += n;
            let mut burst = std::mem::take(&mut self.scratch);
            let delay = self.faults.lock().reply_delay;
            self.send_to_host(t.saturating_add(delay), burst.get(..n).unwrap_or_default());
            burst.resize(256, 0);
            self.scratch = burst;
        }
    }

    fn send_garbage(&mut self, now: Duration) {
        if !matches!(self.model, Model::Stream { .. }) {
            return;
        }
        let garbage: Vec<u8> = {
            let mut state = self.faults.lock();
            if state.garbage.is_empty() {
                return;
            }
            state.garbage.drain(..).collect()
        };
        self.send_to_host(now, &garbage);
    }

    /// Transmits `bytes` from the device side starting no earlier than `earliest`.
    fn send_to_host(&mut self, earliest: Duration, bytes: &[u8]) {
        let device_baud = self.device_baud();
        let Model::Stream {
            baud,
            out_line,
            in_line,
            duplex,
            ..
        } = &mut self.model
        else {
            return;
        };
        let line = match duplex {
            Duplex::Full => in_line,
            Duplex::Half => out_line,
        };
        let host_baud = *baud;
        let mut kept = Vec::with_capacity(bytes.len());
        {
            let mut faults = self.faults.lock();
            kept.extend(
                bytes
                    .iter()
                    .copied()
                    .filter(|_| !faults.drops(Direction::ToHost)),
            );
        }
        if device_baud == host_baud {
            let mut arrivals = Vec::with_capacity(kept.len());
            for byte in kept {
                let (_, end) = line.send(earliest, BITS_8N1);
                arrivals.push(Received {
                    at: end,
                    byte,
                    framing_error: false,
                });
            }
            for r in arrivals {
                self.push_to_host(r);
            }
        } else {
            // The device clocks the bytes out at its own rate; the host's UART resamples.
            let mut dev_line = Line::new(u64::from(device_baud));
            let start = earliest.max(line.free_at());
            let mut end = start;
            for _ in &kept {
                end = dev_line.send(start, BITS_8N1).1;
            }
            line.reset(end);
            let mut arrivals = Vec::new();
            resample(
                &kept,
                start,
                u64::from(device_baud),
                u64::from(host_baud),
                |r| arrivals.push(r),
            );
            for r in arrivals {
                self.push_to_host(r);
            }
        }
    }

    /// The rate the device talks at: a fault override, else the model's, else the link's.
    fn device_baud(&self) -> u32 {
        let Model::Stream { device, baud, .. } = &self.model else {
            return 0;
        };
        self.faults
            .lock()
            .device_baud
            .or_else(|| device.baud())
            .unwrap_or(*baud)
            .max(1)
    }

    fn write_stream(&mut self, now: Duration, parts: &[&[u8]]) -> Result<usize, LinkError> {
        let device_baud = self.device_baud();
        let limit = self.limits.to_device;
        let Model::Stream {
            baud,
            out_line,
            to_device,
            ..
        } = &mut self.model
        else {
            return Ok(0);
        };
        let room = limit.saturating_sub(to_device.len());
        let mut accepted: Vec<u8> = Vec::new();
        for part in parts {
            let take = part.len().min(room - accepted.len());
            accepted.extend_from_slice(part.get(..take).unwrap_or_default());
        }
        if accepted.is_empty() {
            return Ok(0);
        }
        let start = now.max(out_line.free_at());
        let mut wire = Vec::with_capacity(accepted.len());
        {
            let mut faults = self.faults.lock();
            for &byte in &accepted {
                let (_, end) = out_line.send(now, BITS_8N1);
                if !faults.drops(Direction::ToDevice) {
                    wire.push(Received {
                        at: end,
                        byte,
                        framing_error: false,
                    });
                }
            }
        }
        if device_baud == *baud {
            to_device.extend(wire);
        } else {
            let bytes: Vec<u8> = wire.iter().map(|r| r.byte).collect();
            resample(
                &bytes,
                start,
                u64::from(*baud),
                u64::from(device_baud),
                |r| to_device.push_back(r),
            );
        }
        self.stats.bytes_out += accepted.len() as u64;
        Ok(accepted.len())
    }

    fn write_spi(&mut self, now: Duration, parts: &[&[u8]]) -> Result<usize, LinkError> {
        let len: usize = parts.iter().map(|p| p.len()).sum();
        if len > self.limits.max_transaction {
            self.stats.errors += 1;
            return Err(LinkError::Unsupported {
                link: self.name.clone(),
                what: "transaction longer than the simulated link's max_transaction",
            });
        }
        if self.to_host.len() + len > self.limits.to_host {
            self.stats.errors += 1;
            return Err(LinkError::Overflow {
                link: self.name.clone(),
                what: "MISO queue",
                capacity: self.limits.to_host,
            });
        }
        if len == 0 {
            return Ok(0);
        }
        let Model::Spi {
            device,
            line,
            mosi,
            miso,
        } = &mut self.model
        else {
            return Ok(0);
        };
        mosi.clear();
        {
            let mut faults = self.faults.lock();
            for byte in parts.iter().flat_map(|p| p.iter().copied()) {
                mosi.push(if faults.drops(Direction::ToDevice) {
                    0xFF
                } else {
                    byte
                });
            }
        }
        miso.clear();
        miso.resize(len, 0xFF);
        let (_, end) = line.send(now, 8 * len as u64);
        self.device_time = self.device_time.max(end);
        // An undriven MISO floats high: the buffer already reads 0xFF.
        let _driven = device.transfer(self.device_time, mosi, miso);
        // The MISO bytes reach the host together when the transaction's last clock has
        // passed: a spidev transfer (SPI_IOC_MESSAGE) returns whole, and an SPI socket peer
        // answers a transaction with all of its bytes. (Handing them over one by one at each
        // byte's 8th clock woke the link's I/O thread once per byte for nothing: no driver
        // can use half a transaction.)
        let mut faults = self.faults.lock();
        let at = faults.held(end);
        let mut arrivals = Vec::with_capacity(len);
        for byte in miso.iter().copied() {
            let byte = if let Some(g) = faults.garbage.pop_front() {
                g
            } else if faults.drops(Direction::ToHost) {
                0xFF
            } else {
                byte
            };
            arrivals.push(Received {
                at,
                byte,
                framing_error: false,
            });
        }
        drop(faults);
        self.to_host.extend(arrivals);
        self.stats.bytes_out += len as u64;
        self.stats.transactions += 1;
        Ok(len)
    }

    fn transact(&mut self, now: Duration, parts: &[&[u8]]) -> Result<usize, LinkError> {
        self.check_plug(now)?;
        self.pump(now);
        match self.model {
            Model::Stream { .. } => self.write_stream(now, parts),
            Model::Spi { .. } => self.write_spi(now, parts),
        }
    }
}

impl Link for SimLink {
    fn kind(&self) -> LinkKind {
        match self.model {
            Model::Stream { .. } => LinkKind::Stream,
            Model::Spi { .. } => LinkKind::Spi,
        }
    }

    fn name(&self) -> &str {
        &self.name
    }

    fn write(&mut self, now: Duration, bytes: &[u8]) -> Result<usize, LinkError> {
        self.transact(now, &[bytes])
    }

    fn write_parts(&mut self, now: Duration, parts: &[&[u8]]) -> Result<usize, LinkError> {
        self.transact(now, parts)
    }

    /// Readable bytes are those whose last bit arrived at or before `now`. A byte received
    /// with a framing error (baud mismatch) is reported as one `Framing` error when it is
    /// next in line, and consumed.
    fn read(&mut self, now: Duration, buf: &mut [u8]) -> Result<usize, LinkError> {
        self.check_plug(now)?;
        self.pump(now);
        let mut n = 0;
        for slot in buf.iter_mut() {
            let Some(r) = self.to_host.front().copied().filter(|r| r.at <= now) else {
                break;
            };
            if r.framing_error {
                if n == 0 {
                    self.to_host.pop_front();
                    self.stats.errors += 1;
                    return Err(LinkError::Framing {
                        link: self.name.clone(),
                    });
                }
                break;
            }
            self.to_host.pop_front();
            *slot = r.byte;
            n += 1;
        }
        self.stats.bytes_in += n as u64;
        Ok(n)
    }

    fn flush(&mut self, now: Duration) -> Result<(), LinkError> {
        self.check_plug(now)?;
        self.pump(now);
        Ok(())
    }

    /// Discards everything in flight and reconnects, unless the plug is still out.
    fn reopen(&mut self, now: Duration) -> Result<(), LinkError> {
        if self.plug.reconnect(&self.faults).is_err() {
            self.stats.errors += 1;
            return Err(LinkError::Disconnected {
                link: self.name.clone(),
                detail: "the simulated device is still unplugged; replug it first",
            });
        }
        self.drop_in_flight(now);
        if matches!(self.model, Model::Stream { .. }) {
            // A reopened port runs at its configured rate again, as a tty does.
            self.retime(self.opening_baud);
        }
        self.stats.reconnects += 1;
        Ok(())
    }

    /// A stream wire only; takes effect at once (the host's bytes queued for the device
    /// keep the rate they were written at).
    fn set_baud(&mut self, now: Duration, baud: u32) -> Result<(), LinkError> {
        self.check_plug(now)?;
        if !matches!(self.model, Model::Stream { .. }) {
            self.stats.errors += 1;
            return Err(LinkError::Unsupported {
                link: self.name.clone(),
                what: "a line rate on an SPI wire",
            });
        }
        if baud == 0 {
            self.stats.errors += 1;
            return Err(LinkError::Config {
                link: self.name.clone(),
                reason: "baud 0".into(),
            });
        }
        self.pump(now);
        self.retime(baud);
        Ok(())
    }

    fn next_event(&self, now: Duration) -> Option<Duration> {
        let plug_changed = {
            let state = self.faults.lock();
            self.plug.changed(&state) || !state.garbage.is_empty()
        };
        if plug_changed {
            return Some(now);
        }
        let mut next = self.to_host.front().map(|r| r.at);
        if let Model::Stream {
            device, to_device, ..
        } = &self.model
        {
            let candidates = [
                to_device.front().map(|r| r.at),
                device.next_event(self.device_time.max(now)),
            ];
            for t in candidates.into_iter().flatten() {
                next = Some(next.map_or(t, |n| n.min(t)));
            }
        }
        next.map(|t| t.max(now))
    }

    fn stats(&self) -> LinkStats {
        self.stats
    }
}
