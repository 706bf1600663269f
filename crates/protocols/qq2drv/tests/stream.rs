//! The MISO stream decoder: every chunk size, garbage between packets, no panics.

use qq2drv::{
    ChannelMask, DataMask, DataMaskEntry, Entries, Frame, MotionData, MotionLayout, Reply,
    ReplyLayout, Request, ReturnCode, Status, StreamConfig, StreamData, StreamDecoder,
};

/// Deterministic xorshift so the test needs no extra dependency and never flakes.
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    fn byte(&mut self) -> u8 {
        (self.next() >> 24) as u8
    }
}

fn packets() -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    let mut buf = [0u8; 255];
    let e = [DataMaskEntry {
        channels: ChannelMask(0x0F),
        mask: DataMask(0x2B),
    }];
    for req in [
        Request::GetVersion,
        Request::SetStreamPeriod(24),
        Request::SetDataMask(Entries::new(&e)),
    ] {
        let n = req.encode(&mut buf).expect("encode");
        out.push(buf[..n].to_vec());
    }
    let layout = MotionLayout {
        data_masks: [DataMask(0x2B); 4],
        stream_config: StreamConfig(3),
    };
    let data = MotionData::sample(
        &layout.data_masks,
        [2, -2, 0x0202, 3],
        [2; 4],
        [Status(2); 4],
    );
    for reply in [
        Reply::Version {
            code: ReturnCode(0),
            firmware_major: 0,
            firmware_minor: 1,
            protocol: 0,
        },
        Reply::MotionData {
            code: ReturnCode(0),
            data,
        },
        Reply::StreamData(StreamData {
            code: None,
            timing: Some(0x0202),
            periods_elapsed: Some(2),
            data,
        }),
        // Packet 3 with the Return Code its text names ("except for Return Code").
        Reply::StreamData(StreamData {
            code: Some(ReturnCode(0)),
            timing: Some(0x0202),
            periods_elapsed: Some(2),
            data,
        }),
    ] {
        let n = reply.encode(&mut buf).expect("encode");
        out.push(buf[..n].to_vec());
    }
    out
}

/// Garbage that can contain STX (2) and may look like a header, but never a valid packet
/// because its checksum is spoiled.
fn garbage(rng: &mut Lcg) -> Vec<u8> {
    let len = (rng.next() % 12) as usize;
    let mut g: Vec<u8> = (0..len).map(|_| rng.byte() % 5).collect();
    if rng.next().is_multiple_of(3) {
        // A false header: STX, plausible size, id 1, then not enough valid content.
        g.extend_from_slice(&[2, 1]);
    }
    g
}

#[test]
fn every_chunk_size_with_garbage_recovers_every_packet() {
    let packets = packets();
    let mut rng = Lcg(0x9E37_79B9_7F4A_7C15);
    let mut stream = Vec::new();
    let mut expected = Vec::new();
    let mut false_headers = 0u64;
    for round in 0..3 {
        for p in &packets {
            let g = garbage(&mut rng);
            false_headers += g.windows(2).filter(|w| w == &[2, 1]).count() as u64;
            stream.extend_from_slice(&g);
            stream.extend_from_slice(p);
            expected.push(p.clone());
            // A corrupted copy of the packet: checksum flipped (counted as bad).
            if round == 1 {
                let mut bad = p.clone();
                if let Some(last) = bad.last_mut() {
                    *last ^= 0x5A;
                }
                stream.extend_from_slice(&bad);
                stream.extend_from_slice(&[0; 3]);
            }
        }
    }
    stream.extend_from_slice(&[0; 8]);
    let mut reference = None;
    for chunk in 1..=stream.len() {
        let mut d = StreamDecoder::new();
        let mut got = Vec::new();
        for piece in stream.chunks(chunk) {
            d.feed(piece, |p| got.push(p.as_bytes().to_vec()));
        }
        // Every valid packet is recovered, in order.
        assert_eq!(got, expected, "chunk size {chunk}");
        let stats = d.stats();
        assert_eq!(stats.packets, expected.len() as u64);
        // Every false header (size 1) and every corrupted copy is counted as bad.
        assert!(
            stats.bad_size >= false_headers,
            "chunk size {chunk}: {stats:?}"
        );
        assert!(stats.bad_packets() >= false_headers + packets.len() as u64);
        // The result does not depend on the chunking.
        match reference {
            None => reference = Some(stats),
            Some(r) => assert_eq!(r, stats, "chunk size {chunk}"),
        }
    }
}

#[test]
fn no_panic_on_random_bytes() {
    let mut rng = Lcg(12345);
    let mut buf = [0u8; 40];
    let layouts = [
        ReplyLayout::default(),
        ReplyLayout {
            motion: MotionLayout {
                data_masks: [DataMask(0x25); 4],
                stream_config: StreamConfig(3),
            },
            ..Default::default()
        },
    ];
    let mut d = StreamDecoder::new();
    let mut decoded = 0u64;
    for i in 0..300_000u32 {
        let len = (rng.next() % 24) as usize;
        for b in buf.iter_mut().take(len) {
            // Bias towards small values so STX and valid ids occur often.
            *b = if rng.next().is_multiple_of(2) {
                rng.byte() % 40
            } else {
                rng.byte()
            };
        }
        if len >= 3 {
            // Make the frame valid half the time so the payload decoders are exercised.
            buf[0] = 2;
            buf[1] = len as u8;
            if i % 2 == 0 {
                let sum = buf[..len - 1].iter().fold(0u8, |a, b| a.wrapping_add(*b));
                buf[len - 1] = 0u8.wrapping_sub(sum);
            }
        }
        let bytes = &buf[..len];
        if let Ok(frame) = Frame::parse(bytes) {
            decoded += u64::from(Request::decode(frame).is_ok());
            for l in &layouts {
                decoded += u64::from(Reply::decode(frame, l).is_ok());
            }
        }
        let _ = Request::parse(bytes);
        d.feed(bytes, |p| {
            let _ = Reply::decode(p.frame(), &layouts[0]);
        });
    }
    assert!(
        decoded > 0,
        "random inputs never produced a decodable packet"
    );
}
