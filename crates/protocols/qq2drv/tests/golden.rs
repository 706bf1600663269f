//! Golden vectors from the QuadQuad2Drv datasheet.

use qq2drv::{
    ChannelData, ChannelMask, ControlMode, ControlModeEntry, DataMask, DataMaskEntry, EdgeAction,
    Entries, Error, Frame, GetPosition, InputConfig, InputMode, InputModeEntry, MotionData,
    MotionLayout, MotorPowerEntry, PacketId, PositionLayout, PositionSize, PositionValue, Reply,
    ReplyLayout, Request, ReturnCode, SetPositionEntry, Status, StreamConfig, StreamData,
    StreamDecoder, VelocityRampEntry, checksum,
};

fn encode_req(req: &Request<'_>) -> Vec<u8> {
    let mut buf = [0u8; 255];
    let n = req.encode(&mut buf).expect("encode");
    buf[..n].to_vec()
}

fn encode_rep(rep: &Reply) -> Vec<u8> {
    let mut buf = [0u8; 255];
    let n = rep.encode(&mut buf).expect("encode");
    buf[..n].to_vec()
}

/// Byte sum of a whole packet must be zero.
fn sum(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0u8, |a, b| a.wrapping_add(*b))
}

#[test]
fn worked_example_read_version_numbers_request() {
    // "Worked Examples / Read Version Numbers": STX 2, Packet Size 4, Packet ID 1, Checksum 249.
    assert_eq!(encode_req(&Request::GetVersion), [2, 4, 1, 249]);
    assert_eq!(Request::parse(&[2, 4, 1, 249]), Ok(Request::GetVersion));
}

#[test]
fn worked_example_read_version_numbers_reply() {
    // "You should receive the following reply": 2, 8, 1, 0, 0, 1, 0, 244.
    let reply = Reply::Version {
        code: ReturnCode::SUCCESS,
        firmware_major: 0,
        firmware_minor: 1,
        protocol: 0,
    };
    assert_eq!(encode_rep(&reply), [2, 8, 1, 0, 0, 1, 0, 244]);
    assert_eq!(
        Reply::parse(&[2, 8, 1, 0, 0, 1, 0, 244], &ReplyLayout::default()),
        Ok(reply)
    );
}

#[test]
fn packet_format_checksum_sums_to_zero() {
    // "Checksum is the 8-bit checksum of the entire packet" (docs/ARCHITECTURE.md: the sum is zero).
    assert_eq!(checksum(&[2, 4, 1]), 249);
    assert_eq!(checksum(&[2, 8, 1, 0, 0, 1, 0]), 244);
    assert_eq!(Frame::parse(&[2, 4, 1, 248]), Err(Error::BadChecksum));
    assert_eq!(Frame::parse(&[3, 4, 1, 248]), Err(Error::BadStx));
    assert_eq!(Frame::parse(&[2, 5, 1, 249]), Err(Error::BadSize));
    assert_eq!(Frame::parse(&[2, 3, 251]), Err(Error::BadSize));
}

#[test]
fn packet_4_set_stream_period_is_u16_little_endian() {
    // "4 - Set Stream Period": Send U16 Stream Period; example value 100 from packet 3's text.
    let bytes = encode_req(&Request::SetStreamPeriod(100));
    assert_eq!(bytes, [2, 6, 4, 100, 0, 144]);
    let bytes = encode_req(&Request::SetStreamPeriod(0x1234));
    assert_eq!(&bytes[..5], &[2, 6, 4, 0x34, 0x12]);
    assert_eq!(sum(&bytes), 0);
}

#[test]
fn packet_2_default_layout_is_i32_position_and_velocity() {
    // "6 - Set Data Mask": default Position Size 0x03, Velocity 1, Status 0.
    let layout = ReplyLayout::default();
    assert_eq!(layout.motion.data_masks, [DataMask(0x0B); 4]);
    assert_eq!(layout.motion.motion_payload_len(), 1 + 4 * 8);
    let mut packet = vec![2, 37, 2, 0];
    for ch in 0..4i32 {
        packet.extend_from_slice(&(ch * 1000 - 1).to_le_bytes());
        packet.extend_from_slice(&(-ch * 4).to_le_bytes());
    }
    packet.push(checksum(&packet));
    let Reply::MotionData { code, data } = Reply::parse(&packet, &layout).expect("decode") else {
        panic!("not motion data");
    };
    assert!(code.is_success());
    assert_eq!(data.channels[2].position, Some(PositionValue::I32(1999)));
    assert_eq!(data.channels[3].velocity, Some(-12));
    assert_eq!(data.channels[0].status, None);
}

