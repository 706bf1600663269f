//! The payloads of `motion-ipc` as bytes on the network: exactly their C layout (every field
//! at its `#[repr(C)]` offset, padding zero, `size_of::<T>()` bytes), every number
//! little-endian whatever the host. A C, C++ or Python peer reads a frame off the network
//! with the same struct it maps out of shared memory (on a little-endian machine), or field
//! by field from the offsets tabled in `motion-ipc`'s docs.
//!
//! Encoding and decoding are plain safe code, field by field, at the offsets the compiler
//! gives (`offset_of!`): no transmutes, and a payload whose layout changes fails to compile
//! here (see the size pins in `wire/field_table.rs`) rather than travelling wrong.
//!
//! The fields of every payload are listed once, in `wire/field_table.rs`; this file is the
//! machinery that walks them.
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

/// Writes into a zeroed buffer; out-of-range writes are dropped and remembered.
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

/// Reads from a buffer; out-of-range reads give zeros and are remembered.
struct Reader<'a> {
    buf: &'a [u8],
    short: core::cell::Cell<bool>,
}

impl Reader<'_> {
    fn array<const N: usize>(&self, at: usize) -> [u8; N] {
        match self
            .buf
            .get(at..at + N)
            .and_then(|slice| <[u8; N]>::try_from(slice).ok())
        {
            Some(bytes) => bytes,
            None => {
                self.short.set(true);
                [0; N]
            }
        }
    }
}

/// A value at a fixed offset of a payload.
trait Field: Sized {
    fn put(&self, w: &mut Writer<'_>, at: usize);
    fn get(r: &Reader<'_>, at: usize) -> Self;
}

macro_rules! number {
    ($($ty:ty),*) => {$(
        impl Field for $ty {
            fn put(&self, w: &mut Writer<'_>, at: usize) {
                w.bytes(at, &self.to_le_bytes());
            }
            fn get(r: &Reader<'_>, at: usize) -> Self {
                <$ty>::from_le_bytes(r.array(at))
            }
        }
    )*};
}

number!(u8, u16, u32, u64, i64, f64);

/// Byte arrays (text fields, reserved bytes) travel as they are.
impl<const N: usize> Field for [u8; N] {
    fn put(&self, w: &mut Writer<'_>, at: usize) {
        w.bytes(at, self);
    }
    fn get(r: &Reader<'_>, at: usize) -> Self {
        r.array(at)
    }
}

/// Arrays of structs and numbers: element `i` at `at + i · size_of::<T>()`.
macro_rules! array_of {
    ($($ty:ty),*) => {$(
        impl<const N: usize> Field for [$ty; N] {
            fn put(&self, w: &mut Writer<'_>, at: usize) {
                for (index, item) in self.iter().enumerate() {
                    item.put(w, at + index * size_of::<$ty>());
                }
            }
            fn get(r: &Reader<'_>, at: usize) -> Self {
                core::array::from_fn(|index| <$ty>::get(r, at + index * size_of::<$ty>()))
            }
        }
    )*};
}

/// A `#[repr(C)]` struct: each listed field at its `offset_of!`. Decoding builds the struct
/// with every field named, so a field added to the type and not listed here does not
/// compile.
macro_rules! record {
    ($ty:ident { $($field:ident),* $(,)? }) => {
        impl Field for $ty {
            fn put(&self, w: &mut Writer<'_>, at: usize) {
                $(self.$field.put(w, at + offset_of!($ty, $field));)*
            }
            fn get(r: &Reader<'_>, at: usize) -> Self {
                Self { $($field: Field::get(r, at + offset_of!($ty, $field)),)* }
            }
        }
    };
}

mod sealed {
    pub trait Sealed {}
}

/// A payload that travels over the network: one of `motion-ipc`'s service payloads.
#[allow(private_bounds)]
pub trait Payload: sealed::Sealed + Field {
    /// Its name in messages.
    const NAME: &'static str;
    /// Bytes on the wire: `size_of::<Self>()`.
    const SIZE: usize = size_of::<Self>();
}

macro_rules! payload {
    ($($ty:ident),*) => {$(
        impl sealed::Sealed for $ty {}
        impl Payload for $ty {
            const NAME: &'static str = stringify!($ty);
        }
    )*};
}

// After the macros: the table invokes them.
mod field_table;

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
    let reader = Reader {
        buf: bytes,
        short: core::cell::Cell::new(false),
    };
    let value = T::get(&reader, 0);
    if reader.short.get() {
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
