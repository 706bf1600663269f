//! Properties of the simulated wire under random traffic, time steps and faults: it never
//! panics, never reorders or invents bytes on a clean wire, and keeps its clock monotonic.

use std::time::Duration;

use motion_link::sim::{Direction, SimLink, SpiDevice, StreamDevice};
use motion_link::{Link, LinkErrorKind};
use proptest::prelude::*;

/// Echoes, and checks that its clock never goes back.
#[derive(Default)]
struct Echo(Vec<u8>, Duration);

impl Echo {
    fn tick(&mut self, now: Duration) {
        assert!(now >= self.1, "time went back: {now:?} < {:?}", self.1);
        self.1 = now;
    }
}

impl StreamDevice for Echo {
    fn receive(&mut self, now: Duration, bytes: &[u8]) {
        self.tick(now);
        self.0.extend_from_slice(bytes);
    }
    fn transmit(&mut self, now: Duration, out: &mut [u8]) -> usize {
        self.tick(now);
        let n = out.len().min(self.0.len());
        out[..n].copy_from_slice(&self.0[..n]);
        self.0.drain(..n);
        n
    }
    fn next_event(&self, now: Duration) -> Option<Duration> {
        (!self.0.is_empty()).then_some(now)
    }
}

/// Checks that the device's clock never goes back.
struct Monotonic(Duration);

impl SpiDevice for Monotonic {
    fn transfer(&mut self, now: Duration, mosi: &[u8], miso: &mut [u8]) -> bool {
        assert!(now >= self.0, "time went back: {now:?} < {:?}", self.0);
        self.0 = now;
        miso.copy_from_slice(mosi);
        true
    }
    fn advance(&mut self, now: Duration) {
        assert!(now >= self.0, "time went back: {now:?} < {:?}", self.0);
        self.0 = now;
    }
}

#[derive(Debug, Clone)]
enum Op {
    Write(Vec<u8>),
    Read(usize),
    Wait(u64),
    Garbage(Vec<u8>),
    Drop(bool, u8),
    Unplug,
    Replug,
    Reopen,
    Baud(Option<u32>),
    Delay(u16),
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        4 => proptest::collection::vec(any::<u8>(), 0..40).prop_map(Op::Write),
        4 => (0usize..64).prop_map(Op::Read),
        4 => (0u64..5_000_000).prop_map(Op::Wait),
        1 => proptest::collection::vec(any::<u8>(), 0..8).prop_map(Op::Garbage),
        1 => (any::<bool>(), 0u8..4).prop_map(|(d, n)| Op::Drop(d, n)),
        1 => Just(Op::Unplug),
        1 => Just(Op::Replug),
        1 => Just(Op::Reopen),
        1 => prop_oneof![Just(None), (1u32..500_000).prop_map(Some)].prop_map(Op::Baud),
        1 => any::<u16>().prop_map(Op::Delay),
    ]
}

fn run(link: &mut SimLink, ops: &[Op]) {
    let faults = link.faults();
    let mut now = Duration::from_secs(1);
    let mut buf = [0u8; 64];
    for op in ops {
        let result = match op {
            Op::Write(bytes) => link.write(now, bytes).map(drop),
            Op::Read(n) => link.read(now, &mut buf[..*n]).map(drop),
            Op::Wait(ns) => {
                now += Duration::from_nanos(*ns);
                Ok(())
            }
            Op::Garbage(bytes) => {
                faults.inject_garbage(bytes);
                Ok(())
            }
            Op::Drop(to_host, n) => {
                let dir = if *to_host {
                    Direction::ToHost
                } else {
                    Direction::ToDevice
                };
                faults.drop_next(dir, u64::from(*n));
                Ok(())
            }
            Op::Unplug => {
                faults.unplug();
                Ok(())
            }
            Op::Replug => {
                faults.replug();
                Ok(())
            }
            Op::Reopen => link.reopen(now),
            Op::Baud(b) => {
                faults.set_device_baud(*b);
                Ok(())
            }
            Op::Delay(us) => {
                faults.set_reply_delay(Duration::from_micros(u64::from(*us)));
                Ok(())
            }
        };
        if let Err(e) = result {
            assert!(
                matches!(
                    e.kind(),
                    LinkErrorKind::Disconnected
                        | LinkErrorKind::Framing
                        | LinkErrorKind::Overflow
                        | LinkErrorKind::Unsupported
                ),
                "{e}"
            );
        }
        if let Some(t) = link.next_event(now) {
            assert!(t >= now);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn a_faulty_stream_wire_never_panics_and_keeps_time_monotonic(ops in proptest::collection::vec(op(), 0..60),
                                         baud in 1u32..2_000_000) {
        let mut link = SimLink::stream("p", baud, Box::new(Echo::default()));
        run(&mut link, &ops);
    }

    #[test]
    fn a_faulty_spi_wire_never_panics_and_keeps_time_monotonic(
        ops in proptest::collection::vec(op(), 0..60),
        hz in 1u32..20_000_000,
    ) {
        let mut link = SimLink::spi("p", hz, Box::new(Monotonic(Duration::ZERO)));
        run(&mut link, &ops);
    }

    #[test]
    fn a_clean_wire_delivers_every_byte_in_order(
        writes in proptest::collection::vec(proptest::collection::vec(any::<u8>(), 0..30), 0..20),
        gaps in proptest::collection::vec(0u64..3_000_000, 20),
        baud in 300u32..1_000_000,
    ) {
        let mut link = SimLink::stream("p", baud, Box::new(Echo::default()));
        let mut now = Duration::ZERO;
        let mut sent = Vec::new();
        let mut got = Vec::new();
        let mut buf = [0u8; 16];
        for (bytes, gap) in writes.iter().zip(&gaps) {
            let n = link.write(now, bytes).unwrap();
            sent.extend_from_slice(&bytes[..n]);
            now += Duration::from_nanos(*gap);
            let k = link.read(now, &mut buf).unwrap();
            got.extend_from_slice(&buf[..k]);
        }
        now += Duration::from_secs(100);
        loop {
            let k = link.read(now, &mut buf).unwrap();
            if k == 0 { break; }
            got.extend_from_slice(&buf[..k]);
        }
        prop_assert_eq!(got, sent);
    }
}
