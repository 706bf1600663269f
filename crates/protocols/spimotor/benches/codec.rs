//! Encode and decode cost per transaction.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use spimotor::{Address, ReadPort, Reply, Transaction, Write};

fn codec(c: &mut Criterion) {
    let target = Transaction::write(Address::DEFAULT, Write::TargetPosition(0x1234_5678));
    let read = Transaction::read(Address::DEFAULT, ReadPort::CurrentPosition);
    let mut buf = [0u8; 64];

    c.bench_function("encode write target position", |b| {
        b.iter(|| black_box(target).encode(black_box(&mut buf)))
    });
    let n = target.encode(&mut buf).expect("fits");
    let wire = buf;
    c.bench_function("decode write target position", |b| {
        b.iter(|| Transaction::decode(black_box(&wire[..n])))
    });

    c.bench_function("encode read current position", |b| {
        b.iter(|| black_box(read).encode(black_box(&mut buf)))
    });
    let mut miso = [0u8; 6];
    Reply::CurrentPosition(-123_456).encode_miso(&mut miso);
    c.bench_function("decode reply current position", |b| {
        b.iter(|| Reply::decode(black_box(ReadPort::CurrentPosition), black_box(&miso)))
    });

    let mut ident = [0u8; 35];
    Reply::Identification(Default::default()).encode_miso(&mut ident);
    c.bench_function("decode reply identification", |b| {
        b.iter(|| Reply::decode(black_box(ReadPort::Identification), black_box(&ident)))
    });
}

criterion_group!(benches, codec);
criterion_main!(benches);
