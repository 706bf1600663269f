//! The simulated QuadQuad2Drv on the wire and in motion.

use core::time::Duration;

use board_qq2drv::sim::{
    InputPin, InputSource, MotorConfig, Qq2drvSim, Qq2drvSimConfig, RC_MALFORMED, RC_OUT_OF_RANGE,
};
use motion_link::sim::SpiDevice;
use qq2drv::{
    AccelerationLimitEntry, ChannelMask, ControlMode, ControlModeEntry, DataMask, DataMaskEntry,
    EdgeAction, Entries, HistoryDimensions, InputConfig, InputMode, InputModeEntry,
    MotorPowerEntry, PacketId, PositionRampEntry, PositionSize, PositionValue, PowerLimitEntry,
    Reply, ReplyLayout, Request, Status, StreamConfig, StreamDecoder, VelocityLimitEntry,
    VelocityRampEntry,
};

/// 500 kHz SPI: 16 µs a byte.
const BYTE: Duration = Duration::from_micros(16);

/// A master polling the board without SRDY, with a fake clock.
struct Host {
    sim: Qq2drvSim,
    now: Duration,
    decoder: StreamDecoder,
    layout: ReplyLayout,
    /// Stream packets seen while waiting for replies, with their arrival time.
    streams: Vec<(Duration, Reply)>,
}

impl Host {
    fn new(config: Qq2drvSimConfig) -> Self {
        Self {
            sim: Qq2drvSim::new(config),
            now: Duration::ZERO,
            decoder: StreamDecoder::new(),
            layout: ReplyLayout::default(),
            streams: Vec::new(),
        }
    }

    /// One chip-select assertion clocking `mosi` in; returns MISO.
    fn xfer(&mut self, mosi: &[u8]) -> Vec<u8> {
        self.now += BYTE * mosi.len() as u32 + Duration::from_micros(20);
        let mut miso = vec![0xEE; mosi.len()];
        assert!(self.sim.transfer(self.now, mosi, &mut miso));
        miso
    }

    fn send(&mut self, req: &Request<'_>) -> Vec<u8> {
        let mut buf = [0u8; 255];
        let n = req.encode(&mut buf).expect("encode");
        self.xfer(&buf[..n])
    }

    /// Clocks filler out in 8-byte transactions until a non-stream packet arrives.
    fn poll_reply(&mut self) -> (Vec<u8>, Reply) {
        for _ in 0..2000 {
            let miso = self.xfer(&[0; 8]);
            let mut found = None;
            let mut packets = Vec::new();
            self.decoder.feed(&miso, |p| packets.push(p));
            for p in packets {
                let reply = Reply::decode(p.frame(), &self.layout).expect("reply decodes");
                if reply.id() == PacketId::StreamData {
                    self.streams.push((self.now, reply));
                } else if found.is_none() {
                    found = Some((p.as_bytes().to_vec(), reply));
                }
            }
            if let Some(f) = found {
                return f;
            }
        }
        panic!("no reply");
    }

    fn request(&mut self, req: &Request<'_>) -> Reply {
        if let Request::GetPosition(form) = req {
            self.layout.position = form.reply_layout(&self.layout.motion.data_masks);
        }
        let miso = self.send(req);
        assert!(
            miso.iter().all(|b| *b == 0),
            "MISO during a request with nothing pending: {miso:?}"
        );
        let (_, reply) = self.poll_reply();
        assert_eq!(reply.id(), req.id());
        reply
    }

    fn ok(&mut self, req: &Request<'_>) {
        let reply = self.request(req);
        assert_eq!(
            reply,
            Reply::Ack {
                id: req.id(),
                code: qq2drv::ReturnCode(0)
            },
            "{req:?}"
        );
    }

    fn set_masks(&mut self, entries: &[DataMaskEntry]) {
        let req = Request::SetDataMask(Entries::new(entries));
        self.ok(&req);
        assert!(self.layout.motion.apply(&req));
    }

