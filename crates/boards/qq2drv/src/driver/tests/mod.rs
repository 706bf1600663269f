//! Unit tests of the QuadQuad2Drv driver against byte vectors of the `qq2drv` crate.

use core::time::Duration;

use qq2drv::limits::{FIXED_SHIFT, POWER_MAX};
use qq2drv::{
    ChannelData, ChannelMask, ControlMode, DataMask, Entries, MotionData, PacketId, PositionValue,
    Reply, Request, ReturnCode, Status, StreamConfig, StreamData,
};

use super::*;
use motion_drivers::GoalKind;

const MS: Duration = Duration::from_millis(1);

fn config() -> Qq2drvDriverConfig {
    let mut config = Qq2drvDriverConfig::default();
    for channel in &mut config.channels {
        channel.limits = AxisLimits {
            max_velocity: 3_000.0,
            max_accel: 30_000.0,
        };
    }
    config.channels[1].home = Some(HomeInput {
        mode: qq2drv::InputMode::Edge,
        active_high: false,
        positive_end: true,
        position: 500,
        spacing: 0,
    });
    config.channels[3].enabled = false;
    config
}

fn encode_reply(reply: &Reply) -> Vec<u8> {
    let mut buf = [0u8; 256];
    let n = reply.encode(&mut buf).expect("encodes");
    buf[..n].to_vec()
}

/// Splits a MOSI transaction into its packets (by their Packet Size bytes).
fn packets(mosi: &[u8]) -> Vec<Vec<u8>> {
    let mut out = Vec::new();
    let mut rest = mosi;
    while !rest.is_empty() {
        let len = usize::from(rest[1]);
        out.push(rest[..len].to_vec());
        rest = &rest[len..];
    }
    out
}

/// Runs `handle_timeout(now)` and takes every transaction the driver writes.
fn drain(driver: &mut Qq2drvDriver, now: Duration) -> Vec<Vec<u8>> {
    driver.handle_timeout(now);
    let mut out = Vec::new();
    let mut buf = [0u8; 256];
    while let Some(transmit) = driver.poll_transmit(now, &mut buf) {
        out.push(buf[..transmit.len].to_vec());
        assert!(out.len() < 8, "bounded per call");
    }
    out
}

/// Acks of the requests in `mosi` with `code`, as the board would clock them out.
fn acks(mosi: &[u8], code: u8) -> Vec<u8> {
    let mut out = vec![0u8; 3];
    for packet in packets(mosi) {
        let id = PacketId::try_from(packet[2]).unwrap();
        out.extend(encode_reply(&Reply::Ack {
            id,
            code: ReturnCode(code),
        }));
    }
    out
}

fn ours_stream(positions: [i32; 3], velocities: [i32; 3], status: [u8; 3]) -> Vec<u8> {
    let mut data = MotionData::default();
    for i in 0..3 {
        data.channels[i] = ChannelData {
            position: Some(PositionValue::I32(positions[i])),
            velocity: Some(velocities[i]),
            status: Some(Status(status[i])),
        };
    }
    encode_reply(&Reply::StreamData(StreamData {
        code: None,
        timing: Some(25),
        periods_elapsed: None,
        data,
    }))
}

/// The answers of a board at `period` / `masks`.
fn probe_answers(masks: [DataMask; 4], config: StreamConfig, period: u16) -> Vec<u8> {
    let code = ReturnCode::SUCCESS;
    let mut out = vec![0u8; 5];
    // Worked example "Read Version Numbers": 2, 8, 1, 0, 0, 1, 0, 244.
    out.extend([2, 8, 1, 0, 0, 1, 0, 244]);
    out.extend(encode_reply(&Reply::DataMasks { code, masks }));
    out.extend(encode_reply(&Reply::StreamConfig { code, config }));
    out.extend(encode_reply(&Reply::StreamPeriod { code, period }));
    out
}

/// A driver that has started and streams; returns it and the time.
fn running() -> (Qq2drvDriver, Duration) {
    let mut driver = Qq2drvDriver::new(config());
    let mut now = Duration::ZERO;
    drain(&mut driver, now);
    now += MS;
    driver.handle_rx(
        now,
        &probe_answers([DataMask::DEFAULT; 4], StreamConfig(0), 0),
    );
    let sent = drain(&mut driver, now);
    let configure = &sent[0];
    now += MS;
    driver.handle_rx(now, &acks(configure, 0));
    assert!(driver.running());
    // The configuration (about 200 bytes, 3.2 ms at 500 kHz) has left the wire.
    now += 4 * MS;
    driver.handle_rx(now, &ours_stream([10, 20, 30], [0, 0, 0], [0; 3]));
    (driver, now)
}

