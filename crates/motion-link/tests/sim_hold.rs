//! `SimFaults::hold`: a host (or a board's process) that got no CPU for a while. The
//! board's side keeps its timing; the bytes due at the host in the window reach it at the
//! window's end, in order, and nothing else moves.

use std::time::Duration;

use motion_link::Link;
use motion_link::sim::{SimLink, SpiDevice, StreamDevice};

const MS: Duration = Duration::from_millis(1);

/// A board that sends one byte (a counter, 0, 1, 2, …) every millisecond from 1 ms on,
/// like a streamed encoder line.
struct Ticker {
    next: Duration,
    count: u8,
}

impl Ticker {
    fn new() -> Self {
        Self { next: MS, count: 0 }
    }
}

impl StreamDevice for Ticker {
    fn receive(&mut self, _now: Duration, _bytes: &[u8]) {}

    fn transmit(&mut self, now: Duration, out: &mut [u8]) -> usize {
        let mut n = 0;
        while self.next <= now && n < out.len() {
            out[n] = self.count;
            self.count = self.count.wrapping_add(1);
            self.next += MS;
            n += 1;
        }
        n
    }

    fn next_event(&self, _now: Duration) -> Option<Duration> {
        Some(self.next)
    }
}

/// Reads every 0.1 ms up to `end`; returns each byte with the instant it was read.
fn read_until(link: &mut SimLink, from: Duration, end: Duration) -> Vec<(Duration, u8)> {
    let mut got = Vec::new();
    let mut now = from;
    let mut buf = [0u8; 256];
    while now <= end {
        let n = link.read(now, &mut buf).expect("read");
        got.extend(buf[..n].iter().map(|b| (now, *b)));
        now += MS / 10;
    }
    got
}

#[test]
fn bytes_due_in_the_window_arrive_at_its_end_in_order() {
    // 1 Mbaud: one byte's wire time is 10 µs, so byte k (sent at k ms) arrives at k ms
    // + 10 µs, read at the next 0.1 ms.
    let mut link = SimLink::stream("ticker", 1_000_000, Box::new(Ticker::new()));
    let faults = link.faults();
    faults.hold(20 * MS, 50 * MS);
    let got = read_until(&mut link, Duration::ZERO, 100 * MS);
    let bytes: Vec<u8> = got.iter().map(|(_, b)| *b).collect();
    // Byte k is sent at (k + 1) ms: 99 bytes by 100 ms.
    let expected: Vec<u8> = (0..99).collect();
    assert_eq!(bytes, expected, "every byte, in order, none lost");
    for (at, byte) in &got {
        let sent = MS * (u32::from(*byte) + 1);
        let due = sent + Duration::from_micros(10);
        if (20 * MS..70 * MS).contains(&due) {
            assert_eq!(
                *at,
                70 * MS,
                "byte {byte} due at {due:?} is held to the end"
            );
        } else {
            assert!(
                *at >= due && *at < due + MS / 10,
                "byte {byte}: read at {at:?}, due {due:?}"
            );
        }
    }
    // Nothing at all between the window's start and its end.
    assert!(
        !got.iter().any(|(at, _)| (20 * MS..70 * MS).contains(at)),
        "the host heard nothing while held"
    );
}

#[test]
fn holds_chain_and_a_board_behind_usb_gets_them_at_a_frame_end() {
    let mut link =
        SimLink::stream("ticker", 1_000_000, Box::new(Ticker::new())).with_host_frames(MS);
    let faults = link.faults();
    // Two windows, the second starting inside the first: one stall 10..45 ms.
    faults.hold(10 * MS, 20 * MS);
    faults.hold(25 * MS, Duration::from_micros(19_500));
    let got = read_until(&mut link, Duration::ZERO, 60 * MS);
    let bytes: Vec<u8> = got.iter().map(|(_, b)| *b).collect();
    assert_eq!(bytes, (0..59).collect::<Vec<u8>>());
    for (at, byte) in &got {
        let due = MS * (u32::from(*byte) + 1) + Duration::from_micros(10);
        if (10 * MS..Duration::from_micros(44_500)).contains(&due) {
            // 44.5 ms, handed over at the end of its 1 ms USB frame.
            assert_eq!(*at, 45 * MS, "byte {byte}");
        } else {
            assert_eq!(
                at.as_micros() % 1000,
                0,
                "byte {byte} at a frame end: {at:?}"
            );
        }
    }
    // A zero-length hold changes nothing.
    faults.hold(80 * MS, Duration::ZERO);
    let later = read_until(&mut link, 60 * MS + MS / 10, 90 * MS);
    assert!(later.iter().all(|(at, _)| at.as_micros() % 1000 == 0));
    assert_eq!(later.len(), 30);
}

/// An SPI board that answers each transaction with its own count in every MISO byte.
struct Counter(u8);

impl SpiDevice for Counter {
    fn transfer(&mut self, _now: Duration, _mosi: &[u8], miso: &mut [u8]) -> bool {
        self.0 = self.0.wrapping_add(1);
        miso.fill(self.0);
        true
    }

    fn advance(&mut self, _now: Duration) {}
}

#[test]
fn spi_transactions_still_run_and_their_miso_comes_back_at_the_end() {
    // 8 MHz: a 4-byte transaction takes 4 µs.
    let mut link = SimLink::spi("spi", 8_000_000, Box::new(Counter(0)));
    let faults = link.faults();
    faults.hold(5 * MS, 10 * MS);
    let mut buf = [0u8; 64];
    let mut got = Vec::new();
    for tick in 0..20u32 {
        let now = MS * tick;
        assert_eq!(link.write(now, &[0; 4]).expect("write"), 4);
        let n = link.read(now + MS / 2, &mut buf).expect("read");
        got.push((tick, buf[..n].to_vec()));
    }
    for (tick, miso) in &got {
        match tick {
            // The transactions of ticks 5..=14 end inside the window (at k ms + 4 µs).
            5..=14 => assert!(miso.is_empty(), "tick {tick}: nothing while held"),
            // They come back together at 15 ms, in order, before tick 15's own (not
            // held: it ended at 15 ms + 4 µs); counts 6..=16.
            15 => {
                let expected: Vec<u8> = (6..=16).flat_map(|k| [k; 4]).collect();
                assert_eq!(miso, &expected, "tick {tick}");
            }
            _ => {
                let count = u8::try_from(tick + 1).expect("small");
                assert_eq!(miso, &vec![count; 4], "tick {tick}");
            }
        }
    }
}
