#![no_main]
//! Any bytes through the stream decoder: the first byte of each chunk says how long to wait
//! before the chunk (in 100 µs units) and how long the chunk is.

use core::time::Duration;

use libfuzzer_sys::fuzz_target;
use tmcpack::{FrameDecoder, ReplyFrame, RequestFrame};

fuzz_target!(|data: &[u8]| {
    let mut d = FrameDecoder::new(Duration::from_millis(20), Duration::from_nanos(520_833));
    let mut now = Duration::ZERO;
    let mut rest = data;
    while let Some((&head, tail)) = rest.split_first() {
        let len = usize::from(head & 0x0F).min(tail.len());
        now += Duration::from_micros(u64::from(head >> 4) * 2_000);
        let (chunk, next) = tail.split_at(len);
        for w in d.push(now, chunk) {
            let _ = RequestFrame::decode(&w);
            let _ = ReplyFrame::decode(&w);
        }
        if head == 0xFF {
            d.line_break();
        }
        rest = next;
    }
    assert!(d.pending() < 9);
});
