//! The shared-memory contract as data: the one description every mirror of it is generated
//! from.
//!
//! Each payload is declared once, with the `payload!` macro next to its methods
//! (`frame.rs`, `command.rs`, …): the macro emits the `#[repr(C)]` struct with its iceoryx2
//! type name and implements [`Schema`] for it, whose [`Struct`] lists the payload's size,
//! alignment, docs and fields (name, offset, size, [`Type`], docs) as the compiler laid
//! them out (`size_of`, `align_of`, `offset_of!`). [`contract`] gathers every payload,
//! every enumeration and flag set, the constants and the service names into one
//! [`Contract`], and the renderers turn it into:
//!
//! - `include/motiond.h` ([`Contract::c_header`]),
//! - `python/src/motiond/_layout.py`, the ctypes mirrors ([`Contract::python_module`]),
//! - the JSON the C and Python layout checks read ([`Contract::to_json`], printed by
//!   `cargo run -p motion-ipc --example layout`).
//!
//! `cargo run -p motion-ipc --example gen` (or `scripts/gen`) rewrites the checked-in
//! files; `tests/generated.rs` fails while they differ from what the renderers give now.
//!
//! A codec moves a payload number by number through [`Fields`] (implemented by `payload!`
//! as well): it writes a [`ScalarSink`] and a [`ScalarSource`] for the six number types and
//! needs no field list of its own.
//!
//! ```
//! use motion_ipc::schema::{Schema, Scalar, Type};
//! use motion_ipc::AxisState;
//!
//! let axis = &AxisState::SCHEMA;
//! assert_eq!((axis.name, axis.size, axis.align), ("AxisState", 96, 8));
//! let fault = axis.field("fault").expect("AxisState has a fault field");
//! assert_eq!((fault.offset, fault.ty), (44, Type::Scalar(Scalar::U16)));
//! ```

mod c_header;
mod contract;
mod docs;
mod fields;
mod json;
mod python;
pub mod serde_sparse;

pub use c_header::{c_enum_value, c_struct};
pub use contract::contract;
pub use docs::snake;
pub use fields::{Fields, ScalarSink, ScalarSource, each_number, from_numbers};

/// A number type a payload field holds (the contract uses no others).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Scalar {
    /// `u8` / `uint8_t` / `c_uint8`.
    U8,
    /// `u16` / `uint16_t` / `c_uint16`.
    U16,
    /// `u32` / `uint32_t` / `c_uint32`.
    U32,
    /// `u64` / `uint64_t` / `c_uint64`.
    U64,
    /// `i64` / `int64_t` / `c_int64`.
    I64,
    /// `f64` / `double` / `c_double`.
    F64,
}

impl Scalar {
    /// The Rust spelling (`u32`).
    pub const fn name(self) -> &'static str {
        match self {
            Self::U8 => "u8",
            Self::U16 => "u16",
            Self::U32 => "u32",
            Self::U64 => "u64",
            Self::I64 => "i64",
            Self::F64 => "f64",
        }
    }

    /// Bytes.
    pub const fn size(self) -> usize {
        match self {
            Self::U8 => 1,
            Self::U16 => 2,
            Self::U32 => 4,
            Self::U64 | Self::I64 | Self::F64 => 8,
        }
    }
}

/// The type of a payload field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Type {
    /// A number.
    Scalar(Scalar),
    /// Another payload, nested by value.
    Struct {
        /// Its description.
        schema: &'static Struct,
    },
    /// A fixed-size array.
    Array {
        /// The element type.
        element: &'static Type,
        /// The element count.
        len: usize,
        /// The contract constant the length is declared with (`NAME_LEN`), if any.
        len_name: Option<&'static str>,
    },
}

impl Type {
    /// The type as the layout JSON and the layout checks spell it: `u32`, `ClientId`,
    /// `f64[3]`.
    pub fn spelling(&self) -> String {
        match self {
            Self::Scalar(scalar) => scalar.name().to_owned(),
            Self::Struct { schema } => schema.name.to_owned(),
            Self::Array { element, len, .. } => format!("{}[{len}]", element.spelling()),
        }
    }
}

/// One field of a payload.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Field {
    /// The Rust field name (`claimed_by`).
    pub name: &'static str,
    /// Byte offset in the payload (`offset_of!`).
    pub offset: usize,
    /// Bytes (`size_of` of its type).
    pub size: usize,
    /// Its type.
    pub ty: Type,
    /// Its doc comment, one entry per line.
    pub docs: &'static [&'static str],
}

