//! The -M stepper drive registers (0F–13) and the COMMAND register (16) functions,
//! including the baud-rate selection.

use crate::{Error, ProductType};

/// MD STEP RATE (0F) range, steps/s: 32–13000 (0x20–0x32C8).
pub const STEP_RATE_RANGE: core::ops::RangeInclusive<u32> = 0x20..=0x32C8;
/// MD ACCEL (10) range, steps/s²: 64–360000 (0x40–0x57E40).
pub const ACCEL_RANGE: core::ops::RangeInclusive<u32> = 0x40..=0x57E40;
/// MD MOVE STEPS (11) range: ±(2³¹ − 1) (data 80000001–7FFFFFFF).
pub const MOVE_STEPS_RANGE: core::ops::RangeInclusive<i32> = -i32::MAX..=i32::MAX;
/// MD JOG RATE (12) range, steps/s: −13000 to 13000 (FFFFCD38–000032C8).
pub const JOG_RATE_RANGE: core::ops::RangeInclusive<i32> = -13000..=13000;
/// Rates and accelerations change in increments of 16 steps/s (steps/s²).
pub const RATE_INCREMENT: u32 = 16;

/// MD STATUS register (13).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MdStatus {
    /// B0: done / ready.
    pub done: bool,
    /// B1: moving.
    pub moving: bool,
    /// B2: paused.
    pub paused: bool,
    /// B3: jogging.
    pub jogging: bool,
    /// B4: motor drive enabled.
    pub enabled: bool,
}

impl MdStatus {
    /// The factory / power-up value 1: done, drive not enabled.
    pub const POWER_UP: Self = Self {
        done: true,
        moving: false,
        paused: false,
        jogging: false,
        enabled: false,
    };

    /// Decodes an MD STATUS value (data range 0–1F).
    pub fn from_data(data: u32) -> Result<Self, Error> {
        if data > 0x1F {
            return Err(Error::OutOfRange);
        }
        Ok(Self {
            done: data & 1 != 0,
            moving: data & 2 != 0,
            paused: data & 4 != 0,
            jogging: data & 8 != 0,
            enabled: data & 0x10 != 0,
        })
    }

    /// The register value.
    pub const fn data(self) -> u32 {
        (self.done as u32)
            | (self.moving as u32) << 1
            | (self.paused as u32) << 2
            | (self.jogging as u32) << 3
            | (self.enabled as u32) << 4
    }
}

/// The baud rates of the `X0A` selection command.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BaudRate {
    /// X = 0.
    B9600,
    /// X = 1.
    B19200,
    /// X = 2.
    B38400,
    /// X = 3.
    B56000,
    /// X = 4.
    B115200,
    /// X = 5.
    B128000,
    /// X = 6: the factory rate.
    B230400,
    /// X = 7.
    B256000,
}

impl BaudRate {
    /// All rates in selection order.
    pub const ALL: [Self; 8] = [
        Self::B9600,
        Self::B19200,
        Self::B38400,
        Self::B56000,
        Self::B115200,
        Self::B128000,
        Self::B230400,
        Self::B256000,
    ];

    /// The factory data rate, 230.4 kb/s.
    pub const FACTORY: Self = Self::B230400;

    /// The selection digit X.
    pub const fn selector(self) -> u8 {
        self as u8
    }

    /// The rate with selection digit `x`.
    pub fn from_selector(x: u8) -> Option<Self> {
        Self::ALL.get(usize::from(x)).copied()
    }

    /// Bits per second.
    pub const fn bits_per_second(self) -> u32 {
        match self {
            Self::B9600 => 9600,
            Self::B19200 => 19200,
            Self::B38400 => 38400,
            Self::B56000 => 56000,
            Self::B115200 => 115_200,
            Self::B128000 => 128_000,
            Self::B230400 => 230_400,
            Self::B256000 => 256_000,
        }
    }
}

/// A function of the COMMAND register (16).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum QsbCommand {
    /// 0: stop the motor immediately, deactivate the encoder, digital I/O and MD STATUS
    /// streams, set the drive inactive and return the I/O port to its last saved state.
    StopAll,
    /// 1: deactivate the encoder, digital I/O and MD STATUS streams.
    StopStreaming,
    /// 2: activate motor drive mode (I/O bits 1 and 2 become step and direction).
    EnableMotorDrive,
    /// 3: save registers 00–04, 08, 0B, 0C, 0F–12, 15 and the drive-enable flag.
    SaveParameters,
    /// 4: stop the motor using MD ACCEL.
    MotorStop,
    /// 5: stop the motor immediately.
    MotorQuit,
    /// 6: pause the motor using MD ACCEL.
    MotorPause,
    /// 7: resume a paused motion with MD ACCEL.
    MotorResume,
    /// 8: move MD MOVE STEPS.
    MotorMove,
    /// 9: jog at MD JOG RATE.
    MotorJog,
    /// `X0A`: select the communication baud rate (firmware ≥ 13), saved permanently.
    SetBaud(BaudRate),
}

impl QsbCommand {
    /// Decodes COMMAND data (0–9, or `X0A` with X = 0–7; data range 0–70A).
    pub fn from_data(data: u32) -> Result<Self, Error> {
        Ok(match data {
            0 => Self::StopAll,
            1 => Self::StopStreaming,
            2 => Self::EnableMotorDrive,
            3 => Self::SaveParameters,
            4 => Self::MotorStop,
            5 => Self::MotorQuit,
            6 => Self::MotorPause,
            7 => Self::MotorResume,
            8 => Self::MotorMove,
            9 => Self::MotorJog,
            d if d & 0xFF == 0x0A && d <= 0x70A => {
                Self::SetBaud(BaudRate::from_selector((d >> 8) as u8).ok_or(Error::OutOfRange)?)
            }
            _ => return Err(Error::OutOfRange),
        })
    }

    /// The data value.
    pub const fn data(self) -> u32 {
        match self {
            Self::StopAll => 0,
            Self::StopStreaming => 1,
            Self::EnableMotorDrive => 2,
            Self::SaveParameters => 3,
            Self::MotorStop => 4,
            Self::MotorQuit => 5,
            Self::MotorPause => 6,
            Self::MotorResume => 7,
            Self::MotorMove => 8,
            Self::MotorJog => 9,
            Self::SetBaud(b) => (b.selector() as u32) << 8 | 0x0A,
        }
    }

    /// Whether `product` accepts the function ("-D and -S Data=1, 3, x0A; -M Data=0-x0A").
    pub const fn available_on(self, product: ProductType) -> bool {
        match product {
            ProductType::M => true,
            ProductType::D | ProductType::S => matches!(
                self,
                Self::StopStreaming | Self::SaveParameters | Self::SetBaud(_)
            ),
        }
    }
}

/// The effective rate of a requested MD STEP RATE or MD JOG RATE magnitude: rates change
/// in increments of 16 steps/s, so the value is rounded down to a multiple of 16.
pub const fn effective_rate(requested: u32) -> u32 {
    requested / RATE_INCREMENT * RATE_INCREMENT
}
