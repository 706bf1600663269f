//! The variable-layout motion data of packets 2 and 3, and the position list of packet 11.
//!
//! What is on the wire depends on the configured Data Masks (packet 6) and Stream Config
//! (packet 8), so decoding takes the layout as a parameter. Encoding is self-describing:
//! which `Option`s are `Some`, and the size of each [`PositionValue`], decide the bytes.

use crate::error::Error;
use crate::fields::{
    CHANNELS, DataMask, PositionSize, PositionValue, ReturnCode, Status, StreamConfig,
    position_size_of,
};
use crate::wire::{Reader, Writer};

/// The configuration that decides the layout of packets 2 and 3.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub struct MotionLayout {
    /// Data Mask of channels 1..4 (packet 6/7).
    pub data_masks: [DataMask; CHANNELS],
    /// Stream Config Mask (packet 8/9).
    pub stream_config: StreamConfig,
}

impl MotionLayout {
    /// Updates the layout for a request that changes it once acknowledged: packet 6 (each
    /// entry's mask on its channels, in order, so "any latter bit value will override the
    /// former") and packet 8. Returns whether `req` was one of them.
    pub fn apply(&mut self, req: &crate::Request<'_>) -> bool {
        match req {
            crate::Request::SetDataMask(entries) => {
                for e in entries.iter() {
                    for ch in e.channels.channels() {
                        if let Some(m) = self.data_masks.get_mut(ch) {
                            *m = e.mask;
                        }
                    }
                }
                true
            }
            crate::Request::SetStreamConfig(c) => {
                self.stream_config = *c;
                true
            }
            _ => false,
        }
    }

    /// Channel data bytes for all four channels.
    pub fn channels_len(&self) -> usize {
        self.data_masks.iter().map(|m| m.channel_len()).sum()
    }

    /// Payload length of a packet-2 reply (Return Code plus channel data).
    pub fn motion_payload_len(&self) -> usize {
        1 + self.channels_len()
    }

    /// Payload length of a packet-3 stream packet (optional timing fields plus channel
    /// data), without a Return Code; a board that sends one makes it one byte longer
    /// ([`StreamData::code`]).
    pub fn stream_payload_len(&self) -> usize {
        usize::from(self.stream_config.timing()) * 2
            + usize::from(self.stream_config.periods_elapsed())
            + self.channels_len()
    }
}

/// One channel's optional fields, in wire order: Position, Velocity, Status.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct ChannelData {
    /// Position (absolute or relative, per the mask) in its configured size.
    pub position: Option<PositionValue>,
    /// Velocity in transitions/s.
    pub velocity: Option<i32>,
    /// Status bits.
    pub status: Option<Status>,
}

impl ChannelData {
    /// The fields `mask` selects, from full-width values (positions are truncated to the
    /// configured size; the relative bit does not change the layout).
    pub fn sample(mask: DataMask, position: i32, velocity: i32, status: Status) -> Self {
        Self {
            position: PositionValue::truncate(mask.position_size(), position),
            velocity: mask.velocity().then_some(velocity),
            status: mask.status().then_some(status),
        }
    }

    /// Whether these fields are exactly the ones `mask` selects.
    pub fn matches(&self, mask: DataMask) -> bool {
        position_size_of(self.position) == mask.position_size()
            && self.velocity.is_some() == mask.velocity()
            && self.status.is_some() == mask.status()
    }

    fn encoded_len(&self) -> usize {
        position_size_of(self.position).byte_len()
            + if self.velocity.is_some() { 4 } else { 0 }
            + usize::from(self.status.is_some())
    }

    fn write(&self, w: &mut Writer<'_>) -> Result<(), Error> {
        if let Some(p) = self.position {
            p.write(w)?;
        }
        if let Some(v) = self.velocity {
            w.i32(v)?;
        }
        if let Some(s) = self.status {
            w.u8(s.0)?;
        }
        Ok(())
    }

    fn read(r: &mut Reader<'_>, mask: DataMask) -> Result<Self, Error> {
        let position = mask.position_size().read(r)?;
        let velocity = if mask.velocity() {
            Some(r.i32()?)
        } else {
            None
        };
        let status = if mask.status() {
            Some(Status(r.u8()?))
        } else {
            None
        };
        Ok(Self {
            position,
            velocity,
            status,
        })
    }
}

/// The channel part of packets 2 and 3.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct MotionData {
    /// Channels 1..4; a channel whose mask selects nothing has all fields `None`.
    pub channels: [ChannelData; CHANNELS],
}

