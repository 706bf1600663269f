//! The stream decoder: every chunk size, garbage between frames, and no panics.

mod common;

use std::time::Duration;

use proptest::prelude::*;
use proptest::strategy::ValueTree;
use proptest::test_runner::{Config, TestRunner};
use tmcpack::{CanFrame, FrameDecoder, ReplyFrame, RequestFrame, Word};

const BYTE: Duration = Duration::from_nanos(520_833); // 19200 baud, 8N1
const TIMEOUT: Duration = Duration::from_millis(20);

/// A burst of bytes sent back to back, then an idle gap.
struct Burst {
    bytes: Vec<u8>,
    gap_after: Duration,
}

fn build_stream(runner: &mut TestRunner, n: usize) -> (Vec<Burst>, Vec<Word>, u64) {
    let mut bursts = Vec::new();
    let mut words = Vec::new();
    let mut garbage = 0;
    let strategy = common::request();
    for _ in 0..n {
        if runner.rng().random_bool(0.5) {
            // Garbage that is not a whole word, followed by an idle gap longer than the
            // packet timeout: the pack aborts it (manual 6.1) and is in step again.
            let rng = runner.rng();
            let len = rng.random_range(1..=8usize);
            let bytes = (0..len).map(|_| rng.random::<u8>()).collect();
            bursts.push(Burst {
                bytes,
                gap_after: TIMEOUT + Duration::from_millis(1),
            });
            garbage += 1;
        }
        // One to three words back to back (a request, or replies from other packs), then
        // the host's usual pause.
        let mut bytes = Vec::new();
        for _ in 0..runner.rng().random_range(1..=3) {
            let req = strategy.new_tree(runner).expect("strategy").current();
            let w = RequestFrame::new(runner.rng().random(), req)
                .to_word()
                .expect("valid");
            words.push(w);
            bytes.extend_from_slice(&w);
        }
        let gap = Duration::from_micros(runner.rng().random_range(0..3000));
        bursts.push(Burst {
            bytes,
            gap_after: gap,
        });
    }
    (bursts, words, garbage)
}

/// Feeds the bursts in chunks of `chunk` bytes (never across an idle gap: a chunk is what
/// arrived back to back) and returns the words decoded.
fn feed(bursts: &[Burst], chunk: usize) -> (Vec<Word>, FrameDecoder) {
    let mut d = FrameDecoder::new(TIMEOUT, BYTE);
    let mut out = Vec::new();
    let mut t = Duration::from_secs(1);
    for b in bursts {
        for part in b.bytes.chunks(chunk) {
            t += BYTE * part.len() as u32;
            out.extend(d.push(t, part));
        }
        t += b.gap_after;
    }
    d.poll(t + TIMEOUT * 2);
    (out, d)
}

#[test]
fn every_chunk_size_with_garbage_recovers_every_frame() {
    let mut runner = TestRunner::new(Config::default());
    for _ in 0..8 {
        let (bursts, words, garbage) = build_stream(&mut runner, 12);
        let total: usize = bursts.iter().map(|b| b.bytes.len()).sum();
        for chunk in 1..=total {
            let (got, d) = feed(&bursts, chunk);
            assert_eq!(got, words, "chunk size {chunk}");
            assert_eq!(d.stats().aborted, garbage, "chunk size {chunk}");
            assert_eq!(d.stats().words, words.len() as u64);
        }
    }
}

/// Garbage longer than a word: the pack takes every nine bytes as a word (there is no
/// start byte), aborts the rest after the timeout, and is in step for the next frame.
#[test]
fn long_garbage_is_cut_into_words_then_resyncs() {
    let frame = RequestFrame::new(
        3,
        tmcpack::Request::SetTarget {
            motor: 1,
            target: -7,
        },
    )
    .to_word()
    .expect("valid");
    let garbage: Vec<u8> = (0..22u8).map(|i| i.wrapping_mul(37)).collect();
    let bursts = [
        Burst {
            bytes: garbage.clone(),
            gap_after: TIMEOUT * 2,
        },
        Burst {
            bytes: frame.to_vec(),
            gap_after: Duration::ZERO,
        },
    ];
    for chunk in 1..=22 {
        let (got, d) = feed(&bursts, chunk);
        assert_eq!(got.len(), 3);
        assert_eq!(got[0][..], garbage[..9]);
        assert_eq!(got[1][..], garbage[9..18]);
        assert_eq!(got[2], frame);
        assert_eq!(d.stats().aborted, 1);
        assert_eq!(d.stats().aborted_bytes, 4);
    }
}

