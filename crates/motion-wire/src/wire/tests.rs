//! The wire layout against the offsets `motion-ipc` documents (its field tables), and round
//! trips.

use motion_ipc::{
    AxisFlags, AxisInfo, AxisState, AxisWire, ClientId, CommandKind, CommandReply, CommandRequest,
    MachineParam, MachineParams, MotionFrame, Reason, SCHEMA_VERSION, ServerInfo, ServerStats,
    SignalState, Target, write_text,
};
use proptest::prelude::*;

use super::{Payload, WireError, decode, decode_boxed, encode};

fn le_u64(bytes: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"))
}

fn le_f64(bytes: &[u8], at: usize) -> f64 {
    f64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"))
}

fn le_u32(bytes: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"))
}

/// `CommandRequest`'s field table in motion-ipc: schema_version @ 0 (u32), kind @ 4 (u32),
/// client @ 8 (lo u64, hi u64), sequence @ 24 (u64), axis @ 32 (u32), target @ 36 (u32),
/// values @ 40 (3 × f64).
#[test]
fn command_request_golden_bytes() {
    let mut request = CommandRequest::new(
        ClientId::from_u128(0x1122_3344_5566_7788_99AA_BBCC_DDEE_FF00),
        0x0102_0304_0506_0708,
        5,
        CommandKind::RampPosition,
    )
    .with_values([1.5, -2.0, 0.25]);
    request.target = Target::Signal as u32;
    let mut expected = Vec::new();
    expected.extend_from_slice(&SCHEMA_VERSION.to_le_bytes());
    expected.extend_from_slice(&5u32.to_le_bytes()); // RampPosition
    expected.extend_from_slice(&0x99AA_BBCC_DDEE_FF00u64.to_le_bytes()); // lo
    expected.extend_from_slice(&0x1122_3344_5566_7788u64.to_le_bytes()); // hi
    expected.extend_from_slice(&0x0102_0304_0506_0708u64.to_le_bytes());
    expected.extend_from_slice(&5u32.to_le_bytes());
    expected.extend_from_slice(&1u32.to_le_bytes());
    for value in [1.5f64, -2.0, 0.25] {
        expected.extend_from_slice(&value.to_le_bytes());
    }
    assert_eq!(encode(&request), expected);
    assert_eq!(decode::<CommandRequest>(&expected), Ok(request));
}

/// `CommandReply`'s table: schema_version @ 0, reason @ 4, sequence @ 8, tick_applied @ 16,
/// axis @ 24, kind @ 28, at_point @ 32, at_axis @ 36, holder @ 40, value @ 56, limit @ 64;
/// 72 bytes.
#[test]
fn command_reply_golden_bytes() {
    let request = CommandRequest::new(ClientId::NONE, 42, 3, CommandKind::Velocity);
    let reply =
        CommandReply::to(&request, Reason::VelocityLimit, 0xABCD).at_point(7, 2, 60.5, 50.0);
    let bytes = encode(&reply);
    assert_eq!(bytes.len(), 72);
    assert_eq!(le_u32(&bytes, 0), SCHEMA_VERSION);
    assert_eq!(le_u32(&bytes, 4), Reason::VelocityLimit as u32);
    assert_eq!(le_u64(&bytes, 8), 42);
    assert_eq!(le_u64(&bytes, 16), 0xABCD);
    assert_eq!(le_u32(&bytes, 24), 3);
    assert_eq!(le_u32(&bytes, 28), CommandKind::Velocity as u32);
    assert_eq!(le_u32(&bytes, 32), 7);
    assert_eq!(le_u32(&bytes, 36), 2);
    assert_eq!(le_u64(&bytes, 40), 0);
    assert_eq!(le_f64(&bytes, 56), 60.5);
    assert_eq!(le_f64(&bytes, 64), 50.0);
    assert_eq!(decode::<CommandReply>(&bytes), Ok(reply));
}

