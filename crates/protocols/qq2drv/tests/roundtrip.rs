//! Property round trips: every request and reply type encodes and decodes to itself.

use proptest::prelude::*;
use qq2drv::{
    AccelerationLimitEntry, CHANNELS, ChannelData, ChannelMask, ControlMode, ControlModeEntry,
    DataMask, DataMaskEntry, Entries, Entry, GetPosition, HistoryDimensions, InputConfig,
    InputMode, InputModeEntry, MotionData, MotionLayout, MotorPowerEntry, PacketId, PositionLayout,
    PositionPidEntry, PositionRampEntry, PositionSize, PositionTargetEntry, PositionValue,
    PowerLimitEntry, Reply, ReplyLayout, Request, ReturnCode, SetPositionEntry, Status,
    StreamConfig, StreamData, VelocityLimitEntry, VelocityPidEntry, VelocityRampEntry,
    VelocityTargetEntry,
};

fn mask() -> impl Strategy<Value = ChannelMask> {
    any::<u8>().prop_map(ChannelMask)
}

fn position_value() -> impl Strategy<Value = PositionValue> {
    prop_oneof![
        any::<i8>().prop_map(PositionValue::I8),
        any::<i16>().prop_map(PositionValue::I16),
        any::<i32>().prop_map(PositionValue::I32),
    ]
}

fn size() -> impl Strategy<Value = PositionSize> {
    (0u8..4).prop_map(PositionSize::from_bits)
}

fn control_mode() -> impl Strategy<Value = ControlMode> {
    (0u8..4).prop_map(|m| ControlMode::try_from(m).unwrap_or_default())
}

fn input_entry() -> impl Strategy<Value = InputModeEntry> {
    (mask(), any::<u8>(), any::<u16>(), any::<i32>()).prop_map(|(channels, c, spacing, p)| {
        let config = InputConfig(c);
        let position = if config.mode() == InputMode::Disabled {
            0
        } else {
            p
        };
        InputModeEntry {
            channels,
            config,
            spacing,
            position,
        }
    })
}

/// Round-trips a request built over `entries` and checks the packet length it reports.
fn check_request(req: Request<'_>) -> Result<(), TestCaseError> {
    let mut buf = [0u8; 255];
    let n = req
        .encode(&mut buf)
        .map_err(|e| TestCaseError::fail(e.to_string()))?;
    prop_assert_eq!(usize::from(buf[1]), n);
    let back = Request::parse(&buf[..n]).map_err(|e| TestCaseError::fail(e.to_string()))?;
    prop_assert_eq!(back, req);
    Ok(())
}

fn check_entries<'a, T: Entry>(
    entries: &'a [T],
    build: impl Fn(Entries<'a, T>) -> Request<'a>,
) -> Result<(), TestCaseError> {
    let expected_len: usize = entries.iter().map(Entry::encoded_len).sum();
    let req = build(Entries::new(entries));
    let mut buf = [0u8; 255];
    let n = req
        .encode(&mut buf)
        .map_err(|e| TestCaseError::fail(e.to_string()))?;
    prop_assert_eq!(n, expected_len + 4);
    let back = Request::parse(&buf[..n]).map_err(|e| TestCaseError::fail(e.to_string()))?;
    prop_assert_eq!(back, req);
    check_request(back)
}

