//! `payload!`: declares a shared-memory payload and its description together.
//!
//! ```text
//! payload! {
//!     /// What the payload is (docs reach the C header and the Python mirrors).
//!     #[derive(Debug, Clone, Copy, PartialEq)]
//!     #[type_name("motiond::Example")]
//!     pub struct Example {
//!         /// What the field holds.
//!         pub tick: u64,
//!         /// Text, UTF-8, zero padded.
//!         pub name: [u8; NAME_LEN],
//!     }
//! }
//! ```
//!
//! emits the struct, `#[repr(C)]` and `ZeroCopySend` with that iceoryx2 type name, and
//! implements [`Schema`](crate::schema::Schema) (size, alignment, docs and every field's
//! offset, size, type and docs, from the compiler's layout),
//! [`Fields`](crate::schema::Fields) (the payload number by number, for codecs) and
//! [`FieldType`](crate::schema::FieldType) (so another payload may nest it). A field type
//! is one token: a number type, a payload, or an array `[T; N]` whose length is a literal
//! or a contract constant (named as such in the C header). The declaring module imports
//! `iceoryx2::prelude::ZeroCopySend` (the derive names the trait unqualified).

/// Declares a payload struct and implements its description; see the module docs.
macro_rules! payload {
    (
        $(#[doc = $doc:literal])*
        #[derive($($derive:ident),* $(,)?)]
        #[type_name($type_name:literal)]
        pub struct $name:ident {
            $(
                $(#[doc = $field_doc:literal])*
                pub $field:ident: $ty:tt
            ),* $(,)?
        }
    ) => {
        $(#[doc = $doc])*
        #[derive($($derive,)* ZeroCopySend)]
        #[type_name($type_name)]
        #[repr(C)]
        pub struct $name {
            $(
                $(#[doc = $field_doc])*
                pub $field: $ty,
            )*
        }

        impl $crate::schema::Schema for $name {
            const SCHEMA: $crate::schema::Struct = $crate::schema::Struct {
                name: stringify!($name),
                type_name: $type_name,
                size: ::core::mem::size_of::<$name>(),
                align: ::core::mem::align_of::<$name>(),
                docs: &[$($doc),*],
                fields: &[$(
                    $crate::schema::Field {
                        name: stringify!($field),
                        offset: ::core::mem::offset_of!($name, $field),
                        size: ::core::mem::size_of::<$ty>(),
                        ty: field_type!($ty),
                        docs: &[$($field_doc),*],
                    }
                ),*],
            };
        }

        impl ::serde::Serialize for $name {
            fn serialize<S: ::serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
                $crate::schema::serde_sparse::serialize(self, serializer)
            }
        }

        impl<'de> ::serde::Deserialize<'de> for $name {
            fn deserialize<D: ::serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
                $crate::schema::serde_sparse::deserialize(deserializer)
            }
        }

        impl $crate::schema::Fields for $name {
            fn put<S: $crate::schema::ScalarSink>(&self, sink: &mut S, at: usize) {
                $(
                    $crate::schema::Fields::put(
                        &self.$field,
                        sink,
                        at + ::core::mem::offset_of!($name, $field),
                    );
                )*
            }
            fn get<S: $crate::schema::ScalarSource>(source: &mut S, at: usize) -> Self {
                Self {
                    $(
                        $field: $crate::schema::Fields::get(
                            source,
                            at + ::core::mem::offset_of!($name, $field),
                        ),
                    )*
                }
            }
        }

        impl $crate::schema::FieldType for $name {
            const TYPE: $crate::schema::Type = $crate::schema::Type::Struct {
                schema: &<$name as $crate::schema::Schema>::SCHEMA,
            };
        }
    };
}

/// The [`Type`](crate::schema::Type) of a field type token; an array whose length is a
/// constant keeps the constant's name.
macro_rules! field_type {
    ([$element:ty; $len:ident]) => {
        $crate::schema::Type::Array {
            element: &<$element as $crate::schema::FieldType>::TYPE,
            len: $len,
            len_name: Some(stringify!($len)),
        }
    };
    ($ty:ty) => {
        <$ty as $crate::schema::FieldType>::TYPE
    };
}
