//! Sans-I/O codec for the US Digital QSB-S, QSB-D and QSB-M encoder interfaces (the -M
//! also drives a stepper motor), as documented in the "QSB Command List", document version
//! 1.28 (`usdigital-qsb-command-list.txt` in the shared seeds).
//!
//! The QSB talks ASCII over a USB virtual COM port (230400 baud, 8N1 by default). The host
//! sends command lines `R|W|S`, two hex digits of register, optional hex data, CR/LF; the
//! board answers each with a response line: lower-case type, register, eight hex digits of
//! data, optional time stamp, `!`, then the EOR termination it was told to use. A streamed
//! register keeps producing `s` lines until a read of it (or COMMAND 0/1) stops it.
//!
//! This crate does no I/O, reads no clock and never allocates: it encodes into the
//! caller's `&mut [u8]` and decodes from `&[u8]`. Both directions are covered, so the
//! driver and the simulator share every protocol fact:
//!
//! - [`CommandLine`] / [`Request`] (typed, with [`Write`]): host → board;
//! - [`Response`] / [`Value`] (typed): board → host, in every EOR format;
//! - [`CommandDecoder`] and [`ResponseDecoder`]: incremental decoders that resynchronise
//!   after garbage and over-long lines;
//! - [`Register`]: the register map 00–16, the command types each accepts, the products
//!   that have it, factory defaults, what streams and how;
//! - typed register values: [`Mode`], [`DigIo`], [`DigIoConfig`], [`Mdr0`], [`Mdr1`],
//!   [`Str`], [`IntervalRate`], [`Eor`], [`MdStatus`], [`Version`], [`QsbCommand`] (with
//!   [`BaudRate`]), [`ClearTarget`], [`LoadTarget`], and the special analog data format
//!   [`AnalogSample`].
//!
//! ```
//! use qsb::{CommandDecoder, Eor, Register, Request, Response, ResponseDecoder,
//!           ResponseType, Value};
//!
//! // Host: ask for the VERSION register.
//! let mut out = [0u8; qsb::MAX_COMMAND_LEN];
//! let n = Request::Read(Register::Version).encode(&mut out).unwrap();
//! assert_eq!(&out[..n], b"R14\r\n");
//!
//! // Board: decode the command and answer in the factory EOR format.
//! let mut rx = CommandDecoder::new();
//! let (_, line) = rx.decode(&out[..n]);
//! let request = Request::from_line(&line.unwrap().unwrap()).unwrap();
//! assert_eq!(request, Request::Read(Register::Version));
//! let mut reply = [0u8; qsb::MAX_RESPONSE_LEN];
//! let m = Response::new(ResponseType::Read, 0x14, 0x0000_1201)
//!     .encode(Eor::FACTORY, &mut reply)
//!     .unwrap();
//! assert_eq!(&reply[..m], b"r 14 00001201 !\r\n");
//!
//! // Host: decode the reply, surfacing `e`/`x` answers as errors.
//! let mut tx = ResponseDecoder::new();
//! let (_, response) = tx.decode(&reply[..m]);
//! let Value::Version(v) = response.unwrap().value().unwrap() else { panic!() };
//! assert_eq!((v.serial, v.product, v.firmware), (1, qsb::ProductType::S, 0x01));
//! ```
//!
//! # Coverage of the command list
//!
//! "Serial Communication", "Command Format", "Command Acknowledgement Format", "Special
//! Analog Measurement Command Acknowledgement Data Format", "Factory Default Command
//! Parameter Values" and every register of the "Command List", 00 MODE to 16 COMMAND.
//! Timing constants: [`TICK`] (1/512 s), [`ANALOG_TICK`], [`PROCESSING_DELAY`] and
//! [`ANALOG_PROCESSING_DELAY`].
//!
//! # Interpretations
//!
//! Where the command list is silent or contradicts itself, this crate follows the
//! decisions in `docs/ARCHITECTURE.md` ("How we read the datasheets", QSB), and these:
//!
//! - Time stamp ticks are 1/512 s (1.953125 ms), as the TIME STAMP and INTERVAL RATE
//!   registers say; the "(1/256 Hz)" of the acknowledgement section is a slip.
//! - With both CR and LF enabled, CR is sent first. The time stamp goes between the data
//!   and `!`; with spaces enabled a space follows every field, so `!` is preceded by one.
//! - `x` answers unknown registers, command types a register does not accept, registers
//!   the product lacks and lines that cannot be parsed; `e` answers data outside a
//!   register's documented range or meaning (MODE type `11`, MDR1 reserved bits, COMMAND
//!   functions the product lacks) and writes without data. See [`Request::from_line`].
//! - A backspace discards the whole partial command.
//! - The special analog data format replaces the data of streamed READ ENCODER lines in
//!   analog mode; a plain read returns the 10-bit value.
//! - Returned data is always eight digits, also for PWM values (the "4 character" note of
//!   READ ENCODER contradicts the acknowledgement format).
//!
//! # Fuzzing
//!
//! `fuzz/` is a standalone cargo-fuzz project with one target per decoder:
//! `cd crates/protocols/qsb/fuzz && cargo +nightly fuzz run command_decoder` (or
//! `response_decoder`, `typed`).
#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod command;
mod counter;
mod decoder;
mod error;
mod hex;
mod motor;
mod register;
mod response;
mod values;

