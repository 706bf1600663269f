//! `enumeration!`: declares an enumeration of the contract once — its variants and their
//! values, the text clients print, every value in order, and the checked conversion from
//! the raw number that travels.
//!
//! ```text
//! enumeration! {
//!     /// What the value says. Travels as `u8` in `Example::state`.
//!     #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
//!     pub enum ExampleState(u8) -> name {
//!         /// What 0 means.
//!         Idle = 0 => "idle",
//!         /// What 1 means.
//!         Running = 1 => "running",
//!     }
//! }
//! ```
//!
//! emits the enum (`#[repr(u8)]`, with the given attributes), `ALL` (every variant, in
//! declaration order), the text function named after the arrow (`name`, or `message`)
//! and `TryFrom<u8>` failing with [`UnknownValue`](crate::UnknownValue) for a value no
//! variant has.

/// A raw enumeration value widened to the `u32` [`UnknownValue`](crate::UnknownValue)
/// carries.
pub(crate) trait Widen {
    fn widen(self) -> u32;
}

impl Widen for u8 {
    fn widen(self) -> u32 {
        u32::from(self)
    }
}

impl Widen for u16 {
    fn widen(self) -> u32 {
        u32::from(self)
    }
}

impl Widen for u32 {
    fn widen(self) -> u32 {
        self
    }
}

/// Declares an enumeration; see the module docs.
macro_rules! enumeration {
    (
        $(#[$meta:meta])*
        pub enum $name:ident($repr:ident) -> $text_fn:ident {
            $(
                $(#[$variant_meta:meta])*
                $variant:ident = $value:literal => $text:literal,
            )+
        }
    ) => {
        $(#[$meta])*
        #[repr($repr)]
        pub enum $name {
            $(
                $(#[$variant_meta])*
                $variant = $value,
            )+
        }

        impl $name {
            /// Every value, in declaration order.
            pub const ALL: [Self; [$($value),+].len()] = [$(Self::$variant),+];

            /// The text clients print.
            pub const fn $text_fn(self) -> &'static str {
                match self {
                    $(Self::$variant => $text,)+
                }
            }
        }

        impl TryFrom<$repr> for $name {
            type Error = $crate::UnknownValue;
            fn try_from(value: $repr) -> Result<Self, Self::Error> {
                match value {
                    $($value => Ok(Self::$variant),)+
                    other => Err($crate::UnknownValue($crate::enumeration::Widen::widen(other))),
                }
            }
        }
    };
}