    fn motion(&mut self) -> qq2drv::MotionData {
        match self.request(&Request::GetMotionData) {
            Reply::MotionData { code, data } if code.is_success() => data,
            other => panic!("{other:?}"),
        }
    }

    /// Packet 16 for the channels in `mask`.
    fn mode(&mut self, mask: u8, mode: ControlMode) {
        let e = [ControlModeEntry {
            channels: ChannelMask(mask),
            mode,
        }];
        self.ok(&Request::SetControlMode(Entries::new(&e)));
    }

    /// Packet 18 for the channels in `mask`.
    fn power(&mut self, mask: u8, power: i16) {
        let e = [MotorPowerEntry {
            channels: ChannelMask(mask),
            power,
        }];
        self.ok(&Request::SetMotorPower(Entries::new(&e)));
    }

    /// Lets time pass without a transaction.
    fn wait(&mut self, d: Duration) {
        self.now += d;
        self.sim.advance(self.now);
    }
}

fn ch1() -> ChannelMask {
    ChannelMask::single(0)
}

#[test]
fn golden_read_version_numbers() {
    // Datasheet "Worked Examples / Read Version Numbers": 2,4,1,249 → 2,8,1,0,0,1,0,244.
    let mut h = Host::new(Qq2drvSimConfig::default());
    let miso = h.xfer(&[2, 4, 1, 249]);
    assert_eq!(
        miso,
        [0, 0, 0, 0],
        "nothing to say while the request comes in"
    );
    let (bytes, reply) = h.poll_reply();
    assert_eq!(bytes, [2, 8, 1, 0, 0, 1, 0, 244]);
    assert!(matches!(
        reply,
        Reply::Version {
            firmware_major: 0,
            firmware_minor: 1,
            protocol: 0,
            ..
        }
    ));
}

#[test]
fn filler_until_the_reply_is_ready_and_never_in_the_request_transaction() {
    let config = Qq2drvSimConfig {
        processing_time: Duration::from_micros(500),
        ..Default::default()
    };
    let mut sim = Qq2drvSim::new(config);
    // The request followed by 100 filler bytes in ONE transaction (1.6 ms > processing
    // time): the reply still cannot start in it.
    let mut mosi = vec![2, 4, 1, 249];
    mosi.extend_from_slice(&[0; 100]);
    let mut miso = vec![0xEE; mosi.len()];
    let t0 = BYTE * mosi.len() as u32;
    sim.transfer(t0, &mosi, &mut miso);
    assert!(miso.iter().all(|b| *b == 0));
    assert!(sim.packet_ready(t0), "SRDY: the reply is ready now");
    let mut miso = [0xEE; 10];
    sim.transfer(t0 + BYTE * 10, &[0; 10], &mut miso);
    assert_eq!(&miso[..8], &[2, 8, 1, 0, 0, 1, 0, 244]);
    assert_eq!(&miso[8..], &[0, 0]);

    // A short request polled too early: filler, then the reply once processing is over.
    let mut sim = Qq2drvSim::new(Qq2drvSimConfig {
        processing_time: Duration::from_micros(500),
        ..Default::default()
    });
    let mut miso = [0u8; 4];
    let t = BYTE * 4;
    sim.transfer(t, &[2, 4, 1, 249], &mut miso);
    let mut early = [0xEE; 4];
    sim.transfer(t + Duration::from_micros(100), &[0; 4], &mut early);
    assert_eq!(early, [0; 4]);
    assert!(!sim.packet_ready(t + Duration::from_micros(100)));
    // The reply becomes ready inside this transaction: filler first, then the packet.
    let mut late = [0xEE; 40];
    sim.transfer(
        t + Duration::from_micros(100) + BYTE * 40,
        &[0; 40],
        &mut late,
    );
    let start = late.iter().position(|b| *b == 2).expect("STX");
    assert!(start > 0 && late[..start].iter().all(|b| *b == 0));
    assert_eq!(&late[start..start + 8], &[2, 8, 1, 0, 0, 1, 0, 244]);
}

