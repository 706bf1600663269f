//! `flag_set!`: declares a bit set of the contract once — its type, its bits, the names
//! clients print and the list the contract's generator turns into the C header's and the
//! Python mirrors' constants.
//!
//! ```text
//! flag_set! {
//!     /// What the bits describe.
//!     #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
//!     pub struct ExampleFlags(u32) {
//!         /// What bit 0 means.
//!         FIRST = 0, "first";
//!         /// What bit 1 means.
//!         SECOND_ONE = 1, "second-one";
//!     }
//! }
//! ```
//!
//! emits the newtype (`pub struct ExampleFlags(pub u32)`) with the given attributes, a
//! constant per bit (`ExampleFlags::FIRST`, `1 << 0`), `NAMED` (every bit with the name
//! clients print, in bit order), `BITS` (every bit's constant name and value, as
//! `schema::contract` lists them), `names`, `contains` and `with`.

/// Declares a flag set; see the module docs.
macro_rules! flag_set {
    (
        $(#[$meta:meta])*
        pub struct $name:ident($repr:ty) {
            $(
                $(#[doc = $bit_doc:literal])*
                $bit:ident = $shift:literal, $text:literal;
            )+
        }
    ) => {
        $(#[$meta])*
        pub struct $name(pub $repr);

        impl $name {
            $(
                $(#[doc = $bit_doc])*
                pub const $bit: Self = Self(1 << $shift);
            )+

            /// Every flag with the name clients print, in bit order.
            pub const NAMED: [(Self, &'static str); [$($text),+].len()] =
                [$((Self::$bit, $text)),+];

            /// Every flag's constant name and value, as the contract lists them (the C
            /// header's and the Python mirrors' constants).
            pub const BITS: [(&'static str, u64); [$($text),+].len()] =
                [$((stringify!($bit), 1u64 << $shift)),+];

            /// The names of the set flags, in bit order.
            pub fn names(self) -> Vec<&'static str> {
                Self::NAMED
                    .iter()
                    .filter(|(flag, _)| self.contains(*flag))
                    .map(|(_, name)| *name)
                    .collect()
            }

            /// Whether every bit of `other` is set.
            pub const fn contains(self, other: Self) -> bool {
                self.0 & other.0 == other.0
            }

            /// `self` with the bits of `other` set (`on`) or cleared.
            #[must_use]
            pub const fn with(self, other: Self, on: bool) -> Self {
                if on {
                    Self(self.0 | other.0)
                } else {
                    Self(self.0 & !other.0)
                }
            }
        }
    };
}
