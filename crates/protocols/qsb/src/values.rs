//! Typed values of the MODE, DIG I/O, DIG I/O CONFIG, INTERVAL RATE, EOR and VERSION
//! registers, and the special analog data format.

use core::time::Duration;

use crate::{Error, ProductType};

/// Length of one time stamp / INTERVAL RATE tick: 1/512 s = 1.953125 ms ("1.95ms steps
/// (1/512 Hz clock)"; the response section's "1/256 Hz" is read as a slip, see the crate
/// docs).
pub const TICK: Duration = Duration::from_nanos(1_953_125);

/// Resolution of the 16-bit time stamp inside the analog data format: 500 µs.
pub const ANALOG_TICK: Duration = Duration::from_micros(500);

/// Inherent measurement processing delay per reported value in quadrature and PWM mode
/// (INTERVAL RATE note, document version 1.28).
pub const PROCESSING_DELAY: Duration = Duration::from_micros(100);

/// Inherent measurement processing delay per reported value in analog mode.
pub const ANALOG_PROCESSING_DELAY: Duration = Duration::from_micros(200);

/// Encoder input type, MODE bits B1 B0.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub enum EncoderMode {
    /// 00: quadrature (or step/direction, see MDR0) counting.
    #[default]
    Quadrature,
    /// 01: US Digital PWM absolute encoder (250 Hz 12-bit or 1 kHz 10-bit).
    Pwm,
    /// 10: 10-bit analog input, 0–5 V.
    Analog,
}

/// MODE register (00).
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub struct Mode {
    /// B1 B0: encoder type.
    pub encoder: EncoderMode,
    /// B4 (read only): the connected PWM encoder has 12-bit resolution (else 10-bit).
    pub pwm_12bit: bool,
}

impl Mode {
    /// Largest value of the documented data range (00–12).
    pub const MAX: u32 = 0x12;

    /// Decodes a MODE value. Values above 0x12 and the undefined encoder type `11` are
    /// `OutOfRange`; the unused bits B3 B2 are ignored.
    pub fn from_data(data: u32) -> Result<Self, Error> {
        if data > Self::MAX {
            return Err(Error::OutOfRange);
        }
        let encoder = match data & 0x3 {
            0 => EncoderMode::Quadrature,
            1 => EncoderMode::Pwm,
            2 => EncoderMode::Analog,
            _ => return Err(Error::OutOfRange),
        };
        Ok(Self {
            encoder,
            pwm_12bit: data & 0x10 != 0,
        })
    }

    /// The register value.
    pub const fn data(self) -> u32 {
        let mode = match self.encoder {
            EncoderMode::Quadrature => 0,
            EncoderMode::Pwm => 1,
            EncoderMode::Analog => 2,
        };
        mode | if self.pwm_12bit { 0x10 } else { 0 }
    }
}

/// DIG I/O register (01): bit n is I/O bit n; written 1 = open-drain output released high
/// (internal pull-up), 0 = driven low; read = level measured at the pins.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub struct DigIo(pub u8);

impl DigIo {
    /// Decodes a DIG I/O value (data range 0–F).
    pub fn from_data(data: u32) -> Result<Self, Error> {
        u8::try_from(data)
            .ok()
            .filter(|v| *v <= 0xF)
            .map(Self)
            .ok_or(Error::OutOfRange)
    }

    /// The register value.
    pub const fn data(self) -> u32 {
        (self.0 & 0xF) as u32
    }

    /// Level of I/O bit `bit` (0–3).
    pub const fn bit(self, bit: u8) -> bool {
        bit < 4 && self.0 & (1 << bit) != 0
    }
}

/// DIG I/O CONFIG register (02). Each nibble holds one bit per I/O bit 3–0.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub struct DigIoConfig {
    /// B3–B0 interrupt polarity: 1 = high-to-low edge, 0 = low-to-high edge.
    pub falling_edge: u8,
    /// B7–B4 interrupt enable: an enabled edge loads CNTR into CAPTURE.
    pub interrupt_enable: u8,
    /// B11–B8 I/O direction: 1 = output enabled, 0 = input ("Set All I/O as Outputs,
    /// W02F00").
    pub output: u8,
    /// B12 trigger pulse enable: MDR1 trigger events pulse I/O bit 0 for INTERVAL RATE.
    pub trigger_pulse: bool,
}

impl DigIoConfig {
    /// Largest value of the documented data range (0000–1FFF).
    pub const MAX: u32 = 0x1FFF;

    /// Decodes a DIG I/O CONFIG value.
    pub fn from_data(data: u32) -> Result<Self, Error> {
        if data > Self::MAX {
            return Err(Error::OutOfRange);
        }
        Ok(Self {
            falling_edge: (data & 0xF) as u8,
            interrupt_enable: ((data >> 4) & 0xF) as u8,
            output: ((data >> 8) & 0xF) as u8,
            trigger_pulse: data & 0x1000 != 0,
        })
    }

    /// The register value.
    pub const fn data(self) -> u32 {
        (self.falling_edge & 0xF) as u32
            | ((self.interrupt_enable & 0xF) as u32) << 4
            | ((self.output & 0xF) as u32) << 8
            | if self.trigger_pulse { 0x1000 } else { 0 }
    }
}

/// INTERVAL RATE register (0C): the data output timer in [`TICK`] steps.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct IntervalRate(pub u16);

impl IntervalRate {
    /// 0xFFFF disables data output (the factory default).
    pub const DISABLED: Self = Self(0xFFFF);

    /// Decodes an INTERVAL RATE value (data range 0000–FFFF).
    pub fn from_data(data: u32) -> Result<Self, Error> {
        u16::try_from(data).map(Self).map_err(|_| Error::OutOfRange)
    }