#[test]
fn a_reply_read_across_several_transactions() {
    let mut h = Host::new(Qq2drvSimConfig::default());
    h.xfer(&[2, 4, 1, 249]);
    h.wait(Duration::from_millis(1));
    let mut got = Vec::new();
    for _ in 0..4 {
        got.extend(h.xfer(&[0, 0]));
    }
    assert_eq!(got, [2, 8, 1, 0, 0, 1, 0, 244]);
}

#[test]
fn malformed_and_out_of_range_requests_get_a_non_zero_code() {
    let mut h = Host::new(Qq2drvSimConfig::default());
    // Packet 4 with one byte instead of a U16.
    let bytes = [2u8, 5, 4, 7, 0u8.wrapping_sub(2 + 5 + 4 + 7)];
    h.xfer(&bytes);
    let (_, reply) = h.poll_reply();
    assert_eq!(
        reply,
        Reply::Ack {
            id: PacketId::SetStreamPeriod,
            code: qq2drv::ReturnCode(RC_MALFORMED)
        }
    );
    let reply = h.request(&Request::SetHistoryDimensions(HistoryDimensions {
        history_length: 1,
        averaging_bits: 20,
    }));
    assert_eq!(reply.code(), Some(qq2drv::ReturnCode(RC_OUT_OF_RANGE)));
    let p = [MotorPowerEntry {
        channels: ch1(),
        power: 8192,
    }];
    assert_eq!(
        h.request(&Request::SetMotorPower(Entries::new(&p))).code(),
        Some(qq2drv::ReturnCode(RC_OUT_OF_RANGE))
    );
    // A bad checksum is not answered at all.
    h.xfer(&[2, 4, 1, 248]);
    h.wait(Duration::from_millis(2));
    assert!(h.xfer(&[0; 16]).iter().all(|b| *b == 0));
    assert_eq!(h.sim.stats().bad_packets, 1);
    assert_eq!(h.sim.stats().rejected, 3);
}

#[test]
fn power_mode_limits_and_motion_data_layouts() {
    let config = Qq2drvSimConfig {
        motors: [MotorConfig {
            friction: 0.0,
            ..MotorConfig::default()
        }; 4],
        ..Default::default()
    };
    let mut h = Host::new(config);
    h.mode(0b0011, ControlMode::Power);
    h.power(0b0011, 4096);
    let limit = [PowerLimitEntry {
        channels: ChannelMask(0b0010),
        limit: 2048,
    }];
    h.ok(&Request::SetPowerLimit(Entries::new(&limit)));
    h.wait(Duration::from_millis(300));
    assert_eq!(h.sim.motor_power(0), Some(4096));
    assert_eq!(h.sim.motor_power(1), Some(2048));
    let v0 = h.sim.true_velocity(0).expect("ch");
    let v1 = h.sim.true_velocity(1).expect("ch");
    assert!((v0 - 3000.0).abs() < 30.0, "{v0}");
    assert!((v1 - 1500.0).abs() < 30.0, "{v1}");
    // Default layout: 32-bit position and velocity.
    let data = h.motion();
    let v = data.channels[0].velocity.expect("velocity");
    assert!((f64::from(v) - v0).abs() < 60.0 && v % 4 == 0, "{v}");
    assert!(data.channels[2].velocity == Some(0));
    // 8-bit relative positions plus status on channel 1: deltas add up to the distance.
    h.set_masks(&[DataMaskEntry {
        channels: ch1(),
        mask: DataMask::new(PositionSize::I8, true, false, true),
    }]);
    let start = h.sim.counter(0).expect("ch");
    let mut sum = 0i64;
    for _ in 0..40 {
        let d = h.motion();
        let PositionValue::I8(delta) = d.channels[0].position.expect("pos") else {
            panic!()
        };
        assert!(d.channels[0].velocity.is_none());
        assert!(d.channels[0].status.is_some());
        sum += i64::from(delta);
    }
    let moved = i64::from(h.sim.counter(0).expect("ch")) - i64::from(start);
    // `start` and the final counter are read a reply's latency away from the first and last
    // samples (~3 transitions/ms at this speed).
    assert!((sum - moved).abs() <= 8, "{sum} vs {moved}");
    assert!(moved > 30, "{moved}");
    // Off: output zero.
    h.mode(0x0F, ControlMode::Off);
    h.wait(Duration::from_millis(5));
    assert_eq!(h.sim.motor_power(0), Some(0));
}