/// `MotionFrame`'s table: tick @ 8, group_count @ 44, devices @ 48, axes @ 80 (96 bytes each:
/// position @ 0, flags @ 40, mode @ 46, claimed_by @ 48, desired_position @ 80), signals @
/// 12368 (64 bytes each: event_tick @ 48, sequence @ 56), wire @ 16464 (24 bytes each:
/// goal_tick @ 0, wire_tick @ 8, wire_ns @ 16), groups @ 19536 (152 bytes each: path_id @
/// 16, motion @ 80); 21968 bytes.
#[test]
fn frame_fields_sit_at_their_documented_offsets_and_padding_is_zero() {
    let mut frame = MotionFrame::EMPTY;
    frame.tick = 99;
    frame.axis_count = 2;
    frame.device_count = 1;
    frame.devices[0] = 1;
    frame.axes[1].position = -12.5;
    frame.axes[1].flags = AxisFlags::MOVING.with(AxisFlags::HOMED, true).0;
    frame.axes[1].mode = 5;
    frame.axes[1].claimed_by = ClientId::from_u128(7);
    frame.signal_count = 2;
    frame.signals[0].value = 1.0;
    frame.signals[0].kind = 2;
    frame.signals[1].event_tick = 98;
    frame.signals[1].sequence = 3;
    frame.wire[1] = AxisWire {
        goal_tick: 5,
        wire_tick: 6,
        wire_ns: 77,
    };
    frame.axes[1].desired_position = 3.25;
    frame.group_count = 1;
    frame.groups[0].path_id = 11;
    frame.groups[0].motion = 1;
    let bytes = encode(&frame);
    assert_eq!(bytes.len(), 21968);
    assert_eq!(le_u64(&bytes, 16464 + 24), 5);
    assert_eq!(le_u64(&bytes, 16464 + 24 + 8), 6);
    assert_eq!(le_u64(&bytes, 16464 + 24 + 16), 77);
    assert_eq!(le_u64(&bytes, 8), 99);
    assert_eq!(le_u32(&bytes, 44), 1);
    assert_eq!(bytes[48], 1);
    let axis1 = 80 + 96;
    assert_eq!(le_f64(&bytes, axis1), -12.5);
    assert_eq!(le_u32(&bytes, axis1 + 40), 0b11);
    assert_eq!(bytes[axis1 + 46], 5);
    assert_eq!(le_u64(&bytes, axis1 + 48), 7);
    assert_eq!(le_f64(&bytes, axis1 + 80), 3.25);
    assert_eq!(le_f64(&bytes, 12368), 1.0);
    assert_eq!(bytes[12368 + 28], 2);
    assert_eq!(le_u64(&bytes, 12368 + 64 + 48), 98);
    assert_eq!(le_u32(&bytes, 12368 + 64 + 56), 3);
    assert_eq!(le_u32(&bytes, 12368 + 64 + 60), 0);
    assert_eq!(le_u64(&bytes, 19536 + 16), 11);
    assert_eq!(bytes[19536 + 80], 1);
    // `SignalState` has 3 reserved bytes at 29 and nothing after `kind`'s block but them:
    // they are zero, and so is everything of an unused axis but its STALE flag.
    assert_eq!(&bytes[12368 + 29..12368 + 32], &[0, 0, 0]);
    let unused_axis = 80 + 5 * 96;
    assert_eq!(le_u32(&bytes, unused_axis + 40), AxisFlags::STALE.0);
    assert_eq!(decode::<MotionFrame>(&bytes), Ok(frame));
}

#[test]
fn wrong_sizes_are_refused_with_both_sizes() {
    let bytes = encode(&MotionFrame::EMPTY);
    assert_eq!(
        decode::<MotionFrame>(&bytes[..100]),
        Err(WireError::Size {
            what: "MotionFrame",
            expected: 21968,
            got: 100
        })
    );
    let mut longer = bytes.clone();
    longer.push(0);
    assert!(decode::<MotionFrame>(&longer).is_err());
    assert!(decode::<CommandRequest>(&[]).is_err());
    let text = decode::<CommandReply>(&[0; 31]).unwrap_err().to_string();
    assert!(text.contains("31 bytes") && text.contains("72"), "{text}");
}

#[test]
fn big_payloads_round_trip() {
    let mut info = ServerInfo::EMPTY;
    info.axis_count = 1;
    info.tick_hz = 1000;
    info.command_timeout_ms = 250;
    write_text(&mut info.name, "demo");
    let mut axis = AxisInfo::EMPTY;
    write_text(&mut axis.name, "x");
    write_text(&mut axis.unit, "mm");
    axis.max = 100.0;
    axis.estop = 2;
    info.axes[0] = axis;
    info.device_count = 1;
    info.devices[0].model = 99;
    write_text(&mut info.devices[0].name, "pack");
    write_text(&mut info.devices[0].model_id, "widget");
    let bytes = encode(&info);
    assert_eq!(bytes.len(), ServerInfo::SIZE);
    assert_eq!(le_u32(&bytes, 12), 1000);
    assert_eq!(&bytes[32..36], b"demo");
    assert_eq!(&bytes[72..73], b"x"); // axes @ 72, name @ 0
    // devices @ 20552: name @ 0, model @ 96, model_id @ 112.
    assert_eq!(&bytes[20552..20556], b"pack");
    assert_eq!(le_u32(&bytes, 20552 + 96), 99);
    assert_eq!(&bytes[20552 + 112..20552 + 118], b"widget");
    assert_eq!(*decode_boxed::<ServerInfo>(&bytes).expect("decodes"), info);

    let mut params = MachineParams::EMPTY;
    params.count = 1;
    let mut param = MachineParam::EMPTY;
    write_text(&mut param.key, "current.run");
    write_text(&mut param.value, "0.8 A");
    param.owner_kind = 2;
    params.entries[0] = param;
    let bytes = encode(&params);
    assert_eq!(bytes.len(), 180_240);
    assert_eq!(
        *decode_boxed::<MachineParams>(&bytes).expect("decodes"),
        params
    );

    let mut stats = ServerStats::EMPTY;
    stats.tick = 5;
    stats.wakeup.p99_ns = 35_000;
    stats.full_events = 3;
    let bytes = encode(&stats);
    assert_eq!(le_u64(&bytes, 24 + 16), 35_000); // wakeup @ 24, p99_ns @ 16
    assert_eq!(le_u32(&bytes, 1444), 3);
    assert_eq!(decode::<ServerStats>(&bytes), Ok(stats));
}

