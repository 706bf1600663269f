//! The wire: the single-channel packets goals and start-up turn into (encoded through the
//! `qq2drv` crate), the requests sent and not yet answered (oldest first: the board
//! answers in order), which transaction goes next, and the timing that decides it (module
//! docs, "The wire" and "Faults").

use core::time::Duration;

use motion_base::FixedQueue;
use qq2drv::{
    AccelerationLimitEntry, ChannelMask, ControlMode, ControlModeEntry, Entries, InputConfig,
    InputModeEntry, MotionLayout, MotorPowerEntry, PacketId, PositionRampEntry,
    PositionTargetEntry, PositionValue, Request, SetPositionEntry, VelocityRampEntry,
    VelocityTargetEntry,
};

use super::{
    CONFIGURE_REQUESTS, FILLER, OFFLINE_RETRY_PERIOD, POLL_SLACK, Phase, Qq2drvDriver,
    START_ATTEMPTS, STREAM_CONFIG,
};
use motion_drivers::{Priority, Transmit};

/// What [`StreamDecoder::missing`](qq2drv::StreamDecoder::missing) says of a packet whose
/// size has not arrived: the rest of the longest.
const UNKNOWN_REST: usize = qq2drv::MAX_PACKET_LEN - 1;

/// Most packets one goal step sends in its transaction.
pub(super) const MAX_STEP_PACKETS: usize = 5;

/// One packet for one channel (a one-entry payload).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Packet {
    /// 16 - Set Control Mode.
    Mode(ControlMode),
    /// 18 - Set Motor Power, ±8191.
    Power(i16),
    /// 20 - Set Position Control Target.
    Target(i32),
    /// 34 - Position Ramp: target, velocity and acceleration (both shl 12).
    PositionRamp {
        position: i32,
        velocity: u32,
        accel: u32,
    },
    /// 36 - Velocity Ramp: plain transitions/s, acceleration shl 12.
    VelocityRamp { velocity: i32, accel: u32 },
    /// 22 - Set Velocity Control Target, plain transitions/s: a reverse velocity on a board
    /// whose packet 36 is forward only (`velocity_ramp = "unsigned"`).
    VelocityTarget(i32),
    /// 10 - Set Position (32-bit value).
    SetCounter(i32),
    /// 14 - Set Input Mode; `position` is omitted when the mode is Disabled.
    Input {
        config: InputConfig,
        spacing: u16,
        position: i32,
    },
    /// 28 - Set Acceleration Limit, shl 12 (0 disables limiting: a stop lifts it while it
    /// resets the board's velocity target, then restores it).
    AccelLimit(u32),
}

impl Packet {
    /// The packet id (what its reply carries).
    pub(super) fn id(self) -> PacketId {
        match self {
            Self::Mode(_) => PacketId::SetControlMode,
            Self::Power(_) => PacketId::SetMotorPower,
            Self::Target(_) => PacketId::SetPositionTarget,
            Self::PositionRamp { .. } => PacketId::PositionRamp,
            Self::VelocityRamp { .. } => PacketId::VelocityRamp,
            Self::VelocityTarget(_) => PacketId::SetVelocityTarget,
            Self::SetCounter(_) => PacketId::SetPosition,
            Self::Input { .. } => PacketId::SetInputMode,
            Self::AccelLimit(_) => PacketId::SetAccelerationLimit,
        }
    }

    /// Encodes the packet for `channel` (0-based) into `buf`; returns its length.
    pub(super) fn encode(self, channel: usize, buf: &mut [u8]) -> Result<usize, qq2drv::Error> {
        let channels = ChannelMask::single(channel);
        match self {
            Self::Mode(mode) => {
                Request::SetControlMode(Entries::new(&[ControlModeEntry { channels, mode }]))
                    .encode(buf)
            }
            Self::Power(power) => {
                Request::SetMotorPower(Entries::new(&[MotorPowerEntry { channels, power }]))
                    .encode(buf)
            }
            Self::Target(position) => {
                Request::SetPositionTarget(Entries::new(&[PositionTargetEntry {
                    channels,
                    position,
                }]))
                .encode(buf)
            }
            Self::PositionRamp {
                position,
                velocity,
                accel,
            } => Request::PositionRamp(Entries::new(&[PositionRampEntry {
                channels,
                position,
                velocity,
                acceleration: accel,
            }]))
            .encode(buf),
            Self::VelocityRamp { velocity, accel } => {
                Request::VelocityRamp(Entries::new(&[VelocityRampEntry {
                    channels,
                    velocity,
                    acceleration: accel,
                }]))
                .encode(buf)
            }
            Self::VelocityTarget(velocity) => {
                Request::SetVelocityTarget(Entries::new(&[VelocityTargetEntry {
                    channels,
                    velocity,
                }]))
                .encode(buf)
            }
            Self::SetCounter(value) => Request::SetPosition(Entries::new(&[SetPositionEntry {
                channels,
                position: Some(PositionValue::I32(value)),
            }]))
            .encode(buf),
            Self::Input {
                config,
                spacing,
                position,
            } => {
                let position = if config.mode() == qq2drv::InputMode::Disabled {
                    0
                } else {
                    position
                };
                Request::SetInputMode(Entries::new(&[InputModeEntry {
                    channels,
                    config,
                    spacing,
                    position,
                }]))
                .encode(buf)
            }
            Self::AccelLimit(limit) => {
                Request::SetAccelerationLimit(Entries::new(&[AccelerationLimitEntry {
                    channels,
                    limit,
                }]))
                .encode(buf)
            }
        }
    }
}

