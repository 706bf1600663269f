//! Serde for shared-memory payloads, sparse: the `(offset: u32, bits: u64)` of every number
//! that is not all-zero bits, in memory order, walked with [`Fields`]. A 400 KiB path whose
//! line uses a dozen numbers takes a dozen pairs, and serializing allocates nothing (the
//! engine's state snapshot is taken in the tick). Deserializing builds the value number by
//! number through [`Fields::get`], so any bytes give a value of the type (a number absent
//! is zero), never an invalid one.

use serde::de::{SeqAccess, Visitor};
use serde::ser::SerializeSeq;
use serde::{Deserializer, Serializer};

use super::{Fields, each_number, from_numbers};

/// Serializes `value` sparse (two walks: the count, then the pairs; no allocation).
pub fn serialize<T: Fields, S: Serializer>(value: &T, serializer: S) -> Result<S::Ok, S::Error> {
    let mut count = 0;
    each_number(value, |_, bits| count += usize::from(bits != 0));
    let mut seq = serializer.serialize_seq(Some(count))?;
    let mut error = None;
    each_number(value, |at, bits| {
        if bits != 0 && error.is_none() {
            let at = u32::try_from(at).unwrap_or(u32::MAX);
            if let Err(e) = seq.serialize_element(&(at, bits)) {
                error = Some(e);
            }
        }
    });
    match error {
        Some(error) => Err(error),
        None => seq.end(),
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
    let pairs = deserializer.deserialize_seq(PairsVisitor)?;
    Ok(from_numbers(|at| pairs.bits(at)))
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
