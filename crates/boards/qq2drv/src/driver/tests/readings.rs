//! Where the datasheet ("QuadQuad2Drv PCB Datasheet", interface protocol v1) reads two ways
//! (docs/ARCHITECTURE.md): packet 3 with or without a Return Code.

use super::*;

/// `ours_stream` with the Return Code packet 3's text names: "Each quadrature channel and
/// field in the reply payload, except for *Return Code*, is optional".
fn stream_with_code(code: u8, positions: [i32; 3]) -> Vec<u8> {
    let mut data = MotionData::default();
    for (channel, position) in data.channels.iter_mut().zip(positions) {
        *channel = ChannelData {
            position: Some(PositionValue::I32(position)),
            velocity: Some(0),
            status: Some(Status(0)),
        };
    }
    encode_reply(&Reply::StreamData(StreamData {
        code: Some(ReturnCode(code)),
        timing: Some(25),
        periods_elapsed: None,
        data,
    }))
}

/// Packet 3 as its table shows it (no Return Code) and as its text says (a Return Code in
/// front) both refresh the channels, one byte at a time through garbage, with no byte of
/// shift; a packet one byte too long for either is dropped and counted.
#[test]
fn packet_3_with_and_without_a_return_code_refreshes_the_channels() {
    let (mut driver, now) = running();
    let mut bytes = vec![0u8, 2, 9, 7];
    bytes.extend(stream_with_code(0, [-5, 1_234, 7]));
    bytes.extend([0u8, 2, 200, 0]);
    let at = now + MS;
    for chunk in bytes.chunks(1) {
        driver.handle_rx(at, chunk);
    }
    assert_eq!(driver.channel(0).position, -5.0);
    assert_eq!(driver.channel(1).position, 1_234.0);
    assert_eq!(driver.channel(2).refreshed_at, Some(at));
    assert_eq!(driver.stream_packets(), 2);
    // The table's form again, then the text's: both read the same.
    let at = at + MS;
    driver.handle_rx(at, &ours_stream([1, 2, 3], [0; 3], [0; 3]));
    assert_eq!(driver.channel(1).position, 2.0);
    let at = at + MS;
    driver.handle_rx(at, &stream_with_code(0, [4, 5, 6]));
    assert_eq!(driver.channel(1).position, 5.0);
    assert_eq!(driver.stream_packets(), 4);
    assert_eq!(driver.status().fault, None);
    // Two extra bytes: neither reading. Dropped and counted, the channels untouched.
    let mut long = stream_with_code(0, [7, 8, 9]);
    long.insert(3, 0);
    long[1] += 1;
    let last = long.len() - 1;
    long[last] = long[last].wrapping_sub(1);
    let bad = driver.status().bad_replies;
    driver.handle_rx(at + MS, &long);
    assert_eq!(driver.status().bad_replies, bad + 1);
    assert_eq!(driver.channel(1).position, 5.0);
    assert_eq!(driver.stream_packets(), 4);
}

/// A stream packet whose Return Code is not 0 is the board's error: reported
/// (`BoardError`), its data not used; the next good packet clears it.
#[test]
fn a_stream_packet_with_a_non_zero_return_code_is_a_board_error() {
    let (mut driver, now) = running();
    driver.handle_rx(now + MS, &stream_with_code(3, [100, 200, 300]));
    assert_eq!(driver.status().fault, Some(DeviceFault::BoardError));
    assert_eq!(driver.channel(1).position, 20.0, "the data was not used");
    driver.handle_rx(now + 2 * MS, &stream_with_code(0, [100, 200, 300]));
    assert_eq!(driver.status().fault, None);
    assert_eq!(driver.channel(1).position, 200.0);
}