/// Up to [`MAX_STEP_PACKETS`] packets of one goal step, sent back to back in one
/// transaction (the step tables never exceed the capacity).
pub(super) type Packets = FixedQueue<Packet, MAX_STEP_PACKETS>;

/// Requests that may be unanswered at once.
pub const IN_FLIGHT_CAPACITY: usize = 48;

/// What an answer is for.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Tag {
    /// A start-up read (version, data masks, stream config, stream period).
    Probe,
    /// A start-up write.
    Setup,
    /// A goal packet of `channel`, step generation `seq`.
    Goal {
        channel: u8,
        seq: u32,
        packet: Packet,
    },
    /// The stream check: Get Stream Period while the stream stalls (module `liveness`).
    Check,
}

/// One unanswered request.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Sent {
    pub(super) id: PacketId,
    /// Queued at, then (once reported) written at: its reply timeout runs from here.
    pub(super) at: Duration,
    /// The message (transaction) it went out in (`IoStamps::sent`).
    pub(super) number: u64,
    pub(super) tag: Tag,
    /// When the first valid packet after its reply timeout arrived (module `liveness`).
    pub(super) heard_after: Option<Duration>,
}

/// Requests in flight, oldest first.
pub(super) type InFlight = FixedQueue<Sent, IN_FLIGHT_CAPACITY>;

/// What the next transaction would be.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Next {
    Probe,
    Configure,
    Goals,
    Check,
    Poll,
}

impl Qq2drvDriver {
    /// Length of one poll transaction: a stream packet in our layout plus [`POLL_SLACK`].
    pub fn poll_len(&self) -> usize {
        let layout = MotionLayout {
            data_masks: self.stream_masks(),
            stream_config: STREAM_CONFIG,
        };
        (qq2drv::MIN_PACKET_LEN + layout.stream_payload_len() + POLL_SLACK).clamp(16, 255)
    }

    /// How often the driver actually gets to read: the poll period, or the interval
    /// between the last two `handle_timeout` calls when that is longer (a slow tick, or a
    /// late one: the data is as old as the caller's lateness, not the board's fault).
    pub fn cadence(&self) -> Duration {
        self.config.poll_period.max(self.call_interval)
    }

    /// Reply timeout: polls to read it, the wire time of two long transactions, the
    /// board's processing time and a margin.
    pub fn reply_timeout(&self) -> Duration {
        self.cadence()
            .saturating_mul(4)
            .saturating_add(self.config.wire_time(2 * qq2drv::MAX_PACKET_LEN))
            .saturating_add(self.config.processing_time)
            .saturating_add(Duration::from_millis(2))
    }

    /// Without a stream packet for this long the driver probes the board again.
    pub fn stall_timeout(&self) -> Duration {
        self.config
            .stream_period()
            .saturating_mul(4)
            .saturating_add(self.cadence().saturating_mul(3))
            .saturating_add(Duration::from_millis(2))
    }

    pub(super) fn next(&self, now: Duration) -> Option<(Next, Priority)> {
        if !self.link_up {
            return None;
        }
        let backlog = self.line_free_at.saturating_sub(now);
        if self.decoder.missing() == Some(UNKNOWN_REST) {
            // A packet begun whose size has not come yet: read by a poll before anything
            // else ("Master reads out one entire packet", SPI Interface).
            return (backlog <= self.config.poll_period / 2)
                .then_some((Next::Poll, Priority::Poll));
        }
        if self.probe_due && self.in_flight.has_room(4) {
            return Some((Next::Probe, Priority::Setup));
        }
        if self.configure_due && self.in_flight.has_room(CONFIGURE_REQUESTS) {
            return Some((Next::Configure, Priority::Setup));
        }
        // Goals wait while a whole poll period of earlier bytes is still on the wire (a
        // newer goal of the same channel replaces an unsent one meanwhile), polls while
        // half of one is.
        let goals = self.phase == Phase::Running
            && backlog <= self.config.poll_period
            && self.in_flight.has_room(MAX_STEP_PACKETS)
            && self
                .channels
                .iter()
                .any(|c| c.config.enabled && c.unsent && c.ready());
        if goals {
            return Some((Next::Goals, Priority::Command));
        }
        if self.check_due && self.phase == Phase::Running && self.in_flight.has_room(1) {
            return Some((Next::Check, Priority::Poll));
        }
        let reading = self.phase == Phase::Running || !self.in_flight.is_empty();
        let bus_free = backlog <= self.config.poll_period / 2;
        if reading && now >= self.next_poll_at && bus_free {
            return Some((Next::Poll, Priority::Poll));
        }
        None
    }

