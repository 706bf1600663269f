//! The register map of the command list: numbers, the command types each register
//! accepts, the products that have it, and the factory defaults.

use crate::Error;

/// The three command types (command list, "Command Format").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CommandType {
    /// `R`: read the register once.
    Read,
    /// `W`: write the data field to the register.
    Write,
    /// `S`: streaming read; the board keeps sending the register (see [`StreamTrigger`]).
    Stream,
}

impl CommandType {
    /// The upper-case ASCII letter that starts a command line.
    pub const fn letter(self) -> u8 {
        match self {
            Self::Read => b'R',
            Self::Write => b'W',
            Self::Stream => b'S',
        }
    }

    /// The command type of an upper-case command letter.
    pub const fn from_letter(b: u8) -> Option<Self> {
        match b {
            b'R' => Some(Self::Read),
            b'W' => Some(Self::Write),
            b'S' => Some(Self::Stream),
            _ => None,
        }
    }

    const fn bit(self) -> u8 {
        match self {
            Self::Read => 1,
            Self::Write => 2,
            Self::Stream => 4,
        }
    }
}

/// The three products of the QSB line (VERSION register product type code).
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub enum ProductType {
    /// QSB-D: one differential encoder input, 1-bit digital I/O.
    D,
    /// QSB-M: single-ended encoder input, 4-bit digital I/O, stepper drive outputs.
    #[default]
    M,
    /// QSB-S: one single-ended encoder input (quadrature, step/direction, PWM or analog).
    S,
}

impl ProductType {
    /// The product type code of the VERSION register (0 = QSB-D, 1 = QSB-M, 2 = QSB-S).
    pub const fn code(self) -> u8 {
        match self {
            Self::D => 0,
            Self::M => 1,
            Self::S => 2,
        }
    }

    /// The product with VERSION type code `code`.
    pub const fn from_code(code: u8) -> Option<Self> {
        match code {
            0 => Some(Self::D),
            1 => Some(Self::M),
            2 => Some(Self::S),
            _ => None,
        }
    }

    const fn bit(self) -> u8 {
        match self {
            Self::D => 1,
            Self::M => 2,
            Self::S => 4,
        }
    }

    /// Number of digital I/O bits the product has (DIG I/O register): 1 on -D, 4 on -M,
    /// none on -S.
    pub const fn digital_io_bits(self) -> u8 {
        match self {
            Self::D => 1,
            Self::M => 4,
            Self::S => 0,
        }
    }
}

/// When a streamed register (`S` command) sends a new line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum StreamTrigger {
    /// A new value is sent only when it differs from the last one sent (DIG I/O, CAPTURE,
    /// STR, MD STATUS).
    OnChange,
    /// A value is sent at every INTERVAL RATE period when it moved by at least THRESHOLD
    /// counts since the last one sent (READ ENCODER).
    IntervalThreshold,
}

const D: u8 = ProductType::D.bit();
const M: u8 = ProductType::M.bit();
const S: u8 = ProductType::S.bit();
const ALL: u8 = D | M | S;
const R: u8 = CommandType::Read.bit();
const W: u8 = CommandType::Write.bit();
const ST: u8 = CommandType::Stream.bit();

