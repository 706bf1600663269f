//! The codec against the README's command table, in every chunking, after noise.

use proptest::prelude::*;

use super::*;

fn encoded(request: Request) -> Vec<u8> {
    let mut buf = [0u8; MAX_LINE];
    let len = request.encode(&mut buf).expect("in range");
    buf[..len].to_vec()
}

fn decode_all(bytes: &[u8], chunk: usize) -> Vec<Result<Reply, CodecError>> {
    let mut decoder = ReplyDecoder::new();
    let mut out = Vec::new();
    for piece in bytes.chunks(chunk) {
        out.extend(piece.iter().filter_map(|b| decoder.push(*b)));
    }
    out
}

#[test]
fn requests_are_the_readme_table() {
    // README "Commands", one row each.
    assert_eq!(encoded(Request::Identify), b"?\r");
    assert_eq!(encoded(Request::Position { channel: 1 }), b"P1?\r");
    let move_ = Request::Move {
        channel: 0,
        target: 2000,
        speed: 4000,
        accel: 20000,
    };
    assert_eq!(encoded(move_), b"M0 2000 4000 20000\r");
    let jog = Request::Jog {
        channel: 1,
        velocity: -1500,
        accel: 8000,
    };
    assert_eq!(encoded(jog), b"V1 -1500 8000\r");
    let stop = Request::Stop {
        channel: 0,
        decel: 20000,
    };
    assert_eq!(encoded(stop), b"S0 20000\r");
    let zero = Request::SetPosition {
        channel: 0,
        position: 0,
    };
    assert_eq!(encoded(zero), b"Z0 0\r");
    assert_eq!(encoded(Request::Off { channel: 1 }), b"O1\r");
    for request in [move_, jog, stop, zero, Request::Identify] {
        let line = encoded(request);
        assert_eq!(Request::parse(&line[..line.len() - 1]), Ok(request));
    }
}

#[test]
fn replies_are_the_readme_table() {
    let lines: &[(&[u8], Reply)] = &[
        (
            b"AS2 1.4",
            Reply::Identity(Version::new("1.4").expect("valid")),
        ),
        (
            b"P0 2000 0 I",
            Reply::Position {
                channel: 0,
                position: 2000,
                velocity: 0,
                motion: Motion::Idle,
            },
        ),
        (
            b"P1 -37 -1500 M",
            Reply::Position {
                channel: 1,
                position: -37,
                velocity: -1500,
                motion: Motion::Moving,
            },
        ),
        (b"OK", Reply::Done),
        (b"E2", Reply::Error(BoardError::NoSuchChannel)),
    ];
    for (line, reply) in lines {
        assert_eq!(
            Reply::parse(line),
            Ok(*reply),
            "{:?}",
            String::from_utf8_lossy(line)
        );
        let mut buf = [0u8; MAX_LINE];
        let len = reply.encode(&mut buf).expect("fits");
        assert_eq!(&buf[..len - 1], *line);
    }
}

#[test]
fn out_of_range_values_are_refused_not_sent() {
    let mut buf = [0u8; MAX_LINE];
    for request in [
        Request::Position { channel: 2 },
        Request::Move {
            channel: 0,
            target: 0,
            speed: 0,
            accel: 1,
        },
        Request::Jog {
            channel: 0,
            velocity: -50_001,
            accel: 1,
        },
        Request::Stop {
            channel: 0,
            decel: MAX_ACCEL + 1,
        },
    ] {
        assert_eq!(
            request.encode(&mut buf),
            Err(CodecError::OutOfRange),
            "{request:?}"
        );
    }
    assert_eq!(
        Request::Identify.encode(&mut buf[..1]),
        Err(CodecError::BufferTooSmall(1))
    );
    assert_eq!(Request::parse(b"S0 0"), Err(CodecError::OutOfRange));
}

#[test]
fn malformed_lines_are_errors() {
    for line in [
        &b""[..],
        b"P0",
        b"P0 1 2",
        b"P0 1 2 X",
        b"P0 +1 2 I",
        b"P0 99999999999 0 I",
        b"P0 1 60000 I",
        b"P0 1 2 I extra",
        b"AS2",
        b"AS2 \xff",
        b"E9",
        b"ok",
    ] {
        assert_eq!(
            Reply::parse(line),
            Err(CodecError::Malformed),
            "{:?}",
            String::from_utf8_lossy(line)
        );
    }
    for line in [
        &b"M0 1 2"[..],
        b"M0  1 2 3",
        b"P0?x",
        b"O0 1",
        b"X0",
        b"M",
        b"V0 1.5 3",
    ] {
        assert!(
            Request::parse(line).is_err(),
            "{:?}",
            String::from_utf8_lossy(line)
        );
    }
}