/// One payload type: a `#[repr(C)]` struct declared with `payload!`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Struct {
    /// The Rust type name (`MotionFrame`).
    pub name: &'static str,
    /// The iceoryx2 type name (`motiond::MotionFrame`).
    pub type_name: &'static str,
    /// `size_of`.
    pub size: usize,
    /// `align_of`.
    pub align: usize,
    /// Its doc comment, one entry per line.
    pub docs: &'static [&'static str],
    /// Fields in declaration (= memory) order.
    pub fields: &'static [Field],
}

impl Struct {
    /// The field called `name`.
    pub fn field(&self, name: &str) -> Option<&Field> {
        self.fields.iter().find(|field| field.name == name)
    }
}

/// A payload declared with `payload!`: its description, from the compiler's layout.
pub trait Schema {
    /// The description.
    const SCHEMA: Struct;
}

/// A type a payload field may have, as the description names it.
pub trait FieldType {
    /// The description of the type.
    const TYPE: Type;
}

macro_rules! scalar_field_type {
    ($($ty:ty => $scalar:ident),* $(,)?) => {
        $(impl FieldType for $ty {
            const TYPE: Type = Type::Scalar(Scalar::$scalar);
        })*
    };
}

scalar_field_type!(u8 => U8, u16 => U16, u32 => U32, u64 => U64, i64 => I64, f64 => F64);

impl<T: FieldType, const N: usize> FieldType for [T; N] {
    const TYPE: Type = Type::Array {
        element: &T::TYPE,
        len: N,
        len_name: None,
    };
}

/// One value of an enumeration, or one bit of a flag set.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Variant {
    /// The Rust variant name (`RampPosition`) or flag constant name (`MOVING`).
    pub name: String,
    /// Its value.
    pub value: u64,
    /// Its text where the contract has one (`Reason::message`, `CommandKind::name`, …).
    pub text: Option<&'static str>,
}

/// An enumeration (travels as an integer) or a flag set.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Enum {
    /// The Rust type name (`Reason`, `AxisFlags`).
    pub name: &'static str,
    /// The integer it travels as.
    pub repr: Scalar,
    /// `true` for a bit set.
    pub flags: bool,
    /// What it is and where it travels, one sentence.
    pub doc: &'static str,
    /// Values in increasing order.
    pub variants: Vec<Variant>,
}

/// A named number of the contract (`MAX_AXES`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Constant {
    /// The Rust name.
    pub name: &'static str,
    /// Its value.
    pub value: u64,
    /// What it is, one sentence.
    pub doc: &'static str,
}

/// One iceoryx2 service (or the server's node name) of an instance.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Service {
    /// The leaf (`frame`), as [`ServiceNames`](crate::ServiceNames) names its method.
    pub leaf: &'static str,
    /// The name with `%s` for the instance name (`motiond/%s/frame`).
    pub format: String,
    /// Its messaging pattern and what travels on it, one line.
    pub doc: &'static str,
}

/// The whole contract: what every mirror is generated from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Contract {
    /// Named constants, `SCHEMA_VERSION` first.
    pub constants: Vec<Constant>,
    /// Service names.
    pub services: Vec<Service>,
    /// Payloads, each after the payloads it contains.
    pub structs: Vec<&'static Struct>,
    /// Enumerations, then flag sets.
    pub enums: Vec<Enum>,
}

impl Contract {
    /// The constant called `name`.
    pub fn constant(&self, name: &str) -> Option<&Constant> {
        self.constants.iter().find(|constant| constant.name == name)
    }
}

/// A file generated from the contract and checked in.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GeneratedFile {
    /// Its path from the repository root (`include/motiond.h`).
    pub path: &'static str,
    /// What the generator writes there now.
    pub contents: String,
}

impl Contract {
    /// Every checked-in file generated from the contract, as the generator writes it now
    /// (`cargo run -p motion-ipc --example gen` writes them; `tests/generated.rs` compares).
    pub fn generated_files(&self) -> Vec<GeneratedFile> {
        vec![
            GeneratedFile {
                path: "include/motiond.h",
                contents: self.c_header(),
            },
            GeneratedFile {
                path: "python/src/motiond/_layout.py",
                contents: self.python_module(),
            },
        ]
    }
}
