//! Command lines host → board: `R|W|S`, two hex digits of register, optional hex data,
//! end of command (CR and/or LF). [`CommandLine`] is the wire form, [`Request`] the typed
//! one.

use crate::motor::{ACCEL_RANGE, JOG_RATE_RANGE, MOVE_STEPS_RANGE, STEP_RATE_RANGE};
use crate::{
    ClearTarget, CommandType, DigIo, DigIoConfig, Eor, Error, IntervalRate, LoadTarget, Mdr0, Mdr1,
    Mode, ProductType, QsbCommand, Register, hex,
};

/// The end-of-command sequence this crate writes (any single or dual combination of CR
/// and LF is accepted).
pub const EOC: &[u8] = b"\r\n";

/// Longest command line [`CommandLine::encode`] writes: type, register, 8 data digits,
/// CR LF.
pub const MAX_COMMAND_LEN: usize = 1 + 2 + 8 + 2;

/// A command line as it travels on the wire. The register is any two hex digits (00–FF):
/// the board answers `x` to the numbers it does not have, so the wire form keeps them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CommandLine {
    /// `R`, `W` or `S`.
    pub ty: CommandType,
    /// Register number.
    pub register: u8,
    /// The optional data field. Fewer than eight digits are a positive value; negative
    /// values are eight digits of two's complement.
    pub data: Option<u32>,
}

impl CommandLine {
    /// Writes the line with the fewest data digits and [`EOC`]; returns its length.
    pub fn encode(&self, buf: &mut [u8]) -> Result<usize, Error> {
        let mut n = 0;
        *buf.get_mut(n).ok_or(Error::BufferTooSmall)? = self.ty.letter();
        n += 1;
        hex::write(
            buf.get_mut(n..).ok_or(Error::BufferTooSmall)?,
            u32::from(self.register),
            2,
        )?;
        n += 2;
        if let Some(data) = self.data {
            n += hex::write_minimal(buf.get_mut(n..).ok_or(Error::BufferTooSmall)?, data)?;
        }
        let end = buf.get_mut(n..n + EOC.len()).ok_or(Error::BufferTooSmall)?;
        end.copy_from_slice(EOC);
        Ok(n + EOC.len())
    }

    /// Decodes one line without its end-of-command bytes: an upper-case command type, two
    /// register digits (either case), then optionally 1.. data digits (leading zeros
    /// ignored, at most eight significant).
    pub fn decode(line: &[u8]) -> Result<Self, Error> {
        let (&first, rest) = line.split_first().ok_or(Error::Truncated)?;
        let ty = CommandType::from_letter(first).ok_or(Error::BadType)?;
        let reg = rest.get(..2).ok_or(Error::Truncated)?;
        let register = hex::parse(reg)? as u8;
        let data = match rest.get(2..) {
            Some([]) | None => None,
            Some(field) => Some(hex::parse(field)?),
        };
        Ok(Self { ty, register, data })
    }
}

/// A typed write: the register and its typed value.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Write {
    /// `W00`: encoder mode.
    Mode(Mode),
    /// `W01`: digital output states.
    DigIo(DigIo),
    /// `W02`: digital I/O configuration (also sets every I/O pin high).
    DigIoConfig(DigIoConfig),
    /// `W03`: counter mode register 0.
    Mdr0(Mdr0),
    /// `W04`: counter mode register 1.
    Mdr1(Mdr1),
    /// `W08`: DTR.
    Dtr(u32),
    /// `W09`: clear a counter register.
    Clear(ClearTarget),
    /// `W0A`: register transfer.
    Load(LoadTarget),
    /// `W0B`: encoder count threshold.
    Threshold(u16),
    /// `W0C`: data output interval.
    IntervalRate(IntervalRate),
    /// `W0D`: time stamp; the value 1 clears the time stamp counter.
    TimeStamp(u32),
    /// `W0F`: step rate, steps/s (32–13000).
    StepRate(u32),
    /// `W10`: acceleration, steps/s² (64–360000).
    Accel(u32),
    /// `W11`: steps of the next move, signed.
    MoveSteps(i32),
    /// `W12`: jog rate, steps/s, signed (−13000–13000).
    JogRate(i32),
    /// `W15`: end-of-response formatting.
    Eor(Eor),
    /// `W16`: execute a function.
    Command(QsbCommand),
}

/// Value of TIME STAMP data that clears the counter ("write a 1 to this register").
pub const TIME_STAMP_CLEAR: u32 = 1;

impl Write {
    /// The register written.
    pub const fn register(&self) -> Register {
        match self {
            Self::Mode(_) => Register::Mode,
            Self::DigIo(_) => Register::DigIo,
            Self::DigIoConfig(_) => Register::DigIoConfig,
            Self::Mdr0(_) => Register::Mdr0,
            Self::Mdr1(_) => Register::Mdr1,
            Self::Dtr(_) => Register::Dtr,
            Self::Clear(_) => Register::ClearReg,
            Self::Load(_) => Register::LoadReg,
            Self::Threshold(_) => Register::Threshold,
            Self::IntervalRate(_) => Register::IntervalRate,
            Self::TimeStamp(_) => Register::TimeStamp,
            Self::StepRate(_) => Register::MdStepRate,
            Self::Accel(_) => Register::MdAccel,
            Self::MoveSteps(_) => Register::MdMoveSteps,
            Self::JogRate(_) => Register::MdJogRate,
            Self::Eor(_) => Register::Eor,
            Self::Command(_) => Register::Command,
        }
    }