/// Samples the true state every `step` for `total`, returning (time, position, velocity).
fn trace(h: &mut Host, ch: usize, total: Duration, step: Duration) -> Vec<(f64, f64, f64)> {
    let mut out = Vec::new();
    let end = h.now + total;
    while h.now < end {
        h.wait(step);
        out.push((
            h.now.as_secs_f64(),
            h.sim.true_position(ch).expect("ch"),
            h.sim.true_velocity(ch).expect("ch"),
        ));
    }
    out
}

/// Peak acceleration over 20 ms windows: the 2 ms loop on a 12-count encoder makes the
/// PWM output jitter by a count's worth of error each period; the motor's acceleration is
/// judged over ten loop periods.
fn peak_acceleration(samples: &[(f64, f64, f64)]) -> f64 {
    samples
        .windows(21)
        .map(|w| ((w[20].2 - w[0].2) / (w[20].0 - w[0].0)).abs())
        .fold(0.0, f64::max)
}

#[test]
fn position_ramp_arrives_within_limits() {
    let mut h = Host::new(Qq2drvSimConfig::default());
    let vmax = 2000.0;
    let amax = 8000.0;
    h.mode(1, ControlMode::PositionPid);
    let r = [PositionRampEntry {
        channels: ch1(),
        position: 6000,
        velocity: 2000 << 12,
        acceleration: 8000 << 12,
    }];
    h.ok(&Request::PositionRamp(Entries::new(&r)));
    let samples = trace(&mut h, 0, Duration::from_secs(5), Duration::from_millis(1));
    let peak_v = samples.iter().map(|s| s.2.abs()).fold(0.0, f64::max);
    let peak_a = peak_acceleration(&samples);
    // The limits are "not guaranteed" (datasheet, packets 26/28): they bound the loop's
    // setpoint, and a motor that can follow stays within a few percent of them (the
    // remaining acceleration jitter is the one-count quantisation of the 2 ms loop).
    assert!(peak_v <= vmax * 1.03, "peak velocity {peak_v}");
    assert!(
        peak_v >= vmax * 0.97,
        "the move reaches its cruise velocity: {peak_v}"
    );
    assert!(peak_a <= amax * 1.15, "peak acceleration {peak_a}");
    let (_, end_pos, end_v) = *samples.last().expect("samples");
    assert!(
        (end_pos - 6000.0).abs() <= 4.0,
        "arrives within one detent: {end_pos}"
    );
    assert!(end_v.abs() < 1.0);
    // The move takes 6000/2000 s plus one acceleration time: ~3.25 s; it is over well before 5.
    let arrived = samples
        .iter()
        .find(|(_, p, _)| (p - 6000.0).abs() <= 4.0)
        .map(|s| s.0)
        .expect("arrives");
    assert!((3.1..4.0).contains(&arrived), "arrival at {arrived}");
    assert_eq!(h.sim.setpoint_settled(0), Some(true));
    let max_overshoot = samples
        .iter()
        .map(|s| s.1 - 6000.0)
        .fold(f64::MIN, f64::max);
    assert!(max_overshoot <= 8.0, "overshoot {max_overshoot}");
}

