//! Serde for a boxed array of any length (`#[serde(with = "motion_base::serde_boxed_array")]`):
//! the array's elements in order, as `serde_big_array` writes an inline one.

use serde::{Deserialize, Deserializer, Serialize, Serializer};
use serde_big_array::BigArray;

/// Writes the elements of `value`.
#[allow(clippy::borrowed_box)] // serde's `with` hands the field as it is declared
pub fn serialize<S: Serializer, T: Serialize, const N: usize>(
    value: &Box<[T; N]>,
    serializer: S,
) -> Result<S::Ok, S::Error> {
    <[T; N] as BigArray<T>>::serialize(value, serializer)
}

/// Reads `N` elements into a new box.
pub fn deserialize<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(
    deserializer: D,
) -> Result<Box<[T; N]>, D::Error> {
    <[T; N] as BigArray<T>>::deserialize(deserializer).map(Box::new)
}
