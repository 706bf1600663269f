//! Line noise on the QSB's responses (module `guard`). The command list's response format
//! ("Command Response": `Register[2] Data[8] <Time Stamp[8]> '!' <EOR>`, ASCII hex) has no
//! checksum, so a flipped bit can turn a hex digit into another and make a valid line with a
//! wrong count or time stamp. One corrupted line must never show as a count the board did
//! not send while the axis stands still, never move it by more than the counter's
//! quantisation while it moves, and never read as a restart.

use proptest::prelude::*;
use qsb::ResponseType;

use super::tests::{Bench, MD_DONE};
use motion_drivers::Driver;
use qsb::ProductType;

/// One stream tick of a -M (encoder line, MD STATUS line) with bit `flip` of the tick's
/// bytes inverted (`None`: a clean tick).
fn noisy_tick(bench: &mut Bench, flip: Option<usize>) {
    bench.advance(qsb::TICK);
    let mut bytes = bench.line(ResponseType::Stream, 0x0E, bench.counter as u32);
    bytes.extend(bench.line(ResponseType::Stream, 0x13, MD_DONE));
    if let Some(bit) = flip {
        let bit = bit % (bytes.len() * 8);
        bytes[bit / 8] ^= 1 << (bit % 8);
    }
    bench.rx(&bytes);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// The axis stands still at `count`; every third tick carries one flipped bit somewhere
    /// in its two lines.
    #[test]
    fn one_corrupted_line_never_shows_or_resets_a_still_axis(
        count in -1_000_000i32..1_000_000,
        flips in proptest::collection::vec(any::<usize>(), 1..40),
    ) {
        let mut bench = Bench::started(ProductType::M);
        bench.counter = count;
        for _ in 0..12 {
            noisy_tick(&mut bench, None);
        }
        prop_assert_eq!(bench.driver.channel(0).raw_counts, i64::from(count));
        for flip in flips {
            noisy_tick(&mut bench, Some(flip));
            prop_assert_eq!(bench.driver.channel(0).raw_counts, i64::from(count));
            noisy_tick(&mut bench, None);
            noisy_tick(&mut bench, None);
            prop_assert_eq!(bench.driver.channel(0).raw_counts, i64::from(count));
            let status = bench.driver.status();
            prop_assert_eq!(status.resets, 0);
            prop_assert!(status.online);
            prop_assert_eq!(bench.driver.channel(0).fault, None);
        }
    }

    /// The axis moves at 8 counts per tick (4096 counts/s, within the default limits);
    /// the count shown is never further from a count the board sent than the guard's
    /// allowance (`EncoderTrack::offer`: acceleration limit × gap × (gap + velocity window)
    /// / 2 + 2 counts of quantisation: 100000 counts/s² × 1.95 ms × (1.95 + up to 16 ×
    /// 1.95 ms) / 2 + 2 < 6 counts), and the board is never taken for restarted. A flip in
    /// a higher digit, far outside it, is never shown.
    #[test]
    fn one_corrupted_line_moves_a_moving_axis_at_most_by_the_quantisation(
        flips in proptest::collection::vec(any::<usize>(), 1..40),
    ) {
        let mut bench = Bench::started(ProductType::M);
        for _ in 0..12 {
            bench.counter += 8;
            noisy_tick(&mut bench, None);
        }
        for flip in flips {
            for corrupt in [Some(flip), None, None] {
                bench.counter += 8;
                noisy_tick(&mut bench, corrupt);
                let shown = bench.driver.channel(0).raw_counts;
                let sent = i64::from(bench.counter);
                // This tick's count, or the last one's (a held sample is one late).
                prop_assert!(
                    (sent - 8 - 6..=sent + 6).contains(&shown),
                    "shown {} sent {}", shown, sent
                );
            }
            prop_assert_eq!(bench.driver.status().resets, 0);
            prop_assert_eq!(bench.driver.channel(0).fault, None);
        }
    }
}

/// Answers the driver's requests until it is quiet, the first VERSION answer with
/// `first_version` instead of the board's.
fn start_up_with_first_version(bench: &mut Bench, first_version: u32) {
    let mut first = true;
    for _ in 0..64 {
        let Some(sent) = bench.sent() else {
            if bench.driver.awaiting_reply() {
                let deadline = bench.driver.poll_timeout().expect("reply deadline");
                bench.advance(deadline - bench.now);
                continue;
            }
            break;
        };
        let value = match &sent[..3] {
            b"R14" if first => {
                first = false;
                first_version
            }
            b"R14" => bench.version,
            b"S13" => MD_DONE,
            b"S0E" => bench.counter as u32,
            _ => 0,
        };
        bench.advance(core::time::Duration::from_micros(500));
        bench.answer(&sent, value);
    }
}

#[test]
fn a_version_answer_naming_another_board_counts_when_it_comes_twice() {
    // "VERSION … Serial Number": a bit flipped in the serial of one answer looks like
    // another board on the port; the driver asks again before it drops what it set up.
    let mut bench = Bench::started(ProductType::M);
    let serial_bit = 1 << 20;
    bench.driver.link_down(bench.now);
    bench.driver.link_up(bench.now);
    let corrupted = bench.version ^ serial_bit;
    start_up_with_first_version(&mut bench, corrupted);
    let status = bench.driver.status();
    assert!(status.online);
    assert_eq!(status.resets, 0, "one corrupted answer is no other board");
    // Really another board: every answer names it.
    bench.driver.link_down(bench.now);
    bench.driver.link_up(bench.now);
    bench.version ^= serial_bit;
    let other = bench.version;
    start_up_with_first_version(&mut bench, other);
    let status = bench.driver.status();
    assert!(status.online);
    assert_eq!(status.resets, 1);
}
