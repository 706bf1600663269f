//! Sans-I/O codec for the QuadQuad2Drv 4-channel DC motor controller and quadrature decoder
//! (SPI slave, interface protocol v1).
//!
//! The server's driver encodes [`Request`]s and decodes [`Reply`]s; the simulator in
//! `motion-sim` decodes requests and encodes replies, so both directions are here. Everything
//! works on caller slices: no I/O, no clock, no allocation.
//!
//! ```
//! use qq2drv::{Frame, Reply, ReplyLayout, Request, StreamDecoder};
//!
//! // Worked example "Read Version Numbers".
//! let mut buf = [0u8; 8];
//! let n = Request::GetVersion.encode(&mut buf)?;
//! assert_eq!(&buf[..n], &[2, 4, 1, 249]);
//!
//! // The MISO stream: filler, then the reply.
//! let mut decoder = StreamDecoder::new();
//! decoder.push(&[0, 0, 0, 2, 8, 1, 0, 0, 1, 0, 244]);
//! let packet = decoder.next_packet().expect("a whole packet");
//! let reply = Reply::decode(packet.frame(), &ReplyLayout::default())?;
//! assert!(matches!(reply, Reply::Version { firmware_minor: 1, .. }));
//! # Ok::<(), qq2drv::Error>(())
//! ```
//!
//! # Datasheet coverage
//! - "Packet Format": [`Frame`], [`checksum`], [`StreamDecoder`] (finds STX after filler or
//!   garbage, rejects impossible sizes, undocumented ids and bad checksums, counts them).
//! - Packets 1–14, 16, 18, 20, 22, 24, 26, 28, 30, 32, 34, 36: every send form as a
//!   [`Request`] variant, every reply as a [`Reply`] variant (set/ramp packets answer
//!   [`Reply::Ack`]). Multi-entry payloads ("any number of Channel Mask and … pairs") are
//!   [`Entries`]. The three forms of packet 11 are [`GetPosition`].
//! - Packets 2 and 3: [`MotionData`], [`StreamData`] under any [`MotionLayout`] (data masks
//!   with 8/16/32-bit or omitted position, relative mode, velocity, [`Status`] bits; stream
//!   config timing fields).
//! - Bit fields: [`ChannelMask`], [`DataMask`], [`StreamConfig`], [`Status`],
//!   [`InputConfig`] (mode, polarity, edge), [`ControlMode`]; ranges, units and defaults in
//!   [`limits`].
//!
//! # Interpretations
//! Where the datasheet is silent or contradicts itself this crate follows
//! `docs/ARCHITECTURE.md`, "How we read the datasheets": the checksum makes the byte sum zero,
//! fields are little-endian, return code 0 is success, packet 3 is read with or without a
//! Return Code (its text and its table disagree; Packet Size tells), packet 18
//! Power is I16, packets 22/36 velocities are plain transitions/s while 26/34 velocities and
//! all accelerations are shl 12, and the packet-14 Position is omitted in Disabled mode.
//! Packet 36's I32 Velocity with "Range: 0 - 100,000" is read either way, as the caller
//! says ([`limits::VelocityRampSign`]).
//! Two more of our own: the reply to packet 11 in its one-byte (channel mask) form carries
//! 32-bit positions (the datasheet gives no size), and a get request that fails is answered
//! by its Return Code alone ([`Reply::Ack`] with a non-zero code).
//!
//! # Fuzzing
//! `fuzz/` is a standalone cargo-fuzz project with one target per decoder:
//! `cd crates/protocols/qq2drv/fuzz && cargo +nightly fuzz run request` (also `reply`,
//! `stream`).
#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod decoder;
mod entries;
mod error;
mod fields;
mod frame;
pub mod limits;
mod motion;
mod reply;
mod request;
mod wire;

pub use decoder::{DecoderStats, StreamDecoder};
pub use entries::{
    AccelerationLimitEntry, ControlModeEntry, DataMaskEntry, Entries, Entry, EntryIter,
    InputModeEntry, MotorPowerEntry, PositionPidEntry, PositionRampEntry, PositionTargetEntry,
    PowerLimitEntry, SetPositionEntry, VelocityLimitEntry, VelocityPidEntry, VelocityRampEntry,
    VelocityTargetEntry,
};
pub use error::Error;
pub use fields::{
    CHANNELS, ChannelMask, ControlMode, DataMask, EdgeAction, HistoryDimensions, InputConfig,
    InputMode, PositionSize, PositionValue, ReturnCode, Status, StreamConfig, position_size_of,
};
pub use frame::{
    Frame, HEADER_LEN, MAX_PACKET_LEN, MAX_PAYLOAD_LEN, MIN_PACKET_LEN, PacketBuf, PacketId, STX,
    checksum,
};
pub use motion::{ChannelData, MotionData, MotionLayout, PositionLayout, StreamData};
pub use reply::{Reply, ReplyLayout};
pub use request::{GetPosition, Request};