#[test]
fn position_target_under_configured_velocity_and_acceleration_limits() {
    let mut h = Host::new(Qq2drvSimConfig::default());
    h.mode(0b0100, ControlMode::PositionPid);
    let vl = [VelocityLimitEntry {
        channels: ChannelMask(0b0100),
        limit: 1500 << 12,
    }];
    h.ok(&Request::SetVelocityLimit(Entries::new(&vl)));
    let al = [AccelerationLimitEntry {
        channels: ChannelMask(0b0100),
        limit: 5000 << 12,
    }];
    h.ok(&Request::SetAccelerationLimit(Entries::new(&al)));
    let t = [qq2drv::PositionTargetEntry {
        channels: ChannelMask(0b0100),
        position: -3000,
    }];
    h.ok(&Request::SetPositionTarget(Entries::new(&t)));
    let samples = trace(&mut h, 2, Duration::from_secs(4), Duration::from_millis(1));
    let peak_v = samples.iter().map(|s| s.2.abs()).fold(0.0, f64::max);
    assert!(peak_v <= 1500.0 * 1.03, "{peak_v}");
    let peak_a = peak_acceleration(&samples);
    assert!(peak_a <= 5000.0 * 1.15, "{peak_a}");
    let (_, end, _) = *samples.last().expect("samples");
    assert!((end + 3000.0).abs() <= 4.0, "{end}");
    assert_eq!(h.sim.counter(2).map(|c| (c + 3000).abs() <= 4), Some(true));
}

#[test]
fn velocity_ramp_reaches_target_and_measured_velocity_follows() {
    let mut h = Host::new(Qq2drvSimConfig::default());
    h.mode(0b1000, ControlMode::VelocityPid);
    // Packet 36: velocity in plain transitions/s, acceleration shl 12.
    let r = [VelocityRampEntry {
        channels: ChannelMask(0b1000),
        velocity: -2500,
        acceleration: 10_000 << 12,
    }];
    h.ok(&Request::VelocityRamp(Entries::new(&r)));
    h.wait(Duration::from_millis(100));
    let sp = h.sim.velocity_setpoint(3).expect("ch");
    assert!(
        (-1100.0..=-900.0).contains(&sp),
        "ramping at 10 000/s²: {sp}"
    );
    h.wait(Duration::from_millis(900));
    let v = h.sim.true_velocity(3).expect("ch");
    assert!((v + 2500.0).abs() < 60.0, "{v}");
    let data = h.motion();
    let measured = data.channels[3].velocity.expect("velocity");
    assert!((measured + 2500).abs() < 80, "{measured}");
    // Velocity limit clips the target.
    let vl = [VelocityLimitEntry {
        channels: ChannelMask(0b1000),
        limit: 1000 << 12,
    }];
    h.ok(&Request::SetVelocityLimit(Entries::new(&vl)));
    h.wait(Duration::from_secs(1));
    let v = h.sim.true_velocity(3).expect("ch");
    assert!((v + 1000.0).abs() < 40.0, "{v}");
}

#[test]
fn streaming_at_the_configured_period_with_timing_fields() {
    let mut h = Host::new(Qq2drvSimConfig::default());
    h.set_masks(&[DataMaskEntry {
        channels: ChannelMask::ALL,
        mask: DataMask::new(PositionSize::I32, false, true, true),
    }]);
    let config = Request::SetStreamConfig(StreamConfig::new(true, true));
    h.ok(&config);
    h.layout.motion.apply(&config);
    h.ok(&Request::SetStreamPeriod(100)); // 4.096 ms
    let t_set = h.now;
    // Poll 48 bytes every 1 ms for 500 ms; collect stream packets.
    let mut arrivals = Vec::new();
    let end = h.now + Duration::from_millis(500);
    while h.now < end {
        let miso = h.xfer(&[0; 48]);
        let now = h.now;
        let layout = h.layout;
        h.decoder.feed(&miso, |p| {
            let r = Reply::decode(p.frame(), &layout).expect("stream decodes");
            arrivals.push((now, r));
        });
        h.wait(Duration::from_micros(200));
    }
    let expected = (end - t_set).as_secs_f64() / 0.004096;
    assert!(
        (arrivals.len() as f64 - expected).abs() <= 2.0,
        "{} vs {expected}",
        arrivals.len()
    );
    for (_, r) in &arrivals {
        let Reply::StreamData(s) = r else {
            panic!("{r:?}")
        };
        // Period 100 + overhead 8: the datasheet's own example reads 108.
        assert_eq!(s.timing, Some(108));
        assert_eq!(s.periods_elapsed, Some(1));
        assert!(
            s.data
                .channels
                .iter()
                .all(|c| c.status.is_some() && c.velocity.is_some())
        );
    }
    let gaps: Vec<f64> = arrivals
        .windows(2)
        .map(|w| (w[1].0 - w[0].0).as_secs_f64())
        .collect();
    let mean = gaps.iter().sum::<f64>() / gaps.len() as f64;
    assert!((mean - 0.004096).abs() < 0.0002, "mean interval {mean}");
    // Stop the stream: no more packet 3.
    h.ok(&Request::SetStreamPeriod(0));
    h.wait(Duration::from_millis(20));
    h.streams.clear();
    let miso = h.xfer(&[0; 64]);
    assert!(miso.iter().all(|b| *b == 0), "{miso:?}");
}

