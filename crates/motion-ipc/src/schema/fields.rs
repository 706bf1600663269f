//! [`Fields`]: a payload as the numbers it is made of, each at its byte offset — what a
//! codec (the bridge's wire format) needs to write or read a payload field by field, in safe
//! code, without a field list of its own.
//!
//! `payload!` implements [`Fields`] for every payload from its declaration; the numbers,
//! arrays of anything that implements it, and nested payloads compose. A codec implements
//! [`ScalarSink`] (to encode) and [`ScalarSource`] (to decode) once, for the six number
//! types:
//!
//! ```
//! use motion_ipc::schema::{Fields, ScalarSink};
//! use motion_ipc::{ClientId, CommandKind, CommandRequest};
//!
//! /// Little-endian bytes at the payload's own offsets.
//! struct Bytes(Vec<u8>);
//! impl Bytes {
//!     fn put(&mut self, at: usize, bytes: &[u8]) {
//!         self.0[at..at + bytes.len()].copy_from_slice(bytes);
//!     }
//! }
//! impl ScalarSink for Bytes {
//!     fn u8(&mut self, at: usize, value: u8) { self.put(at, &[value]) }
//!     fn u16(&mut self, at: usize, value: u16) { self.put(at, &value.to_le_bytes()) }
//!     fn u32(&mut self, at: usize, value: u32) { self.put(at, &value.to_le_bytes()) }
//!     fn u64(&mut self, at: usize, value: u64) { self.put(at, &value.to_le_bytes()) }
//!     fn i64(&mut self, at: usize, value: i64) { self.put(at, &value.to_le_bytes()) }
//!     fn f64(&mut self, at: usize, value: f64) { self.put(at, &value.to_le_bytes()) }
//! }
//!
//! let request = CommandRequest::new(ClientId::NONE, 7, 2, CommandKind::Stop);
//! let mut bytes = Bytes(vec![0; size_of::<CommandRequest>()]);
//! request.put(&mut bytes, 0);
//! assert_eq!(&bytes.0[24..32], &7u64.to_le_bytes()); // `sequence` at offset 24
//! ```

/// Takes the numbers of a value, each with its byte offset.
pub trait ScalarSink {
    /// A `u8` at byte `at`.
    fn u8(&mut self, at: usize, value: u8);
    /// A `u16` at byte `at`.
    fn u16(&mut self, at: usize, value: u16);
    /// A `u32` at byte `at`.
    fn u32(&mut self, at: usize, value: u32);
    /// A `u64` at byte `at`.
    fn u64(&mut self, at: usize, value: u64);
    /// An `i64` at byte `at`.
    fn i64(&mut self, at: usize, value: i64);
    /// An `f64` at byte `at`.
    fn f64(&mut self, at: usize, value: f64);
}

/// Gives the numbers of a value, each from its byte offset.
pub trait ScalarSource {
    /// The `u8` at byte `at`.
    fn u8(&mut self, at: usize) -> u8;
    /// The `u16` at byte `at`.
    fn u16(&mut self, at: usize) -> u16;
    /// The `u32` at byte `at`.
    fn u32(&mut self, at: usize) -> u32;
    /// The `u64` at byte `at`.
    fn u64(&mut self, at: usize) -> u64;
    /// The `i64` at byte `at`.
    fn i64(&mut self, at: usize) -> i64;
    /// The `f64` at byte `at`.
    fn f64(&mut self, at: usize) -> f64;
}

/// A value moved number by number at the offsets of its `#[repr(C)]` layout.
pub trait Fields: Sized {
    /// Hands every number of `self` to `sink`, at `at` plus its offset, in memory order.
    fn put<S: ScalarSink>(&self, sink: &mut S, at: usize);
    /// Builds a value from the numbers `source` gives at `at` plus their offsets.
    fn get<S: ScalarSource>(source: &mut S, at: usize) -> Self;
}

macro_rules! scalar_fields {
    ($($ty:ident),*) => {
        $(impl Fields for $ty {
            fn put<S: ScalarSink>(&self, sink: &mut S, at: usize) {
                sink.$ty(at, *self);
            }
            fn get<S: ScalarSource>(source: &mut S, at: usize) -> Self {
                source.$ty(at)
            }
        })*
    };
}

scalar_fields!(u8, u16, u32, u64, i64, f64);

/// Element `i` at `at + i · size_of::<T>()`.
impl<T: Fields, const N: usize> Fields for [T; N] {
    fn put<S: ScalarSink>(&self, sink: &mut S, at: usize) {
        for (index, item) in self.iter().enumerate() {
            item.put(sink, at + index * size_of::<T>());
        }
    }
    fn get<S: ScalarSource>(source: &mut S, at: usize) -> Self {
        core::array::from_fn(|index| T::get(source, at + index * size_of::<T>()))
    }
}

/// A sink handing each number to a closure as `(offset, bits)`.
struct EachNumber<F>(F);

impl<F: FnMut(usize, u64)> ScalarSink for EachNumber<F> {
    fn u8(&mut self, at: usize, value: u8) {
        (self.0)(at, u64::from(value));
    }
    fn u16(&mut self, at: usize, value: u16) {
        (self.0)(at, u64::from(value));
    }
    fn u32(&mut self, at: usize, value: u32) {
        (self.0)(at, u64::from(value));
    }
    fn u64(&mut self, at: usize, value: u64) {
        (self.0)(at, value);
    }
    fn i64(&mut self, at: usize, value: i64) {
        (self.0)(at, value as u64);
    }
    fn f64(&mut self, at: usize, value: f64) {
        (self.0)(at, value.to_bits());
    }
}

/// A source asking a closure for each number's bits at its offset.
struct FromNumbers<F>(F);