#[test]
fn packet_2_mixed_masks_8_16_bit_relative_status_and_omitted_channel() {
    // Channel 1: 8-bit + status; channel 2: omitted; channel 3: 16-bit relative + velocity;
    // channel 4: status only.
    let masks = [
        DataMask::new(PositionSize::I8, false, false, true),
        DataMask(0),
        DataMask::new(PositionSize::I16, true, true, false),
        DataMask::new(PositionSize::Omitted, false, false, true),
    ];
    let layout = ReplyLayout {
        motion: MotionLayout {
            data_masks: masks,
            stream_config: StreamConfig(0),
        },
        position: PositionLayout::default(),
    };
    let payload = [0u8, 0xFF, 0x88, 0x34, 0x12, 0x10, 0, 0, 0, 0x08];
    let mut packet = vec![2, (payload.len() + 4) as u8, 2];
    packet.extend_from_slice(&payload);
    packet.push(checksum(&packet));
    let reply = Reply::parse(&packet, &layout).expect("decode");
    let expect = MotionData {
        channels: [
            ChannelData {
                position: Some(PositionValue::I8(-1)),
                velocity: None,
                status: Some(Status(0x88)),
            },
            ChannelData::default(),
            ChannelData {
                position: Some(PositionValue::I16(0x1234)),
                velocity: Some(16),
                status: None,
            },
            ChannelData {
                position: None,
                velocity: None,
                status: Some(Status(0x08)),
            },
        ],
    };
    assert_eq!(
        reply,
        Reply::MotionData {
            code: ReturnCode(0),
            data: expect
        }
    );
    assert_eq!(encode_rep(&reply), packet);
    let s = expect.channels[0].status.expect("status");
    assert!(s.glitch() && s.input_active() && !s.overspeed());
}

#[test]
fn packet_3_stream_has_no_return_code_and_optional_timing_fields() {
    // "3 - Binary Stream Data": [Stream Period Timing U16][Stream Periods Elapsed U8] channels.
    let mut layout = ReplyLayout::default();
    layout.motion.data_masks = [DataMask::new(PositionSize::I16, false, false, false); 4];
    layout.motion.stream_config = StreamConfig::new(true, true);
    let stream = StreamData {
        code: None,
        timing: Some(108),
        periods_elapsed: Some(1),
        data: MotionData::sample(
            &layout.motion.data_masks,
            [1, 2, 3, 70000],
            [0; 4],
            [Status(0); 4],
        ),
    };
    let bytes = encode_rep(&Reply::StreamData(stream));
    assert_eq!(&bytes[..6], &[2, 15, 3, 108, 0, 1]);
    // 70000 wraps to its lower 16 bits ("wrapping will occur on overflow").
    assert_eq!(&bytes[12..14], &(70000u32 as u16).to_le_bytes());
    assert_eq!(Reply::parse(&bytes, &layout), Ok(Reply::StreamData(stream)));
    // Without the timing fields the same channel data is three bytes shorter.
    layout.motion.stream_config = StreamConfig(0);
    assert_eq!(layout.motion.stream_payload_len(), 8);
}

