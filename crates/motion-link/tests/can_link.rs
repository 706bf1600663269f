//! The simulated CAN bus ([`SimCanLink`], [`CanBus`]): 16-byte records in and out, frame
//! times on one shared bus, arbitration, a full transmit queue, lost frames and unplugging.

use core::time::Duration;

use motion_base::{CAN_RECORD_LEN, CanRecord};
use motion_link::sim::{CanBus, CanDevice, Direction, SimCanLink, TX_QUEUE_FRAMES};
use motion_link::{Link, LinkErrorKind, LinkKind};

const US: Duration = Duration::from_micros(1);

/// Answers every frame for `id` with a frame on `id + 1` carrying the same data, `delay`
/// after it arrived; remembers everything it heard.
struct Echo {
    id: u16,
    delay: Duration,
    heard: Vec<(Duration, CanRecord)>,
    outbox: Vec<(Duration, CanRecord)>,
}

impl Echo {
    fn new(id: u16, delay: Duration) -> Self {
        Self {
            id,
            delay,
            heard: Vec::new(),
            outbox: Vec::new(),
        }
    }
}

impl CanDevice for Echo {
    fn receive(&mut self, now: Duration, frame: &CanRecord) {
        self.heard.push((now, *frame));
        if frame.standard_id() == Some(self.id) {
            let answer = CanRecord::standard(self.id + 1, frame.payload()).expect("valid");
            self.outbox.push((now + self.delay, answer));
        }
    }
    fn transmit(&mut self, now: Duration) -> Option<(Duration, CanRecord)> {
        let first = self.outbox.first().copied().filter(|(at, _)| *at <= now)?;
        self.outbox.remove(0);
        Some(first)
    }
    fn next_event(&self, _now: Duration) -> Option<Duration> {
        self.outbox.first().map(|(at, _)| *at)
    }
}

fn record(id: u16, data: &[u8]) -> [u8; CAN_RECORD_LEN] {
    CanRecord::standard(id, data).expect("valid").to_bytes()
}

fn read_records(link: &mut SimCanLink, now: Duration) -> Vec<CanRecord> {
    let mut buf = [0u8; 256];
    let n = link.read(now, &mut buf).expect("read");
    assert_eq!(n % CAN_RECORD_LEN, 0, "whole records");
    buf[..n]
        .chunks_exact(CAN_RECORD_LEN)
        .map(|c| CanRecord::from_bytes(c.try_into().expect("16 bytes")).expect("valid"))
        .collect()
}

#[test]
fn a_frame_takes_its_bits_on_the_bus_both_ways() {
    let mut link = SimCanLink::new("can", 250_000, Box::new(Echo::new(0x010, 2000 * US)));
    assert_eq!(link.kind(), LinkKind::Stream);
    assert_eq!(link.name(), "sim can CAN @ 250000 bit/s");
    let t0 = Duration::from_millis(10);
    let query = record(0x010, &[0x20, 1, 0xFE, 0, 0, 0, 0, 0]);
    assert_eq!(link.write(t0, &query).expect("write"), 16);
    // 111 bits at 250 kbit/s: 444 µs to the device, 2 ms processing, 444 µs back.
    let back = t0 + 444 * US + 2000 * US + 444 * US;
    assert!(read_records(&mut link, back - US).is_empty());
    assert_eq!(link.next_event(back - US), Some(back));
    let got = read_records(&mut link, back);
    assert_eq!(got.len(), 1);
    assert_eq!(got[0].standard_id(), Some(0x011));
    assert_eq!(got[0].payload(), &query[8..]);
    assert_eq!(link.frames(), (1, 1));
}

#[test]
fn records_may_come_and_go_in_pieces() {
    let mut link = SimCanLink::new("can", 1_000_000, Box::new(Echo::new(0x008, 100 * US)));
    let t0 = Duration::from_millis(1);
    let bytes = record(0x008, &[1, 2, 3]);
    // Five bytes, then the rest: one frame.
    assert_eq!(link.write(t0, &bytes[..5]).expect("write"), 5);
    assert_eq!(link.write(t0, &bytes[5..]).expect("write"), 11);
    let later = t0 + Duration::from_millis(1);
    let mut small = [0u8; 7];
    let mut got = Vec::new();
    loop {
        let n = link.read(later, &mut small).expect("read");
        if n == 0 {
            break;
        }
        got.extend_from_slice(&small[..n]);
    }
    assert_eq!(got.len(), 16);
    assert_eq!(got[..2], [0x09, 0x00]);
    assert_eq!(got[8..11], [1, 2, 3]);
    // A length byte above 8 is refused, and the link goes on.
    let mut bad = record(0x008, &[]);
    bad[4] = 9;
    let err = link.write(later, &bad).unwrap_err();
    assert_eq!(err.kind(), LinkErrorKind::Unsupported, "{err}");
    assert_eq!(link.write(later, &bytes).expect("write"), 16);
}