pub use command::{CommandLine, EOC, MAX_COMMAND_LEN, Request, TIME_STAMP_CLEAR, Write};
pub use counter::{ClearTarget, CountMode, CycleMode, IndexMode, LoadTarget, Mdr0, Mdr1, Str};
pub use decoder::{BACKSPACE, COMMAND_LINE_CAPACITY, CommandDecoder, ResponseDecoder};
pub use error::Error;
pub use motor::{
    ACCEL_RANGE, BaudRate, JOG_RATE_RANGE, MOVE_STEPS_RANGE, MdStatus, QsbCommand, RATE_INCREMENT,
    STEP_RATE_RANGE, effective_rate,
};
pub use register::{CommandType, ProductType, Register, StreamTrigger};
pub use response::{MAX_RESPONSE_LEN, Response, ResponseType, Value};
pub use values::{
    ANALOG_PROCESSING_DELAY, ANALOG_TICK, AnalogSample, DigIo, DigIoConfig, EncoderMode, Eor,
    IntervalRate, Mode, PROCESSING_DELAY, TICK, Version,
};

/// Factory default register values ("Factory Default Command Parameter Values").
pub mod defaults {
    /// 00 MODE.
    pub const MODE: u32 = 0x00;
    /// 01 DIG I/O.
    pub const DIG_IO: u32 = 0xF;
    /// 02 DIG I/O CONFIG.
    pub const DIG_IO_CONFIG: u32 = 0x0000;
    /// 03 MDR0: x4, modulo-n, index disabled, synchronous index.
    pub const MDR0: u32 = 0x4F;
    /// 04 MDR1.
    pub const MDR1: u32 = 0x000;
    /// 05 CAPTURE.
    pub const CAPTURE: u32 = 0;
    /// 06 STR: count enabled, counting up.
    pub const STR: u32 = 0x0A;
    /// 07 OTR.
    pub const OTR: u32 = 0;
    /// 08 DTR: 499.
    pub const DTR: u32 = 0x1F3;
    /// 0B THRESHOLD.
    pub const THRESHOLD: u32 = 0x0000;
    /// 0C INTERVAL RATE: output disabled.
    pub const INTERVAL_RATE: u32 = 0xFFFF;
    /// 0E READ ENCODER.
    pub const READ_ENCODER: u32 = 0;
    /// 0F MD STEP RATE: 32 steps/s.
    pub const MD_STEP_RATE: u32 = 0x20;
    /// 10 MD ACCEL: 100 000 steps/s².
    pub const MD_ACCEL: u32 = 0x186A0;
    /// 11 MD MOVE STEPS.
    pub const MD_MOVE_STEPS: u32 = 0;
    /// 12 MD JOG RATE: 32 steps/s.
    pub const MD_JOG_RATE: u32 = 0x20;
    /// 13 MD STATUS: done.
    pub const MD_STATUS: u32 = 0x1;
    /// 15 EOR: CR, LF, spaces.
    pub const EOR: u32 = 0xB;
    /// The factory data rate.
    pub const BAUD: u32 = 230_400;
}
