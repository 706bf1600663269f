//! Encode and decode cost per packet.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use qq2drv::{
    ChannelMask, DataMask, Entries, MotionData, MotionLayout, PositionRampEntry, Reply,
    ReplyLayout, Request, Status, StreamConfig, StreamData, StreamDecoder,
};

fn bench(c: &mut Criterion) {
    let masks = [DataMask(0x2B); 4];
    let layout = ReplyLayout {
        motion: MotionLayout {
            data_masks: masks,
            stream_config: StreamConfig(3),
        },
        ..Default::default()
    };
    let data = MotionData::sample(&masks, [1, -2, 3, -4], [10, 20, 30, 40], [Status(8); 4]);
    let stream = Reply::StreamData(StreamData {
        code: None,
        timing: Some(108),
        periods_elapsed: Some(1),
        data,
    });
    let ramps = [PositionRampEntry {
        channels: ChannelMask(0x0F),
        position: 100_000,
        velocity: 2000 << 12,
        acceleration: 10_000 << 12,
    }];
    let mut buf = [0u8; 255];

    c.bench_function("encode stream packet (4 ch pos+vel+status, 42 B)", |b| {
        b.iter(|| black_box(&stream).encode(black_box(&mut buf)))
    });
    let n = stream.encode(&mut buf).unwrap_or(0);
    let packet = buf[..n].to_vec();
    c.bench_function("decode stream packet", |b| {
        b.iter(|| Reply::parse(black_box(&packet), black_box(&layout)))
    });
    c.bench_function("stream decoder: filler + stream packet", |b| {
        let mut input = vec![0u8; 8];
        input.extend_from_slice(&packet);
        let mut d = StreamDecoder::new();
        b.iter(|| {
            let mut count = 0;
            d.feed(black_box(&input), |_| count += 1);
            count
        })
    });
    let ramp = Request::PositionRamp(Entries::new(&ramps));
    let mut rbuf = [0u8; 255];
    c.bench_function("encode position ramp request", |b| {
        b.iter(|| black_box(&ramp).encode(black_box(&mut rbuf)))
    });
    let n = ramp.encode(&mut rbuf).unwrap_or(0);
    let rpacket = rbuf[..n].to_vec();
    c.bench_function("decode position ramp request", |b| {
        b.iter(|| Request::parse(black_box(&rpacket)).map(|r| r.id()))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