    /// The data field (negative values as two's complement).
    pub const fn data(&self) -> u32 {
        match *self {
            Self::Mode(v) => v.data(),
            Self::DigIo(v) => v.data(),
            Self::DigIoConfig(v) => v.data(),
            Self::Mdr0(v) => v.data(),
            Self::Mdr1(v) => v.data(),
            Self::Dtr(v) | Self::TimeStamp(v) | Self::StepRate(v) | Self::Accel(v) => v,
            Self::Clear(v) => v.data(),
            Self::Load(v) => v.data(),
            Self::Threshold(v) => v as u32,
            Self::IntervalRate(v) => v.data(),
            Self::MoveSteps(v) | Self::JogRate(v) => v as u32,
            Self::Eor(v) => v.data(),
            Self::Command(v) => v.data(),
        }
    }

    /// The typed write of `data` to `register`: `NotPermitted` when the register cannot be
    /// written (the board answers `x`), `OutOfRange` when the data is outside its documented
    /// range (the board answers `e`).
    pub fn from_data(register: Register, data: u32) -> Result<Self, Error> {
        let signed = data as i32;
        Ok(match register {
            Register::Mode => Self::Mode(Mode::from_data(data)?),
            Register::DigIo => Self::DigIo(DigIo::from_data(data)?),
            Register::DigIoConfig => Self::DigIoConfig(DigIoConfig::from_data(data)?),
            Register::Mdr0 => Self::Mdr0(Mdr0::from_data(data)?),
            Register::Mdr1 => Self::Mdr1(Mdr1::from_data(data)?),
            Register::Dtr => Self::Dtr(data),
            Register::ClearReg => Self::Clear(ClearTarget::from_data(data)?),
            Register::LoadReg => Self::Load(LoadTarget::from_data(data)?),
            Register::Threshold => {
                Self::Threshold(u16::try_from(data).map_err(|_| Error::OutOfRange)?)
            }
            Register::IntervalRate => Self::IntervalRate(IntervalRate::from_data(data)?),
            Register::TimeStamp => Self::TimeStamp(data),
            Register::MdStepRate if STEP_RATE_RANGE.contains(&data) => Self::StepRate(data),
            Register::MdAccel if ACCEL_RANGE.contains(&data) => Self::Accel(data),
            Register::MdMoveSteps if MOVE_STEPS_RANGE.contains(&signed) => Self::MoveSteps(signed),
            Register::MdJogRate if JOG_RATE_RANGE.contains(&signed) => Self::JogRate(signed),
            Register::MdStepRate
            | Register::MdAccel
            | Register::MdMoveSteps
            | Register::MdJogRate => return Err(Error::OutOfRange),
            Register::Eor => Self::Eor(Eor::from_data(data)?),
            Register::Command => Self::Command(QsbCommand::from_data(data)?),
            Register::Capture
            | Register::Str
            | Register::Otr
            | Register::ReadEncoder
            | Register::MdStatus
            | Register::Version => return Err(Error::NotPermitted),
        })
    }
}

/// A typed command.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Request {
    /// `Rnn`: read a register once (cancels a stream of that register).
    Read(Register),
    /// `Snn`: stream a register.
    Stream(Register),
    /// `Wnn<data>`: write a register.
    Write(Write),
}

impl Request {
    /// The register addressed.
    pub const fn register(&self) -> Register {
        match self {
            Self::Read(r) | Self::Stream(r) => *r,
            Self::Write(w) => w.register(),
        }
    }

    /// The command type.
    pub const fn command_type(&self) -> CommandType {
        match self {
            Self::Read(_) => CommandType::Read,
            Self::Stream(_) => CommandType::Stream,
            Self::Write(_) => CommandType::Write,
        }
    }

    /// The wire form.
    pub const fn to_line(&self) -> CommandLine {
        CommandLine {
            ty: self.command_type(),
            register: self.register().number(),
            data: match self {
                Self::Write(w) => Some(w.data()),
                Self::Read(_) | Self::Stream(_) => None,
            },
        }
    }

    /// Writes the command line; returns its length.
    pub fn encode(&self, buf: &mut [u8]) -> Result<usize, Error> {
        self.to_line().encode(buf)
    }

    /// The typed command of a wire line. `UnknownRegister` and `NotPermitted` are answered
    /// `x` by the board; `OutOfRange` and `MissingData` are answered `e`. A data field on a
    /// read or stream command is ignored.
    pub fn from_line(line: &CommandLine) -> Result<Self, Error> {
        let register = Register::try_from(line.register)?;
        if !register.allows(line.ty) {
            return Err(Error::NotPermitted);
        }
        Ok(match line.ty {
            CommandType::Read => Self::Read(register),
            CommandType::Stream => Self::Stream(register),
            CommandType::Write => Self::Write(Write::from_data(
                register,
                line.data.ok_or(Error::MissingData)?,
            )?),
        })
    }

    /// Decodes one line without its end-of-command bytes.
    pub fn decode(line: &[u8]) -> Result<Self, Error> {
        Self::from_line(&CommandLine::decode(line)?)
    }

    /// Checks the command against a product: registers the product lacks are
    /// `NotPermitted` (`x`), COMMAND functions it lacks are `OutOfRange` (`e`).
    pub const fn check(&self, product: ProductType) -> Result<(), Error> {
        if let Err(e) = self.register().check(self.command_type(), product) {
            return Err(e);
        }
        match self {
            Self::Write(Write::Command(c)) if !c.available_on(product) => Err(Error::OutOfRange),
            _ => Ok(()),
        }
    }
}