impl MotionData {
    /// The layout's fields from full-width per-channel values.
    pub fn sample(
        masks: &[DataMask; CHANNELS],
        positions: [i32; CHANNELS],
        velocities: [i32; CHANNELS],
        statuses: [Status; CHANNELS],
    ) -> Self {
        let mut channels = [ChannelData::default(); CHANNELS];
        for (i, ch) in channels.iter_mut().enumerate() {
            if let (Some(m), Some(p), Some(v), Some(s)) = (
                masks.get(i),
                positions.get(i),
                velocities.get(i),
                statuses.get(i),
            ) {
                *ch = ChannelData::sample(*m, *p, *v, *s);
            }
        }
        Self { channels }
    }

    /// Whether every channel matches its mask.
    pub fn matches(&self, masks: &[DataMask; CHANNELS]) -> bool {
        self.channels.iter().zip(masks).all(|(c, m)| c.matches(*m))
    }

    pub(crate) fn encoded_len(&self) -> usize {
        self.channels.iter().map(ChannelData::encoded_len).sum()
    }

    pub(crate) fn write(&self, w: &mut Writer<'_>) -> Result<(), Error> {
        self.channels.iter().try_for_each(|c| c.write(w))
    }

    pub(crate) fn read(r: &mut Reader<'_>, masks: &[DataMask; CHANNELS]) -> Result<Self, Error> {
        let mut channels = [ChannelData::default(); CHANNELS];
        for (ch, mask) in channels.iter_mut().zip(masks) {
            *ch = ChannelData::read(r, *mask)?;
        }
        Ok(Self { channels })
    }
}

/// Packet 3 - Binary Stream Data.
///
/// Its text says every field is optional "except for *Return Code*", its table shows no
/// Return Code ("QuadQuad2Drv PCB Datasheet", interface protocol v1, packet 3). Both forms
/// are read: the layout gives the payload's length without one, and Packet Size says whether
/// the board sent one more byte in front (docs/ARCHITECTURE.md). Any other length is an
/// error.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct StreamData {
    /// Return Code, when the board sends one (the text's reading); `None` as the table
    /// shows the packet.
    pub code: Option<ReturnCode>,
    /// Stream Period Timing in 40.96 µs units, clipped at 0xFFFF.
    pub timing: Option<u16>,
    /// Stream Periods Elapsed since the last transmitted packet, clipped at 0xFF.
    pub periods_elapsed: Option<u8>,
    /// Channel data.
    pub data: MotionData,
}

impl StreamData {
    pub(crate) fn write(&self, w: &mut Writer<'_>) -> Result<(), Error> {
        if let Some(code) = self.code {
            w.u8(code.0)?;
        }
        if let Some(t) = self.timing {
            w.u16(t)?;
        }
        if let Some(p) = self.periods_elapsed {
            w.u8(p)?;
        }
        self.data.write(w)
    }

    /// Reads a payload of `len` bytes: with a Return Code in front when it is one byte
    /// longer than the layout's.
    pub(crate) fn read(
        r: &mut Reader<'_>,
        layout: &MotionLayout,
        len: usize,
    ) -> Result<Self, Error> {
        let code = if len == layout.stream_payload_len() + 1 {
            Some(ReturnCode(r.u8()?))
        } else {
            None
        };
        let timing = if layout.stream_config.timing() {
            Some(r.u16()?)
        } else {
            None
        };
        let periods_elapsed = if layout.stream_config.periods_elapsed() {
            Some(r.u8()?)
        } else {
            None
        };
        let data = MotionData::read(r, &layout.data_masks)?;
        Ok(Self {
            code,
            timing,
            periods_elapsed,
            data,
        })
    }

    /// Bytes of payload.
    pub fn encoded_len(&self) -> usize {
        usize::from(self.code.is_some())
            + usize::from(self.timing.is_some()) * 2
            + usize::from(self.periods_elapsed.is_some())
            + self.data.encoded_len()
    }
}

/// Presence and size of each position in a packet-11 reply.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct PositionLayout(pub [PositionSize; CHANNELS]);

impl PositionLayout {
    /// Payload length of the packet-11 reply (Return Code plus positions).
    pub fn payload_len(&self) -> usize {
        1 + self.0.iter().map(|s| s.byte_len()).sum::<usize>()
    }

    /// The layout of a reply carrying `positions`.
    pub fn of(positions: &[Option<PositionValue>; CHANNELS]) -> Self {
        let mut sizes = [PositionSize::Omitted; CHANNELS];
        for (s, p) in sizes.iter_mut().zip(positions) {
            *s = position_size_of(*p);
        }
        Self(sizes)
    }
}
