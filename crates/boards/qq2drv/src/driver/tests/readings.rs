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

/// `running()` with every channel reading packet 36 as `velocity_ramp` says.
fn running_with(velocity_ramp: qq2drv::limits::VelocityRampSign) -> (Qq2drvDriver, Duration) {
    let mut config = config();
    for channel in &mut config.channels {
        channel.velocity_ramp = velocity_ramp;
    }
    let mut driver = Qq2drvDriver::new(config);
    let mut now = Duration::ZERO;
    drain(&mut driver, now);
    now += MS;
    driver.handle_rx(
        now,
        &probe_answers([DataMask::DEFAULT; 4], StreamConfig(0), 0),
    );
    let sent = drain(&mut driver, now);
    now += MS;
    driver.handle_rx(now, &acks(&sent[0], 0));
    assert!(driver.running());
    now += 4 * MS;
    driver.handle_rx(now, &ours_stream([10, 20, 30], [0, 0, 0], [0; 3]));
    (driver, now)
}

/// Packet 36: "Velocity: Velocity target, specified as: Velocity = <transitions/s>. Range:
/// 0 - 100,000", in an I32 field. Read as unsigned, a reverse velocity goes out as packet
/// 28 (the ramp's acceleration as the limit: "The acceleration limit set using packet 28 …
/// still applies") and packet 22, the channel's own limit written back by the next step;
/// forward still uses packet 36. Read as signed (the default), packet 36 carries it.
#[test]
fn a_reverse_velocity_on_a_forward_only_packet_36_goes_out_as_packets_28_and_22() {
    use qq2drv::limits::VelocityRampSign;
    let (mut driver, mut now) = running_with(VelocityRampSign::Unsigned);
    let reverse = Goal::Velocity {
        velocity: -1_500.0,
        accel: 20_000.0,
    };
    now += 2 * MS;
    let mosi = acked(&mut driver, now, 2, reverse);
    match requests(&mosi).as_slice() {
        [
            Request::SetControlMode(mode),
            Request::SetAccelerationLimit(limit),
            Request::SetVelocityTarget(target),
        ] => {
            assert_eq!(one(mode).mode, ControlMode::VelocityPid);
            assert_eq!(one(limit).limit, 20_000 << FIXED_SHIFT);
            assert_eq!(one(target).velocity, -1_500);
        }
        other => panic!("{other:?}"),
    }
    // Forward: the channel's own limit (30 000 shl 12) back first, then packet 36.
    now += 2 * MS;
    let forward = Goal::Velocity {
        velocity: 1_500.0,
        accel: 20_000.0,
    };
    let mosi = acked(&mut driver, now, 2, forward);
    match requests(&mosi).as_slice() {
        [
            Request::SetAccelerationLimit(limit),
            Request::SetControlMode(_),
            Request::VelocityRamp(ramp),
        ] => {
            assert_eq!(one(limit).limit, 30_000 << FIXED_SHIFT);
            assert_eq!(
                (one(ramp).velocity, one(ramp).acceleration),
                (1_500, 20_000 << FIXED_SHIFT)
            );
        }
        other => panic!("{other:?}"),
    }
    // A stop from a measured reverse velocity: the limit lifted (28 ← 0, which replaces
    // the reverse ramp's) and the setpoint reset to it by packet 22 instead of 36.
    now += 2 * MS;
    acked(&mut driver, now, 0, reverse);
    now += 4 * MS;
    driver.handle_rx(now, &ours_stream([100, 0, 0], [-900, 0, 0], [0; 3]));
    let mosi = goal_packets(&mut driver, now, 0, Goal::Stop { decel: 20_000.0 });
    match requests(&mosi).as_slice() {
        [
            Request::SetControlMode(off),
            Request::SetControlMode(_),
            Request::SetAccelerationLimit(lifted),
            Request::SetVelocityTarget(target),
        ] => {
            assert_eq!(one(off).mode, ControlMode::Off);
            assert_eq!(one(lifted).limit, 0);
            assert_eq!(one(target).velocity, -900);
        }
        other => panic!("{other:?}"),
    }
    // Signed (the default): packet 36 carries the negative velocity.
    let (mut driver, now) = running_with(VelocityRampSign::Signed);
    let mosi = acked(&mut driver, now + 2 * MS, 2, reverse);
    match requests(&mosi).as_slice() {
        [Request::SetControlMode(_), Request::VelocityRamp(ramp)] => {
            assert_eq!(one(ramp).velocity, -1_500);
        }
        other => panic!("{other:?}"),
    }
}
