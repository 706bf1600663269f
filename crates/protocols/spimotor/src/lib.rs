//! Sans-I/O codec for the BitWizard-style **SPI_motor** board: two brushed motors or one
//! stepper on an SPI bus shared by address byte.
//!
//! Every byte motiond sends to an SPI_motor board, and every byte the simulator
//! (`motion-sim`) answers with, goes through this crate. It encodes into caller slices and
//! decodes from `&[u8]`; it does no I/O, reads no clock and never allocates.
//!
//! # The wire
//!
//! One SPI transaction (one chip-select assertion) is
//!
//! | offset | MOSI (host → board)                          | MISO (board → host)      |
//! |--------|----------------------------------------------|--------------------------|
//! | 0      | address byte: even address, bit 0 set = read | nothing (not yet selected) |
//! | 1      | port byte                                    | nothing (port not yet known) |
//! | 2…     | write: data; read: [`DUMMY`] bytes           | read: the answer, then [`PAD`] |
//!
//! Multi-byte values are little-endian: the datasheet's example writes 0x12345678 as
//! `78 56 34 12`. Positions are 32-bit two's complement ([`i32`]): a relative move must be
//! able to go backwards.
//!
//! ## Where the answer appears on MISO
//!
//! SPI is full duplex: while the host shifts a byte in on MOSI, the board shifts one out on
//! MISO. The board only knows it is selected once the address byte is in, and only knows
//! *what* to answer once the port byte is in; so the earliest byte that can carry the
//! answer is the one clocked right after the port byte, offset [`REPLY_OFFSET`] = 2. This is
//! exactly the datasheet's "read identification" table: `0x91 / xx`, `0x01 / xx`,
//! `xx / 0x73 's'`. The bytes at offsets 0 and 1 are "xx" (don't care) and the decoder
//! ignores them. The board cannot know how many bytes the host will clock either: it
//! clocks out the answer for as long as the host clocks, so a host reads a value by
//! clocking as many [`DUMMY`] bytes as the value is long ([`ReadPort::default_len`]).
//!
//! Nothing in an answer tells a present board from an absent one: an undriven MISO line
//! reads 0xFF, which decodes as position −1. A driver identifies its boards by reading
//! port 0x01: 0xFF bytes never terminate the string ([`Error::Unterminated`]).
//!
//! (A real board's AVR must reload its shift register between the port byte and the first
//! answer byte; a host on real hardware may need a short pause there. The simulator
//! answers at any clock rate.)
//!
//! # Example
//!
//! ```
//! use spimotor::{Address, ReadPort, Reply, Transaction, Write};
//!
//! // Move the stepper to step 0x12345678 (datasheet example "move stepper to step 0x12345678").
//! let mut mosi = [0u8; 40];
//! let n = Transaction::write(Address::DEFAULT, Write::TargetPosition(0x1234_5678))
//!     .encode(&mut mosi)?;
//! assert_eq!(&mosi[..n], &[0x90, 0x41, 0x78, 0x56, 0x34, 0x12]);
//!
//! // Read the identification string: address 0x91, port 0x01, then dummy bytes.
//! let read = Transaction::read(Address::DEFAULT, ReadPort::Identification);
//! let n = read.encode(&mut mosi)?;
//! assert_eq!(&mosi[..3], &[0x91, 0x01, 0x00]);
//!
//! // What a board clocks back on MISO: two don't-care bytes, then the string and its 0.
//! let mut miso = [0xffu8; 40];
//! miso[2..12].copy_from_slice(b"spi_motor\0");
//! let Reply::Identification(id) = Reply::decode(ReadPort::Identification, &miso[..n])? else {
//!     unreachable!("a read of port 0x01 decodes to an identification");
//! };
//! assert_eq!(id.as_str(), Some("spi_motor"));
//!
//! // A simulator decodes the MOSI side the same way.
//! assert_eq!(Transaction::decode(&mosi[..n])?, read);
//! # Ok::<(), spimotor::Error>(())
//! ```
//!
//! # Datasheet coverage (`spi-motor-protocol.txt`)
//!
//! - "Introduction": address byte with the read/write bit ([`Address`], [`Access`]), port
//!   byte ([`Header`]), boards ignoring other addresses ([`Header::decode`] gives the
//!   address before anything else is decoded).
//! - "write ports": 0x10 ([`Write::StepperIntensity`]), 0x20/0x21/0x30/0x31
//!   ([`Write::Spin`]), 0x22/0x32 ([`Write::Stop`]), 0x40 ([`Write::CurrentPosition`]),
//!   0x41 ([`Write::TargetPosition`]), 0x42 ([`Write::RelativePosition`]), 0x43
//!   ([`Write::StepDelay`]), 0x44 ([`Write::Coils`]), 0xf1 ← 0x55
//!   ([`Write::UnlockAddress1`]), 0xf2 ← 0xaa ([`Write::UnlockAddress2`]), 0xf0 ← new
//!   address ([`Write::ChangeAddress`]).
//! - "read ports": 0x01 ([`ReadPort::Identification`], [`Identification`]), 0x02
//!   ([`ReadPort::Serial`], [`SerialNumber`]), 0x40, 0x41 (positions), 0x43 ([`StepDelay`]).
//! - "examples": both byte tables are golden-vector tests (`tests/golden.rs`).
//!
//! # Interpretations
//!
//! Where the datasheet is silent or contradicts itself, this crate follows `docs/ARCHITECTURE.md`
//! ("How we read the datasheets", SPI_motor): little-endian values; ports 0x43 and 0x44 take
//! one byte; the step delay is in tenths of a millisecond both ways; the unlock sequence is
//! 0x55 → 0xf1, 0xaa → 0xf2, new address → 0xf0. Further readings of this crate:
//!
//! - The answer starts at MISO offset 2 (above).
//! - Stop ports (0x22, 0x32) carry no data: the table lists none.
//! - One-byte ports written with several bytes take the last one ("writing more than one
//!   byte to such a port is redundant"); 4-byte ports take exactly 4.
//! - Port 0x44: any non-zero byte means two coils; this crate writes 0x01.
//! - The serial number (0x02) is 4 bytes little-endian; the datasheet gives no width.
//! - A new address (0xf0) must be even: bit 0 of the address byte is the read flag.
//! - Positions are signed 32-bit.
//!
//! There is no byte stream on this board (every exchange is one transaction), so there is
//! no incremental decoder: [`Transaction::decode`] takes one whole MOSI transaction and
//! [`Reply::decode`] one whole MISO answer. Both reject malformed input with an [`Error`]
//! and never panic.
//!
//! # Fuzzing
//!
//! `fuzz/` is a standalone cargo-fuzz project with one target per decoder
//! (`decode_transaction`, `decode_reply`). With a nightly toolchain and cargo-fuzz:
//!
//! ```text
//! cd crates/protocols/spimotor/fuzz
//! cargo +nightly fuzz run decode_transaction
//! cargo +nightly fuzz run decode_reply
//! ```
#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod address;
mod error;
pub mod port;
mod reply;
mod request;
mod value;

pub use address::{Access, Address, Header};
pub use error::Error;
pub use reply::{PAD, REPLY_OFFSET, Reply};
pub use request::{
    DUMMY, IDENTIFICATION_READ_LEN, MAX_DATA_LEN, Read, ReadPort, Request, Transaction, Write,
};
pub use value::{
    Coils, Direction, IDENTIFICATION_CAPACITY, Identification, Motor, SerialNumber, StepDelay,
};