#[test]
fn start_up_probes_with_the_worked_example_packet_first() {
    let mut driver = Qq2drvDriver::new(config());
    let sent = drain(&mut driver, Duration::ZERO);
    assert_eq!(sent.len(), 2, "the probe, then a poll to read its answers");
    // Worked example "Read Version Numbers": send 2, 4, 1, 249.
    assert_eq!(&sent[0][..4], &[2, 4, 1, 249]);
    let ids: Vec<u8> = packets(&sent[0]).iter().map(|p| p[2]).collect();
    assert_eq!(ids, [1, 7, 9, 5]);
    assert!(sent[1].iter().all(|b| *b == FILLER));
    assert_eq!(sent[1].len(), driver.poll_len());
    assert!(!driver.status().online);
}

#[test]
fn configuration_follows_the_axis_limits_in_shl_12() {
    let mut driver = Qq2drvDriver::new(config());
    drain(&mut driver, Duration::ZERO);
    driver.handle_rx(
        MS,
        &probe_answers([DataMask::DEFAULT; 4], StreamConfig(0), 0),
    );
    assert_eq!(driver.status().firmware(), "fw 0.1 protocol 0");
    let sent = drain(&mut driver, MS);
    let configure = packets(&sent[0]);
    let mut ids = Vec::new();
    for packet in &configure {
        let request = Request::parse(packet).expect("valid");
        ids.push(request.id().as_u8());
        match request {
            Request::SetHistoryDimensions(d) => {
                assert_eq!((d.history_length, d.averaging_bits), (31, 16));
            }
            Request::SetDataMask(entries) => {
                let e: Vec<_> = entries.iter().collect();
                assert_eq!(e[0].channels, ChannelMask(0b0111));
                assert_eq!(e[0].mask, STREAM_MASK);
                assert_eq!(
                    e[0].mask.0, 0b0010_1011,
                    "status, velocity, 32-bit position"
                );
                assert_eq!(e[1].channels, ChannelMask(0b1000));
                assert_eq!(e[1].mask, DataMask(0));
            }
            Request::SetStreamConfig(c) => assert_eq!(c, StreamConfig(1)),
            Request::SetVelocityLimit(entries) => {
                // Packet 26: "Velocity Limit = <transitions/s> shl 12".
                let limits: Vec<_> = entries.iter().map(|e| (e.channels.0, e.limit)).collect();
                assert_eq!(
                    limits,
                    [(1, 3_000 << 12), (2, 3_000 << 12), (4, 3_000 << 12)]
                );
            }
            Request::SetAccelerationLimit(entries) => {
                assert!(entries.iter().all(|e| e.limit == 30_000 << FIXED_SHIFT));
            }
            Request::SetPowerLimit(entries) => assert!(entries.iter().all(|e| e.limit == 8_191)),
            // Packet 30: "P … Default: 100", "I … Default: 500", "D … Default: 500",
            // "Windup Limit … Default: 600"; written for every channel with an axis.
            Request::SetPositionPid(entries) => {
                let e: Vec<_> = entries
                    .iter()
                    .map(|e| (e.channels.0, e.p, e.i, e.d, e.windup))
                    .collect();
                assert_eq!(
                    e,
                    [
                        (1, 100, 500, 500, 600),
                        (2, 100, 500, 500, 600),
                        (4, 100, 500, 500, 600)
                    ]
                );
            }
            // Packet 32: P 100, I 200, D 500.
            Request::SetVelocityPid(entries) => {
                assert_eq!(entries.len(), 3);
                assert!(entries.iter().all(|e| (e.p, e.i, e.d) == (100, 200, 500)));
            }
            Request::SetInputMode(entries) => {
                let e: Vec<_> = entries.iter().collect();
                assert_eq!(e.len(), 1);
                assert_eq!(e[0].channels, ChannelMask(0b10));
                assert_eq!(e[0].config.mode(), qq2drv::InputMode::Disabled);
                assert!(!e[0].config.active_high());
            }
            // 1 ms / 40.96 µs = 24.4: the largest whole number not above the poll period.
            Request::SetStreamPeriod(p) => assert_eq!(p, 24),
            other => panic!("unexpected {other:?}"),
        }
    }
    assert_eq!(ids, [12, 6, 8, 24, 26, 28, 30, 32, 14, 4]);
    // Until every write is answered the driver is not running.
    let sent_bytes = sent[0].clone();
    let all = acks(&sent_bytes, 0);
    let (first, rest) = all.split_at(10);
    driver.handle_rx(2 * MS, first);
    assert!(!driver.running());
    driver.handle_rx(2 * MS, rest);
    assert!(driver.running());
    assert!(driver.status().online);
}

