//! Response lines board → host: type, register, eight data digits, optional time stamp,
//! `!`, then the EOR termination, with or without spaces between the fields.

use crate::{
    ClearTarget, DigIo, DigIoConfig, Eor, Error, IntervalRate, LoadTarget, MdStatus, Mdr0, Mdr1,
    Mode, QsbCommand, Register, Str, Version, hex,
};

/// Longest response line: `r 0E 00001234 0000ABCD !\r\n`.
pub const MAX_RESPONSE_LEN: usize = 26;

/// The lower-case response type letter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ResponseType {
    /// `r`: answer to a read.
    Read,
    /// `w`: answer to a write, echoing the data written.
    Write,
    /// `s`: answer to a stream command, and every streamed value after it.
    Stream,
    /// `e`: error; the data is the refused value, which was not written.
    Error,
    /// `x`: unsupported command.
    Unsupported,
}

impl ResponseType {
    /// The ASCII letter.
    pub const fn letter(self) -> u8 {
        match self {
            Self::Read => b'r',
            Self::Write => b'w',
            Self::Stream => b's',
            Self::Error => b'e',
            Self::Unsupported => b'x',
        }
    }

    /// The type of a response letter.
    pub const fn from_letter(b: u8) -> Option<Self> {
        match b {
            b'r' => Some(Self::Read),
            b'w' => Some(Self::Write),
            b's' => Some(Self::Stream),
            b'e' => Some(Self::Error),
            b'x' => Some(Self::Unsupported),
            _ => None,
        }
    }
}

/// One response line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Response {
    /// Response type.
    pub ty: ResponseType,
    /// Register of the command answered (00–FF).
    pub register: u8,
    /// Data, always eight digits on the wire; negative counts are two's complement.
    pub data: u32,
    /// Time stamp in 1/512 s ticks, present when EOR bit 2 is set.
    pub time_stamp: Option<u32>,
}

/// Outcome of parsing the start of a byte string as a response line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Prefix {
    /// A valid beginning; more bytes are needed.
    Incomplete,
    /// A complete line ending at `!`, of this many bytes.
    Complete(Response, usize),
    /// Cannot be the beginning of a response line.
    Invalid(Error),
}

/// Fixed-width hex field at `*i`: `Ok(None)` when the input ends inside it.
fn field(bytes: &[u8], i: &mut usize, width: usize) -> Result<Option<u32>, Error> {
    let Some(digits) = bytes.get(*i..) else {
        return Ok(None);
    };
    let avail = digits.len().min(width);
    let digits = digits.get(..avail).unwrap_or_default();
    if digits.iter().any(|b| hex::digit(*b).is_none()) {
        return Err(Error::BadHex);
    }
    if avail < width {
        return Ok(None);
    }
    *i += width;
    hex::parse(digits).map(Some)
}

/// Skips one optional space separator at `*i`.
fn space(bytes: &[u8], i: &mut usize) {
    if bytes.get(*i) == Some(&b' ') {
        *i += 1;
    }
}

pub(crate) fn parse_prefix(bytes: &[u8]) -> Prefix {
    let Some(&first) = bytes.first() else {
        return Prefix::Incomplete;
    };
    let Some(ty) = ResponseType::from_letter(first) else {
        return Prefix::Invalid(Error::BadType);
    };
    let mut i = 1;
    space(bytes, &mut i);
    let register = match field(bytes, &mut i, 2) {
        Ok(Some(r)) => r as u8,
        Ok(None) => return Prefix::Incomplete,
        Err(e) => return Prefix::Invalid(e),
    };
    space(bytes, &mut i);
    let data = match field(bytes, &mut i, 8) {
        Ok(Some(d)) => d,
        Ok(None) => return Prefix::Incomplete,
        Err(e) => return Prefix::Invalid(e),
    };
    space(bytes, &mut i);
    let mut time_stamp = None;
    match bytes.get(i) {
        None => return Prefix::Incomplete,
        Some(b'!') => {}
        Some(_) => {
            match field(bytes, &mut i, 8) {
                Ok(Some(t)) => time_stamp = Some(t),
                Ok(None) => return Prefix::Incomplete,
                Err(_) => return Prefix::Invalid(Error::MissingBang),
            }
            space(bytes, &mut i);
            match bytes.get(i) {
                None => return Prefix::Incomplete,
                Some(b'!') => {}
                Some(_) => return Prefix::Invalid(Error::MissingBang),
            }
        }
    }
    let response = Response {
        ty,
        register,
        data,
        time_stamp,
    };
    Prefix::Complete(response, i + 1)
}

/// A write position in a caller's buffer.
struct Cursor<'a> {
    buf: &'a mut [u8],
    n: usize,
}

