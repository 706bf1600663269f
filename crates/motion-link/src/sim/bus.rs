//! Several simulated devices on one wire: an RS-485 pair ([`StreamBus`]) or an SPI bus with
//! a shared chip select ([`SpiBus`]).
//!
//! Both buses implement the device traits themselves, so a bus can stand wherever one
//! device can (a [`SimLink`](crate::sim::SimLink), the `motion-sim` binary, another bus).

use core::fmt;
use core::time::Duration;
use std::collections::VecDeque;

use super::device::{SpiDevice, StreamDevice};
use super::line::garble;

/// Largest chunk a bus pulls from one device per call to [`StreamDevice::transmit`].
const CHUNK: usize = 256;

/// Several [`StreamDevice`]s on one shared pair (RS-485 multi-drop).
///
/// Every byte the host sends reaches every device. Every byte a device transmits reaches
/// the host *and* every other device on the bus, as on a real two-wire RS-485 segment where
/// all receivers listen to the one pair. The bus forwards bytes at the instant they are
/// polled from the device; wire time is charged by whoever drives the bus (a
/// [`SimLink`](crate::sim::SimLink) charges it on the way to the host).
///
/// When more than one device has bytes in the same [`transmit`](StreamDevice::transmit)
/// call, their transmissions overlapped in time: the bus counts a
/// [`collision`](Self::collisions) and delivers the bytes one device after the other (a
/// real pair would garble them; the count lets a test assert that the driver never lets
/// two boards talk at once).
///
/// Once told the rate the pair runs at ([`StreamDevice::line_rate`], as a
/// [`SimLink`](crate::sim::SimLink) does), the bus reports that rate as its own and garbles
/// ([`garble`](crate::sim::garble)) what crosses between the pair and a device listening at
/// another rate ([`StreamDevice::baud`]): a board switched to a new rate hears only garbage
/// from a host still at the old one, and the other way round.
pub struct StreamBus {
    devices: Vec<Box<dyn StreamDevice>>,
    /// The rate of the pair, once told.
    line: Option<u32>,
    /// Bytes transmitted by the devices, not yet handed to the host.
    to_host: VecDeque<u8>,
    scratch: Vec<u8>,
    collisions: u64,
}

impl StreamBus {
    /// An empty bus.
    pub fn new() -> Self {
        Self {
            devices: Vec::new(),
            line: None,
            to_host: VecDeque::new(),
            scratch: vec![0; CHUNK],
            collisions: 0,
        }
    }

    /// Attaches a device to the bus.
    pub fn push(&mut self, device: Box<dyn StreamDevice>) {
        self.devices.push(device);
    }

    /// Builder form of [`push`](Self::push).
    #[must_use]
    pub fn with(mut self, device: Box<dyn StreamDevice>) -> Self {
        self.push(device);
        self
    }

    /// Number of devices on the bus.
    pub fn len(&self) -> usize {
        self.devices.len()
    }

    /// `true` when no device is attached.
    pub fn is_empty(&self) -> bool {
        self.devices.is_empty()
    }

    /// How many times two or more devices transmitted in the same poll.
    pub fn collisions(&self) -> u64 {
        self.collisions
    }

    /// Polls every device at `now`, forwarding what each sends to the others and queueing
    /// it for the host.
    fn poll_devices(&mut self, now: Duration) {
        let mut talkers = 0usize;
        for i in 0..self.devices.len() {
            let mut talked = false;
            while let Some(device) = self.devices.get_mut(i) {
                let n = device
                    .transmit(now, &mut self.scratch)
                    .min(self.scratch.len());
                if n == 0 {
                    break;
                }
                talked = true;
                let sent = self.scratch.get(..n).unwrap_or_default();
                let own = device.baud();
                match (own, self.line) {
                    (Some(own), Some(line)) if own != line => {
                        self.to_host.extend(garble(sent, own, line));
                    }
                    _ => self.to_host.extend(sent.iter().copied()),
                }
                for (j, other) in self.devices.iter_mut().enumerate() {
                    if j != i {
                        deliver(other.as_mut(), now, sent, own);
                    }
                }
                if n < self.scratch.len() {
                    break;
                }
            }
            talkers += usize::from(talked);
        }
        if talkers > 1 {
            self.collisions += 1;
        }
    }
}

impl Default for StreamBus {
    fn default() -> Self {
        Self::new()
    }
}

impl fmt::Debug for StreamBus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("StreamBus")
            .field("devices", &self.devices.len())
            .field("queued_to_host", &self.to_host.len())
            .field("collisions", &self.collisions)
            .finish()
    }
}