fn axis_state() -> impl Strategy<Value = AxisState> {
    (
        (any::<f64>(), any::<f64>(), any::<f64>(), any::<i64>()),
        (
            any::<u64>(),
            any::<u32>(),
            any::<u16>(),
            any::<u8>(),
            any::<u8>(),
        ),
        (
            any::<u128>(),
            any::<f64>(),
            any::<f64>(),
            any::<f64>(),
            any::<f64>(),
        ),
    )
        .prop_map(
            |(
                (position, velocity, target, raw_counts),
                (last_refresh_tick, flags, fault, mode, device_state),
                (claimed_by, fault_value, fault_limit, desired_position, desired_velocity),
            )| AxisState {
                position,
                velocity,
                target,
                raw_counts,
                last_refresh_tick,
                flags,
                fault,
                mode,
                device_state,
                claimed_by: ClientId::from_u128(claimed_by),
                fault_value,
                fault_limit,
                desired_position,
                desired_velocity,
            },
        )
}

fn signal_state() -> impl Strategy<Value = SignalState> {
    (
        any::<f64>(),
        any::<f64>(),
        any::<u64>(),
        any::<u32>(),
        any::<u8>(),
        any::<[u8; 3]>(),
        any::<u128>(),
        any::<(u64, u32, u32)>(),
    )
        .prop_map(
            |(
                value,
                raw,
                last_refresh_tick,
                flags,
                kind,
                reserved,
                claimed_by,
                (event_tick, sequence, reserved2),
            )| SignalState {
                value,
                raw,
                last_refresh_tick,
                flags,
                kind,
                reserved,
                claimed_by: ClientId::from_u128(claimed_by),
                event_tick,
                sequence,
                reserved2,
            },
        )
}

proptest! {
    /// Any frame survives the wire bit for bit (NaNs included: compared as bytes).
    #[test]
    fn frames_round_trip(
        tick in any::<u64>(),
        counts in (any::<u32>(), any::<u32>(), any::<u32>()),
        devices in any::<[u8; 32]>(),
        axes in proptest::collection::vec((0..128usize, axis_state()), 0..8),
        signals in proptest::collection::vec((0..64usize, signal_state()), 0..4),
    ) {
        let mut frame = MotionFrame::EMPTY;
        frame.tick = tick;
        (frame.axis_count, frame.signal_count, frame.device_count) = counts;
        frame.devices = devices;
        for (index, axis) in axes {
            frame.axes[index] = axis;
        }
        for (index, signal) in signals {
            frame.signals[index] = signal;
        }
        let bytes = encode(&frame);
        let back = decode::<MotionFrame>(&bytes).expect("decodes");
        prop_assert_eq!(encode(&back), bytes);
    }

    #[test]
    fn requests_round_trip(
        kind in any::<u32>(), client in any::<u128>(), sequence in any::<u64>(),
        axis in any::<u32>(), target in any::<u32>(), values in any::<[f64; 3]>(),
    ) {
        let request = CommandRequest {
            schema_version: SCHEMA_VERSION,
            kind,
            client: ClientId::from_u128(client),
            sequence,
            axis,
            target,
            values,
        };
        let bytes = encode(&request);
        prop_assert_eq!(encode(&decode::<CommandRequest>(&bytes).expect("decodes")), bytes);
    }

    /// Garbage of any length never panics; only the exact size decodes.
    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..200)) {
        let request = decode::<CommandRequest>(&bytes);
        prop_assert_eq!(request.is_ok(), bytes.len() == 64);
        let reply = decode::<CommandReply>(&bytes);
        prop_assert_eq!(reply.is_ok(), bytes.len() == 72);
        prop_assert!(decode::<MotionFrame>(&bytes).is_err());
    }
}