impl Cursor<'_> {
    fn put(&mut self, b: u8) -> Result<(), Error> {
        *self.buf.get_mut(self.n).ok_or(Error::BufferTooSmall)? = b;
        self.n += 1;
        Ok(())
    }

    fn hex(&mut self, value: u32, width: usize) -> Result<(), Error> {
        hex::write(
            self.buf.get_mut(self.n..).ok_or(Error::BufferTooSmall)?,
            value,
            width,
        )?;
        self.n += width;
        Ok(())
    }

    fn separator(&mut self, eor: Eor) -> Result<(), Error> {
        if eor.spaces { self.put(b' ') } else { Ok(()) }
    }
}

impl Response {
    /// A response without time stamp.
    pub const fn new(ty: ResponseType, register: u8, data: u32) -> Self {
        Self {
            ty,
            register,
            data,
            time_stamp: None,
        }
    }

    /// Writes the line formatted by `eor`: spaces between the fields when `eor.spaces`, the
    /// time stamp when `self.time_stamp` is set (a board sets it when `eor.time_stamp`),
    /// `!`, then CR and/or LF. Returns its length.
    pub fn encode(&self, eor: Eor, buf: &mut [u8]) -> Result<usize, Error> {
        let mut w = Cursor { buf, n: 0 };
        w.put(self.ty.letter())?;
        w.separator(eor)?;
        w.hex(u32::from(self.register), 2)?;
        w.separator(eor)?;
        w.hex(self.data, 8)?;
        w.separator(eor)?;
        if let Some(ts) = self.time_stamp {
            w.hex(ts, 8)?;
            w.separator(eor)?;
        }
        w.put(b'!')?;
        if eor.carriage_return {
            w.put(b'\r')?;
        }
        if eor.line_feed {
            w.put(b'\n')?;
        }
        Ok(w.n)
    }

    /// Decodes one complete line: from the type letter through `!`, optionally followed by
    /// CR and LF bytes. Spaces between fields are optional, so both the factory
    /// `r 14 00001201 !` and the terse `r1400001201!` forms are accepted.
    pub fn decode(line: &[u8]) -> Result<Self, Error> {
        match parse_prefix(line) {
            Prefix::Incomplete => Err(Error::Truncated),
            Prefix::Invalid(e) => Err(e),
            Prefix::Complete(r, used) => {
                let rest = line.get(used..).unwrap_or_default();
                if rest.iter().all(|b| matches!(b, b'\r' | b'\n')) {
                    Ok(r)
                } else {
                    Err(Error::TrailingBytes)
                }
            }
        }
    }

    /// The data as a signed 32-bit value (two's complement).
    pub const fn signed(&self) -> i32 {
        self.data as i32
    }

    /// `Ok(self)` for `r`, `w` and `s` lines; the board's `e` and `x` answers become
    /// [`Error::Rejected`] and [`Error::Unsupported`], so that they cannot be dropped.
    pub const fn check(self) -> Result<Self, Error> {
        match self.ty {
            ResponseType::Error => Err(Error::Rejected {
                register: self.register,
                data: self.data,
            }),
            ResponseType::Unsupported => Err(Error::Unsupported {
                register: self.register,
            }),
            ResponseType::Read | ResponseType::Write | ResponseType::Stream => Ok(self),
        }
    }

    /// The typed value of an `r`, `w` or `s` line (see [`Value::decode`]).
    pub fn value(&self) -> Result<Value, Error> {
        let ok = self.check()?;
        Value::decode(Register::try_from(ok.register)?, ok.data)
    }
}

/// The typed value a response carries for its register.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Value {
    /// 00.
    Mode(Mode),
    /// 01: the levels measured at the pins (read), or the outputs written (write).
    DigIo(DigIo),
    /// 02.
    DigIoConfig(DigIoConfig),
    /// 03.
    Mdr0(Mdr0),
    /// 04.
    Mdr1(Mdr1),
    /// 05: captured count.
    Capture(i32),
    /// 06.
    Str(Str),
    /// 07: snapshot of CNTR.
    Otr(i32),
    /// 08.
    Dtr(u32),
    /// 09 (write echo).
    Clear(ClearTarget),
    /// 0A (write echo).
    Load(LoadTarget),
    /// 0B.
    Threshold(u16),
    /// 0C.
    IntervalRate(IntervalRate),
    /// 0D: 1/512 s ticks.
    TimeStamp(u32),
    /// 0E: the encoder value in the board's MODE: a signed count in quadrature mode
    /// (`as i32`), a 10/12-bit position in PWM mode, a 10-bit value in analog mode, or an
    /// [`crate::AnalogSample`] on streamed lines in analog mode.
    Encoder(u32),
    /// 0F.
    StepRate(u32),
    /// 10.
    Accel(u32),
    /// 11.
    MoveSteps(i32),
    /// 12.
    JogRate(i32),
    /// 13.
    MdStatus(MdStatus),
    /// 14.
    Version(Version),
    /// 15.
    Eor(Eor),
    /// 16 (write echo).
    Command(QsbCommand),
}