/// Hands `device` the bytes sent at `rate` (`None`: at the device's own), garbled when it
/// listens at another.
fn deliver(device: &mut dyn StreamDevice, now: Duration, bytes: &[u8], rate: Option<u32>) {
    match (rate, device.baud()) {
        (Some(sent), Some(own)) if sent != own => {
            let heard = garble(bytes, sent, own);
            if !heard.is_empty() {
                device.receive(now, &heard);
            }
        }
        _ => device.receive(now, bytes),
    }
}

impl StreamDevice for StreamBus {
    fn receive(&mut self, now: Duration, bytes: &[u8]) {
        // Replies already started before these bytes arrived must be seen first by the
        // other devices, in time order.
        self.poll_devices(now);
        for device in &mut self.devices {
            deliver(device.as_mut(), now, bytes, self.line);
        }
    }

    fn transmit(&mut self, now: Duration, out: &mut [u8]) -> usize {
        self.poll_devices(now);
        let n = out.len().min(self.to_host.len());
        for (slot, byte) in out.iter_mut().zip(self.to_host.drain(..n)) {
            *slot = byte;
        }
        n
    }

    fn next_event(&self, now: Duration) -> Option<Duration> {
        if !self.to_host.is_empty() {
            return Some(now);
        }
        self.devices.iter().filter_map(|d| d.next_event(now)).min()
    }

    /// The pair's rate once told ([`line_rate`](StreamDevice::line_rate)); before, the
    /// rate of the first device that reports one.
    fn baud(&self) -> Option<u32> {
        self.line
            .or_else(|| self.devices.iter().find_map(|d| d.baud()))
    }

    fn line_rate(&mut self, baud: u32) {
        self.line = Some(baud);
        for device in &mut self.devices {
            device.line_rate(baud);
        }
    }
}

/// Several [`SpiDevice`]s sharing MOSI, MISO, SCLK and one chip select.
///
/// Every device sees every transaction. A MISO line no device drives floats high and reads
/// 0xFF. When two devices drive MISO in the same transaction the bus ANDs their bytes (a
/// driven low wins, as with open-drain outputs) and counts a
/// [`contention`](Self::contentions).
pub struct SpiBus {
    devices: Vec<Box<dyn SpiDevice>>,
    scratch: Vec<u8>,
    contentions: u64,
}

impl SpiBus {
    /// An empty bus.
    pub fn new() -> Self {
        Self {
            devices: Vec::new(),
            scratch: Vec::new(),
            contentions: 0,
        }
    }

    /// Attaches a device to the bus.
    pub fn push(&mut self, device: Box<dyn SpiDevice>) {
        self.devices.push(device);
    }

    /// Builder form of [`push`](Self::push).
    #[must_use]
    pub fn with(mut self, device: Box<dyn SpiDevice>) -> Self {
        self.push(device);
        self
    }

    /// Number of devices on the bus.
    pub fn len(&self) -> usize {
        self.devices.len()
    }

    /// `true` when no device is attached.
    pub fn is_empty(&self) -> bool {
        self.devices.is_empty()
    }

    /// How many transactions had more than one device driving MISO.
    pub fn contentions(&self) -> u64 {
        self.contentions
    }
}

impl Default for SpiBus {
    fn default() -> Self {
        Self::new()
    }
}

impl fmt::Debug for SpiBus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SpiBus")
            .field("devices", &self.devices.len())
            .field("contentions", &self.contentions)
            .finish()
    }
}

impl SpiDevice for SpiBus {
    fn transfer(&mut self, now: Duration, mosi: &[u8], miso: &mut [u8]) -> bool {
        let len = mosi.len().min(miso.len());
        let mosi = mosi.get(..len).unwrap_or_default();
        self.scratch.resize(len, 0xFF);
        let mut drivers = 0usize;
        for device in &mut self.devices {
            self.scratch.fill(0xFF);
            if !device.transfer(now, mosi, &mut self.scratch) {
                continue;
            }
            drivers += 1;
            for (line, driven) in miso.iter_mut().zip(&self.scratch) {
                *line = if drivers == 1 {
                    *driven
                } else {
                    *line & *driven
                };
            }
        }
        if drivers > 1 {
            self.contentions += 1;
        }
        drivers > 0
    }

