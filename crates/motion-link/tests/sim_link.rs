//! What only the simulated wire does: wire time, event-exact device stepping, buses and
//! fault injection, all under a fake clock.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use motion_link::sim::{
    Direction, Duplex, SimLimits, SimLink, SimWire, SpiBus, SpiDevice, StreamBus, StreamDevice,
};
use motion_link::{Link, LinkErrorKind};

const T0: Duration = Duration::from_secs(10);
const NS: Duration = Duration::from_nanos(1);

fn ms(x: f64) -> Duration {
    Duration::from_secs_f64(x / 1000.0)
}

/// A Trinamic-like responder: after a whole 9-byte frame whose first byte is its address,
/// it answers 9 bytes (the frame with the command byte incremented) after `processing`.
/// It logs the instant each frame completed.
struct Responder {
    address: u8,
    processing: Duration,
    frame: Vec<u8>,
    reply: Vec<u8>,
    reply_at: Option<Duration>,
    heard_at: Arc<Mutex<Vec<Duration>>>,
    baud: Option<u32>,
}

impl Responder {
    fn new(address: u8) -> (Self, Arc<Mutex<Vec<Duration>>>) {
        let heard_at = Arc::new(Mutex::new(Vec::new()));
        let device = Self {
            address,
            processing: Duration::ZERO,
            frame: Vec::new(),
            reply: Vec::new(),
            reply_at: None,
            heard_at: heard_at.clone(),
            baud: None,
        };
        (device, heard_at)
    }
}

impl StreamDevice for Responder {
    fn receive(&mut self, now: Duration, bytes: &[u8]) {
        for &b in bytes {
            self.frame.push(b);
            if self.frame.len() == 9 {
                self.heard_at.lock().unwrap().push(now);
                if self.frame[0] == self.address {
                    self.reply = self.frame.clone();
                    self.reply[1] = self.reply[1].wrapping_add(1);
                    self.reply_at = Some(now + self.processing);
                }
                self.frame.clear();
            }
        }
    }
    fn transmit(&mut self, now: Duration, out: &mut [u8]) -> usize {
        match self.reply_at {
            Some(at) if at <= now => {}
            _ => return 0,
        }
        let n = out.len().min(self.reply.len());
        out[..n].copy_from_slice(&self.reply[..n]);
        self.reply.drain(..n);
        if self.reply.is_empty() {
            self.reply_at = None;
        }
        n
    }
    fn next_event(&self, _now: Duration) -> Option<Duration> {
        self.reply_at
    }
    fn baud(&self) -> Option<u32> {
        self.baud
    }
}

const REQUEST: [u8; 9] = [1, 0x43, 0, 0, 0, 0, 0, 0, 0];
const REPLY: [u8; 9] = [1, 0x44, 0, 0, 0, 0, 0, 0, 0];

fn read_all(link: &mut SimLink, now: Duration) -> Vec<u8> {
    let mut buf = [0u8; 64];
    let n = link.read(now, &mut buf).expect("read");
    buf[..n].to_vec()
}

#[test]
fn nine_bytes_at_19200_baud_take_4_6875_ms_each_way() {
    let (device, heard_at) = Responder::new(1);
    let mut link = SimLink::stream("pack", 19_200, Box::new(device));
    assert_eq!(
        link.wire(),
        SimWire::Serial {
            baud: 19_200,
            duplex: Duplex::Full
        }
    );
    assert_eq!(link.write(T0, &REQUEST).unwrap(), 9);
    // The request's last stop bit crosses the wire 9 × 10 / 19200 s = 4.6875 ms later.
    let frame_time = ms(4.6875);
    // One byte: 10 / 19200 s = 520833.3 ns, rounded up to the nanosecond.
    let byte_time = Duration::from_nanos(520_834);
    assert_eq!(link.next_event(T0), Some(T0 + byte_time));
    assert!(read_all(&mut link, T0 + frame_time - NS).is_empty());
    assert!(heard_at.lock().unwrap().is_empty());
    assert!(read_all(&mut link, T0 + frame_time).is_empty());
    assert_eq!(*heard_at.lock().unwrap(), vec![T0 + frame_time]);
    // The reply starts at once and needs another 4.6875 ms: nothing is readable before a
    // byte's last bit arrived.
    let done = T0 + frame_time * 2;
    assert_eq!(
        link.next_event(T0 + frame_time),
        Some(T0 + frame_time + byte_time)
    );
    let early = read_all(&mut link, done - NS);
    assert_eq!(early, REPLY[..8]);
    assert_eq!(read_all(&mut link, done), REPLY[8..]);
    assert_eq!(link.next_event(done), None);
}