impl Value {
    /// The typed value of `data` for `register`. Fields with a fixed meaning are
    /// checked (`OutOfRange` when they are not); plain numbers are taken as reported.
    pub fn decode(register: Register, data: u32) -> Result<Self, Error> {
        Ok(match register {
            Register::Mode => Self::Mode(Mode::from_data(data)?),
            Register::DigIo => Self::DigIo(DigIo::from_data(data)?),
            Register::DigIoConfig => Self::DigIoConfig(DigIoConfig::from_data(data)?),
            Register::Mdr0 => Self::Mdr0(Mdr0::from_data(data)?),
            Register::Mdr1 => Self::Mdr1(Mdr1::from_data(data)?),
            Register::Capture => Self::Capture(data as i32),
            Register::Str => Self::Str(Str::from_data(data)?),
            Register::Otr => Self::Otr(data as i32),
            Register::Dtr => Self::Dtr(data),
            Register::ClearReg => Self::Clear(ClearTarget::from_data(data)?),
            Register::LoadReg => Self::Load(LoadTarget::from_data(data)?),
            Register::Threshold => {
                Self::Threshold(u16::try_from(data).map_err(|_| Error::OutOfRange)?)
            }
            Register::IntervalRate => Self::IntervalRate(IntervalRate::from_data(data)?),
            Register::TimeStamp => Self::TimeStamp(data),
            Register::ReadEncoder => Self::Encoder(data),
            Register::MdStepRate => Self::StepRate(data),
            Register::MdAccel => Self::Accel(data),
            Register::MdMoveSteps => Self::MoveSteps(data as i32),
            Register::MdJogRate => Self::JogRate(data as i32),
            Register::MdStatus => Self::MdStatus(MdStatus::from_data(data)?),
            Register::Version => Self::Version(Version::from_data(data)?),
            Register::Eor => Self::Eor(Eor::from_data(data)?),
            Register::Command => Self::Command(QsbCommand::from_data(data)?),
        })
    }

    /// The register the value belongs to.
    pub const fn register(&self) -> Register {
        match self {
            Self::Mode(_) => Register::Mode,
            Self::DigIo(_) => Register::DigIo,
            Self::DigIoConfig(_) => Register::DigIoConfig,
            Self::Mdr0(_) => Register::Mdr0,
            Self::Mdr1(_) => Register::Mdr1,
            Self::Capture(_) => Register::Capture,
            Self::Str(_) => Register::Str,
            Self::Otr(_) => Register::Otr,
            Self::Dtr(_) => Register::Dtr,
            Self::Clear(_) => Register::ClearReg,
            Self::Load(_) => Register::LoadReg,
            Self::Threshold(_) => Register::Threshold,
            Self::IntervalRate(_) => Register::IntervalRate,
            Self::TimeStamp(_) => Register::TimeStamp,
            Self::Encoder(_) => Register::ReadEncoder,
            Self::StepRate(_) => Register::MdStepRate,
            Self::Accel(_) => Register::MdAccel,
            Self::MoveSteps(_) => Register::MdMoveSteps,
            Self::JogRate(_) => Register::MdJogRate,
            Self::MdStatus(_) => Register::MdStatus,
            Self::Version(_) => Register::Version,
            Self::Eor(_) => Register::Eor,
            Self::Command(_) => Register::Command,
        }
    }

    /// The data field.
    pub const fn data(&self) -> u32 {
        match *self {
            Self::Mode(v) => v.data(),
            Self::DigIo(v) => v.data(),
            Self::DigIoConfig(v) => v.data(),
            Self::Mdr0(v) => v.data(),
            Self::Mdr1(v) => v.data(),
            Self::Capture(v) | Self::Otr(v) | Self::MoveSteps(v) | Self::JogRate(v) => v as u32,
            Self::Str(v) => v.data(),
            Self::Dtr(v) | Self::TimeStamp(v) | Self::Encoder(v) => v,
            Self::StepRate(v) | Self::Accel(v) => v,
            Self::Clear(v) => v.data(),
            Self::Load(v) => v.data(),
            Self::Threshold(v) => v as u32,
            Self::IntervalRate(v) => v.data(),
            Self::MdStatus(v) => v.data(),
            Self::Version(v) => v.data(),
            Self::Eor(v) => v.data(),
            Self::Command(v) => v.data(),
        }
    }
}