#[test]
fn stream_periods_elapsed_counts_missed_periods() {
    let mut h = Host::new(Qq2drvSimConfig::default());
    h.set_masks(&[DataMaskEntry {
        channels: ChannelMask::ALL,
        mask: DataMask(0),
    }]);
    let config = Request::SetStreamConfig(StreamConfig::new(true, true));
    h.ok(&config);
    h.layout.motion.apply(&config);
    h.ok(&Request::SetStreamPeriod(50)); // 2.048 ms
    // Do not read for 20 ms: one packet waits, the periods after it are missed.
    h.wait(Duration::from_millis(20));
    let mut got = Vec::new();
    for _ in 0..10 {
        let miso = h.xfer(&[0; 8]);
        let layout = h.layout;
        h.decoder.feed(&miso, |p| {
            got.push(Reply::decode(p.frame(), &layout).expect("decodes"))
        });
        h.wait(Duration::from_micros(1500));
    }
    let elapsed: Vec<u8> = got
        .iter()
        .filter_map(|r| {
            if let Reply::StreamData(s) = r {
                s.periods_elapsed
            } else {
                None
            }
        })
        .collect();
    assert!(elapsed.len() >= 3, "{got:?}");
    assert_eq!(elapsed[0], 1, "the packet that waited was produced on time");
    assert!(
        elapsed[1] >= 8,
        "the next one counts the missed periods: {elapsed:?}"
    );
    assert!(h.sim.stats().stream_missed >= 7);
    for r in &got {
        if let Reply::StreamData(s) = r {
            assert_eq!(s.timing, Some(58), "timing excludes missed periods");
        }
    }
}

#[test]
fn home_switch_sets_the_position_counter_and_status_bits() {
    let mut config = Qq2drvSimConfig::default();
    // An end-stop at +800 transitions, switching to ground (active low).
    config.inputs[0] = InputPin {
        source: InputSource::EndStop {
            position: 800.0,
            positive_end: true,
        },
        actuated_high: false,
    };
    let mut h = Host::new(config);
    let cfg = InputConfig::new(InputMode::Edge, false, EdgeAction::SetOnPositive);
    let e = [InputModeEntry {
        channels: ch1(),
        config: cfg,
        spacing: 0,
        position: 10_000,
    }];
    h.ok(&Request::SetInputMode(Entries::new(&e)));
    h.set_masks(&[DataMaskEntry {
        channels: ChannelMask::ALL,
        mask: DataMask::new(PositionSize::I32, false, false, true),
    }]);
    let data = h.motion();
    assert_eq!(data.channels[0].status, Some(Status(0)));
    h.mode(1, ControlMode::Power);
    h.power(1, 2000);
    let mut hit = None;
    for _ in 0..200 {
        h.wait(Duration::from_millis(5));
        if h.sim.input_active(0) == Some(true) {
            hit = Some(h.sim.true_position(0).expect("ch"));
            break;
        }
    }
    let at = hit.expect("the switch is reached");
    let counter = h.sim.counter(0).expect("ch");
    assert!(
        (f64::from(counter) - (10_000.0 + at - 800.0)).abs() <= 6.0,
        "{counter} at {at}"
    );
    let s = h.motion().channels[0].status.expect("status");
    assert!(s.input_active() && s.input_active_accumulator());
    assert_eq!(s.trigger_accumulator(), Status::TRIGGER_POSITIVE);
    // Accumulators clear once transmitted; Input Active stays while the switch is pressed.
    let s = h.motion().channels[0].status.expect("status");
    assert_eq!(s.trigger_accumulator(), 0);
    assert!(s.input_active());
    // The edge triggers once: the counter keeps counting past the switch.
    let before = h.sim.counter(0).expect("ch");
    h.wait(Duration::from_millis(100));
    assert!(h.sim.counter(0).expect("ch") > before + 50);
}

