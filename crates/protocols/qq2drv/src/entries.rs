//! Multi-entry payloads: "Any number of Channel Mask and … pairs can be concatenated".
//!
//! A request holds its entries either as a typed slice (when the host builds it) or as the
//! validated wire bytes (when decoded), so neither direction allocates.

use core::fmt;

use crate::error::Error;
use crate::fields::{
    ChannelMask, ControlMode, DataMask, InputConfig, InputMode, PositionSize, PositionValue,
    position_size_of,
};
use crate::wire::{Reader, Writer};

/// One entry of a multi-entry payload.
pub trait Entry: Copy + PartialEq + fmt::Debug {
    /// Bytes this entry takes on the wire.
    fn encoded_len(&self) -> usize;
    /// Writes the entry at the start of `buf`; returns the bytes written.
    fn encode(&self, buf: &mut [u8]) -> Result<usize, Error>;
    /// Reads one entry from the start of `bytes`; returns it and the bytes it took.
    fn decode(bytes: &[u8]) -> Result<(Self, usize), Error>;
}

/// A non-empty list of entries, borrowed either as typed values or as validated wire bytes.
#[derive(Clone, Copy)]
pub struct Entries<'a, T> {
    repr: Repr<'a, T>,
}

#[derive(Clone, Copy)]
enum Repr<'a, T> {
    Typed(&'a [T]),
    Wire(&'a [u8]),
}

impl<'a, T: Entry> Entries<'a, T> {
    /// Entries to encode. The datasheet requires at least one; encoding an empty list fails.
    pub const fn new(entries: &'a [T]) -> Self {
        Self {
            repr: Repr::Typed(entries),
        }
    }

    /// Validates a whole payload as a sequence of at least one entry.
    pub(crate) fn from_wire(payload: &'a [u8]) -> Result<Self, Error> {
        if payload.is_empty() {
            return Err(Error::Length);
        }
        let mut rest = payload;
        while !rest.is_empty() {
            let (_, used) = T::decode(rest)?;
            rest = rest.get(used..).ok_or(Error::Length)?;
        }
        Ok(Self {
            repr: Repr::Wire(payload),
        })
    }

    /// The entries in order.
    pub fn iter(&self) -> EntryIter<'a, T> {
        match self.repr {
            Repr::Typed(s) => EntryIter::Typed(s.iter()),
            Repr::Wire(b) => EntryIter::Wire(b),
        }
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        match self.repr {
            Repr::Typed(s) => s.len(),
            Repr::Wire(_) => self.iter().count(),
        }
    }

    /// True when there is no entry (only possible for a typed list).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    pub(crate) fn write(&self, w: &mut Writer<'_>) -> Result<(), Error> {
        match self.repr {
            Repr::Wire(b) => w.bytes(b),
            Repr::Typed([]) => Err(Error::Inconsistent),
            Repr::Typed(s) => {
                let mut tmp = [0u8; 16];
                for e in s {
                    let n = e.encode(&mut tmp)?;
                    w.bytes(tmp.get(..n).ok_or(Error::BufferTooSmall)?)?;
                }
                Ok(())
            }
        }
    }
}

impl<T: Entry> PartialEq for Entries<'_, T> {
    fn eq(&self, other: &Self) -> bool {
        self.iter().eq(other.iter())
    }
}

impl<T: Entry> fmt::Debug for Entries<'_, T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.iter()).finish()
    }
}

/// Iterator over [`Entries`].
#[derive(Debug, Clone)]
pub enum EntryIter<'a, T> {
    /// Over typed values.
    Typed(core::slice::Iter<'a, T>),
    /// Over validated wire bytes.
    Wire(&'a [u8]),
}

impl<T: Entry> Iterator for EntryIter<'_, T> {
    type Item = T;

    fn next(&mut self) -> Option<T> {
        match self {
            Self::Typed(it) => it.next().copied(),
            Self::Wire(bytes) => {
                let (e, used) = T::decode(bytes).ok()?;
                *bytes = bytes.get(used..).unwrap_or_default();
                Some(e)
            }
        }
    }
}

