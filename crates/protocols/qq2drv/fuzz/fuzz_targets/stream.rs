//! MISO stream decoder: arbitrary bytes in arbitrary chunks; every packet out is valid.
#![no_main]

use libfuzzer_sys::fuzz_target;
use qq2drv::{Frame, StreamDecoder};

fuzz_target!(|data: &[u8]| {
    let Some((&chunk, rest)) = data.split_first() else {
        return;
    };
    let mut d = StreamDecoder::new();
    for piece in rest.chunks(usize::from(chunk).max(1)) {
        d.feed(piece, |p| assert!(Frame::parse(p.as_bytes()).is_ok()));
    }
});