#[test]
fn stream_packets_refresh_the_channels_through_filler_and_garbage() {
    let (mut driver, now) = running();
    let state = driver.channel(2);
    assert_eq!(state.position, 30.0);
    assert_eq!(state.refreshed_at, Some(now));
    let mut bytes = vec![0u8, 0, 7, 2, 200, 2, 9, 1];
    bytes.extend(ours_stream([-5, 1_234, 7], [-400, 8, 0], [0; 3]));
    bytes.extend([0u8; 4]);
    let later = now + MS;
    for chunk in bytes.chunks(1) {
        driver.handle_rx(later, chunk);
    }
    let state = driver.channel(1);
    assert_eq!(state.position, 1_234.0);
    assert_eq!(state.raw_counts, 1_234);
    assert_eq!(state.velocity, 8.0);
    assert!(state.moving);
    assert!(!driver.channel(0).moving || driver.channel(0).velocity == -400.0);
    assert_eq!(driver.channel(3), ChannelState::UNKNOWN, "disabled channel");
    assert_eq!(driver.stream_packets(), 2);
    assert!(driver.decoder_stats().bad_packets() > 0);
    assert_eq!(driver.status().fault, None);
}

fn goal_packets(driver: &mut Qq2drvDriver, now: Duration, channel: usize, goal: Goal) -> Vec<u8> {
    driver.set_goal(now, channel, goal).expect("accepted");
    assert_eq!(driver.wants_transmit(now), Some(Priority::Command));
    let sent = drain(driver, now);
    sent[0].clone()
}

/// 2 ms later (the wire is idle again).
fn later(now: &mut Duration) -> Duration {
    *now += 2 * MS;
    *now
}

/// Sets a goal, takes its transaction and answers it.
fn acked(driver: &mut Qq2drvDriver, now: Duration, channel: usize, goal: Goal) -> Vec<u8> {
    let mosi = goal_packets(driver, now, channel, goal);
    driver.handle_rx(now + MS, &acks(&mosi, 0));
    driver.handle_rx(now + MS, &ours_stream([10, 20, 30], [0; 3], [0; 3]));
    assert!(!driver.goals_pending());
    mosi
}

