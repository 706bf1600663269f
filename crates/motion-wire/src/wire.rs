//! The payloads of `motion-ipc` as bytes on the network: exactly their C layout (every field
//! at its `#[repr(C)]` offset, padding zero, `size_of::<T>()` bytes), every number
//! little-endian whatever the host. A C, C++ or Python peer reads a frame off the network
//! with the same struct it maps out of shared memory (on a little-endian machine), or field
//! by field from the offsets tabled in `motion-ipc`'s docs.
//!
//! Encoding and decoding are plain safe code, number by number, at the offsets the compiler
//! gives: the codec walks each payload through the schema of `motion-ipc`
//! ([`Fields`](motion_ipc::schema::Fields), implemented by the `payload!` declaration of
//! the type), so it has no field list of its own and a field added to a payload travels
//! without a change here. No transmutes; the sizes below are pinned, so that a change of
//! what crosses the network is made knowingly (a peer of another size is refused).
//!
//! ```
//! use motion_wire::wire;
//! use motion_ipc::{ClientId, CommandKind, CommandRequest};
//!
//! let request = CommandRequest::new(ClientId::NONE, 7, 2, CommandKind::RampPosition)
//!     .with_values([10.0, 5.0, 50.0]);
//! let bytes = wire::encode(&request);
//! assert_eq!(bytes.len(), 64);
//! assert_eq!(&bytes[24..32], &7u64.to_le_bytes()); // `sequence` at offset 24
//! assert_eq!(wire::decode::<CommandRequest>(&bytes), Ok(request));
//! ```

use core::mem::size_of;

use motion_ipc::schema::{Fields, ScalarSink, ScalarSource, Schema};
use motion_ipc::{
    CommandReply, CommandRequest, MachineParams, MotionFrame, ServerInfo, ServerStats,
};

/// Why bytes could not be decoded into a payload.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum WireError {
    /// The byte count is not the payload's size: the peer was built against another
    /// version of `motion-ipc` (or sent something else).
    #[error(
        "{what} of {got} bytes where {expected} were expected (peer built against another \
         motion-ipc schema?)"
    )]
    Size {
        /// The payload type.
        what: &'static str,
        /// Its size in this build.
        expected: usize,
        /// The bytes received.
        got: usize,
    },
}

/// Writes little-endian numbers into a zeroed buffer; out-of-range writes are dropped and
/// remembered.
struct Writer<'a> {
    buf: &'a mut [u8],
    overflow: bool,
}

impl Writer<'_> {
    fn bytes(&mut self, at: usize, src: &[u8]) {
        match self.buf.get_mut(at..at + src.len()) {
            Some(dst) => dst.copy_from_slice(src),
            None => self.overflow = true,
        }
    }
}

/// Reads little-endian numbers from a buffer; out-of-range reads give zeros and are
/// remembered.
struct Reader<'a> {
    buf: &'a [u8],
    short: bool,
}

impl Reader<'_> {
    fn array<const N: usize>(&mut self, at: usize) -> [u8; N] {
        match self
            .buf
            .get(at..at + N)
            .and_then(|slice| <[u8; N]>::try_from(slice).ok())
        {
            Some(bytes) => bytes,
            None => {
                self.short = true;
                [0; N]
            }
        }
    }
}

/// The six number types as little-endian bytes, both ways.
macro_rules! little_endian {
    ($($ty:ident),*) => {
        impl ScalarSink for Writer<'_> {
            $(fn $ty(&mut self, at: usize, value: $ty) {
                self.bytes(at, &value.to_le_bytes());
            })*
        }
        impl ScalarSource for Reader<'_> {
            $(fn $ty(&mut self, at: usize) -> $ty {
                $ty::from_le_bytes(self.array(at))
            })*
        }
    };
}

little_endian!(u8, u16, u32, u64, i64, f64);

mod sealed {
    pub trait Sealed {}
}

/// A payload that travels over the network: one of `motion-ipc`'s service payloads.
pub trait Payload: sealed::Sealed + Schema + Fields {
    /// Its name in messages (the Rust type name).
    const NAME: &'static str = Self::SCHEMA.name;
    /// Bytes on the wire: `size_of::<Self>()`.
    const SIZE: usize = size_of::<Self>();
}

/// The payloads that cross the network, each with its size on the wire (`motion-ipc`'s
/// `tests/layout.rs` pins every offset).
macro_rules! payloads {
    ($($ty:ident = $size:literal),* $(,)?) => {$(
        const _: () = assert!(size_of::<$ty>() == $size);
        impl sealed::Sealed for $ty {}
        impl Payload for $ty {}
    )*};
}

payloads!(
    MotionFrame = 21968,
    ServerInfo = 38864,
    ServerStats = 2016,
    MachineParams = 180_240,
    CommandRequest = 64,
    CommandReply = 72,
);

/// `value` in its C layout, little-endian: `T::SIZE` bytes, padding zero.
pub fn encode<T: Payload>(value: &T) -> Vec<u8> {
    let mut buf = vec![0; T::SIZE];
    let mut writer = Writer {
        buf: &mut buf,
        overflow: false,
    };
    value.put(&mut writer, 0);
    debug_assert!(!writer.overflow, "{} encoder wrote past its size", T::NAME);
    buf
}

/// Decodes a payload of exactly `T::SIZE` bytes.
pub fn decode<T: Payload>(bytes: &[u8]) -> Result<T, WireError> {
    let size_error = WireError::Size {
        what: T::NAME,
        expected: T::SIZE,
        got: bytes.len(),
    };
    if bytes.len() != T::SIZE {
        return Err(size_error);
    }
    let mut reader = Reader {
        buf: bytes,
        short: false,
    };
    let value = T::get(&mut reader, 0);
    if reader.short {
        return Err(size_error);
    }
    Ok(value)
}

/// [`decode`] into a box (for the large payloads: a
/// [`MachineParams`](motion_ipc::MachineParams) is 176 KiB).
pub fn decode_boxed<T: Payload>(bytes: &[u8]) -> Result<Box<T>, WireError> {
    decode(bytes).map(Box::new)
}

#[cfg(test)]
mod tests;