#[test]
fn every_chunk_size_gives_the_same_replies_and_noise_in_front_costs_nothing() {
    let stream = b"AS2 1.4\r\x00\xffgarbageP0 12 -3 M\r\nOK\r\xfe\xfeE3\rP1 0 0 O\r";
    let expected = vec![
        Ok(Reply::Identity(Version::new("1.4").expect("valid"))),
        Ok(Reply::Position {
            channel: 0,
            position: 12,
            velocity: -3,
            motion: Motion::Moving,
        }),
        Ok(Reply::Done),
        Ok(Reply::Error(BoardError::OutOfRange)),
        Ok(Reply::Position {
            channel: 1,
            position: 0,
            velocity: 0,
            motion: Motion::Off,
        }),
    ];
    for chunk in 1..=stream.len() {
        assert_eq!(decode_all(stream, chunk), expected, "chunk {chunk}");
    }
}

#[test]
fn an_overlong_line_is_one_error_and_the_next_line_decodes() {
    let mut stream = vec![b'7'; 3 * MAX_LINE];
    stream.extend_from_slice(b"\rOK\r");
    assert_eq!(
        decode_all(&stream, 5),
        vec![Err(CodecError::LineTooLong), Ok(Reply::Done)]
    );
    // A line of exactly MAX_LINE bytes with its terminator is still a line.
    let mut longest = b"AS2 ".to_vec();
    longest.resize(MAX_LINE - 1, b'x');
    longest.push(END);
    assert_eq!(decode_all(&longest, 1).len(), 1);
}

fn request() -> impl Strategy<Value = Request> {
    let channel = 0..CHANNELS as u8;
    let speed = 1..=MAX_SPEED;
    let accel = 1..=MAX_ACCEL;
    let velocity = -(MAX_SPEED as i32)..=MAX_SPEED as i32;
    prop_oneof![
        Just(Request::Identify),
        channel
            .clone()
            .prop_map(|channel| Request::Position { channel }),
        (channel.clone(), any::<i32>(), speed, accel.clone()).prop_map(
            |(channel, target, speed, accel)| Request::Move {
                channel,
                target,
                speed,
                accel
            }
        ),
        (channel.clone(), velocity, accel.clone()).prop_map(|(channel, velocity, accel)| {
            Request::Jog {
                channel,
                velocity,
                accel,
            }
        }),
        (channel.clone(), accel).prop_map(|(channel, decel)| Request::Stop { channel, decel }),
        (channel.clone(), any::<i32>())
            .prop_map(|(channel, position)| Request::SetPosition { channel, position }),
        channel.prop_map(|channel| Request::Off { channel }),
    ]
}

fn reply() -> impl Strategy<Value = Reply> {
    let motion = prop_oneof![Just(Motion::Idle), Just(Motion::Moving), Just(Motion::Off)];
    prop_oneof![
        "[!-~]{1,16}".prop_map(|text| Reply::Identity(Version::new(&text).expect("valid"))),
        (
            0..CHANNELS as u8,
            any::<i32>(),
            -(MAX_SPEED as i32)..=MAX_SPEED as i32,
            motion
        )
            .prop_map(|(channel, position, velocity, motion)| Reply::Position {
                channel,
                position,
                velocity,
                motion,
            }),
        Just(Reply::Done),
        Just(Reply::Error(BoardError::Syntax)),
    ]
}

proptest! {
    #[test]
    fn requests_round_trip(request in request()) {
        let line = encoded(request);
        prop_assert!(line.len() <= MAX_LINE);
        let mut lines = LineDecoder::new();
        let parsed: Vec<_> = line.iter().filter_map(|b| lines.push(*b).map(|l| l.map(Request::parse))).collect();
        prop_assert_eq!(parsed, vec![Ok(Ok(request))]);
    }

    #[test]
    fn replies_round_trip_after_noise(reply in reply(), noise in proptest::collection::vec(any::<u8>(), 0..60)) {
        let mut buf = [0u8; MAX_LINE];
        let len = reply.encode(&mut buf).expect("fits");
        // Noise, a terminator (so the noise is its own line or is cut), then the reply.
        let mut stream = noise.clone();
        stream.push(END);
        stream.extend_from_slice(&buf[..len]);
        let decoded = decode_all(&stream, 3);
        prop_assert_eq!(decoded.last(), Some(&Ok(reply)));
    }

    #[test]
    fn any_bytes_decode_without_panicking(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let _ = decode_all(&bytes, 7);
        let mut lines = LineDecoder::new();
        for byte in bytes {
            if let Some(Ok(line)) = lines.push(byte) {
                let _ = Request::parse(line);
            }
        }
    }
}