macro_rules! registers {
    ($( $(#[$doc:meta])* $name:ident = $num:literal, $types:expr, $products:expr, $default:expr, $nv:literal; )*) => {
        /// The registers 00–16 of the command list.
        #[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        #[repr(u8)]
        pub enum Register {
            $( $(#[$doc])* $name = $num, )*
        }

        impl Register {
            /// Every register, in number order.
            pub const ALL: [Register; 23] = [ $( Register::$name, )* ];

            /// The register with number `n`, if the command list has it.
            pub const fn from_u8(n: u8) -> Option<Self> {
                match n {
                    $( $num => Some(Self::$name), )*
                    _ => None,
                }
            }

            const fn types(self) -> u8 {
                match self { $( Self::$name => $types, )* }
            }

            const fn products(self) -> u8 {
                match self { $( Self::$name => $products, )* }
            }

            /// The factory default value ("Factory Default Command Parameter Values"),
            /// `None` for the registers the table leaves blank (CLEAR, LOAD, TIME STAMP,
            /// VERSION, COMMAND).
            pub const fn factory_default(self) -> Option<u32> {
                match self { $( Self::$name => $default, )* }
            }

            /// Whether COMMAND #3 saves the register across power cycles (the table's
            /// "Non-Volatile" column; registers 00–04, 08, 0B, 0C, 0F–12, 15).
            pub const fn non_volatile(self) -> bool {
                match self { $( Self::$name => $nv, )* }
            }
        }
    };
}

registers! {
    /// 00 MODE: encoder mode (quadrature, PWM, analog), PWM resolution.
    Mode = 0x00, R | W, ALL, Some(0x00), true;
    /// 01 DIG I/O: digital I/O pin states / open-drain outputs.
    DigIo = 0x01, R | W | ST, D | M, Some(0xF), true;
    /// 02 DIG I/O CONFIG: interrupt polarity/enable, direction, trigger pulse.
    DigIoConfig = 0x02, R | W, D | M, Some(0x0000), true;
    /// 03 MDR0: counter mode register 0.
    Mdr0 = 0x03, R | W, ALL, Some(0x4F), true;
    /// 04 MDR1: counter mode register 1.
    Mdr1 = 0x04, R | W, ALL, Some(0x000), true;
    /// 05 CAPTURE: counter value captured at an index or I/O interrupt event.
    Capture = 0x05, R | ST, ALL, Some(0), false;
    /// 06 STR: counter status register.
    Str = 0x06, R | ST, ALL, Some(0x0A), false;
    /// 07 OTR: output transfer register, a snapshot of CNTR.
    Otr = 0x07, R, ALL, Some(0), false;
    /// 08 DTR: input data transfer register (load / compare / range / modulus value).
    Dtr = 0x08, R | W, ALL, Some(0x1F3), true;
    /// 09 CLEAR REG: clear MDR0, MDR1, CNTR or STR.
    ClearReg = 0x09, W, ALL, None, false;
    /// 0A LOAD REG: transfer DTR to CNTR or CNTR to OTR.
    LoadReg = 0x0A, W, ALL, None, false;
    /// 0B THRESHOLD: count change needed before a streamed encoder value is sent.
    Threshold = 0x0B, R | W, ALL, Some(0x0000), true;
    /// 0C INTERVAL RATE: data output timer in 1/512 s steps, 0xFFFF disables output.
    IntervalRate = 0x0C, R | W, ALL, Some(0xFFFF), true;
    /// 0D TIME STAMP: 32-bit 1/512 s counter; writing 1 clears it.
    TimeStamp = 0x0D, R | W, ALL, None, false;
    /// 0E READ ENCODER: current encoder value in the selected MODE.
    ReadEncoder = 0x0E, R | ST, ALL, Some(0), false;
    /// 0F MD STEP RATE: stepper step rate, steps/s (-M only).
    MdStepRate = 0x0F, R | W, M, Some(0x20), true;
    /// 10 MD ACCEL: stepper acceleration, steps/s² (-M only).
    MdAccel = 0x10, R | W, M, Some(0x186A0), true;
    /// 11 MD MOVE STEPS: signed steps of the next move (-M only).
    MdMoveSteps = 0x11, R | W, M, Some(0), true;
    /// 12 MD JOG RATE: signed jog rate, steps/s (-M only).
    MdJogRate = 0x12, R | W, M, Some(0x20), true;
    /// 13 MD STATUS: motor movement status (-M only).
    MdStatus = 0x13, R | ST, M, Some(0x1), false;
    /// 14 VERSION: serial number, product type, firmware version.
    Version = 0x14, R, ALL, None, false;
    /// 15 EOR: end-of-response termination and formatting.
    Eor = 0x15, R | W, ALL, Some(0xB), true;
    /// 16 COMMAND: execute a function (stop, save, motor functions, baud rate).
    Command = 0x16, W, ALL, None, false;
}

impl Register {
    /// The register number (00–16).
    pub const fn number(self) -> u8 {
        self as u8
    }

    /// Whether the register accepts command type `ty` (the command list's "Command Type"
    /// column).
    pub const fn allows(self, ty: CommandType) -> bool {
        self.types() & ty.bit() != 0
    }

    /// Whether product `product` has the register (the "Product Type" column).
    pub const fn available_on(self, product: ProductType) -> bool {
        self.products() & product.bit() != 0
    }

    /// Checks that `ty` is allowed on this register of `product`: `Err(NotPermitted)`
    /// is what the board answers with an `x`.
    pub const fn check(self, ty: CommandType, product: ProductType) -> Result<(), Error> {
        if self.allows(ty) && self.available_on(product) {
            Ok(())
        } else {
            Err(Error::NotPermitted)
        }
    }

    /// How a stream of this register produces lines, `None` for registers that cannot be
    /// streamed. A read (`R`) of a streamed register cancels its stream.
    pub const fn stream_trigger(self) -> Option<StreamTrigger> {
        match self {
            Self::DigIo | Self::Capture | Self::Str | Self::MdStatus => {
                Some(StreamTrigger::OnChange)
            }
            Self::ReadEncoder => Some(StreamTrigger::IntervalThreshold),
            _ => None,
        }
    }
}

impl TryFrom<u8> for Register {
    type Error = Error;

    fn try_from(n: u8) -> Result<Self, Error> {
        Self::from_u8(n).ok_or(Error::UnknownRegister)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn command_list_permissions() {
        use CommandType::*;
        let table: [(u8, &[CommandType]); 23] = [
            (0x00, &[Read, Write]),
            (0x01, &[Read, Write, Stream]),
            (0x02, &[Read, Write]),
            (0x03, &[Read, Write]),
            (0x04, &[Read, Write]),
            (0x05, &[Read, Stream]),
            (0x06, &[Read, Stream]),
            (0x07, &[Read]),
            (0x08, &[Read, Write]),
            (0x09, &[Write]),
            (0x0A, &[Write]),
            (0x0B, &[Read, Write]),
            (0x0C, &[Read, Write]),
            (0x0D, &[Read, Write]),
            (0x0E, &[Read, Stream]),
            (0x0F, &[Read, Write]),
            (0x10, &[Read, Write]),
            (0x11, &[Read, Write]),
            (0x12, &[Read, Write]),
            (0x13, &[Read, Stream]),
            (0x14, &[Read]),
            (0x15, &[Read, Write]),
            (0x16, &[Write]),
        ];
        for (n, types) in table {
            let reg = Register::from_u8(n).unwrap();
            assert_eq!(reg.number(), n);
            for ty in [Read, Write, Stream] {
                assert_eq!(reg.allows(ty), types.contains(&ty), "{reg:?} {ty:?}");
            }
            assert_eq!(
                reg.stream_trigger().is_some(),
                reg.allows(Stream),
                "{reg:?} streams"
            );
        }
        assert_eq!(Register::from_u8(0x17), None);
        assert!(!Register::DigIo.available_on(ProductType::S));
        assert!(Register::MdStatus.available_on(ProductType::M));
        assert!(!Register::MdStepRate.available_on(ProductType::D));
    }
}