#[test]
fn index_input_and_forced_levels() {
    let mut config = Qq2drvSimConfig::default();
    config.inputs[1] = InputPin {
        source: InputSource::Index {
            offset: 0.0,
            width: 4.0,
        },
        actuated_high: true,
    };
    let mut h = Host::new(config);
    let cfg = InputConfig::new(InputMode::Index, true, EdgeAction::SetOnPositive);
    let e = [InputModeEntry {
        channels: ChannelMask(0b0010),
        config: cfg,
        spacing: 0,
        position: 0,
    }];
    h.ok(&Request::SetInputMode(Entries::new(&e)));
    h.mode(0b0010, ControlMode::VelocityPid);
    let r = [VelocityRampEntry {
        channels: ChannelMask(0b0010),
        velocity: 300,
        acceleration: 0,
    }];
    h.ok(&Request::VelocityRamp(Entries::new(&r)));
    h.wait(Duration::from_millis(700));
    // Every 12 transitions the index resets the counter: it never exceeds one revolution.
    let c = h.sim.counter(1).expect("ch");
    assert!((0..16).contains(&c), "{c}");
    assert!(h.sim.true_position(1).expect("ch") > 50.0);
    // Forcing the level on a Disabled channel changes Input Active only.
    h.set_masks(&[DataMaskEntry {
        channels: ChannelMask::ALL,
        mask: DataMask(0x20),
    }]);
    h.sim.force_input_level(2, Some(false));
    let s = h.motion().channels[2].status.expect("status");
    assert!(s.input_active(), "default polarity: active when low");
    assert_eq!(s.trigger_accumulator(), 0);
}

#[test]
fn glitch_and_overspeed_status_bits() {
    let mut config = Qq2drvSimConfig::default();
    config.motors[3] = MotorConfig {
        no_load_velocity: 90_000.0,
        friction: 0.0,
        ..MotorConfig::default()
    };
    let mut h = Host::new(config);
    h.set_masks(&[DataMaskEntry {
        channels: ChannelMask::ALL,
        mask: DataMask(0x20),
    }]);
    h.sim.inject_glitch(0);
    let d = h.motion();
    assert!(d.channels[0].status.expect("status").glitch());
    assert!(!d.channels[1].status.expect("status").glitch());
    assert!(
        !h.motion().channels[0].status.expect("status").glitch(),
        "cleared once transmitted"
    );
    h.mode(0b1000, ControlMode::Power);
    h.power(0b1000, 8191);
    h.wait(Duration::from_millis(200));
    let s = h.motion().channels[3].status.expect("status");
    assert!(s.overspeed() && s.glitch(), "{s:?}");
}

