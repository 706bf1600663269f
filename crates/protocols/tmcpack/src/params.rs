//! Little-endian parameter access on the seven parameter bytes P0..P6 (manual section 8:
//! "Parameters with more than 1 byte are to be transmitted with the least significant byte
//! first").

use crate::{Command, Error, FRAME_LEN, Word};

/// Number of parameter bytes in a frame.
pub(crate) const PARAMS: usize = 7;

pub(crate) fn u16_at(p: &[u8; PARAMS], i: usize) -> u16 {
    u16::from_le_bytes([byte(p, i), byte(p, i + 1)])
}

pub(crate) fn i16_at(p: &[u8; PARAMS], i: usize) -> i16 {
    i16::from_le_bytes([byte(p, i), byte(p, i + 1)])
}

pub(crate) fn u32_at(p: &[u8; PARAMS], i: usize) -> u32 {
    u32::from_le_bytes([byte(p, i), byte(p, i + 1), byte(p, i + 2), byte(p, i + 3)])
}

pub(crate) fn i32_at(p: &[u8; PARAMS], i: usize) -> i32 {
    u32_at(p, i) as i32
}

pub(crate) fn byte(p: &[u8; PARAMS], i: usize) -> u8 {
    p.get(i).copied().unwrap_or(0)
}

pub(crate) fn put(p: &mut [u8; PARAMS], i: usize, bytes: &[u8]) {
    for (k, b) in bytes.iter().enumerate() {
        if let Some(slot) = p.get_mut(i + k) {
            *slot = *b;
        }
    }
}

pub(crate) fn bit0(p: &[u8; PARAMS], i: usize) -> bool {
    byte(p, i) & 1 != 0
}