#[test]
fn every_device_on_a_bus_answers_its_own_identifier_in_order() {
    let a = Echo::new(0x008, 500 * US);
    let b = Echo::new(0x010, 500 * US);
    let bus = CanBus::new().with(Box::new(a)).with(Box::new(b));
    let mut link = SimCanLink::new("can", 500_000, Box::new(bus));
    let t0 = Duration::from_millis(1);
    link.write(t0, &record(0x008, &[0xAA])).expect("write");
    link.write(t0, &record(0x010, &[0xBB])).expect("write");
    let got = read_records(&mut link, t0 + Duration::from_millis(5));
    let ids: Vec<_> = got.iter().filter_map(CanRecord::standard_id).collect();
    assert_eq!(ids, [0x009, 0x011], "each answers its own, in order");
}

#[test]
fn frames_ready_together_go_lowest_identifier_first() {
    // Two devices answer the same broadcast after the same delay: $011 loses to $009.
    struct Both(u16);
    impl CanDevice for Both {
        fn receive(&mut self, _now: Duration, _frame: &CanRecord) {}
        fn transmit(&mut self, now: Duration) -> Option<(Duration, CanRecord)> {
            let at = Duration::from_millis(2);
            (now >= at && self.0 != 0).then(|| {
                let id = core::mem::take(&mut self.0);
                (at, CanRecord::standard(id, &[0; 8]).expect("valid"))
            })
        }
        fn next_event(&self, _now: Duration) -> Option<Duration> {
            (self.0 != 0).then_some(Duration::from_millis(2))
        }
    }
    let bus = CanBus::new()
        .with(Box::new(Both(0x011)))
        .with(Box::new(Both(0x009)));
    let mut link = SimCanLink::new("can", 125_000, Box::new(bus));
    let got = read_records(&mut link, Duration::from_millis(10));
    let ids: Vec<_> = got.iter().filter_map(CanRecord::standard_id).collect();
    assert_eq!(ids, [0x009, 0x011]);
}

#[test]
fn a_full_transmit_queue_takes_no_more_until_the_bus_drains() {
    // A device that never answers: the host's frames queue behind each other on the bus.
    let mut link = SimCanLink::new("can", 125_000, Box::new(Echo::new(0x7F8, US)));
    let t0 = Duration::from_millis(1);
    let frame = record(0x100, &[0; 8]);
    let mut all = Vec::new();
    for _ in 0..TX_QUEUE_FRAMES + 3 {
        all.extend_from_slice(&frame);
    }
    let taken = link.write(t0, &all).expect("write");
    assert_eq!(taken, TX_QUEUE_FRAMES * CAN_RECORD_LEN);
    // 888 µs a frame at 125 kbit/s: after 10 ms eleven have crossed.
    let later = t0 + Duration::from_millis(10);
    assert_eq!(link.read(later, &mut [0u8; 64]).expect("read"), 0);
    let more = link.write(later, &all[taken..]).expect("write");
    assert_eq!(more, 3 * CAN_RECORD_LEN);
}

#[test]
fn lost_frames_and_an_unplugged_bus() {
    let mut link = SimCanLink::new("can", 250_000, Box::new(Echo::new(0x010, 100 * US)));
    let faults = link.faults();
    let t0 = Duration::from_millis(1);
    faults.drop_next(Direction::ToDevice, 1);
    link.write(t0, &record(0x010, &[1])).expect("write");
    assert!(read_records(&mut link, t0 + Duration::from_millis(5)).is_empty());
    assert_eq!(faults.dropped(Direction::ToDevice), 1);
    faults.unplug();
    let err = link
        .read(t0 + Duration::from_millis(6), &mut [0; 16])
        .unwrap_err();
    assert_eq!(err.kind(), LinkErrorKind::Disconnected);
    assert!(link.reopen(t0 + Duration::from_millis(7)).is_err());
    faults.replug();
    link.reopen(t0 + Duration::from_millis(8)).expect("reopen");
    let t1 = t0 + Duration::from_millis(9);
    link.write(t1, &record(0x010, &[2])).expect("write");
    let got = read_records(&mut link, t1 + Duration::from_millis(5));
    assert_eq!(got.len(), 1);
    assert_eq!(got[0].payload(), [2]);
}
