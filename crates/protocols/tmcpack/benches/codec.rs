//! Encode and decode cost per frame.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use tmcpack::{Action, FrameDecoder, Reply, ReplyFrame, Request, RequestFrame};

fn codec(c: &mut Criterion) {
    let req = RequestFrame::new(
        1,
        Request::StartRamp {
            motor: 3,
            target: -123_456,
        },
    );
    let rep = ReplyFrame::new(
        0xFE,
        Reply::Position {
            motor: 3,
            position: 98_765,
            action: Action::Ramp,
            stopped: false,
        },
    );
    let req_word = req.to_word().expect("valid request");
    let rep_word = rep.to_word().expect("valid reply");
    let mut buf = [0u8; 9];

    c.bench_function("encode request $23", |b| {
        b.iter(|| black_box(&req).encode(black_box(&mut buf)))
    });
    c.bench_function("decode request $23", |b| {
        b.iter(|| RequestFrame::decode(black_box(&req_word)))
    });
    c.bench_function("encode reply $20", |b| {
        b.iter(|| black_box(&rep).encode(black_box(&mut buf)))
    });
    c.bench_function("decode reply $20", |b| {
        b.iter(|| ReplyFrame::decode(black_box(&rep_word)))
    });
    c.bench_function("stream decode 1 word", |b| {
        let mut d = FrameDecoder::new(Duration::from_millis(20), Duration::from_micros(521));
        let mut now = Duration::ZERO;
        b.iter(|| {
            now += Duration::from_millis(30);
            d.push(now, black_box(&rep_word)).count()
        })
    });
}

criterion_group!(benches, codec);
criterion_main!(benches);
