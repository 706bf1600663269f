//! What the firmware does with each request: range checks, register and loop updates, and
//! the reply.

use core::time::Duration;

use qq2drv::limits::{
    ACCELERATION_MAX, AVERAGING_BITS_RANGE, HISTORY_LENGTH_RANGE, POWER_LIMIT_MAX, POWER_MAX,
    VELOCITY_LIMIT_MAX, VELOCITY_TARGET_MAX, VelocityRampSign, WINDUP_MAX,
};
use qq2drv::{
    CHANNELS, ChannelData, ChannelMask, MotionData, PacketBuf, PacketId, PositionValue, Reply,
    Request, ReturnCode, Status, StreamData,
};

use super::{Qq2drvSim, RC_MALFORMED, RC_OUT_OF_RANGE};

/// Whether every value of the request is inside its documented range; packet 36's
/// Velocity as the board's firmware reads it (`reading`: signed, or "Range: 0 - 100,000").
fn in_range(req: &Request<'_>, reading: VelocityRampSign) -> bool {
    match req {
        Request::SetMotorPower(e) => e
            .iter()
            .all(|x| x.power.unsigned_abs() <= POWER_MAX.unsigned_abs()),
        Request::SetPowerLimit(e) => e.iter().all(|x| x.limit <= POWER_LIMIT_MAX),
        Request::SetVelocityLimit(e) => e.iter().all(|x| x.limit <= VELOCITY_LIMIT_MAX),
        Request::SetAccelerationLimit(e) => e.iter().all(|x| x.limit <= ACCELERATION_MAX),
        Request::SetPositionPid(e) => e.iter().all(|x| x.windup <= WINDUP_MAX),
        Request::SetVelocityTarget(e) => e
            .iter()
            .all(|x| x.velocity.unsigned_abs() <= VELOCITY_TARGET_MAX.unsigned_abs()),
        Request::PositionRamp(e) => e
            .iter()
            .all(|x| x.velocity <= VELOCITY_LIMIT_MAX && x.acceleration <= ACCELERATION_MAX),
        Request::VelocityRamp(e) => e
            .iter()
            .all(|x| reading.carries(x.velocity) && x.acceleration <= ACCELERATION_MAX),
        Request::SetHistoryDimensions(d) => {
            HISTORY_LENGTH_RANGE.contains(&d.history_length)
                && AVERAGING_BITS_RANGE.contains(&d.averaging_bits)
        }
        _ => true,
    }
}

fn encode(reply: &Reply) -> Option<PacketBuf> {
    let mut buf = [0u8; qq2drv::MAX_PACKET_LEN];
    let n = reply.encode(&mut buf).ok()?;
    PacketBuf::from_packet(buf.get(..n)?).ok()
}

impl Qq2drvSim {
    /// One MOSI byte finished arriving at `at`.
    pub(super) fn receive_byte(&mut self, at: Duration, byte: u8) {
        self.wire.rx.push(&[byte]);
        while let Some(packet) = self.wire.rx.next_packet() {
            self.on_packet(at, &packet);
        }
    }

    fn on_packet(&mut self, at: Duration, packet: &PacketBuf) {
        let frame = packet.frame();
        let reply = match Request::decode(frame) {
            Ok(req) => self.handle(at, &req),
            Err(_) => match PacketId::try_from(frame.id) {
                // "This packet must not be sent by the master device": ignored.
                Ok(PacketId::StreamData) | Err(_) => return,
                Ok(id) => Reply::Ack {
                    id,
                    code: ReturnCode(RC_MALFORMED),
                },
            },
        };
        self.requests += 1;
        if reply.code().is_some_and(|c| !c.is_success()) {
            self.rejected += 1;
        }
        if let Some(out) = encode(&reply) {
            self.wire.queue_reply(at, self.config.processing_time, out);
        }
    }