/// A board behind USB (the QSB: "a virtual COM port connection through the USB", QSB
/// command list) is polled once per 1 ms frame: its bytes reach the host together at the
/// end of the frame in which their last bit arrived, never before, and the link's next
/// event is that frame's end, not each byte.
#[test]
fn a_board_behind_usb_hands_its_bytes_over_at_the_end_of_each_frame() {
    let (device, _) = Responder::new(1);
    let mut link = SimLink::stream("usb", 19_200, Box::new(device)).with_host_frames(ms(1.0));
    link.write(T0, &REQUEST).unwrap();
    let frame_time = ms(4.6875);
    assert!(read_all(&mut link, T0 + frame_time).is_empty());
    // The reply's bytes arrive from T0 + 5.208 ms to T0 + 9.375 ms; the first (arrived at
    // 5.208 ms) is the host's at the end of that frame, 6 ms.
    assert_eq!(link.next_event(T0 + frame_time), Some(T0 + ms(6.0)));
    assert!(read_all(&mut link, T0 + ms(6.0) - NS).is_empty());
    // Bytes 1 and 2 (5.208, 5.729 ms) at 6 ms; 3 and 4 (6.25, 6.77 ms) at 7 ms.
    assert_eq!(read_all(&mut link, T0 + ms(6.0)), REPLY[..2]);
    assert_eq!(link.next_event(T0 + ms(6.0)), Some(T0 + ms(7.0)));
    assert!(read_all(&mut link, T0 + ms(6.5)).is_empty());
    assert_eq!(read_all(&mut link, T0 + ms(7.0)), REPLY[2..4]);
    // The last byte (9.375 ms) at 10 ms: the whole reply, in frame-sized pieces.
    let mut rest = read_all(&mut link, T0 + ms(9.9));
    assert_eq!(rest, REPLY[4..8]);
    rest = read_all(&mut link, T0 + ms(10.0));
    assert_eq!(rest, REPLY[8..]);
    assert_eq!(link.next_event(T0 + ms(10.0)), None);
}

#[test]
fn a_late_reader_sees_exactly_the_same_bytes_and_times() {
    let (device, heard_at) = Responder::new(1);
    let mut link = SimLink::stream("pack", 19_200, Box::new(device));
    link.write(T0, &REQUEST).unwrap();
    link.write(T0, &REQUEST).unwrap();
    // One coarse read long after: both replies complete, the device heard both frames at
    // their exact instants.
    let got = read_all(&mut link, T0 + Duration::from_secs(1));
    assert_eq!(got, [REPLY, REPLY].concat());
    assert_eq!(
        *heard_at.lock().unwrap(),
        vec![T0 + ms(4.6875), T0 + ms(9.375)]
    );
}

#[test]
fn half_duplex_reply_waits_for_the_pair_to_be_free() {
    for (duplex, reply_done) in [(Duplex::Full, ms(9.375)), (Duplex::Half, ms(14.0625))] {
        let (device, _) = Responder::new(1);
        let mut link = SimLink::stream_with("rs485", 19_200, duplex, Box::new(device));
        link.write(T0, &REQUEST).unwrap();
        // A second frame to another address occupies the host transmitter until 9.375 ms.
        let mut other = REQUEST;
        other[0] = 7;
        link.write(T0 + ms(1.0), &other).unwrap();
        assert_eq!(
            read_all(&mut link, T0 + reply_done - NS).len(),
            8,
            "{duplex:?}"
        );
        assert_eq!(read_all(&mut link, T0 + reply_done).len(), 1, "{duplex:?}");
    }
}

#[test]
fn processing_time_and_injected_delay_postpone_the_reply() {
    let (mut device, _) = Responder::new(1);
    device.processing = ms(6.0);
    let mut link = SimLink::stream("pack", 19_200, Box::new(device));
    let faults = link.faults();
    faults.set_reply_delay(ms(10.0));
    link.write(T0, &REQUEST).unwrap();
    let done = T0 + ms(4.6875 + 6.0 + 10.0 + 4.6875);
    assert_eq!(read_all(&mut link, done - NS).len(), 8);
    assert_eq!(read_all(&mut link, done).len(), 1);
}