fn entries<T: std::fmt::Debug>(s: impl Strategy<Value = T>) -> impl Strategy<Value = Vec<T>> {
    prop::collection::vec(s, 1..8)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(
        // scripts/fuzz without a nightly toolchain asks for more.
        std::env::var("PROPTEST_CASES").ok().and_then(|c| c.parse().ok()).unwrap_or(256)
    ))]

    #[test]
    fn simple_requests(period in any::<u16>(), cfg in any::<u8>(), len in any::<u8>(), bits in any::<u8>()) {
        for req in [
            Request::GetVersion,
            Request::GetMotionData,
            Request::SetStreamPeriod(period),
            Request::GetStreamPeriod,
            Request::GetDataMask,
            Request::SetStreamConfig(StreamConfig(cfg)),
            Request::GetStreamConfig,
            Request::SetHistoryDimensions(HistoryDimensions { history_length: len, averaging_bits: bits }),
            Request::GetHistoryDimensions,
        ] {
            check_request(req)?;
        }
    }

    #[test]
    fn get_position_forms(m in mask(), sizes in [size(), size(), size(), size()]) {
        check_request(Request::GetPosition(GetPosition::Configured))?;
        check_request(Request::GetPosition(GetPosition::Channels(m)))?;
        check_request(Request::GetPosition(GetPosition::Sizes(sizes)))?;
    }

    #[test]
    fn data_mask_entries(e in entries((mask(), any::<u8>()).prop_map(|(channels, m)| DataMaskEntry { channels, mask: DataMask(m) }))) {
        check_entries(&e, Request::SetDataMask)?;
    }

    #[test]
    fn set_position_entries(e in entries((0u8..16, prop::option::of(position_value())).prop_map(|(c, position)| SetPositionEntry { channels: ChannelMask(c), position }))) {
        check_entries(&e, Request::SetPosition)?;
    }

    #[test]
    fn input_mode_entries(e in entries(input_entry())) {
        check_entries(&e, Request::SetInputMode)?;
    }

    #[test]
    fn control_and_power_entries(
        c in entries((mask(), control_mode()).prop_map(|(channels, mode)| ControlModeEntry { channels, mode })),
        p in entries((mask(), any::<i16>()).prop_map(|(channels, power)| MotorPowerEntry { channels, power })),
        pl in entries((mask(), any::<u16>()).prop_map(|(channels, limit)| PowerLimitEntry { channels, limit })),
    ) {
        check_entries(&c, Request::SetControlMode)?;
        check_entries(&p, Request::SetMotorPower)?;
        check_entries(&pl, Request::SetPowerLimit)?;
    }

    #[test]
    fn target_and_limit_entries(
        pt in entries((mask(), any::<i32>()).prop_map(|(channels, position)| PositionTargetEntry { channels, position })),
        vt in entries((mask(), any::<i32>()).prop_map(|(channels, velocity)| VelocityTargetEntry { channels, velocity })),
        vl in entries((mask(), any::<u32>()).prop_map(|(channels, limit)| VelocityLimitEntry { channels, limit })),
        al in entries((mask(), any::<u32>()).prop_map(|(channels, limit)| AccelerationLimitEntry { channels, limit })),
    ) {
        check_entries(&pt, Request::SetPositionTarget)?;
        check_entries(&vt, Request::SetVelocityTarget)?;
        check_entries(&vl, Request::SetVelocityLimit)?;
        check_entries(&al, Request::SetAccelerationLimit)?;
    }

    #[test]
    fn pid_and_ramp_entries(
        pp in entries((mask(), any::<u16>(), any::<u16>(), any::<u16>(), any::<u16>()).prop_map(|(channels, p, i, d, windup)| PositionPidEntry { channels, p, i, d, windup })),
        vp in entries((mask(), any::<u16>(), any::<u16>(), any::<u16>()).prop_map(|(channels, p, i, d)| VelocityPidEntry { channels, p, i, d })),
        pr in entries((mask(), any::<i32>(), any::<u32>(), any::<u32>()).prop_map(|(channels, position, velocity, acceleration)| PositionRampEntry { channels, position, velocity, acceleration })),
        vr in entries((mask(), any::<i32>(), any::<u32>()).prop_map(|(channels, velocity, acceleration)| VelocityRampEntry { channels, velocity, acceleration })),
    ) {
        check_entries(&pp, Request::SetPositionPid)?;
        check_entries(&vp, Request::SetVelocityPid)?;
        check_entries(&pr, Request::PositionRamp)?;
        check_entries(&vr, Request::VelocityRamp)?;
    }

    #[test]
    fn motion_and_stream_replies_under_any_layout(
        masks in [any::<u8>(), any::<u8>(), any::<u8>(), any::<u8>()],
        cfg in any::<u8>(),
        pos in [any::<i32>(), any::<i32>(), any::<i32>(), any::<i32>()],
        vel in [any::<i32>(), any::<i32>(), any::<i32>(), any::<i32>()],
        st in [any::<u8>(), any::<u8>(), any::<u8>(), any::<u8>()],
        code in any::<u8>(),
        timing in any::<u16>(),
        elapsed in any::<u8>(),
    ) {
        let data_masks = masks.map(DataMask);
        let motion = MotionLayout { data_masks, stream_config: StreamConfig(cfg) };
        let layout = ReplyLayout { motion, position: PositionLayout::default() };
        let data = MotionData::sample(&data_masks, pos, vel, st.map(Status));
        prop_assert!(data.matches(&data_masks));
        // A non-zero code with no data at all is an error reply (Ack); keep the typed one.
        let code = if motion.channels_len() == 0 { ReturnCode(0) } else { ReturnCode(code) };
        let stream = StreamData {
            code: None,
            timing: motion.stream_config.timing().then_some(timing),
            periods_elapsed: motion.stream_config.periods_elapsed().then_some(elapsed),
            data,
        };
        let replies = [
            (Reply::MotionData { code, data }, motion.motion_payload_len()),
            // Packet 3 as its table shows it, and with the Return Code its text names.
            (Reply::StreamData(stream), motion.stream_payload_len()),
            (
                Reply::StreamData(StreamData { code: Some(code), ..stream }),
                motion.stream_payload_len() + 1,
            ),
        ];
        for (reply, expect_len) in replies {
            let mut buf = [0u8; 255];
            let n = reply.encode(&mut buf).map_err(|e| TestCaseError::fail(e.to_string()))?;
            prop_assert_eq!(n, expect_len + 4);
            prop_assert_eq!(Reply::parse(&buf[..n], &layout), Ok(reply));
        }
        for (ch, (m, p)) in data.channels.iter().zip(data_masks.iter().zip(pos)) {
            // Positions keep their lower bits; sign extension on decode.
            if let Some(v) = ch.position {
                prop_assert_eq!(v.size(), m.position_size());
                prop_assert_eq!(PositionValue::truncate(m.position_size(), p), Some(v));
            }
        }
    }

    #[test]
    fn other_replies(
        code in any::<u8>(),
        a in any::<u8>(), b in any::<u8>(), c in any::<u8>(),
        period in any::<u16>(),
        masks in [any::<u8>(), any::<u8>(), any::<u8>(), any::<u8>()],
        positions in [prop::option::of(position_value()), prop::option::of(position_value()), prop::option::of(position_value()), prop::option::of(position_value())],
        id_ix in 0usize..PacketId::ALL.len(),
    ) {
        let layout = ReplyLayout { motion: MotionLayout::default(), position: PositionLayout::of(&positions) };
        let all_omitted = positions.iter().all(Option::is_none);
        let mut replies = vec![
            Reply::Version { code: ReturnCode(code), firmware_major: a, firmware_minor: b, protocol: c },
            Reply::StreamPeriod { code: ReturnCode(code), period },
            Reply::DataMasks { code: ReturnCode(code), masks: masks.map(DataMask) },
            Reply::StreamConfig { code: ReturnCode(code), config: StreamConfig(a) },
            Reply::Positions { code: ReturnCode(if all_omitted { 0 } else { code }), positions },
            Reply::HistoryDimensions { code: ReturnCode(code), dimensions: HistoryDimensions { history_length: a, averaging_bits: b } },
        ];
        let id = PacketId::ALL[id_ix];
        if id != PacketId::StreamData {
            let code = if id.reply_is_return_code_only() { code } else { code.max(1) };
            replies.push(Reply::Ack { id, code: ReturnCode(code) });
        }
        for reply in replies {
            let mut buf = [0u8; 255];
            let n = reply.encode(&mut buf).map_err(|e| TestCaseError::fail(e.to_string()))?;
            prop_assert_eq!(Reply::parse(&buf[..n], &layout), Ok(reply));
        }
    }

    #[test]
    fn channel_data_layout_lengths(m in any::<u8>()) {
        let mask = DataMask(m);
        let ch = ChannelData::sample(mask, 0, 0, Status(0));
        prop_assert!(ch.matches(mask));
        let layout = MotionLayout { data_masks: [mask; CHANNELS], stream_config: StreamConfig(0) };
        prop_assert_eq!(layout.channels_len(), 4 * mask.channel_len());
    }
}
