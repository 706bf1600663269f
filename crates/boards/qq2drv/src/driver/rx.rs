//! What the driver does with the MISO bytes: stream packets refresh the channels and the
//! pins, answers are matched to the oldest unanswered request with their packet id, and
//! requests skipped or unanswered are lost.

use core::time::Duration;

use qq2drv::{PacketBuf, PacketId, Reply, ReplyLayout, StreamData};

use super::wire::{Sent, Tag};
use super::{OFFLINE_RETRY_PERIOD, Phase, Qq2drvDriver, STREAM_CONFIG};
use motion_drivers::DeviceFault;

impl Qq2drvDriver {
    /// Bytes clocked in on MISO: every packet the decoder finds in them.
    pub(super) fn receive(&mut self, now: Duration, mut bytes: &[u8]) {
        if !self.link_up {
            return;
        }
        while !bytes.is_empty() {
            let taken = self.decoder.push(bytes);
            bytes = bytes.get(taken..).unwrap_or(&[]);
            while let Some(packet) = self.decoder.next_packet() {
                self.on_packet(now, &packet);
            }
            if taken == 0 {
                break;
            }
        }
    }

    pub(super) fn on_packet(&mut self, now: Duration, packet: &PacketBuf) {
        self.heard_packet(now);
        let frame = packet.frame();
        if frame.id == PacketId::StreamData.as_u8() && self.phase != Phase::Running {
            return; // Its layout is not known yet.
        }
        let layout = ReplyLayout {
            motion: self.layout,
            ..ReplyLayout::default()
        };
        let Ok(reply) = Reply::decode(frame, &layout) else {
            self.status.bad_replies = self.status.bad_replies.saturating_add(1);
            return;
        };
        if let Reply::StreamData(data) = reply {
            // Packet 3 with a Return Code (its text's reading: docs/ARCHITECTURE.md): a
            // non-zero one is the board's error to report, and its data is not used.
            if data.code.is_some_and(|code| !code.is_success()) {
                self.status.bad_replies = self.status.bad_replies.saturating_add(1);
                self.raise(DeviceFault::BoardError);
                return;
            }
            self.on_stream(now, &data);
            return;
        }
        let Some(index) = self.in_flight.position(|sent| sent.id == reply.id()) else {
            // The reply to a request declared lost, after all: recognised, never paired.
            match self.lost_ids.position(|id| *id == reply.id()) {
                Some(at) => {
                    self.lost_ids.remove(at);
                    self.late_replies = self.late_replies.saturating_add(1);
                }
                None => self.status.bad_replies = self.status.bad_replies.saturating_add(1),
            }
            return;
        };
        for _ in 0..index {
            if let Some(lost) = self.in_flight.pop() {
                self.status.bad_replies = self.status.bad_replies.saturating_add(1);
                self.on_lost(now, lost);
            }
        }
        if let Some(sent) = self.in_flight.pop() {
            self.status.replies = self.status.replies.saturating_add(1);
            self.on_reply(now, sent, reply);
        }
    }

    pub(super) fn on_stream(&mut self, now: Duration, data: &StreamData) {
        self.last_stream_at = now;
        self.stream_packets = self.stream_packets.saturating_add(1);
        for ((channel, inputs), sample) in self
            .channels
            .iter_mut()
            .zip(&mut self.inputs)
            .zip(data.data.channels)
        {
            if let Some(status) = sample.status {
                inputs.update(now, status);
            }
            if let (true, Some(position), Some(velocity)) =
                (channel.config.enabled, sample.position, sample.velocity)
            {
                let status = sample.status.unwrap_or_default();
                channel.data(now, position.get(), velocity, status);
            }
        }
        if self.link_up {
            self.status.fault = None;
            self.status.online = true;
        }
    }

    pub(super) fn on_reply(&mut self, now: Duration, sent: Sent, reply: Reply) {
        let code = reply.code().map_or(0, |code| code.0);
        match sent.tag {
            Tag::Probe => {
                match reply {
                    Reply::Version {
                        code,
                        firmware_major,
                        firmware_minor,
                        protocol,
                    } if code.is_success() => {
                        self.probe.version = Some((firmware_major, firmware_minor, protocol));
                    }
                    Reply::DataMasks { code, masks } if code.is_success() => {
                        self.probe.masks = Some(masks);
                    }
                    Reply::StreamConfig { code, config } if code.is_success() => {
                        self.probe.config = Some(config);
                    }
                    Reply::StreamPeriod { code, period } if code.is_success() => {
                        self.probe.period = Some(period);
                    }
                    _ => {}
                }
                self.evaluate_probe(now);
            }
            Tag::Setup => {
                if code != 0 {
                    self.raise(DeviceFault::BoardError);
                    self.restart(now);
                    self.phase = Phase::Probe {
                        attempts: 0,
                        next_at: now.saturating_add(OFFLINE_RETRY_PERIOD),
                    };
                    return;
                }
                match sent.id {
                    PacketId::SetDataMask => self.layout.data_masks = self.stream_masks(),
                    PacketId::SetStreamConfig => self.layout.stream_config = STREAM_CONFIG,
                    // The configured limits and disarmed inputs are in force again.
                    PacketId::SetAccelerationLimit => {
                        for channel in &mut self.channels {
                            channel.lifted = false;
                        }
                    }
                    PacketId::SetInputMode => {
                        for channel in &mut self.channels {
                            channel.armed = false;
                        }
                    }
                    _ => {}
                }
                self.setup_unanswered = self.setup_unanswered.saturating_sub(1);
                if self.setup_unanswered == 0 && self.phase == Phase::Configure {
                    self.phase = Phase::Running;
                    self.configured_once = true;
                    self.status.online = true;
                    self.last_stream_at = now;
                    self.next_poll_at = now;
                }
            }
            Tag::Goal {
                channel,
                seq,
                packet,
            } => {
                if let Some(channel) = self.channels.get_mut(usize::from(channel)) {
                    channel.answered(now, seq, packet, code);
                }
            }
            Tag::Check => {
                let period = match reply {
                    Reply::StreamPeriod { code, period } if code.is_success() => Some(period),
                    _ => None,
                };
                self.checked(now, period);
            }
        }
    }

    pub(super) fn on_lost(&mut self, now: Duration, sent: Sent) {
        self.lost_ids.push_overwrite(sent.id);
        match sent.tag {
            Tag::Probe | Tag::Check => {}
            Tag::Setup => {
                if self.phase == Phase::Configure {
                    self.restart(now);
                }
            }
            Tag::Goal { channel, seq, .. } => {
                if let Some(channel) = self.channels.get_mut(usize::from(channel)) {
                    channel.lost(seq);
                }
            }
        }
    }
}