#[test]
fn garbage_is_read_as_bytes_ahead_of_the_reply_and_takes_wire_time() {
    let (device, _) = Responder::new(1);
    let mut link = SimLink::stream("pack", 19_200, Box::new(device));
    let faults = link.faults();
    faults.inject_garbage(&[0xAA, 0x55, 0x00]);
    assert_eq!(link.next_event(T0), Some(T0));
    assert!(read_all(&mut link, T0).is_empty());
    let three = ms(4.6875) / 3;
    assert_eq!(read_all(&mut link, T0 + three), [0xAA, 0x55, 0x00]);
    link.write(T0 + three, &REQUEST).unwrap();
    let got = read_all(&mut link, T0 + Duration::from_secs(1));
    assert_eq!(got, REPLY);
    // Seeded noise is reproducible.
    let noise = |seed| {
        let (device, _) = Responder::new(1);
        let mut link = SimLink::stream("pack", 19_200, Box::new(device)).with_seed(seed);
        link.faults().inject_noise(16);
        // Injected bytes go on the wire at the link's next call.
        assert!(read_all(&mut link, T0).is_empty());
        read_all(&mut link, T0 + Duration::from_secs(1))
    };
    assert_eq!(noise(5), noise(5));
    assert_ne!(noise(5), noise(6));
    assert_eq!(noise(5).len(), 16);
}

#[test]
fn dropped_bytes_by_count_and_by_seeded_probability() {
    let (device, heard) = Responder::new(1);
    let mut link = SimLink::stream("pack", 19_200, Box::new(device));
    let faults = link.faults();
    faults.drop_next(Direction::ToHost, 2);
    link.write(T0, &REQUEST).unwrap();
    assert_eq!(read_all(&mut link, T0 + Duration::from_secs(1)), REPLY[2..]);
    assert_eq!(faults.dropped(Direction::ToHost), 2);
    // A request short of one byte never completes a frame.
    faults.drop_next(Direction::ToDevice, 1);
    link.write(T0 + Duration::from_secs(2), &REQUEST).unwrap();
    assert!(read_all(&mut link, T0 + Duration::from_secs(3)).is_empty());
    assert_eq!(heard.lock().unwrap().len(), 1);

    let lossy = |seed| {
        let (device, _) = Responder::new(1);
        let mut link = SimLink::stream("pack", 115_200, Box::new(device)).with_seed(seed);
        link.faults().set_drop_probability(Direction::ToHost, 0.5);
        let mut got = Vec::new();
        for i in 0..20u64 {
            let t = T0 + Duration::from_millis(10 * i);
            link.write(t, &REQUEST).unwrap();
            got.extend(read_all(&mut link, t + Duration::from_millis(5)));
        }
        got.len()
    };
    let kept = lossy(1);
    assert_eq!(kept, lossy(1));
    assert!((40..140).contains(&kept), "about half of 180 kept: {kept}");
}

#[test]
fn unplug_is_disconnected_until_replug_and_reopen() {
    let (device, _) = Responder::new(1);
    let mut link = SimLink::stream("pack", 19_200, Box::new(device));
    let faults = link.faults();
    link.write(T0, &REQUEST).unwrap();
    faults.unplug();
    assert!(faults.is_unplugged());
    let err = link.read(T0 + ms(20.0), &mut [0; 16]).unwrap_err();
    assert_eq!(err.kind(), LinkErrorKind::Disconnected);
    assert!(err.to_string().contains("sim pack"), "{err}");
    let err = link.write(T0 + ms(21.0), &REQUEST).unwrap_err();
    assert_eq!(err.kind(), LinkErrorKind::Disconnected);
    let err = link.reopen(T0 + ms(22.0)).unwrap_err();
    assert_eq!(err.kind(), LinkErrorKind::Disconnected);
    assert!(err.to_string().contains("replug"), "{err}");
    faults.replug();
    // A replugged device is not enough: the old connection is dead.
    let err = link.read(T0 + ms(23.0), &mut [0; 16]).unwrap_err();
    assert_eq!(err.kind(), LinkErrorKind::Disconnected);
    link.reopen(T0 + ms(24.0)).unwrap();
    // The reply in flight at the unplug is gone; new traffic flows.
    assert!(read_all(&mut link, T0 + ms(25.0)).is_empty());
    link.write(T0 + ms(30.0), &REQUEST).unwrap();
    assert_eq!(read_all(&mut link, T0 + ms(50.0)), REPLY);
    let stats = link.stats();
    assert_eq!(stats.reconnects, 1);
    assert_eq!(stats.errors, 4);
}