/// Packet 3 - Binary Stream Data: its text, "Each quadrature channel and field in the reply
/// payload, except for *Return Code*, is optional", names a Return Code its table
/// ("[Stream Period Timing] [Stream Periods Elapsed] [Channel 1 Data] …") does not show.
/// Both forms decode, told apart by Packet Size; any other size is an error, never a
/// shifted read.
#[test]
fn packet_3_with_and_without_a_return_code() {
    let mut layout = ReplyLayout::default();
    layout.motion.data_masks = [DataMask::new(PositionSize::I16, false, false, false); 4];
    layout.motion.stream_config = StreamConfig::new(true, false);
    let data = MotionData::sample(
        &layout.motion.data_masks,
        [1, -2, 3, -4],
        [0; 4],
        [Status(0); 4],
    );
    // The table's form: timing 108 (0x6C), then four I16 positions.
    let table = [2, 14, 3, 108, 0, 1, 0, 0xFE, 0xFF, 3, 0, 0xFC, 0xFF, 0];
    let mut table = table;
    fix_checksum(&mut table);
    let without = StreamData {
        code: None,
        timing: Some(108),
        periods_elapsed: None,
        data,
    };
    assert_eq!(
        Reply::parse(&table, &layout),
        Ok(Reply::StreamData(without))
    );
    assert_eq!(encode_rep(&Reply::StreamData(without)), table);
    // The text's form: Return Code 0 in front, one byte longer; the same fields.
    let mut text = [2, 15, 3, 0, 108, 0, 1, 0, 0xFE, 0xFF, 3, 0, 0xFC, 0xFF, 0];
    fix_checksum(&mut text);
    let with = StreamData {
        code: Some(ReturnCode(0)),
        ..without
    };
    assert_eq!(Reply::parse(&text, &layout), Ok(Reply::StreamData(with)));
    assert_eq!(encode_rep(&Reply::StreamData(with)), text);
    // A non-zero code is kept for the caller to report (docs/ARCHITECTURE.md).
    text[3] = 5;
    fix_checksum(&mut text);
    let Ok(reply) = Reply::parse(&text, &layout) else {
        panic!("a stream packet with code 5 decodes");
    };
    assert_eq!(reply.code(), Some(ReturnCode(5)));
    // One byte short, or two long: neither reading; an error, not a shifted packet.
    for size in [13u8, 16, 17] {
        let mut odd = vec![0u8; usize::from(size)];
        odd[..3].copy_from_slice(&[2, size, 3]);
        fix_checksum(&mut odd);
        assert!(Reply::parse(&odd, &layout).is_err(), "size {size}");
    }
}

/// Sets the last byte so that the 8-bit sum of the packet is 0.
fn fix_checksum(packet: &mut [u8]) {
    let Some((last, rest)) = packet.split_last_mut() else {
        return;
    };
    *last = rest
        .iter()
        .fold(0u8, |sum, b| sum.wrapping_add(*b))
        .wrapping_neg();
}

#[test]
fn packet_6_multiple_channel_mask_pairs() {
    // "Any number of Channel Mask and Data Mask pairs can be concatenated".
    let entries = [
        DataMaskEntry {
            channels: ChannelMask(0x0F),
            mask: DataMask(0x0B),
        },
        DataMaskEntry {
            channels: ChannelMask(0x04),
            mask: DataMask(0x21),
        },
    ];
    let bytes = encode_req(&Request::SetDataMask(Entries::new(&entries)));
    assert_eq!(&bytes[..7], &[2, 8, 6, 0x0F, 0x0B, 0x04, 0x21]);
    let Ok(Request::SetDataMask(got)) = Request::parse(&bytes) else {
        panic!()
    };
    assert_eq!(got.iter().collect::<Vec<_>>(), entries);
    // "If any mask conflicts occur, any latter bit value will override the former."
    let mut layout = MotionLayout::default();
    assert!(layout.apply(&Request::SetDataMask(Entries::new(&entries))));
    assert_eq!(
        layout.data_masks,
        [
            DataMask(0x0B),
            DataMask(0x0B),
            DataMask(0x21),
            DataMask(0x0B)
        ]
    );
    assert!(layout.apply(&Request::SetStreamConfig(StreamConfig(2))));
    assert!(!layout.apply(&Request::GetVersion));
    assert_eq!(layout.stream_payload_len(), 1 + 3 * 8 + 2);
    // An odd payload is not a whole number of pairs.
    let mut bad = vec![2, 7, 6, 0x0F, 0x0B, 0x04];
    bad.push(checksum(&bad));
    assert_eq!(Request::parse(&bad), Err(Error::Length));
}

