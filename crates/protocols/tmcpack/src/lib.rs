//! Sans-I/O codec for the Trinamic SIXpack (6 steppers) and QUADpack (4 steppers)
//! controllers, as described in their manual (V2.43, seed
//! `trinamic-sixpack-quadpack-manual.txt`).
//!
//! The pack speaks 9-byte words on RS-232 / RS-485 (19200 baud by default) and 8-byte
//! telegrams on CAN 2.0A. This crate turns them into typed values and back: it encodes into
//! the caller's slices, decodes from `&[u8]`, never allocates, never does I/O and never reads
//! a clock (the stream decoder takes the time as an argument). The motiond driver decodes
//! replies with it and the simulator in `motion-sim` decodes requests with it, so every
//! protocol fact lives here once.
//!
//! ```
//! use tmcpack::{Reply, ReplyFrame, Request, RequestFrame};
//!
//! // Manual 7.2 "Starting a two axis interpolated movement": set motor 0's target to 1000
//! // ($03E8) with $26, then start the interpolation of motors 0 and 1 with $50 mask 3.
//! let set = RequestFrame::new(1, Request::SetTarget { motor: 0, target: 1000 });
//! let mut buf = [0u8; 9];
//! assert_eq!(set.encode(&mut buf)?, 9);
//! assert_eq!(buf, [0x01, 0x26, 0x00, 0xE8, 0x03, 0x00, 0x00, 0x00, 0x00]);
//! assert_eq!(RequestFrame::decode(&buf)?, set);
//!
//! // A $20 position reply, sent to response address 0xFE.
//! let reply = ReplyFrame::decode(&[0xFE, 0x20, 0x01, 0xD0, 0x07, 0x00, 0x00, 0x05, 0x00])?;
//! assert!(matches!(reply.reply, Reply::Position { motor: 1, position: 2000, .. }));
//! # Ok::<(), tmcpack::Error>(())
//! ```
//!
//! # Coverage (manual sections)
//!
//! - 6.1 word format (address, command, P0..P6), packet timeout and break resync:
//!   [`RequestFrame`], [`ReplyFrame`], [`FrameDecoder`].
//! - 6.2 / 6.3 CAN telegrams (identifier = address << 3, the response identifier = the
//!   query's response address << 3, RS-232 forwarding `…001`, CAN bit-rate jumpers, the
//!   16-command cache at about 2 ms a command): [`CanFrame`], [`can_id`],
//!   [`can_command_id`], [`CanBitrate`], [`CAN_CACHE_COMMANDS`], [`CAN_COMMAND_TIME`].
//! - 8.3–8.8 and the section 9 table, every instruction $10–$19, $20–$2A, $30–$33,
//!   $40–$45, $50, $CC, $F2–$F7: [`Request`], [`Command`]; every tabled response ($20,
//!   $21, $28, $30, $43, $44, $45, $F2, $F4, $F5, $F6, $F7): [`Reply`]; the $15 and $16
//!   bitfields: [`MotorType`], [`MotorOptions`], [`ReferenceFlags`]; actions: [`Action`].
//! - 8.3 `$17` motor characteristics table (the factory sine, four requests per table, the
//!   coil currents a table gives): [`table`]; 8.6 `$45` power-down on the firmware
//!   revisions that have it: [`power_down_supported`].
//! - 8.2 microstep frequency and the $14 acceleration with the 200 kHz and ±511 limits,
//!   $40 baud divisor, $10 current, channel 7 supply scale: [`StepClock`], [`convert`].
//!
//! # Interpretations
//!
//! The team's readings of the manual are in `docs/ARCHITECTURE.md`, "How we read the datasheets"
//! (9-byte words both ways, LSB first, unused bytes zero; the step-rate formula; one request
//! in flight). Where the manual is silent this crate chooses, and says so:
//!
//! - Requests are validated against the tabled ranges on encode and on decode (a word out of
//!   range is an error, not clamped); unused bytes are ignored when decoding.
//! - $15 `poslimit` is tabled as "0..0x7FFFFFF"; we accept the full positive 32-bit range.
//! - $14 says amax/64 is accumulated at 500 Hz; the 7.1 defaults comment "128/16=8" disagrees.
//!   Both readings are [`AmaxDivisor`] (the $14 text's 64 by default); the caller says
//!   which its pack follows.
//! - $15 P6 StopNoRef is bit 5 in the table and bit 6 in the prose: both readings are
//!   [`OptionsLayout`] (the table's by default), which maps [`MotorOptions`] onto the byte.
//! - The $41 timeout has no documented default: [`DEFAULT_PACKET_TIMEOUT`] is 20 ms.
//! - $F7 (read EEPROM) is tabled with the same parameters and response as $F6; we encode it
//!   as tabled.
//! - $CC P0 is labelled "HW-Reset" without a value; we send 0 and ignore it when decoding.
//!
//! # Fuzzing
//!
//! `fuzz/` is a standalone cargo-fuzz project with one target per decoder
//! (`request`, `reply`, `stream`, `can`) and one for the CAN command cache (`can_cache`):
//!
//! ```text
//! cd crates/protocols/tmcpack/fuzz && cargo +nightly fuzz run stream
//! ```
#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod can;
mod command;
pub mod convert;
mod decoder;
mod error;
#[macro_use]
mod params;
mod reply;
mod request;
pub mod table;
mod types;

pub use can::{
    CAN_CACHE_COMMANDS, CAN_COMMAND_TIME, CAN_DEFAULT_BITRATE, CAN_ID_MAX, CAN_ID_MIN, CAN_LEN,
    CanCache, CanChannel, CanFrame, can_command_id, can_id, split_can_id,
};
pub use command::Command;
pub use convert::{AmaxDivisor, StepClock, Variant};
pub use decoder::{DEFAULT_PACKET_TIMEOUT, DecoderStats, FrameDecoder, Words};
pub use error::Error;
pub use reply::{MAX_ANALOG, Reply, ReplyFrame};
pub use request::{
    MAX_AMAX, MAX_CHANNEL, MAX_CLKDIV, MAX_DIV, MAX_POSLIMIT, MAX_SWITCHOVER, MAX_VELOCITY,
    Request, RequestFrame,
};
pub use types::{
    Action, CanBitrate, CurrentLevel, MAX_MOTOR, MotorMask, MotorOptions, MotorType, OptionsLayout,
    PowerDownRequest, PowerDownStatus, RefInputs, ReferenceFlags, check_motor,
    power_down_supported,
};

/// Length of a word on RS-232 / RS-485, requests and replies alike.
pub const FRAME_LEN: usize = 9;

/// One 9-byte word.
pub type Word = [u8; FRAME_LEN];