/// Manual 6.1: a word not completed within the timeout is aborted; a break aborts too.
#[test]
fn timeout_and_break_abort_partial_words() {
    let mut d = FrameDecoder::new(TIMEOUT, BYTE);
    let w = [1u8, 0x22, 0, 0, 0, 0, 0, 0, 0];
    let t0 = Duration::from_secs(5);
    assert_eq!(d.push(t0, &w[..4]).count(), 0);
    assert_eq!(d.deadline(), Some(t0 - BYTE * 3 + TIMEOUT));
    // The rest comes too late: the first half is aborted and the rest starts a new word.
    assert_eq!(d.push(t0 + TIMEOUT * 2, &w[4..]).count(), 0);
    assert_eq!(d.stats().aborted, 1);
    assert_eq!(d.pending(), 5);
    d.line_break();
    assert_eq!(d.stats().aborted, 2);
    assert_eq!(d.stats().breaks, 1);
    let got: Vec<Word> = d.push(t0 + TIMEOUT * 3, &w).collect();
    assert_eq!(got, [w]);
    // Exactly at the timeout still counts as in time.
    let mut e = FrameDecoder::new(TIMEOUT, BYTE);
    assert_eq!(e.push_byte(t0, 1), None);
    for _ in 0..7 {
        assert_eq!(e.push_byte(t0 + TIMEOUT, 0), None);
    }
    assert!(e.push_byte(t0 + TIMEOUT, 0).is_some());
}

/// A few hundred thousand short random strings through every decoder: no panic.
#[test]
fn no_panic_on_random_bytes() {
    let mut runner = TestRunner::new(Config::default());
    let mut d = FrameDecoder::new(TIMEOUT, BYTE);
    let mut t = Duration::ZERO;
    let mut ok = 0u32;
    for _ in 0..300_000 {
        let rng = runner.rng();
        let len = rng.random_range(0..=12usize);
        let mut b = [0u8; 12];
        rng.fill(&mut b[..]);
        let bytes = &b[..len];
        ok += u32::from(RequestFrame::decode(bytes).is_ok());
        ok += u32::from(ReplyFrame::decode(bytes).is_ok());
        let mut data = [0u8; 8];
        data.copy_from_slice(&b[4..12]);
        let can = CanFrame {
            id: u16::from_le_bytes([b[0], b[1]]),
            len: b[2],
            data,
        };
        ok += u32::from(RequestFrame::from_can(&can).is_ok());
        ok += u32::from(ReplyFrame::from_can(&can).is_ok());
        let _ = can.payload();
        t += Duration::from_micros(u64::from(b[3]) * 100);
        for w in d.push(t, bytes) {
            ok += u32::from(RequestFrame::decode(&w).is_ok());
        }
    }
    assert!(ok > 0);
}

proptest! {
    #[test]
    fn decoder_words_are_the_input_in_nines(bytes in prop::collection::vec(any::<u8>(), 0..100)) {
        let mut d = FrameDecoder::new(TIMEOUT, BYTE);
        let got: Vec<Word> = d.push(Duration::from_secs(1), &bytes).collect();
        prop_assert_eq!(got.len(), bytes.len() / 9);
        for (w, c) in got.iter().zip(bytes.chunks_exact(9)) {
            prop_assert_eq!(&w[..], c);
        }
        prop_assert_eq!(d.pending(), bytes.len() % 9);
    }
}