#[test]
fn packet_10_channel_and_size_mask() {
    // "10 - Set Position": bits 5..4 Position Size, 3..0 Channel Mask; size 0 omits position.
    let entries = [
        SetPositionEntry {
            channels: ChannelMask(0x03),
            position: Some(PositionValue::I16(-2)),
        },
        SetPositionEntry {
            channels: ChannelMask(0x08),
            position: None,
        },
        SetPositionEntry {
            channels: ChannelMask(0x04),
            position: Some(PositionValue::I32(7)),
        },
    ];
    let bytes = encode_req(&Request::SetPosition(Entries::new(&entries)));
    assert_eq!(&bytes[3..12], &[0x23, 0xFE, 0xFF, 0x08, 0x34, 7, 0, 0, 0]);
    let Ok(Request::SetPosition(got)) = Request::parse(&bytes) else {
        panic!()
    };
    assert_eq!(
        got.iter().map(|e| e.value()).collect::<Vec<_>>(),
        [-2, 0, 7]
    );
}

#[test]
fn packet_11_three_request_forms() {
    // "11 - Get Position": the format is identified by the size of the payload (0, 1 or 4).
    assert_eq!(
        encode_req(&Request::GetPosition(GetPosition::Configured)),
        [2, 4, 11, 239]
    );
    let one = encode_req(&Request::GetPosition(GetPosition::Channels(ChannelMask(
        0x05,
    ))));
    assert_eq!(&one[..4], &[2, 5, 11, 5]);
    let sizes = [
        PositionSize::I8,
        PositionSize::Omitted,
        PositionSize::I32,
        PositionSize::I16,
    ];
    let four = encode_req(&Request::GetPosition(GetPosition::Sizes(sizes)));
    assert_eq!(&four[..7], &[2, 8, 11, 1, 0, 3, 2]);
    for b in [&one, &four] {
        assert!(matches!(Request::parse(b), Ok(Request::GetPosition(_))));
    }
    let mut two = vec![2, 6, 11, 1, 1];
    two.push(checksum(&two));
    assert_eq!(Request::parse(&two), Err(Error::Length));
    // Reply layout per form.
    let masks = [DataMask(0x01), DataMask(0), DataMask(0x0B), DataMask(0x02)];
    let form4 = GetPosition::Sizes(sizes).reply_layout(&masks);
    assert_eq!(form4.payload_len(), 1 + 1 + 4 + 2);
    let form0 = GetPosition::Configured.reply_layout(&masks);
    assert_eq!(
        form0.0,
        [
            PositionSize::I8,
            PositionSize::Omitted,
            PositionSize::I32,
            PositionSize::I16
        ]
    );
    let form1 = GetPosition::Channels(ChannelMask(0x05)).reply_layout(&masks);
    assert_eq!(
        form1.0,
        [
            PositionSize::I32,
            PositionSize::Omitted,
            PositionSize::I32,
            PositionSize::Omitted
        ]
    );
    let layout = ReplyLayout {
        position: form4,
        ..Default::default()
    };
    let reply = Reply::Positions {
        code: ReturnCode(0),
        positions: [
            Some(PositionValue::I8(-3)),
            None,
            Some(PositionValue::I32(1 << 20)),
            Some(PositionValue::I16(300)),
        ],
    };
    let bytes = encode_rep(&reply);
    assert_eq!(bytes.len(), 4 + form4.payload_len());
    assert_eq!(Reply::parse(&bytes, &layout), Ok(reply));
}

#[test]
fn packet_14_position_omitted_when_disabled() {
    // docs/ARCHITECTURE.md: Position is omitted when Input Mode is Disabled; Edge is bits 5..4.
    let home = InputConfig::new(InputMode::Home, true, EdgeAction::SetOnNegative);
    assert_eq!(home.0, 0x39);
    let entries = [
        InputModeEntry {
            channels: ChannelMask(1),
            config: home,
            spacing: 10,
            position: -500,
        },
        InputModeEntry {
            channels: ChannelMask(2),
            config: InputConfig(0),
            spacing: 0,
            position: 0,
        },
    ];
    let bytes = encode_req(&Request::SetInputMode(Entries::new(&entries)));
    assert_eq!(bytes.len(), 4 + 8 + 4);
    assert_eq!(
        &bytes[3..15],
        &[1, 0x39, 10, 0, 0x0C, 0xFE, 0xFF, 0xFF, 2, 0, 0, 0]
    );
    let Ok(Request::SetInputMode(got)) = Request::parse(&bytes) else {
        panic!()
    };
    assert_eq!(got.iter().collect::<Vec<_>>(), entries);
}