#[test]
fn a_baud_mismatch_garbles_bytes_and_reports_framing_errors() {
    let run = |device_baud: Option<u32>, by_fault: bool| {
        let (mut device, heard) = Responder::new(1);
        let mut link_baud = 19_200;
        if by_fault {
            link_baud = 38_400;
        } else {
            device.baud = device_baud;
        }
        let mut link = SimLink::stream("pack", link_baud, Box::new(device));
        if by_fault {
            link.faults().set_device_baud(device_baud);
        }
        link.faults()
            .inject_garbage(b"R14\r\nr1400001201!\r\n\xff\x00\x0f\xf0");
        let mut got = Vec::new();
        let mut framing = 0;
        let mut buf = [0u8; 64];
        for i in 0..100u64 {
            let now = T0 + Duration::from_millis(i);
            match link.read(now, &mut buf) {
                Ok(n) => got.extend_from_slice(&buf[..n]),
                Err(e) => {
                    assert_eq!(e.kind(), LinkErrorKind::Framing, "{e}");
                    assert!(e.to_string().contains("baud"), "{e}");
                    framing += 1;
                }
            }
        }
        link.write(T0 + Duration::from_secs(1), &REQUEST).unwrap();
        let _ = link.read(T0 + Duration::from_secs(2), &mut buf);
        let frames = heard.lock().unwrap().len();
        (got, framing, frames)
    };
    let sent = b"R14\r\nr1400001201!\r\n\xff\x00\x0f\xf0".to_vec();
    let (clean, framing, frames) = run(Some(19_200), false);
    assert_eq!((clean, framing, frames), (sent.clone(), 0, 1));
    for (baud, by_fault) in [
        (Some(9_600), false),
        (Some(38_400), false),
        (Some(115_200), true),
    ] {
        let (got, framing, _) = run(baud, by_fault);
        assert_ne!(got, sent, "{baud:?}");
        assert!(
            framing > 0 || got.len() != sent.len(),
            "{baud:?}: {got:?} {framing}"
        );
        assert_eq!(run(baud, by_fault).0, got, "deterministic");
    }
}

#[test]
fn a_stream_bus_shares_the_pair_between_boards() {
    let (one, heard_one) = Responder::new(1);
    let (two, heard_two) = Responder::new(2);
    let bus = StreamBus::new().with(Box::new(one)).with(Box::new(two));
    let mut link = SimLink::stream_with("rs485", 19_200, Duplex::Half, Box::new(bus));
    let mut to_two = REQUEST;
    to_two[0] = 2;
    link.write(T0, &to_two).unwrap();
    let got = read_all(&mut link, T0 + Duration::from_secs(1));
    assert_eq!(got, [2, 0x44, 0, 0, 0, 0, 0, 0, 0]);
    // Board 1 heard the request and board 2's reply; board 2 only the request.
    assert_eq!(heard_one.lock().unwrap().len(), 2);
    assert_eq!(heard_two.lock().unwrap().len(), 1);
}

/// An SPI_motor-like board: answers transactions addressed to it with a counter.
struct Addressed {
    address: u8,
    count: u8,
    times: Arc<Mutex<Vec<Duration>>>,
}

impl SpiDevice for Addressed {
    fn transfer(&mut self, now: Duration, mosi: &[u8], miso: &mut [u8]) -> bool {
        self.times.lock().unwrap().push(now);
        if mosi.first().map(|a| a & 0xFE) != Some(self.address) {
            return false;
        }
        for b in miso.iter_mut() {
            self.count = self.count.wrapping_add(1);
            *b = self.count;
        }
        true
    }
    fn advance(&mut self, _now: Duration) {}
}

