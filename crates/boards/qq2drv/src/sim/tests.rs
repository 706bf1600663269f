//! Register semantics, exercised below the wire (the wire itself is covered by
//! `tests/qq2drv.rs`).

use core::time::Duration;

use motion_link::sim::SpiDevice;

use qq2drv::{
    ChannelMask, DataMask, DataMaskEntry, Entries, GetPosition, HistoryDimensions, PositionSize,
    PositionValue, Reply, Request, ReturnCode, SetPositionEntry, StreamConfig,
};

use super::{Qq2drvSim, Qq2drvSimConfig};

const OK: ReturnCode = ReturnCode::SUCCESS;

fn ask(sim: &mut Qq2drvSim, req: &Request<'_>) -> Reply {
    let now = sim.now;
    sim.handle(now, req)
}

fn ok(sim: &mut Qq2drvSim, req: &Request<'_>) {
    assert_eq!(
        ask(sim, req),
        Reply::Ack {
            id: req.id(),
            code: OK
        },
        "{req:?}"
    );
}

#[test]
fn registers_start_up_and_read_back() {
    let mut sim = Qq2drvSim::default();
    let masks = [DataMask(0x0B); 4];
    assert_eq!(
        ask(&mut sim, &Request::GetDataMask),
        Reply::DataMasks { code: OK, masks }
    );
    let period = Reply::StreamPeriod {
        code: OK,
        period: 0,
    };
    assert_eq!(ask(&mut sim, &Request::GetStreamPeriod), period);
    let config = Reply::StreamConfig {
        code: OK,
        config: StreamConfig(0),
    };
    assert_eq!(ask(&mut sim, &Request::GetStreamConfig), config);
    let dimensions = HistoryDimensions {
        history_length: 31,
        averaging_bits: 20,
    };
    let dims = Reply::HistoryDimensions {
        code: OK,
        dimensions,
    };
    assert_eq!(ask(&mut sim, &Request::GetHistoryDimensions), dims);
    // "If any mask conflicts occur, any latter bit value will override the former."
    let e = [
        DataMaskEntry {
            channels: ChannelMask::ALL,
            mask: DataMask(0x21),
        },
        DataMaskEntry {
            channels: ChannelMask(0b0110),
            mask: DataMask(0x0E),
        },
    ];
    ok(&mut sim, &Request::SetDataMask(Entries::new(&e)));
    let masks = [
        DataMask(0x21),
        DataMask(0x0E),
        DataMask(0x0E),
        DataMask(0x21),
    ];
    assert_eq!(
        ask(&mut sim, &Request::GetDataMask),
        Reply::DataMasks { code: OK, masks }
    );
    ok(&mut sim, &Request::SetStreamConfig(StreamConfig(3)));
    let config = Reply::StreamConfig {
        code: OK,
        config: StreamConfig(3),
    };
    assert_eq!(ask(&mut sim, &Request::GetStreamConfig), config);
    let dimensions = HistoryDimensions {
        history_length: 7,
        averaging_bits: 16,
    };
    ok(&mut sim, &Request::SetHistoryDimensions(dimensions));
    let dims = Reply::HistoryDimensions {
        code: OK,
        dimensions,
    };
    assert_eq!(ask(&mut sim, &Request::GetHistoryDimensions), dims);
    ok(&mut sim, &Request::SetStreamPeriod(123));
    let period = Reply::StreamPeriod {
        code: OK,
        period: 123,
    };
    assert_eq!(ask(&mut sim, &Request::GetStreamPeriod), period);
}