fn encode_with(
    buf: &mut [u8],
    f: impl FnOnce(&mut Writer<'_>) -> Result<(), Error>,
) -> Result<usize, Error> {
    let mut w = Writer::new(buf);
    f(&mut w)?;
    Ok(w.written())
}

fn decode_with<T>(
    bytes: &[u8],
    f: impl FnOnce(&mut Reader<'_>) -> Result<T, Error>,
) -> Result<(T, usize), Error> {
    let mut r = Reader::new(bytes);
    let v = f(&mut r)?;
    Ok((v, bytes.len() - r.remaining()))
}

/// Declares a fixed-layout entry: a Channel Mask followed by little-endian fields.
macro_rules! fixed_entry {
    ($(#[$doc:meta])* $name:ident { $($(#[$fdoc:meta])* $field:ident : $ty:ident),+ $(,)? }) => {
        $(#[$doc])*
        #[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
        pub struct $name {
            /// Channels the entry applies to.
            pub channels: ChannelMask,
            $($(#[$fdoc])* pub $field: $ty,)+
        }

        impl Entry for $name {
            fn encoded_len(&self) -> usize {
                1 $(+ core::mem::size_of::<$ty>())+
            }

            fn encode(&self, buf: &mut [u8]) -> Result<usize, Error> {
                encode_with(buf, |w| {
                    w.u8(self.channels.0)?;
                    $(w.$ty(self.$field)?;)+
                    Ok(())
                })
            }

            fn decode(bytes: &[u8]) -> Result<(Self, usize), Error> {
                decode_with(bytes, |r| {
                    Ok(Self { channels: ChannelMask(r.u8()?), $($field: r.$ty()?,)+ })
                })
            }
        }
    };
}

fixed_entry!(
    /// Packet 18 entry: motor output power, sign is direction, range ±8191 (I16, docs/ARCHITECTURE.md).
    MotorPowerEntry { /** Power. */ power: i16 }
);
fixed_entry!(
    /// Packet 20 entry: position target in quadrature transitions.
    PositionTargetEntry { /** Position Target. */ position: i32 }
);
fixed_entry!(
    /// Packet 22 entry: velocity target in plain transitions/s (docs/ARCHITECTURE.md).
    VelocityTargetEntry { /** Velocity Target, transitions/s. */ velocity: i32 }
);
fixed_entry!(
    /// Packet 24 entry: power limit 0..=8191.
    PowerLimitEntry { /** Power Limit. */ limit: u16 }
);
fixed_entry!(
    /// Packet 26 entry: velocity limit, transitions/s shl 12.
    VelocityLimitEntry { /** Velocity Limit, transitions/s shl 12. */ limit: u32 }
);
fixed_entry!(
    /// Packet 28 entry: acceleration limit, transitions/s² shl 12; 0 disables limiting.
    AccelerationLimitEntry { /** Acceleration Limit, transitions/s² shl 12. */ limit: u32 }
);
fixed_entry!(
    /// Packet 30 entry: position PID constants and integration windup limit.
    PositionPidEntry {
        /** Proportional constant (default 100). */ p: u16,
        /** Integration constant (default 500). */ i: u16,
        /** Differential constant (default 500). */ d: u16,
        /** Integration windup limit 0..=8191 (default 600). */ windup: u16,
    }
);
fixed_entry!(
    /// Packet 32 entry: velocity PID constants.
    VelocityPidEntry {
        /** Proportional constant (default 100). */ p: u16,
        /** Integration constant (default 200). */ i: u16,
        /** Differential constant (default 500). */ d: u16,
    }
);
fixed_entry!(
    /// Packet 34 entry: ramp to a position at a velocity (shl 12) and acceleration (shl 12).
    PositionRampEntry {
        /** Position target. */ position: i32,
        /** Velocity, transitions/s shl 12. */ velocity: u32,
        /** Acceleration, transitions/s² shl 12; 0 = not limited by the ramp. */ acceleration: u32,
    }
);
fixed_entry!(
    /// Packet 36 entry: ramp to a velocity (plain transitions/s) at an acceleration (shl 12).
    VelocityRampEntry {
        /** Velocity target, transitions/s. */ velocity: i32,
        /** Acceleration, transitions/s² shl 12; 0 = ignored. */ acceleration: u32,
    }
);

/// Packet 6 entry: apply a Data Mask to the selected channels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct DataMaskEntry {
    /// Channels the mask applies to.
    pub channels: ChannelMask,
    /// The data mask.
    pub mask: DataMask,
}

impl Entry for DataMaskEntry {
    fn encoded_len(&self) -> usize {
        2
    }

    fn encode(&self, buf: &mut [u8]) -> Result<usize, Error> {
        encode_with(buf, |w| w.bytes(&[self.channels.0, self.mask.0]))
    }

    fn decode(bytes: &[u8]) -> Result<(Self, usize), Error> {
        decode_with(bytes, |r| {
            Ok(Self {
                channels: ChannelMask(r.u8()?),
                mask: DataMask(r.u8()?),
            })
        })
    }
}

/// Packet 16 entry: control mode for the selected channels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ControlModeEntry {
    /// Channels the mode applies to.
    pub channels: ChannelMask,
    /// The control mode.
    pub mode: ControlMode,
}

impl Entry for ControlModeEntry {
    fn encoded_len(&self) -> usize {
        2
    }

    fn encode(&self, buf: &mut [u8]) -> Result<usize, Error> {
        encode_with(buf, |w| w.bytes(&[self.channels.0, self.mode as u8]))
    }

    fn decode(bytes: &[u8]) -> Result<(Self, usize), Error> {
        decode_with(bytes, |r| {
            Ok(Self {
                channels: ChannelMask(r.u8()?),
                mode: ControlMode::try_from(r.u8()?)?,
            })
        })
    }
}

/// Packet 10 entry: Channel & Size Mask (bits 5..4 size, 3..0 channels) and the position.
///
/// `position: None` is size 0x00: "Position omitted and assumed zero". Bits 7..6 are unused
/// and sent as zero; the whole 32-bit counter is overwritten whatever the size.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SetPositionEntry {
    /// Channels to write (bits 3..0 only).
    pub channels: ChannelMask,
    /// The value and its size; `None` writes zero.
    pub position: Option<PositionValue>,
}

impl SetPositionEntry {
    /// The value the channel counters are set to.
    pub fn value(&self) -> i32 {
        self.position.map_or(0, PositionValue::get)
    }
}

impl Entry for SetPositionEntry {
    fn encoded_len(&self) -> usize {
        1 + position_size_of(self.position).byte_len()
    }

    fn encode(&self, buf: &mut [u8]) -> Result<usize, Error> {
        if self.channels.0 > 0x0F {
            return Err(Error::InvalidField);
        }
        encode_with(buf, |w| {
            w.u8((position_size_of(self.position) as u8) << 4 | self.channels.0)?;
            match self.position {
                Some(p) => p.write(w),
                None => Ok(()),
            }
        })
    }

    fn decode(bytes: &[u8]) -> Result<(Self, usize), Error> {
        decode_with(bytes, |r| {
            let head = r.u8()?;
            let size = PositionSize::from_bits(head >> 4);
            Ok(Self {
                channels: ChannelMask(head & 0x0F),
                position: size.read(r)?,
            })
        })
    }
}

/// Packet 14 entry: Channel Mask, Input Configuration, Spacing and Position.
///
/// Position is not sent when the Input Mode is Disabled (docs/ARCHITECTURE.md); it then decodes as 0
/// and must be 0 to encode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct InputModeEntry {
    /// Channels the configuration applies to.
    pub channels: ChannelMask,
    /// Edge, polarity and mode.
    pub config: InputConfig,
    /// Hysteresis between the two ends; 0 means a single end-stop.
    pub spacing: u16,
    /// Value written into the position counter on a trigger (if the Edge field says so).
    pub position: i32,
}

impl InputModeEntry {
    fn has_position(&self) -> bool {
        self.config.mode() != InputMode::Disabled
    }
}

impl Entry for InputModeEntry {
    fn encoded_len(&self) -> usize {
        if self.has_position() { 8 } else { 4 }
    }

    fn encode(&self, buf: &mut [u8]) -> Result<usize, Error> {
        if !self.has_position() && self.position != 0 {
            return Err(Error::Inconsistent);
        }
        encode_with(buf, |w| {
            w.u8(self.channels.0)?;
            w.u8(self.config.0)?;
            w.u16(self.spacing)?;
            if self.has_position() {
                w.i32(self.position)
            } else {
                Ok(())
            }
        })
    }

    fn decode(bytes: &[u8]) -> Result<(Self, usize), Error> {
        decode_with(bytes, |r| {
            let channels = ChannelMask(r.u8()?);
            let config = InputConfig(r.u8()?);
            let spacing = r.u16()?;
            let position = if config.mode() == InputMode::Disabled {
                0
            } else {
                r.i32()?
            };
            Ok(Self {
                channels,
                config,
                spacing,
                position,
            })
        })
    }
}