#[test]
fn spi_wire_time_float_high_and_contention() {
    let times = Arc::new(Mutex::new(Vec::new()));
    let board = |address| {
        Box::new(Addressed {
            address,
            count: 0,
            times: times.clone(),
        })
    };
    let bus = SpiBus::new()
        .with(board(0x90))
        .with(board(0x92))
        .with(board(0x92));
    let mut link = SimLink::spi("motors", 500_000, Box::new(bus));
    // 42 bytes at 500 kHz: 42 × 8 / 500000 s = 672 µs; the MISO bytes are readable together
    // once the last clock has passed (a spidev transfer returns whole).
    let mut mosi = [0u8; 42];
    mosi[0] = 0x91;
    assert_eq!(link.write(T0, &mosi).unwrap(), 42);
    assert_eq!(
        *times.lock().unwrap(),
        vec![T0 + Duration::from_micros(672); 3]
    );
    let mut buf = [0u8; 64];
    assert_eq!(
        link.read(T0 + Duration::from_micros(672) - NS, &mut buf)
            .unwrap(),
        0
    );
    assert_eq!(
        link.read(T0 + Duration::from_micros(672), &mut buf)
            .unwrap(),
        42
    );
    assert_eq!(buf[..42], (1..=42).collect::<Vec<u8>>()[..]);
    // A transaction nobody answers reads 0xFF; two drivers AND.
    mosi[0] = 0x94;
    link.write(T0 + ms(1.0), &mosi[..3]).unwrap();
    mosi[0] = 0x92;
    link.write(T0 + ms(1.0), &mosi[..3]).unwrap();
    let got = read_all(&mut link, T0 + ms(2.0));
    assert_eq!(got, [0xFF, 0xFF, 0xFF, 1 & 1, 2 & 2, 3 & 3]);
    // Back-to-back transactions queue on the bus: the second ended 48 µs after the first.
    let t = times.lock().unwrap().clone();
    assert_eq!(t[6] - t[3], Duration::from_micros(48));
}

#[test]
fn spi_faults_corrupt_miso_and_unplug_disconnects() {
    let times = Arc::new(Mutex::new(Vec::new()));
    let board = Addressed {
        address: 0x90,
        count: 0,
        times,
    };
    let mut link = SimLink::spi("motor", 1_000_000, Box::new(board));
    let faults = link.faults();
    faults.inject_garbage(&[0xEE]);
    faults.drop_next(Direction::ToHost, 1);
    link.write(T0, &[0x90, 0, 0, 0]).unwrap();
    assert_eq!(read_all(&mut link, T0 + ms(1.0)), [0xEE, 0xFF, 3, 4]);
    faults.unplug();
    let err = link.write(T0 + ms(2.0), &[0x90]).unwrap_err();
    assert_eq!(err.kind(), LinkErrorKind::Disconnected);
    faults.replug();
    link.reopen(T0 + ms(3.0)).unwrap();
    link.write(T0 + ms(4.0), &[0x90]).unwrap();
    assert_eq!(read_all(&mut link, T0 + ms(5.0)), [5]);
}

#[test]
fn bounded_queues_refuse_or_count_overruns() {
    let limits = SimLimits {
        to_device: 4,
        to_host: 3,
        max_transaction: 2,
    };
    let (device, _) = Responder::new(1);
    let mut link = SimLink::stream("pack", 19_200, Box::new(device)).with_limits(limits);
    assert_eq!(
        link.write(T0, &REQUEST).unwrap(),
        4,
        "accepts only what fits"
    );
    assert_eq!(link.write(T0, &REQUEST[4..]).unwrap(), 0);
    link.write(T0 + ms(3.0), &REQUEST[4..]).unwrap();
    link.write(T0 + ms(6.0), &REQUEST[8..]).unwrap();
    assert_eq!(read_all(&mut link, T0 + Duration::from_secs(1)).len(), 3);
    assert_eq!(link.overruns(), 6);

    let mut spi = SimLink::spi(
        "s",
        1_000_000,
        Box::new(Addressed {
            address: 0,
            count: 0,
            times: Arc::new(Mutex::new(Vec::new())),
        }),
    )
    .with_limits(limits);
    let err = spi.write(T0, &[0, 0, 0]).unwrap_err();
    assert_eq!(err.kind(), LinkErrorKind::Unsupported);
    spi.write(T0, &[0, 0]).unwrap();
    let err = spi.write(T0, &[0, 0]).unwrap_err();
    assert_eq!(err.kind(), LinkErrorKind::Overflow);
}