#[test]
fn goals_become_the_documented_packets() {
    let (mut driver, mut now) = running();
    let ch1 = ChannelMask(0b01).0;
    // Position: 16 (Position PID), 20 target.
    let mosi = goal_packets(
        &mut driver,
        later(&mut now),
        0,
        Goal::Position { counts: 1_000.4 },
    );
    let p = packets(&mosi);
    assert_eq!(
        p[0],
        [
            2,
            6,
            16,
            ch1,
            2,
            256u16.wrapping_sub(2 + 6 + 16 + 1 + 2) as u8
        ]
    );
    assert_eq!(
        Request::parse(&p[1]).unwrap(),
        Request::SetPositionTarget(Entries::new(&[qq2drv::PositionTargetEntry {
            channels: ChannelMask(1),
            position: 1_000
        }]))
    );
    assert!(driver.goals_pending());
    driver.handle_rx(now + MS, &acks(&mosi, 0));
    assert!(!driver.goals_pending());
    // Power: 16 Power, 18 I16 round(0.5 × 8191).
    let mosi = acked(
        &mut driver,
        later(&mut now),
        0,
        Goal::Power { fraction: -0.5 },
    );
    match Request::parse(&packets(&mosi)[1]).unwrap() {
        Request::SetMotorPower(e) => {
            assert_eq!(e.iter().next().unwrap().power, -4_096);
        }
        other => panic!("{other:?}"),
    }
    // Velocity: 16 Velocity PID, 36 plain transitions/s, acceleration shl 12.
    let mosi = acked(
        &mut driver,
        later(&mut now),
        2,
        Goal::Velocity {
            velocity: -1_500.0,
            accel: 20_000.0,
        },
    );
    let p = packets(&mosi);
    assert_eq!(p[0][3..5], [0b100, ControlMode::VelocityPid as u8]);
    match Request::parse(&p[1]).unwrap() {
        Request::VelocityRamp(e) => {
            let e = e.iter().next().unwrap();
            assert_eq!((e.velocity, e.acceleration), (-1_500, 20_000 << 12));
        }
        other => panic!("{other:?}"),
    }
    // Ramp position: 16 Position PID, 34 with shl-12 velocity and acceleration.
    let mosi = acked(
        &mut driver,
        later(&mut now),
        1,
        Goal::RampPosition {
            counts: -300.0,
            velocity: 0.5,
            accel: 1_000.25,
        },
    );
    match Request::parse(&packets(&mosi)[1]).unwrap() {
        Request::PositionRamp(e) => {
            let e = e.iter().next().unwrap();
            assert_eq!(
                (e.position, e.velocity, e.acceleration),
                (-300, 2_048, 4_097_024)
            );
        }
        other => panic!("{other:?}"),
    }
    // Set position while the motor is held: 10, then hold there (16, 20).
    let mosi = goal_packets(
        &mut driver,
        later(&mut now),
        1,
        Goal::SetPosition { counts: -7.0 },
    );
    let p = packets(&mosi);
    assert_eq!(p.len(), 3);
    assert_eq!(
        p[0],
        [2, 9, 10, 0x30 | 0b10, 0xF9, 0xFF, 0xFF, 0xFF, {
            let sum: u8 = [2u8, 9, 10, 0x32, 0xF9, 0xFF, 0xFF, 0xFF]
                .iter()
                .fold(0u8, |a, b| a.wrapping_add(*b));
            sum.wrapping_neg()
        }]
    );
    assert!(!driver.channel(1).homed);
    driver.handle_rx(now + MS, &acks(&mosi, 0));
    assert!(driver.channel(1).homed, "a set position is a reference");
    // Off: 16 Off.
    let mosi = goal_packets(&mut driver, later(&mut now), 2, Goal::Off);
    assert_eq!(packets(&mosi).len(), 1);
    assert_eq!(mosi[4], ControlMode::Off as u8);
}

#[test]
fn values_the_board_cannot_represent_are_refused() {
    let (mut driver, now) = running();
    let out = |kind| Err(GoalError::OutOfBoardRange(kind));
    assert_eq!(
        driver.set_goal(now, 0, Goal::Power { fraction: 1.5 }),
        out(GoalKind::Power)
    );
    assert_eq!(
        driver.set_goal(
            now,
            0,
            Goal::Velocity {
                velocity: 100_001.0,
                accel: 1.0
            }
        ),
        out(GoalKind::Velocity)
    );
    // 1e-5 transitions/s² shl 12 rounds to 0, which would mean "not limited".
    assert_eq!(
        driver.set_goal(
            now,
            0,
            Goal::RampPosition {
                counts: 1.0,
                velocity: 10.0,
                accel: 1e-5
            }
        ),
        out(GoalKind::RampPosition)
    );
    assert_eq!(
        driver.set_goal(now, 0, Goal::Position { counts: 3e9 }),
        out(GoalKind::Position)
    );
    assert_eq!(
        driver.set_goal(now, 0, Goal::Home { velocity: 10.0 }),
        Err(GoalError::Unsupported(GoalKind::Home)),
        "channel 1 has no home input"
    );
    assert_eq!(
        driver.set_goal(now, 3, Goal::Off),
        Err(GoalError::Unsupported(GoalKind::Off)),
        "a disabled channel takes nothing"
    );
    assert_eq!(
        driver.set_goal(now, 4, Goal::Off),
        Err(GoalError::NoSuchChannel(4))
    );
    assert!(!driver.goals_pending(), "nothing reached the wire");
    // A stop is always representable: an absurd deceleration is clipped.
    driver
        .set_goal(now, 0, Goal::Stop { decel: 1e12 })
        .expect("stop always works");
    assert!(driver.capabilities(1).contains(GoalKind::Home));
    assert!(!driver.capabilities(0).contains(GoalKind::Home));
    assert_eq!(POWER_MAX, 8_191);
}

/// The parsed requests of one transaction.
fn requests(mosi: &[u8]) -> Vec<Request<'_>> {
    let mut out = Vec::new();
    let mut rest = mosi;
    while !rest.is_empty() {
        let len = usize::from(rest[1]);
        out.push(Request::parse(&rest[..len]).expect("a valid request"));
        rest = &rest[len..];
    }
    out
}