    /// The register value.
    pub const fn data(self) -> u32 {
        self.0 as u32
    }

    /// The output period, `None` when output is disabled. `Some(ZERO)` means "no delay":
    /// each value still takes the inherent processing delay.
    pub fn period(self) -> Option<Duration> {
        (self != Self::DISABLED).then(|| TICK * u32::from(self.0))
    }

    /// The longest period that still outputs data: 0xFFFE ticks (127.99 s); 0xFFFF would
    /// disable output.
    pub const LONGEST: Self = Self(0xFFFE);

    /// The INTERVAL RATE whose period is nearest to `period` ("sets the data output timer
    /// in 1.95ms steps"): `period` rounded to whole [`TICK`]s, halves up. `None` when that
    /// is beyond [`LONGEST`](Self::LONGEST) (the next value, 0xFFFF, disables output).
    pub fn nearest(period: Duration) -> Option<Self> {
        let tick = TICK.as_nanos();
        let ticks = (period.as_nanos() + tick / 2) / tick;
        u16::try_from(ticks)
            .ok()
            .filter(|t| *t <= Self::LONGEST.0)
            .map(Self)
    }
}

impl Default for IntervalRate {
    fn default() -> Self {
        Self::DISABLED
    }
}

/// EOR register (15): end-of-response termination and formatting.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Eor {
    /// B0: line feed after `!`.
    pub line_feed: bool,
    /// B1: carriage return after `!` (sent before the line feed).
    pub carriage_return: bool,
    /// B2: 4-byte time stamp appended to the response, before `!`.
    pub time_stamp: bool,
    /// B3: spaces between the returned fields.
    pub spaces: bool,
}

impl Eor {
    /// The factory setting 0x0B: CR, LF and spaces, no time stamp.
    pub const FACTORY: Self = Self {
        line_feed: true,
        carriage_return: true,
        time_stamp: false,
        spaces: true,
    };

    /// Decodes an EOR value (data range 0–F).
    pub fn from_data(data: u32) -> Result<Self, Error> {
        if data > 0xF {
            return Err(Error::OutOfRange);
        }
        Ok(Self {
            line_feed: data & 1 != 0,
            carriage_return: data & 2 != 0,
            time_stamp: data & 4 != 0,
            spaces: data & 8 != 0,
        })
    }

    /// The register value.
    pub const fn data(self) -> u32 {
        (self.line_feed as u32)
            | (self.carriage_return as u32) << 1
            | (self.time_stamp as u32) << 2
            | (self.spaces as u32) << 3
    }
}

impl Default for Eor {
    fn default() -> Self {
        Self::FACTORY
    }
}

/// VERSION register (14): "the first five most significant digits are the serial number,
/// the next digit is the product type and the last two digits are the firmware version".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Version {
    /// Serial number, the five most significant hex digits (20 bits).
    pub serial: u32,
    /// Product type digit.
    pub product: ProductType,
    /// Firmware version, the last two digits as written (e.g. `0x13` is version "13").
    pub firmware: u8,
}

impl Version {
    /// First firmware that has the baud-rate selection command (`X0A`, "firmware version
    /// >= 13").
    pub const BAUD_SELECTION_FIRMWARE: u8 = 0x13;

    /// Decodes a VERSION value; an unknown product type digit is `OutOfRange`.
    pub fn from_data(data: u32) -> Result<Self, Error> {
        let product = ProductType::from_code(((data >> 8) & 0xF) as u8).ok_or(Error::OutOfRange)?;
        Ok(Self {
            serial: data >> 12,
            product,
            firmware: (data & 0xFF) as u8,
        })
    }

    /// The register value. Serial numbers wider than 20 bits are truncated.
    pub const fn data(self) -> u32 {
        (self.serial & 0xF_FFFF) << 12 | (self.product.code() as u32) << 8 | self.firmware as u32
    }

    /// Whether this firmware accepts the baud-rate selection command.
    pub const fn supports_baud_selection(self) -> bool {
        self.firmware >= Self::BAUD_SELECTION_FIRMWARE
    }
}

/// One sample of the "Special Analog Measurement" data format, which replaces the data
/// field of streamed READ ENCODER lines in analog mode:
/// time stamp \[16 bits\], digital I/O \[4 bits\], `00`, analog \[10 bits\].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct AnalogSample {
    /// 16-bit counter of [`ANALOG_TICK`] (500 µs), rolls over every ~32 s.
    pub time_stamp: u16,
    /// Digital inputs bit 3–bit 0.
    pub digital: u8,
    /// 10-bit conversion of the 0–5 V analog input.
    pub analog: u16,
}

impl AnalogSample {
    /// Full scale of the 10-bit analog value.
    pub const ANALOG_MAX: u16 = 0x3FF;

    /// Decodes the data field; the two fixed zero bits must be zero.
    pub fn from_data(data: u32) -> Result<Self, Error> {
        if data & 0x0C00 != 0 {
            return Err(Error::OutOfRange);
        }
        Ok(Self {
            time_stamp: (data >> 16) as u16,
            digital: ((data >> 12) & 0xF) as u8,
            analog: (data & 0x3FF) as u16,
        })
    }

    /// The data field. Out-of-width digital and analog values are masked.
    pub const fn data(self) -> u32 {
        (self.time_stamp as u32) << 16
            | ((self.digital & 0xF) as u32) << 12
            | (self.analog & Self::ANALOG_MAX) as u32
    }

    /// The analog input in volts (0–5 V full scale).
    pub fn volts(self) -> f64 {
        f64::from(self.analog) * 5.0 / f64::from(Self::ANALOG_MAX)
    }
}