/// One table per message drives its type, its encoder and its decoder: each variant of the
/// enum is written once, every field with the byte of P0..P6 it starts at (`field: Type =
/// offset`, little-endian, [`Param`]; `via codec` where a field is not read as its type's
/// `Param`), and with the [`Command`](crate::Command) it is (a request: the variant's own
/// name) or answers (a reply: `Variant => Command`). The macro defines the enum,
/// `command()`, and `put_params` / `take_params` (the two directions of the parameter
/// bytes) from that one list, so they cannot drift apart. `unmatched` maps a command the
/// table has no variant for to an error (replies: the instructions with no reply).
macro_rules! message_table {
    (
        $(#[$meta:meta])*
        pub enum $name:ident {
            $(
                $(#[$vmeta:meta])*
                $variant:ident $(=> $command:ident)? $({
                    $(
                        $(#[$fmeta:meta])*
                        $field:ident : $ty:ty = $at:literal $(via $codec:ident)?
                    ),* $(,)?
                })?
            ),* $(,)?
        }
        $(unmatched: $unmatched:expr)?
    ) => {
        $(#[$meta])*
        pub enum $name {
            $(
                $(#[$vmeta])*
                $variant $({ $( $(#[$fmeta])* $field: $ty ),* })?
            ),*
        }

        impl $name {
            /// The instruction code (of the instruction a reply answers).
            pub const fn command(&self) -> $crate::Command {
                match self {
                    $( Self::$variant { .. } => command_of!($variant $(, $command)?) ),*
                }
            }

            /// Writes P0..P6 (unused bytes zero). Validates first.
            pub fn encode_params(&self) -> Result<[u8; $crate::params::PARAMS], $crate::Error> {
                self.validate()?;
                let mut p = [0u8; $crate::params::PARAMS];
                self.put_params(&mut p);
                Ok(p)
            }

            /// Parses P0..P6 of a message of `command` and validates the result.
            pub fn decode_params(
                command: $crate::Command,
                p: &[u8; $crate::params::PARAMS],
            ) -> Result<Self, $crate::Error> {
                let message = Self::take_params(command, p)?;
                message.validate()?;
                Ok(message)
            }

            /// Writes the fields at their offsets (no validation).
            fn put_params(&self, p: &mut [u8; $crate::params::PARAMS]) {
                match *self {
                    $( Self::$variant $({ $($field),* })? => {
                        $( $( put_field!($field, p, $at $(, $codec)?); )* )?
                    } )*
                }
            }

            /// Reads the fields of a message of `command` from their offsets (no
            /// validation).
            fn take_params(
                command: $crate::Command,
                p: &[u8; $crate::params::PARAMS],
            ) -> Result<Self, $crate::Error> {
                Ok(match command {
                    $( command_of!($variant $(, $command)?) => Self::$variant $({
                        $( $field: take_field!(p, $at $(, $codec)?)? ),*
                    })?, )*
                    $( other => return Err(($unmatched)(other)), )?
                })
            }
        }
    };
}

/// The command of a table row: the one named after `=>`, else the variant's own name.
macro_rules! command_of {
    ($variant:ident) => {
        $crate::Command::$variant
    };
    ($variant:ident, $command:ident) => {
        $crate::Command::$command
    };
}

/// A whole 9-byte word type (manual 6.1): an address byte and a typed message (`$field`)
/// whose `command()`, `encode_params` and `decode_params` give the rest. Requests and
/// replies are framed alike.
macro_rules! word_frame {
    (
        $(#[$meta:meta])*
        $frame:ident {
            $(#[$ameta:meta])*
            address,
            $(#[$fmeta:meta])*
            $field:ident: $ty:ident,
        }
        $(#[$newmeta:meta])*
        new
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        pub struct $frame {
            $(#[$ameta])*
            pub address: u8,
            $(#[$fmeta])*
            pub $field: $ty,
        }

        impl $frame {
            $(#[$newmeta])*
            pub const fn new(address: u8, $field: $ty) -> Self {
                Self { address, $field }
            }

            /// The 9-byte word.
            pub fn to_word(&self) -> Result<$crate::Word, $crate::Error> {
                let p = self.$field.encode_params()?;
                Ok($crate::params::assemble(self.address, self.$field.command(), &p))
            }

            /// Encodes the 9-byte word into `buf`; returns 9.
            pub fn encode(&self, buf: &mut [u8]) -> Result<usize, $crate::Error> {
                $crate::params::write_word(&self.to_word()?, buf)
            }

            /// Decodes exactly one 9-byte word.
            pub fn decode(bytes: &[u8]) -> Result<Self, $crate::Error> {
                let (address, command, p) = $crate::params::split_word(bytes)?;
                Ok(Self {
                    address,
                    $field: $ty::decode_params(command, &p)?,
                })
            }
        }
    };
}

/// The 9-byte word of `address`, `command` and the parameters `p` (manual 6.1): the
/// framing requests and replies share.
pub(crate) fn assemble(address: u8, command: Command, p: &[u8; PARAMS]) -> Word {
    let mut w = [0u8; FRAME_LEN];
    w[0] = address;
    w[1] = command.code();
    w[2..].copy_from_slice(p);
    w
}

/// Writes `word` at the start of `buf`; returns 9.
pub(crate) fn write_word(word: &Word, buf: &mut [u8]) -> Result<usize, Error> {
    let out = buf
        .get_mut(..FRAME_LEN)
        .ok_or(Error::BufferTooSmall { needed: FRAME_LEN })?;
    out.copy_from_slice(word);
    Ok(FRAME_LEN)
}

/// Splits exactly one 9-byte word into address, command and parameters.
pub(crate) fn split_word(bytes: &[u8]) -> Result<(u8, Command, [u8; PARAMS]), Error> {
    let w: &Word = bytes.try_into().map_err(|_| Error::WrongLength {
        expected: FRAME_LEN,
        got: bytes.len(),
    })?;
    let command = Command::from_u8(w[1])?;
    let mut p = [0u8; PARAMS];
    p.copy_from_slice(&w[2..]);
    Ok((w[0], command, p))
}

/// A value that sits at a byte offset of P0..P6, little-endian: one definition serves the
/// encoder and the decoder of every instruction that carries it.
pub(crate) trait Param: Sized {
    /// Writes `self` at `at`.
    fn put(self, p: &mut [u8; PARAMS], at: usize);
    /// Reads a value at `at` (an index out of its table is an error, never a panic).
    fn take(p: &[u8; PARAMS], at: usize) -> Result<Self, Error>;
}

impl Param for u8 {
    fn put(self, p: &mut [u8; PARAMS], at: usize) {
        put(p, at, &[self]);
    }
    fn take(p: &[u8; PARAMS], at: usize) -> Result<Self, Error> {
        Ok(byte(p, at))
    }
}

/// Multi-byte integers, least significant byte first (manual section 8).
macro_rules! le_param {
    ($($ty:ty => $at:ident),*) => {$(
        impl Param for $ty {
            fn put(self, p: &mut [u8; PARAMS], at: usize) {
                put(p, at, &self.to_le_bytes());
            }
            fn take(p: &[u8; PARAMS], at: usize) -> Result<Self, Error> {
                Ok($at(p, at))
            }
        }
    )*};
}

le_param!(u16 => u16_at, i16 => i16_at, u32 => u32_at, i32 => i32_at);

impl Param for i8 {
    fn put(self, p: &mut [u8; PARAMS], at: usize) {
        put(p, at, &self.to_le_bytes());
    }
    fn take(p: &[u8; PARAMS], at: usize) -> Result<Self, Error> {
        Ok(i8::from_le_bytes([byte(p, at)]))
    }
}

/// A success byte read strictly: 1 is success, anything else is not ("P0 = 1 when … went
/// well"); written as 1 or 0. Named in a table with `via exact_one`.
pub(crate) mod exact_one {
    use super::{PARAMS, Param, byte};
    use crate::Error;

    pub(crate) fn put(value: bool, p: &mut [u8; PARAMS], at: usize) {
        value.put(p, at);
    }

    pub(crate) fn take(p: &[u8; PARAMS], at: usize) -> Result<bool, Error> {
        Ok(byte(p, at) == 1)
    }
}

/// Writes `$value` at `$at` with the field's codec: its type's [`Param`], or the module
/// named after `via`.
macro_rules! put_field {
    ($value:expr, $p:expr, $at:expr) => {
        $crate::params::Param::put($value, $p, $at)
    };
    ($value:expr, $p:expr, $at:expr, $codec:ident) => {
        $crate::params::$codec::put($value, $p, $at)
    };
}

/// Reads a field at `$at` with its codec (see [`put_field!`]).
macro_rules! take_field {
    ($p:expr, $at:expr) => {
        $crate::params::Param::take($p, $at)
    };
    ($p:expr, $at:expr, $codec:ident) => {
        $crate::params::$codec::take($p, $at)
    };
}

/// A flag byte: 1 or 0 on the wire, bit 0 read back.
impl Param for bool {
    fn put(self, p: &mut [u8; PARAMS], at: usize) {
        put(p, at, &[u8::from(self)]);
    }
    fn take(p: &[u8; PARAMS], at: usize) -> Result<Self, Error> {
        Ok(bit0(p, at))
    }
}

/// Consecutive bytes (a microstep table slice, flash data).
impl<const N: usize> Param for [u8; N] {
    fn put(self, p: &mut [u8; PARAMS], at: usize) {
        put(p, at, &self);
    }
    fn take(p: &[u8; PARAMS], at: usize) -> Result<Self, Error> {
        Ok(core::array::from_fn(|k| byte(p, at + k)))
    }
}