fn one<T: qq2drv::Entry + Copy>(entries: &Entries<'_, T>) -> T {
    let all: Vec<T> = entries.iter().collect();
    assert_eq!(all.len(), 1, "one entry");
    all[0]
}

#[test]
fn home_arms_the_input_and_stops_on_its_trigger() {
    let (mut driver, mut now) = running();
    let mosi = goal_packets(&mut driver, now, 1, Goal::Home { velocity: 800.0 });
    let p = packets(&mosi);
    match Request::parse(&p[0]).unwrap() {
        Request::SetInputMode(e) => {
            let e = e.iter().next().unwrap();
            assert_eq!(e.config.mode(), qq2drv::InputMode::Edge);
            assert_eq!(e.config.edge(), qq2drv::EdgeAction::SetOnPositive);
            assert_eq!((e.spacing, e.position), (0, 500));
        }
        other => panic!("{other:?}"),
    }
    match Request::parse(&p[2]).unwrap() {
        Request::VelocityRamp(e) => assert_eq!(e.iter().next().unwrap().velocity, 800),
        other => panic!("{other:?}"),
    }
    now += MS;
    driver.handle_rx(now, &acks(&mosi, 0));
    driver.handle_rx(now, &ours_stream([0, 300, 0], [0, 800, 0], [0; 3]));
    assert!(!driver.channel(1).homed);
    assert!(
        drain(&mut driver, now)
            .iter()
            .all(|t| t.iter().all(|b| *b == 0))
    );
    // The trigger: Input Active and the positive Trigger Accumulator bit.
    let bits = Status::INPUT_ACTIVE | Status::TRIGGER_POSITIVE;
    driver.handle_rx(now, &ours_stream([0, 505, 0], [0, 800, 0], [0, bits, 0]));
    assert!(driver.channel(1).homed);
    let sent = drain(&mut driver, now);
    // The stop from the measured 800: input disarmed, then the setpoint reset.
    match requests(&sent[0]).as_slice() {
        [
            Request::SetInputMode(input),
            Request::SetControlMode(_),
            Request::SetControlMode(_),
            Request::SetAccelerationLimit(_),
            Request::VelocityRamp(ramp),
        ] => {
            assert_eq!(one(input).config.mode(), qq2drv::InputMode::Disabled);
            assert_eq!(one(ramp).velocity, 800);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn an_error_return_code_faults_the_channel_until_its_next_goal() {
    let (mut driver, now) = running();
    let mosi = goal_packets(&mut driver, now, 0, Goal::Position { counts: 5.0 });
    driver.handle_rx(now + MS, &acks(&mosi, 2));
    assert_eq!(driver.channel(0).fault, Some(DeviceFault::BoardError));
    assert_eq!(driver.channel(1).fault, None);
    driver
        .set_goal(now, 0, Goal::Stop { decel: 1_000.0 })
        .unwrap();
    assert_eq!(driver.channel(0).fault, None);
}

#[test]
fn a_lost_answer_sends_the_goal_again() {
    let (mut driver, mut now) = running();
    let mosi = goal_packets(&mut driver, now, 0, Goal::Position { counts: 5.0 });
    // Stream data keeps arriving, but the answers never do.
    let deadline = now + driver.reply_timeout() + 2 * MS;
    let mut resent = false;
    while now < deadline {
        now += MS;
        driver.handle_rx(now, &ours_stream([0; 3], [0; 3], [0; 3]));
        for transaction in drain(&mut driver, now) {
            resent |= transaction == mosi;
        }
    }
    assert!(resent);
    assert!(driver.status().timeouts >= 2);
}

#[test]
fn link_down_faults_and_stops_what_was_moving_once_back() {
    let (mut driver, now) = running();
    let mosi = goal_packets(
        &mut driver,
        now,
        2,
        Goal::Velocity {
            velocity: 900.0,
            accel: 5_000.0,
        },
    );
    driver.handle_rx(now + MS, &acks(&mosi, 0));
    driver.link_down(now + 2 * MS);
    assert_eq!(driver.channel(2).fault, Some(DeviceFault::LinkDown));
    assert_eq!(driver.set_goal(now, 0, Goal::Off), Err(GoalError::Offline));
    assert_eq!(driver.wants_transmit(now + 3 * MS), None);
    let t = now + 100 * MS;
    driver.link_up(t);
    let probe = drain(&mut driver, t);
    assert!(probe[0].starts_with(&[2, 4, 1, 249]));
    let masks = driver.stream_masks();
    driver.handle_rx(t + MS, &probe_answers(masks, STREAM_CONFIG, 24));
    assert_eq!(
        driver.status().resets,
        0,
        "the board kept its configuration"
    );
    let sent = drain(&mut driver, t + MS);
    driver.handle_rx(t + 2 * MS, &acks(&sent[0], 0));
    driver.handle_rx(t + 2 * MS, &ours_stream([0; 3], [0, 0, 900], [0; 3]));
    assert_eq!(driver.channel(2).fault, None);
    // Once the configuration has left the wire.
    let sent = drain(&mut driver, t + 6 * MS);
    match requests(&sent[0]).as_slice() {
        [.., Request::VelocityRamp(ramp)] => {
            assert_eq!(one(ramp).velocity, 900, "from the measured velocity");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_late_tick_is_not_a_stalled_board() {
    let (mut driver, mut now) = running();
    now += MS;
    drain(&mut driver, now);
    // The caller comes back 100 ms late (host noise); the board's packet is waiting.
    now += 100 * MS;
    driver.handle_rx(now, &ours_stream([4, 5, 6], [0; 3], [0; 3]));
    let sent = drain(&mut driver, now);
    assert!(
        sent.iter().all(|t| t.iter().all(|b| *b == FILLER)),
        "no probe"
    );
    assert!(driver.running());
    assert_eq!(driver.status().fault, None);
    assert!(driver.refresh_budget() > 100 * MS);
    // Back to a 1 ms tick: the budget shrinks again.
    now += MS;
    drain(&mut driver, now);
    assert!(driver.refresh_budget() < 20 * MS);
}

#[test]
fn home_on_an_active_edge_input_backs_off_first() {
    let (mut driver, now) = running();
    driver.handle_rx(
        now,
        &ours_stream([0, 700, 0], [0; 3], [0, Status::INPUT_ACTIVE, 0]),
    );
    let mosi = goal_packets(&mut driver, now, 1, Goal::Home { velocity: 800.0 });
    driver.handle_rx(now, &acks(&mosi, 0));
    let p = packets(&mosi);
    match (
        Request::parse(&p[0]).unwrap(),
        Request::parse(&p[2]).unwrap(),
    ) {
        (Request::SetInputMode(input), Request::VelocityRamp(ramp)) => {
            let input = input.iter().next().unwrap();
            assert_eq!(
                input.config.mode(),
                qq2drv::InputMode::Disabled,
                "not armed yet"
            );
            assert_eq!(
                ramp.iter().next().unwrap().velocity,
                -800,
                "away from the switch"
            );
        }
        other => panic!("{other:?}"),
    }
    assert!(driver.channel(1).at_limit);
    // Off the switch: the search starts, armed, towards it.
    driver.handle_rx(now + MS, &ours_stream([0, 650, 0], [0, -800, 0], [0; 3]));
    let sent = drain(&mut driver, now + MS);
    let p = packets(&sent[0]);
    match (
        Request::parse(&p[0]).unwrap(),
        Request::parse(&p[2]).unwrap(),
    ) {
        (Request::SetInputMode(input), Request::VelocityRamp(ramp)) => {
            assert_eq!(
                input.iter().next().unwrap().config.mode(),
                qq2drv::InputMode::Edge
            );
            assert_eq!(ramp.iter().next().unwrap().velocity, 800);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn goals_every_tick_never_build_a_backlog_on_the_wire() {
    let (mut driver, mut now) = running();
    let mut bytes = 0usize;
    let start = now;
    for tick in 0..200 {
        now += MS;
        for channel in 0..3 {
            let counts = f64::from(tick * 10 + channel);
            driver
                .set_goal(
                    now,
                    channel as usize,
                    Goal::RampPosition {
                        counts,
                        velocity: 1_000.0,
                        accel: 10_000.0,
                    },
                )
                .unwrap();
        }
        driver.handle_rx(now, &ours_stream([0; 3], [0; 3], [0; 3]));
        for transaction in drain(&mut driver, now) {
            bytes += transaction.len();
            if transaction.iter().any(|b| *b != FILLER) {
                driver.handle_rx(now, &acks(&transaction, 0));
            }
        }
    }
    // 500 kHz carries 62.5 bytes per ms: what was sent fits the time that passed.
    let elapsed = (now - start).as_secs_f64();
    let wire = bytes as f64 * 8.0 / 500_000.0;
    assert!(wire <= elapsed + 0.002, "{wire} s of bytes in {elapsed} s");
}

mod io;
mod late;
mod liveness;
mod readings;
mod stops;
