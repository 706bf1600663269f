//! Encode and decode cost per line, both directions.

use criterion::{Criterion, criterion_group, criterion_main};
use qsb::{
    CommandDecoder, Eor, MAX_RESPONSE_LEN, Mdr0, Request, Response, ResponseDecoder, ResponseType,
    Write,
};
use std::hint::black_box;

fn codec(c: &mut Criterion) {
    let request = Request::Write(Write::Mdr0(Mdr0::from_data(0x63).unwrap_or_default()));
    let response = Response {
        ty: ResponseType::Stream,
        register: 0x0E,
        data: 0xFFFF_FF9C,
        time_stamp: Some(0x1234),
    };
    let eor = Eor::from_data(0xF).unwrap_or_default();
    let mut buf = [0u8; MAX_RESPONSE_LEN];

    c.bench_function("encode command W0363", |b| {
        b.iter(|| black_box(request).encode(&mut buf))
    });
    let mut cmd = [0u8; qsb::MAX_COMMAND_LEN];
    let n = request.encode(&mut cmd).unwrap_or(0);
    c.bench_function("decode command W0363", |b| {
        b.iter(|| {
            let mut d = CommandDecoder::new();
            black_box(d.decode(black_box(&cmd[..n])))
        })
    });
    c.bench_function("encode response s0E+ts (EOR F)", |b| {
        b.iter(|| black_box(response).encode(eor, &mut buf))
    });
    let mut line = [0u8; MAX_RESPONSE_LEN];
    let m = response.encode(eor, &mut line).unwrap_or(0);
    c.bench_function("decode response s0E+ts (EOR F)", |b| {
        b.iter(|| {
            let mut d = ResponseDecoder::new();
            black_box(d.decode(black_box(&line[..m])))
        })
    });
}

criterion_group!(benches, codec);
criterion_main!(benches);