#[test]
fn set_position_and_the_three_get_position_forms() {
    let mut sim = Qq2drvSim::default();
    let e = [
        SetPositionEntry {
            channels: ChannelMask(0b0011),
            position: Some(PositionValue::I16(-300)),
        },
        SetPositionEntry {
            channels: ChannelMask(0b0100),
            position: Some(PositionValue::I32(1 << 20)),
        },
        SetPositionEntry {
            channels: ChannelMask(0b1000),
            position: None,
        },
    ];
    ok(&mut sim, &Request::SetPosition(Entries::new(&e)));
    let i32s = [-300, -300, 1 << 20, 0].map(|p| Some(PositionValue::I32(p)));
    let all = Reply::Positions {
        code: OK,
        positions: i32s,
    };
    assert_eq!(
        ask(&mut sim, &Request::GetPosition(GetPosition::Configured)),
        all
    );
    let mask = GetPosition::Channels(ChannelMask(0b0101));
    let some = Reply::Positions {
        code: OK,
        positions: [i32s[0], None, i32s[2], None],
    };
    assert_eq!(ask(&mut sim, &Request::GetPosition(mask)), some);
    let sizes = [
        PositionSize::I8,
        PositionSize::Omitted,
        PositionSize::I16,
        PositionSize::I32,
    ];
    let positions = [
        Some(PositionValue::I8(-300i32 as i8)),
        None,
        Some(PositionValue::I16(0)),
        Some(PositionValue::I32(0)),
    ];
    let sized = Reply::Positions {
        code: OK,
        positions,
    };
    assert_eq!(
        ask(&mut sim, &Request::GetPosition(GetPosition::Sizes(sizes))),
        sized
    );
    // Form 0 follows the configured position sizes.
    let e = [DataMaskEntry {
        channels: ChannelMask(0b0001),
        mask: DataMask(0x02),
    }];
    ok(&mut sim, &Request::SetDataMask(Entries::new(&e)));
    let Reply::Positions { positions, .. } =
        ask(&mut sim, &Request::GetPosition(GetPosition::Configured))
    else {
        panic!("not positions");
    };
    assert_eq!(positions[0], Some(PositionValue::I16(-300)));
}

#[test]
fn reset_returns_registers_to_start_up() {
    let mut sim = Qq2drvSim::new(Qq2drvSimConfig::default());
    let e = [DataMaskEntry {
        channels: ChannelMask::ALL,
        mask: DataMask(0x21),
    }];
    ok(&mut sim, &Request::SetDataMask(Entries::new(&e)));
    let e = [SetPositionEntry {
        channels: ChannelMask::ALL,
        position: Some(PositionValue::I32(77)),
    }];
    ok(&mut sim, &Request::SetPosition(Entries::new(&e)));
    ok(&mut sim, &Request::SetStreamPeriod(10));
    assert_eq!(sim.counter(0), Some(77));
    sim.reset();
    assert_eq!(sim.stream_period(), 0);
    assert_eq!(sim.data_masks(), [DataMask(0x0B); 4]);
    assert_eq!(sim.counter(0), Some(0));
    sim.advance(Duration::from_millis(5));
    assert_eq!(sim.stats().stream_packets, 0);
}

#[test]
fn random_glitches_are_deterministic_under_the_seed() {
    let run = |seed| {
        let mut sim = Qq2drvSim::new(Qq2drvSimConfig {
            seed,
            glitch_rate: 50.0,
            ..Default::default()
        });
        let e = [DataMaskEntry {
            channels: ChannelMask::ALL,
            mask: DataMask(0x20),
        }];
        ok(&mut sim, &Request::SetDataMask(Entries::new(&e)));
        let mut bits = Vec::new();
        for k in 1..=30u64 {
            sim.advance(Duration::from_millis(3 * k));
            let Reply::MotionData { data, .. } = ask(&mut sim, &Request::GetMotionData) else {
                panic!("not motion data");
            };
            bits.push(data.channels.map(|c| c.status.map(|s| s.glitch())));
        }
        bits
    };
    let a = run(3);
    assert_eq!(a, run(3));
    assert_ne!(a, run(4));
    assert!(a.iter().flatten().any(|g| *g == Some(true)));
}

