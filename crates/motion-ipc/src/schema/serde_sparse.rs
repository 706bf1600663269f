//! Serde for shared-memory payloads, sparse: the `(offset: u32, bits: u64)` of every number
//! that is not all-zero bits, in memory order, walked with [`Fields`]. A 400 KiB path whose
//! line uses a dozen numbers takes a dozen pairs, and serializing allocates nothing (the
//! engine's state snapshot is taken in the tick). Deserializing builds the value number by
//! number through [`Fields::get`], so any bytes give a value of the type (a number absent
//! is zero), never an invalid one.

use serde::de::{SeqAccess, Visitor};
use serde::ser::SerializeSeq;
use serde::{Deserializer, Serializer};

use super::{Fields, ScalarSink, ScalarSource};

/// Counts the numbers that are not all-zero bits.
struct Count(usize);

impl Count {
    fn bits(&mut self, bits: u64) {
        if bits != 0 {
            self.0 += 1;
        }
    }
}

impl ScalarSink for Count {
    fn u8(&mut self, _: usize, value: u8) {
        self.bits(u64::from(value));
    }
    fn u16(&mut self, _: usize, value: u16) {
        self.bits(u64::from(value));
    }
    fn u32(&mut self, _: usize, value: u32) {
        self.bits(u64::from(value));
    }
    fn u64(&mut self, _: usize, value: u64) {
        self.bits(value);
    }
    fn i64(&mut self, _: usize, value: i64) {
        self.bits(value as u64);
    }
    fn f64(&mut self, _: usize, value: f64) {
        self.bits(value.to_bits());
    }
}

/// Emits the pairs into a serde sequence; the first error is kept.
struct Emit<S: SerializeSeq> {
    seq: S,
    error: Option<S::Error>,
}

impl<S: SerializeSeq> Emit<S> {
    fn bits(&mut self, at: usize, bits: u64) {
        if bits != 0 && self.error.is_none() {
            let at = u32::try_from(at).unwrap_or(u32::MAX);
            if let Err(error) = self.seq.serialize_element(&(at, bits)) {
                self.error = Some(error);
            }
        }
    }
}

impl<S: SerializeSeq> ScalarSink for Emit<S> {
    fn u8(&mut self, at: usize, value: u8) {
        self.bits(at, u64::from(value));
    }
    fn u16(&mut self, at: usize, value: u16) {
        self.bits(at, u64::from(value));
    }
    fn u32(&mut self, at: usize, value: u32) {
        self.bits(at, u64::from(value));
    }
    fn u64(&mut self, at: usize, value: u64) {
        self.bits(at, value);
    }
    fn i64(&mut self, at: usize, value: i64) {
        self.bits(at, value as u64);
    }
    fn f64(&mut self, at: usize, value: f64) {
        self.bits(at, value.to_bits());
    }
}

/// Serializes `value` sparse (two walks: the count, then the pairs; no allocation).
pub fn serialize<T: Fields, S: Serializer>(value: &T, serializer: S) -> Result<S::Ok, S::Error> {
    let mut count = Count(0);
    value.put(&mut count, 0);
    let mut emit = Emit {
        seq: serializer.serialize_seq(Some(count.0))?,
        error: None,
    };
    value.put(&mut emit, 0);
    match emit.error {
        Some(error) => Err(error),
        None => emit.seq.end(),
    }
}

/// The pairs read back, sorted by offset; a number absent is zero.
struct Pairs(Vec<(u32, u64)>);

impl Pairs {
    fn bits(&self, at: usize) -> u64 {
        let Ok(at) = u32::try_from(at) else {
            return 0;
        };
        self.0
            .binary_search_by_key(&at, |&(offset, _)| offset)
            .map_or(0, |i| self.0[i].1)
    }
}

impl ScalarSource for Pairs {
    fn u8(&mut self, at: usize) -> u8 {
        self.bits(at) as u8
    }
    fn u16(&mut self, at: usize) -> u16 {
        self.bits(at) as u16
    }
    fn u32(&mut self, at: usize) -> u32 {
        self.bits(at) as u32
    }
    fn u64(&mut self, at: usize) -> u64 {
        self.bits(at)
    }
    fn i64(&mut self, at: usize) -> i64 {
        self.bits(at) as i64
    }
    fn f64(&mut self, at: usize) -> f64 {
        f64::from_bits(self.bits(at))
    }
}

struct PairsVisitor;

impl<'de> Visitor<'de> for PairsVisitor {
    type Value = Pairs;

    fn expecting(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("a sequence of (offset, bits) pairs")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Pairs, A::Error> {
        let mut pairs = Vec::with_capacity(seq.size_hint().unwrap_or(0).min(1 << 16));
        while let Some(pair) = seq.next_element::<(u32, u64)>()? {
            pairs.push(pair);
        }
        // Memory order when written; sorted anyway so that any input reads the same way.
        pairs.sort_unstable_by_key(|&(offset, _)| offset);
        Ok(Pairs(pairs))
    }
}

/// Deserializes a value written by [`serialize`].
pub fn deserialize<'de, T: Fields, D: Deserializer<'de>>(deserializer: D) -> Result<T, D::Error> {
    let mut pairs = deserializer.deserialize_seq(PairsVisitor)?;
    Ok(T::get(&mut pairs, 0))
}

#[cfg(test)]
mod tests {
    use crate::{ClientId, GroupPath};

    #[test]
    fn a_payload_goes_through_postcard_sparse_and_back() {
        let id = ClientId { lo: 7, hi: 0 };
        let mut buf = [0u8; 64];
        let bytes = postcard::to_slice(&id, &mut buf).expect("fits");
        // One pair: the count, offset 0, bits 7.
        assert_eq!(bytes, &[1, 0, 7]);
        let back: ClientId = postcard::from_bytes(bytes).expect("decodes");
        assert_eq!(back, id);
    }

    #[test]
    fn a_large_path_takes_the_numbers_it_uses() {
        // A path (392 KiB) is built by value: a thread with room for it.
        std::thread::Builder::new()
            .stack_size(64 << 20)
            .spawn(|| {
                let mut path = Box::new(GroupPath::EMPTY);
                path.point_count = 2;
                path.positions[3] = -1.5;
                let mut buf = vec![0u8; 256];
                let len = postcard::to_slice(&*path, &mut buf).expect("fits").len();
                assert!(len < 40, "{len} bytes for three numbers");
                let back: Box<GroupPath> =
                    Box::new(postcard::from_bytes(&buf[..len]).expect("decodes"));
                assert_eq!(back.point_count, 2);
                assert_eq!(back.positions[3], -1.5);
                assert_eq!(back.positions[2], 0.0);
                assert_eq!(back.schema_version, path.schema_version);
            })
            .expect("a thread")
            .join()
            .expect("the checks pass");
    }
}