#[test]
fn pid_constants_drive_the_position_loop() {
    // Packet 30 with P = I = D = 0: the loop outputs nothing and the target is not reached.
    let mut h = Host::new(Qq2drvSimConfig::default());
    let pid = [qq2drv::PositionPidEntry {
        channels: ch1(),
        p: 0,
        i: 0,
        d: 0,
        windup: 0,
    }];
    h.ok(&Request::SetPositionPid(Entries::new(&pid)));
    h.mode(1, ControlMode::PositionPid);
    let t = [qq2drv::PositionTargetEntry {
        channels: ChannelMask(0b0011),
        position: 500,
    }];
    h.ok(&Request::SetPositionTarget(Entries::new(&t)));
    h.wait(Duration::from_millis(500));
    assert_eq!(h.sim.motor_power(0), Some(0));
    assert_eq!(h.sim.counter(0), Some(0));
    // Channel 2 got the target but is Off: stored, no motion.
    assert_eq!(h.sim.counter(1), Some(0));
    // Default constants restored: the target is reached.
    let pid = [qq2drv::PositionPidEntry {
        channels: ch1(),
        p: 100,
        i: 500,
        d: 500,
        windup: 600,
    }];
    h.ok(&Request::SetPositionPid(Entries::new(&pid)));
    h.wait(Duration::from_millis(800));
    let c = h.sim.counter(0).expect("ch");
    assert!((c - 500).abs() <= 4, "{c} {:?}", h.sim.true_velocity(0));
    // Windup above 8191 is out of range.
    let pid = [qq2drv::PositionPidEntry {
        channels: ch1(),
        p: 1,
        i: 1,
        d: 1,
        windup: 9000,
    }];
    let reply = h.request(&Request::SetPositionPid(Entries::new(&pid)));
    assert_eq!(reply.code(), Some(qq2drv::ReturnCode(RC_OUT_OF_RANGE)));
    let vpid = [qq2drv::VelocityPidEntry {
        channels: ch1(),
        p: 100,
        i: 200,
        d: 500,
    }];
    h.ok(&Request::SetVelocityPid(Entries::new(&vpid)));
}

#[test]
fn history_dimensions_shape_the_measured_velocity() {
    // A shorter averaging time winds the reported velocity down sooner after a stop.
    let config = Qq2drvSimConfig {
        motors: [MotorConfig {
            friction: 0.0,
            time_constant: Duration::from_millis(2),
            ..MotorConfig::default()
        }; 4],
        ..Default::default()
    };
    let run = |bits: u8| {
        let mut h = Host::new(config.clone());
        let dims = HistoryDimensions {
            history_length: 31,
            averaging_bits: bits,
        };
        h.ok(&Request::SetHistoryDimensions(dims));
        h.mode(1, ControlMode::Power);
        h.power(1, 200);
        h.wait(Duration::from_millis(500));
        h.power(1, 0);
        h.wait(Duration::from_millis(30));
        h.motion().channels[0].velocity.expect("velocity")
    };
    // At ~140 transitions/s one capture event every ~28 ms: 14 bits (10.5 ms) sees too
    // few events and reads 0; the default 20 bits still averages the last events.
    assert_eq!(run(14), 0);
    assert!(run(20) > 0);
}

#[test]
fn srdy_and_next_event_tell_when_to_read() {
    let mut sim = Qq2drvSim::new(Qq2drvSimConfig::default());
    assert_eq!(sim.next_event(), None);
    let t = BYTE * 6;
    let mut miso = [0u8; 6];
    let mut buf = [0u8; 8];
    let n = Request::SetStreamPeriod(25)
        .encode(&mut buf)
        .expect("encode");
    sim.transfer(t, &buf[..n], &mut miso);
    let ready = sim.next_event().expect("a reply is pending");
    assert_eq!(ready, t + Qq2drvSimConfig::default().processing_time);
    assert!(!sim.packet_ready(ready - Duration::from_nanos(1)));
    assert!(sim.packet_ready(ready));
    sim.advance(Duration::from_millis(10));
    assert_eq!(sim.stream_period(), 25);
    // The stream has produced one packet (unread: later periods are missed).
    assert_eq!(sim.stats().stream_packets, 1);
    assert!(sim.stats().stream_missed >= 7);
}