    /// Applies `req` (received at `at`) and builds its reply.
    pub(super) fn handle(&mut self, at: Duration, req: &Request<'_>) -> Reply {
        let id = req.id();
        let code = ReturnCode::SUCCESS;
        if !in_range(req, self.config.velocity_ramp) {
            return Reply::Ack {
                id,
                code: ReturnCode(RC_OUT_OF_RANGE),
            };
        }
        let ack = Reply::Ack { id, code };
        match req {
            Request::GetVersion => Reply::Version {
                code,
                firmware_major: self.config.firmware_version.0,
                firmware_minor: self.config.firmware_version.1,
                protocol: self.config.protocol_version,
            },
            Request::GetMotionData => Reply::MotionData {
                code,
                data: self.sample_motion(),
            },
            Request::SetStreamPeriod(p) => {
                self.stream.set_period(*p, at);
                ack
            }
            Request::GetStreamPeriod => Reply::StreamPeriod {
                code,
                period: self.stream.period,
            },
            Request::SetDataMask(_) => {
                let before = self.regs.layout.data_masks;
                self.regs.layout.apply(req);
                for ((c, was), now) in self
                    .channels
                    .iter_mut()
                    .zip(before)
                    .zip(self.regs.layout.data_masks)
                {
                    if now.relative() && !was.relative() {
                        c.last_read = c.counter();
                    }
                }
                ack
            }
            Request::GetDataMask => Reply::DataMasks {
                code,
                masks: self.regs.layout.data_masks,
            },
            Request::SetStreamConfig(_) => {
                self.regs.layout.apply(req);
                ack
            }
            Request::GetStreamConfig => Reply::StreamConfig {
                code,
                config: self.regs.layout.stream_config,
            },
            Request::SetPosition(entries) => {
                for e in entries.iter() {
                    self.for_channels(e.channels, |sim, ch| {
                        sim.channels[ch].set_counter(e.value())
                    });
                }
                ack
            }
            Request::GetPosition(form) => {
                let layout = form.reply_layout(&self.regs.layout.data_masks);
                let mut positions = [None; CHANNELS];
                for ((p, size), ch) in positions.iter_mut().zip(layout.0).zip(&self.channels) {
                    *p = PositionValue::truncate(size, ch.counter_i32());
                }
                Reply::Positions { code, positions }
            }
            Request::SetHistoryDimensions(d) => {
                self.regs.history = *d;
                ack
            }
            Request::GetHistoryDimensions => Reply::HistoryDimensions {
                code,
                dimensions: self.regs.history,
            },
            Request::SetInputMode(entries) => {
                for e in entries.iter() {
                    self.for_channels(e.channels, |sim, ch| {
                        let c = &mut sim.channels[ch];
                        c.input.configure(e.config, e.spacing, e.position);
                        c.evaluate_input();
                    });
                }
                ack
            }
            Request::SetControlMode(entries) => {
                for e in entries.iter() {
                    self.for_channels(e.channels, |sim, ch| sim.channels[ch].set_mode(e.mode));
                }
                ack
            }
            Request::SetMotorPower(entries) => {
                for e in entries.iter() {
                    self.for_channels(e.channels, |sim, ch| {
                        sim.channels[ch].control.power = e.power
                    });
                }
                ack
            }
            Request::SetPositionTarget(entries) => {
                for e in entries.iter() {
                    self.for_channels(e.channels, |sim, ch| {
                        sim.channels[ch].control.set_position_target(e.position);
                    });
                }
                ack
            }
            Request::SetVelocityTarget(entries) => {
                for e in entries.iter() {
                    self.for_channels(e.channels, |sim, ch| {
                        sim.channels[ch].control.set_velocity_target(e.velocity);
                    });
                }
                ack
            }
            Request::SetPowerLimit(entries) => {
                for e in entries.iter() {
                    self.for_channels(e.channels, |sim, ch| {
                        sim.channels[ch].control.power_limit = e.limit
                    });
                }
                ack
            }
            Request::SetVelocityLimit(entries) => {
                for e in entries.iter() {
                    self.for_channels(e.channels, |sim, ch| {
                        sim.channels[ch].control.velocity_limit = e.limit;
                    });
                }
                ack
            }
            Request::SetAccelerationLimit(entries) => {
                for e in entries.iter() {
                    self.for_channels(e.channels, |sim, ch| {
                        sim.channels[ch].control.acceleration_limit = e.limit;
                    });
                }
                ack
            }
            Request::SetPositionPid(entries) => {
                for e in entries.iter() {
                    self.for_channels(e.channels, |sim, ch| {
                        sim.channels[ch].control.position_pid = e
                    });
                }
                ack
            }
            Request::SetVelocityPid(entries) => {
                for e in entries.iter() {
                    self.for_channels(e.channels, |sim, ch| {
                        sim.channels[ch].control.velocity_pid = e
                    });
                }
                ack
            }
            Request::PositionRamp(entries) => {
                for e in entries.iter() {
                    self.for_channels(e.channels, |sim, ch| {
                        sim.channels[ch].control.position_ramp(
                            e.position,
                            e.velocity,
                            e.acceleration,
                        );
                    });
                }
                ack
            }
            Request::VelocityRamp(entries) => {
                for e in entries.iter() {
                    self.for_channels(e.channels, |sim, ch| {
                        sim.channels[ch]
                            .control
                            .velocity_ramp(e.velocity, e.acceleration);
                    });
                }
                ack
            }
        }
    }

    /// Runs `f` for every channel (0-based) the mask selects.
    fn for_channels(&mut self, mask: ChannelMask, mut f: impl FnMut(&mut Self, usize)) {
        for ch in mask.channels() {
            f(self, ch);
        }
    }

    /// Motion data under the configured data masks. Reading positions moves the relative
    /// reference; reading status clears its accumulated bits.
    pub(super) fn sample_motion(&mut self) -> MotionData {
        let (len, avg) = self.history_params();
        let t = self.now.as_secs_f64();
        let mut data = MotionData::default();
        for ((out, c), mask) in data
            .channels
            .iter_mut()
            .zip(&mut self.channels)
            .zip(self.regs.layout.data_masks)
        {
            let position = if mask.position_size().is_omitted() {
                0
            } else {
                c.read_position(mask.relative())
            };
            let velocity = c.motor.measured_velocity(t, len, avg);
            let status = if mask.status() {
                c.take_status()
            } else {
                Status(0)
            };
            *out = ChannelData::sample(mask, position, velocity, status);
        }
        data
    }

    /// A packet-3 stream packet with the configured optional fields.
    pub(super) fn stream_packet(&mut self, timing: u16, elapsed: u8) -> Option<PacketBuf> {
        let config = self.regs.layout.stream_config;
        let data = self.sample_motion();
        encode(&Reply::StreamData(StreamData {
            code: self.config.stream_return_code.then_some(ReturnCode(0)),
            timing: config.timing().then_some(timing),
            periods_elapsed: config.periods_elapsed().then_some(elapsed),
            data,
        }))
    }
}