impl<F: FnMut(usize) -> u64> ScalarSource for FromNumbers<F> {
    fn u8(&mut self, at: usize) -> u8 {
        (self.0)(at) as u8
    }
    fn u16(&mut self, at: usize) -> u16 {
        (self.0)(at) as u16
    }
    fn u32(&mut self, at: usize) -> u32 {
        (self.0)(at) as u32
    }
    fn u64(&mut self, at: usize) -> u64 {
        (self.0)(at)
    }
    fn i64(&mut self, at: usize) -> i64 {
        (self.0)(at) as i64
    }
    fn f64(&mut self, at: usize) -> f64 {
        f64::from_bits((self.0)(at))
    }
}

/// Hands every number of `value` to `number` as `(offset, bits)`, in memory order: the bits
/// widened to 64 (an `f64`'s exact bits: -0.0 and NaN payloads are kept). Allocates nothing.
pub fn each_number<T: Fields>(value: &T, number: impl FnMut(usize, u64)) {
    value.put(&mut EachNumber(number), 0);
}

/// Builds a `T` number by number, in memory order, from the bits `bits(offset)` gives (the
/// inverse of [`each_number`]).
pub fn from_numbers<T: Fields>(bits: impl FnMut(usize) -> u64) -> T {
    T::get(&mut FromNumbers(bits), 0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::schema::{Scalar, Type, contract};
    use crate::{AxisState, ClientId, MotionFrame, ServerStats};

    /// Records what it is given; replays it.
    #[derive(Debug, Default)]
    struct Tape(Vec<(usize, Scalar, u64)>);

    impl ScalarSink for Tape {
        fn u8(&mut self, at: usize, value: u8) {
            self.0.push((at, Scalar::U8, value.into()));
        }
        fn u16(&mut self, at: usize, value: u16) {
            self.0.push((at, Scalar::U16, value.into()));
        }
        fn u32(&mut self, at: usize, value: u32) {
            self.0.push((at, Scalar::U32, value.into()));
        }
        fn u64(&mut self, at: usize, value: u64) {
            self.0.push((at, Scalar::U64, value));
        }
        fn i64(&mut self, at: usize, value: i64) {
            self.0.push((at, Scalar::I64, value.cast_unsigned()));
        }
        fn f64(&mut self, at: usize, value: f64) {
            self.0.push((at, Scalar::F64, value.to_bits()));
        }
    }

    impl Tape {
        fn take(&mut self, at: usize, scalar: Scalar) -> u64 {
            let (offset, kind, value) = self.0.remove(0);
            assert_eq!((offset, kind), (at, scalar));
            value
        }
    }

    impl ScalarSource for Tape {
        fn u8(&mut self, at: usize) -> u8 {
            self.take(at, Scalar::U8) as u8
        }
        fn u16(&mut self, at: usize) -> u16 {
            self.take(at, Scalar::U16) as u16
        }
        fn u32(&mut self, at: usize) -> u32 {
            self.take(at, Scalar::U32) as u32
        }
        fn u64(&mut self, at: usize) -> u64 {
            self.take(at, Scalar::U64)
        }
        fn i64(&mut self, at: usize) -> i64 {
            self.take(at, Scalar::I64).cast_signed()
        }
        fn f64(&mut self, at: usize) -> f64 {
            f64::from_bits(self.take(at, Scalar::F64))
        }
    }

    /// The numbers of a type in memory order, from the description alone.
    fn scalars_of(ty: &Type, at: usize, out: &mut Vec<(usize, Scalar)>) {
        match ty {
            Type::Scalar(scalar) => out.push((at, *scalar)),
            Type::Struct { schema } => {
                for field in schema.fields {
                    scalars_of(&field.ty, at + field.offset, out);
                }
            }
            Type::Array { element, len, .. } => {
                let size = match element {
                    Type::Scalar(scalar) => scalar.size(),
                    Type::Struct { schema } => schema.size,
                    Type::Array { .. } => unreachable!("no arrays of arrays in the contract"),
                };
                for index in 0..*len {
                    scalars_of(element, at + index * size, out);
                }
            }
        }
    }

    #[test]
    fn every_payload_puts_the_numbers_its_description_lists() {
        let mut frame = MotionFrame::EMPTY;
        frame.tick = 42;
        frame.axes[3] = AxisState {
            position: -1.5,
            raw_counts: -7,
            claimed_by: ClientId::from_u128(9 << 64 | 5),
            ..AxisState::UNKNOWN
        };
        let mut tape = Tape::default();
        frame.put(&mut tape, 0);
        let description = contract()
            .structs
            .into_iter()
            .find(|s| s.name == "MotionFrame")
            .expect("MotionFrame");
        let mut expected = Vec::new();
        scalars_of(
            &Type::Struct {
                schema: description,
            },
            0,
            &mut expected,
        );
        let listed: Vec<(usize, Scalar)> = tape.0.iter().map(|&(at, kind, _)| (at, kind)).collect();
        assert_eq!(listed, expected);
        assert_eq!(MotionFrame::get(&mut tape, 0), frame);
        assert!(tape.0.is_empty());
    }

    #[test]
    fn nested_payloads_and_arrays_are_offset() {
        let mut stats = ServerStats::EMPTY;
        stats.work.p99_ns = 77;
        stats.link_io[2].reads = 5;
        let mut tape = Tape::default();
        stats.put(&mut tape, 100);
        let p99 = 100 + core::mem::offset_of!(ServerStats, work) + 16;
        assert!(tape.0.contains(&(p99, Scalar::U64, 77)));
        let reads = 100 + core::mem::offset_of!(ServerStats, link_io) + 2 * 32 + 24;
        assert!(tape.0.contains(&(reads, Scalar::U64, 5)));
        assert_eq!(ServerStats::get(&mut tape, 100), stats);
    }
}
