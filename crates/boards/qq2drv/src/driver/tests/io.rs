//! The I/O pins: Status bits of the stream, a channel streamed for its signal alone.

use super::*;

#[test]
fn a_channel_without_an_axis_but_with_a_signal_streams_its_status() {
    let mut config = config();
    // Channel 4 has no axis; a signal reads its IN pin and its glitch bit.
    config.channels[3].pins = (1 << 0) | (1 << 4);
    let mut driver = Qq2drvDriver::new(config);
    assert_eq!(driver.stream_masks()[3], STATUS_MASK);
    assert_eq!(STATUS_MASK.0, 0b0010_0000, "Status only (packet 6 bit 5)");
    drain(&mut driver, Duration::ZERO);
    driver.handle_rx(
        MS,
        &probe_answers([DataMask::DEFAULT; 4], StreamConfig(0), 0),
    );
    let sent = drain(&mut driver, MS);
    let r = requests(&sent[0]);
    let masks = r
        .iter()
        .find_map(|r| match r {
            Request::SetDataMask(e) => Some(e.iter().map(|e| (e.channels.0, e.mask)).collect()),
            _ => None,
        })
        .unwrap_or_else(Vec::new);
    assert_eq!(masks, [(0b0111, STREAM_MASK), (0b1000, STATUS_MASK)]);
    driver.handle_rx(2 * MS, &acks(&sent[0], 0));
    // A stream packet with channel 4's status: Input Active and Glitch.
    let mut data = MotionData::default();
    for i in 0..3 {
        data.channels[i] = ChannelData {
            position: Some(PositionValue::I32(0)),
            velocity: Some(0),
            status: Some(Status(0)),
        };
    }
    data.channels[3] = ChannelData {
        position: None,
        velocity: None,
        status: Some(Status(Status::INPUT_ACTIVE | Status::GLITCH)),
    };
    let stream = encode_reply(&Reply::StreamData(StreamData {
        code: None,
        timing: Some(25),
        periods_elapsed: None,
        data,
    }));
    driver.handle_rx(3 * MS, &stream);
    let in4 = pin_of(3, 0).unwrap();
    let glitch4 = pin_of(3, 4).unwrap();
    assert_eq!(driver.read_pin(in4).map(|r| r.value), Some(1.0));
    assert_eq!(driver.read_pin(glitch4).map(|r| r.value), Some(1.0));
    assert_eq!(driver.read_pin(in4).unwrap().refreshed_at, Some(3 * MS));
    // Pins no signal reads, and pins beyond the table, are not read.
    assert_eq!(driver.read_pin(pin_of(3, 1).unwrap()), None);
    assert_eq!(driver.read_pin(pin_of(0, 0).unwrap()), None);
    assert_eq!(driver.read_pin(Pin(99)), None);
    // And nothing can be driven.
    assert_eq!(
        driver.set_output(3 * MS, in4, true),
        Err(GoalError::NoSuchPin(in4))
    );
    assert_eq!(driver.channel(3), ChannelState::UNKNOWN, "still no axis");
}