#[test]
fn random_traffic_never_breaks_the_model_and_every_request_is_answered_once() {
    use motion_sim::rng::SimRng;
    use qq2drv::{ControlMode, ControlModeEntry, MotorPowerEntry, PacketId, StreamDecoder};

    let mut rng = SimRng::new(99);
    let mut sim = Qq2drvSim::default();
    let mut decoder = StreamDecoder::new();
    let mut now = Duration::ZERO;
    let mut sent = 0u64;
    let mut answered = 0u64;
    let modes = [ControlModeEntry {
        channels: ChannelMask(0x0F),
        mode: ControlMode::Power,
    }];
    let power = [MotorPowerEntry {
        channels: ChannelMask(0x05),
        power: -3000,
    }];
    let requests = [
        Request::GetVersion,
        Request::GetMotionData,
        Request::SetControlMode(Entries::new(&modes)),
        Request::SetMotorPower(Entries::new(&power)),
        Request::GetPosition(GetPosition::Channels(ChannelMask(0x0A))),
        Request::SetStreamPeriod(0),
    ];
    for round in 0..3000u32 {
        let mut mosi = Vec::new();
        // Garbage that never contains STX, so it cannot swallow a real request.
        for _ in 0..(rng.next_u64() % 6) {
            mosi.push((rng.next_u64() % 250) as u8 | 0x04);
        }
        if round % 3 == 0 {
            let req = &requests[(rng.next_u64() % requests.len() as u64) as usize];
            let mut buf = [0u8; 64];
            let n = req.encode(&mut buf).expect("encode");
            mosi.extend_from_slice(&buf[..n]);
            sent += 1;
        }
        mosi.extend(core::iter::repeat_n(0u8, (rng.next_u64() % 24) as usize));
        now += Duration::from_micros(50 + rng.next_u64() % 900);
        let mut miso = vec![0u8; mosi.len()];
        assert!(sim.transfer(now, &mosi, &mut miso));
        decoder.feed(&miso, |p| {
            assert_ne!(p.frame().id, PacketId::StreamData.as_u8());
            answered += 1;
        });
    }
    for _ in 0..10 {
        now += Duration::from_millis(1);
        let mut miso = [0u8; 64];
        sim.transfer(now, &[0; 64], &mut miso);
        decoder.feed(&miso, |_| answered += 1);
    }
    assert_eq!(answered, sent);
    assert_eq!(decoder.stats().bad_packets(), 0);
    assert_eq!(sim.stats().requests, sent);
    // Fully random MOSI, STX included: whatever decodes is answered, nothing panics, and
    // MISO only ever carries whole valid packets and filler.
    let mut decoder = StreamDecoder::new();
    for _ in 0..3000u32 {
        let len = (rng.next_u64() % 40) as usize;
        let mosi: Vec<u8> = (0..len).map(|_| (rng.next_u64() % 40) as u8).collect();
        now += Duration::from_micros(rng.next_u64() % 2000);
        let mut miso = vec![0u8; len];
        sim.transfer(now, &mosi, &mut miso);
        decoder.push(&miso);
        while decoder.next_packet().is_some() {}
    }
    assert_eq!(decoder.stats().bad_packets(), 0);
}

/// Packet 3: its table shows no Return Code (the default), its text has one ("except for
/// Return Code"); the simulator sends either, one byte longer with the code.
#[test]
fn stream_packets_carry_a_return_code_only_when_configured() {
    for (with_code, extra) in [(false, 0), (true, 1)] {
        let mut sim = Qq2drvSim::new(Qq2drvSimConfig {
            stream_return_code: with_code,
            ..Qq2drvSimConfig::default()
        });
        let layout = qq2drv::ReplyLayout {
            motion: sim.regs.layout,
            ..qq2drv::ReplyLayout::default()
        };
        let packet = sim.stream_packet(25, 1).expect("a stream packet");
        let frame = packet.frame();
        assert_eq!(
            frame.payload.len(),
            layout.motion.stream_payload_len() + extra
        );
        let reply = Reply::decode(frame, &layout).expect("decodes");
        assert_eq!(reply.code(), with_code.then_some(OK));
    }
}
