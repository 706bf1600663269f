//! The decoders never panic: a few hundred thousand short random byte strings each.
//!
//! The first two bytes are biased towards this board's address and documented ports so the
//! strings reach the value decoders, not just the header check.

use spimotor::{Header, ReadPort, Reply, Transaction, Write};

/// SplitMix64, so the test needs no extra dependency and is the same on every run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn fill(&mut self, buf: &mut [u8]) -> usize {
        let len = (self.next() % buf.len() as u64) as usize;
        for b in buf.iter_mut().take(len) {
            *b = self.next() as u8;
        }
        if len >= 2 && self.next().is_multiple_of(2) {
            const PORTS: [u8; 19] = [
                0x01, 0x02, 0x10, 0x20, 0x21, 0x22, 0x30, 0x31, 0x32, 0x40, 0x41, 0x42, 0x43, 0x44,
                0xf0, 0xf1, 0xf2, 0x55, 0xaa,
            ];
            buf[0] = 0x90 | (self.next() as u8 & 1);
            buf[1] = PORTS[(self.next() % PORTS.len() as u64) as usize];
        }
        len
    }
}

const ROUNDS: usize = 300_000;

#[test]
fn transaction_decoder_never_panics() {
    let mut rng = Rng(1);
    let mut buf = [0u8; 12];
    let mut ok = 0usize;
    for _ in 0..ROUNDS {
        let n = rng.fill(&mut buf);
        if let Ok(t) = Transaction::decode(&buf[..n]) {
            ok += 1;
            // A decoded transaction never claims more bytes than were clocked (redundant
            // bytes on one-value ports and data on stop ports make it shorter).
            assert!(t.len() <= n, "{t:?} from {n} bytes");
            assert_eq!(Header::decode(&buf[..n]).map(|h| h.port), Ok(buf[1]));
        }
        let _ = Write::decode(buf[0], &buf[1..n.max(1)]);
    }
    // The bias makes a good share of the strings valid, so the deep paths ran too.
    assert!(ok > ROUNDS / 10, "only {ok} valid transactions");
}

#[test]
fn reply_decoder_never_panics() {
    let mut rng = Rng(2);
    let mut buf = [0u8; 12];
    let mut ok = 0usize;
    for i in 0..ROUNDS {
        let n = rng.fill(&mut buf);
        let port = ReadPort::ALL[i % ReadPort::ALL.len()];
        if let Ok(r) = Reply::decode(port, &buf[..n]) {
            ok += 1;
            assert_eq!(r.port(), port);
        }
        let _ = Reply::decode_data(port, &buf[..n]);
    }
    assert!(ok > ROUNDS / 10, "only {ok} valid replies");
}