    /// Writes the next transaction (probe, configuration, goals or a poll) into `buf`.
    pub(super) fn transmit(&mut self, now: Duration, buf: &mut [u8]) -> Option<Transmit> {
        let (next, _) = self.next(now)?;
        let mut goal_starts = 0;
        // A packet partly read is read out entirely before a request ("Master reads out
        // one entire packet", SPI Interface): its rest is clocked with filler first, in
        // the request's own transaction.
        let prefix = match next {
            Next::Poll => 0,
            _ => self.decoder.missing().unwrap_or(0),
        };
        let written = match buf.get_mut(prefix..) {
            Some(rest) => match next {
                Next::Probe => self.write_probe(now, rest),
                Next::Configure => self.write_configure(now, rest),
                Next::Goals => Some(self.write_goals(now, rest, &mut goal_starts)),
                Next::Check => self.write_check(now, rest),
                Next::Poll => self.write_poll(now, buf),
            },
            None => None,
        };
        let (len, next) = match written {
            Some(len) if len > 0 && next == Next::Poll => (len, next),
            Some(len) if len > 0 => {
                buf.get_mut(..prefix)?.fill(FILLER);
                (prefix + len, next)
            }
            // The request does not fit behind the rest of the packet: that rest alone
            // first, the request at the next call.
            _ if prefix > 0 => (self.write_poll(now, buf)?, Next::Poll),
            _ => return None,
        };
        let _number = self.io_stamps.sent();
        self.line_free_at = self
            .line_free_at
            .max(now)
            .saturating_add(self.config.wire_time(len));
        Some(Transmit {
            len,
            expects_reply: next != Next::Poll,
            goal_starts,
        })
    }

    /// Writes a poll: filler for one stream packet and a reply, or for the rest of a
    /// packet partly read.
    fn write_poll(&mut self, now: Duration, buf: &mut [u8]) -> Option<usize> {
        // (A packet whose size has not come yet is read on by an ordinary poll: then its
        // rest is known.)
        let rest = self
            .decoder
            .missing()
            .filter(|missing| *missing != UNKNOWN_REST)
            .map_or(0, |missing| missing + POLL_SLACK);
        let len = self.poll_len().max(rest).min(qq2drv::MAX_PACKET_LEN);
        buf.get_mut(..len)?.fill(FILLER);
        // Three quarters: a tick at exactly the poll period always polls.
        let period = self.config.poll_period;
        self.next_poll_at = now.saturating_add(period - period / 4);
        Some(len)
    }

    /// A transaction went out at `at`: the reply timeouts of its requests run from there,
    /// and so does the wait for a probe's answers.
    pub(super) fn on_written(&mut self, at: Duration) {
        let number = self.io_stamps.written();
        if number == 0 {
            return;
        }
        self.in_flight.for_each_mut(|sent| {
            if sent.number == number {
                sent.at = sent.at.max(at);
            }
        });
        if number == self.probe_number
            && let Phase::Probe { attempts, next_at } = self.phase
        {
            self.phase = Phase::Probe {
                attempts,
                next_at: next_at.max(at.saturating_add(self.reply_timeout())),
            };
        }
    }

    /// Lets time pass: lost requests, a silent board, the probe schedule, a stalled
    /// stream, and the channels' steps.
    pub(super) fn pass_time(&mut self, now: Duration) {
        if let Some(last) = self.last_call_at {
            self.call_interval = now.saturating_sub(last).min(Duration::from_secs(1));
        }
        self.last_call_at = Some(now);
        for inputs in &mut self.inputs {
            inputs.tick();
        }
        if !self.link_up {
            return;
        }
        let timeout = self.reply_timeout();
        // Unanswered, silent, stalled: only as far as the link was looked at.
        let judged = self.io_stamps.judged(now);
        self.listening_since.get_or_insert(judged);
        self.judge_requests(now, judged);
        self.judge_silence(now, judged);
        match self.phase {
            Phase::Probe { attempts, next_at } if judged >= next_at => {
                // Probes are reads: one more while an earlier one's answers may still come
                // is harmless. Not answering is the silence's verdict alone.
                self.probe_due = true;
                let attempts = attempts.saturating_add(1);
                let wait = if attempts >= START_ATTEMPTS {
                    OFFLINE_RETRY_PERIOD
                } else {
                    timeout
                };
                self.phase = Phase::Probe {
                    attempts,
                    next_at: now.saturating_add(wait),
                };
            }
            Phase::Running => {
                self.judge_stream(judged);
                for channel in &mut self.channels {
                    channel.progress(now);
                }
            }
            Phase::Probe { .. } | Phase::Configure => {}
        }
    }
}