    fn advance(&mut self, now: Duration) {
        for device in &mut self.devices {
            device.advance(now);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::{Arc, Mutex};

    /// Records what it receives; transmits a scripted reply once it has heard `trigger`.
    struct Talker {
        heard: Arc<Mutex<Vec<u8>>>,
        trigger: u8,
        reply: Vec<u8>,
        pending: Vec<u8>,
    }

    impl StreamDevice for Talker {
        fn receive(&mut self, _now: Duration, bytes: &[u8]) {
            self.heard.lock().unwrap().extend_from_slice(bytes);
            if bytes.contains(&self.trigger) {
                self.pending.extend_from_slice(&self.reply);
            }
        }
        fn transmit(&mut self, _now: Duration, out: &mut [u8]) -> usize {
            let n = out.len().min(self.pending.len());
            out[..n].copy_from_slice(&self.pending[..n]);
            self.pending.drain(..n);
            n
        }
        fn next_event(&self, now: Duration) -> Option<Duration> {
            (!self.pending.is_empty()).then_some(now)
        }
    }

    fn talker(trigger: u8, reply: &[u8]) -> (Box<dyn StreamDevice>, Arc<Mutex<Vec<u8>>>) {
        let heard = Arc::new(Mutex::new(Vec::new()));
        let device = Talker {
            heard: heard.clone(),
            trigger,
            reply: reply.to_vec(),
            pending: Vec::new(),
        };
        (Box::new(device), heard)
    }

    #[test]
    fn stream_bus_delivers_host_bytes_to_all_and_device_bytes_to_host_and_others() {
        let (a, heard_a) = talker(1, b"AAA");
        let (b, heard_b) = talker(2, b"B");
        let mut bus = StreamBus::new().with(a).with(b);
        let t = Duration::from_millis(1);
        bus.receive(t, &[1]);
        assert_eq!(bus.next_event(t), Some(t));
        let mut out = [0u8; 2];
        // Output larger than the caller's buffer stays queued.
        assert_eq!(bus.transmit(t, &mut out), 2);
        assert_eq!(&out, b"AA");
        assert_eq!(bus.transmit(t, &mut out), 1);
        assert_eq!(out[0], b'A');
        assert_eq!(bus.transmit(t, &mut out), 0);
        assert_eq!(*heard_a.lock().unwrap(), vec![1]);
        assert_eq!(*heard_b.lock().unwrap(), vec![1, b'A', b'A', b'A']);
        assert_eq!(bus.collisions(), 0);
        bus.receive(t, &[1, 2]);
        let mut big = [0u8; 16];
        assert_eq!(bus.transmit(t, &mut big), 4);
        assert_eq!(bus.collisions(), 1);
    }

    struct Addressed {
        address: u8,
        answer: u8,
        seen: usize,
    }

    impl SpiDevice for Addressed {
        fn transfer(&mut self, _now: Duration, mosi: &[u8], miso: &mut [u8]) -> bool {
            self.seen += 1;
            if mosi.first() != Some(&self.address) {
                return false;
            }
            miso.fill(self.answer);
            true
        }
        fn advance(&mut self, _now: Duration) {}
    }

    #[test]
    fn spi_bus_floats_high_selects_by_address_and_ands_contention() {
        let mut bus = SpiBus::new()
            .with(Box::new(Addressed {
                address: 0x90,
                answer: 0x3C,
                seen: 0,
            }))
            .with(Box::new(Addressed {
                address: 0x92,
                answer: 0x0F,
                seen: 0,
            }))
            .with(Box::new(Addressed {
                address: 0x92,
                answer: 0xF5,
                seen: 0,
            }));
        let t = Duration::ZERO;
        let mut miso = [0xAAu8; 3];
        assert!(!bus.transfer(t, &[0x94, 0, 0], &mut miso));
        assert_eq!(miso, [0xAA; 3], "undriven: caller's buffer untouched");
        assert!(bus.transfer(t, &[0x90, 0, 0], &mut miso));
        assert_eq!(miso, [0x3C; 3]);
        assert_eq!(bus.contentions(), 0);
        assert!(bus.transfer(t, &[0x92, 0, 0], &mut miso));
        assert_eq!(miso, [0x05; 3]);
        assert_eq!(bus.contentions(), 1);
    }

    #[test]
    fn buses_nest() {
        let inner = SpiBus::new().with(Box::new(Addressed {
            address: 1,
            answer: 7,
            seen: 0,
        }));
        let mut outer = SpiBus::new().with(Box::new(inner));
        let mut miso = [0u8; 2];
        assert!(outer.transfer(Duration::ZERO, &[1, 0], &mut miso));
        assert_eq!(miso, [7, 7]);
        let (a, _) = talker(5, b"x");
        let mut outer = StreamBus::new().with(Box::new(StreamBus::new().with(a)));
        outer.receive(Duration::ZERO, &[5]);
        let mut out = [0u8; 4];
        assert_eq!(outer.transmit(Duration::ZERO, &mut out), 1);
    }
}