#[test]
fn packet_18_power_is_i16() {
    // docs/ARCHITECTURE.md: packet 18 Power is I16, range ±8191.
    let e = [MotorPowerEntry {
        channels: ChannelMask(0x0F),
        power: -8191,
    }];
    let bytes = encode_req(&Request::SetMotorPower(Entries::new(&e)));
    assert_eq!(&bytes[..6], &[2, 7, 18, 0x0F, 0x01, 0xE0]);
}

#[test]
fn packet_16_rejects_undefined_control_mode() {
    let e = [ControlModeEntry {
        channels: ChannelMask(1),
        mode: ControlMode::VelocityPid,
    }];
    let mut bytes = encode_req(&Request::SetControlMode(Entries::new(&e)));
    assert_eq!(&bytes[..5], &[2, 6, 16, 1, 3]);
    bytes[4] = 4;
    bytes[5] = checksum(&bytes[..5]);
    assert_eq!(Request::parse(&bytes), Err(Error::InvalidField));
}

#[test]
fn packet_36_velocity_plain_acceleration_shl_12() {
    // docs/ARCHITECTURE.md: packet 36 velocity target plain transitions/s, acceleration shl 12.
    let e = [VelocityRampEntry {
        channels: ChannelMask(2),
        velocity: 1000,
        acceleration: 500 << 12,
    }];
    let bytes = encode_req(&Request::VelocityRamp(Entries::new(&e)));
    assert_eq!(
        &bytes[..12],
        &[2, 13, 36, 2, 0xE8, 0x03, 0, 0, 0x00, 0x40, 0x1F, 0x00]
    );
}

#[test]
fn set_packets_answer_return_code_only() {
    for id in PacketId::ALL
        .into_iter()
        .filter(|id| id.reply_is_return_code_only())
    {
        let reply = Reply::Ack {
            id,
            code: ReturnCode(0),
        };
        let bytes = encode_rep(&reply);
        assert_eq!(
            bytes,
            [2, 5, id.as_u8(), 0, checksum(&[2, 5, id.as_u8(), 0])]
        );
        assert_eq!(Reply::parse(&bytes, &ReplyLayout::default()), Ok(reply));
    }
    // A failed get: Return Code alone, non-zero.
    let err = Reply::Ack {
        id: PacketId::GetVersion,
        code: ReturnCode(3),
    };
    assert_eq!(
        Reply::parse(&encode_rep(&err), &ReplyLayout::default()),
        Ok(err)
    );
    let mut buf = [0u8; 8];
    let ok_get = Reply::Ack {
        id: PacketId::GetVersion,
        code: ReturnCode(0),
    };
    assert_eq!(ok_get.encode(&mut buf), Err(Error::Inconsistent));
}

#[test]
fn packet_3_must_not_be_sent_by_master() {
    let mut bytes = vec![2, 4, 3];
    bytes.push(checksum(&bytes));
    assert_eq!(Request::parse(&bytes), Err(Error::WrongDirection(3)));
}

#[test]
fn stream_decoder_finds_reply_after_filler() {
    // The master polls without SRDY by clocking filler; the slave answers filler until ready.
    let mut d = StreamDecoder::new();
    d.push(&[0, 0, 0, 0, 0xFF, 2, 8, 1, 0, 0, 1, 0, 244, 0, 0]);
    let p = d.next_packet().expect("packet");
    assert_eq!(p.as_bytes(), &[2, 8, 1, 0, 0, 1, 0, 244]);
    assert!(d.next_packet().is_none());
    assert_eq!(d.stats().skipped, 7);
    assert_eq!(d.stats().bad_packets(), 0);
}

#[test]
fn buffer_too_small_is_reported() {
    let mut buf = [0u8; 3];
    assert_eq!(
        Request::GetVersion.encode(&mut buf),
        Err(Error::BufferTooSmall)
    );
    let mut buf = [0u8; 5];
    assert_eq!(
        Request::SetStreamPeriod(1).encode(&mut buf),
        Err(Error::BufferTooSmall)
    );
}
