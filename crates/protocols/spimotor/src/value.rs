//! Typed values carried by the ports.

use core::time::Duration;

use crate::Error;

/// One of the two brushed motors ("two separate brushed motors section").
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Motor {
    /// Motor A: ports 0x20–0x22.
    A,
    /// Motor B: ports 0x30–0x32.
    B,
}

impl Motor {
    /// Both motors, in channel order.
    pub const ALL: [Self; 2] = [Self::A, Self::B];

    /// motiond's channel number of the motor: A = 0, B = 1.
    pub const fn channel(self) -> u8 {
        match self {
            Self::A => 0,
            Self::B => 1,
        }
    }

    /// The motor of a channel number.
    pub const fn from_channel(channel: u8) -> Option<Self> {
        match channel {
            0 => Some(Self::A),
            1 => Some(Self::B),
            _ => None,
        }
    }
}

/// Spin direction of a brushed motor, named as in the datasheet ("direction A",
/// "direction B"); which way that turns the shaft depends on the wiring.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Direction {
    /// Ports 0x20 / 0x30.
    A,
    /// Ports 0x21 / 0x31.
    B,
}

/// Port 0x44: "Writing 0x00 means driving one coil, other values mean driving two coils".
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Coils {
    /// Wave drive: one coil energised at a time (written as 0x00).
    One,
    /// Two coils energised at a time (written as 0x01; any non-zero byte means this).
    Two,
}

impl Coils {
    /// The meaning of a byte written to port 0x44.
    pub const fn from_byte(byte: u8) -> Self {
        if byte == 0 { Self::One } else { Self::Two }
    }

    /// The byte this crate writes for the setting.
    pub const fn to_byte(self) -> u8 {
        match self {
            Self::One => 0x00,
            Self::Two => 0x01,
        }
    }
}

/// Port 0x43: time between two steps, one byte in tenths of a millisecond both ways
/// (docs/ARCHITECTURE.md: the read table's "microsecond" is a slip). Default 200 = 20 ms.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord,
)]
pub struct StepDelay(u8);

impl StepDelay {
    /// The power-on step delay: "default 200: 20ms between steps".
    pub const DEFAULT: Self = Self(200);
    /// One unit of the port: a tenth of a millisecond.
    pub const UNIT: Duration = Duration::from_micros(100);

    /// A step delay of `tenths` tenths of a millisecond.
    pub const fn from_tenths_ms(tenths: u8) -> Self {
        Self(tenths)
    }

    /// The byte on the wire.
    pub const fn tenths_ms(self) -> u8 {
        self.0
    }

    /// The delay as a duration (`tenths` × 100 µs).
    pub const fn duration(self) -> Duration {
        Duration::from_micros(self.0 as u64 * 100)
    }

    /// The shortest step delay that is at least `delay` (rounds up to the next tenth of a
    /// millisecond, so a motor is never asked to step faster than requested).
    ///
    /// # Errors
    /// [`Error::StepDelayRange`] above 25.5 ms.
    pub fn at_least(delay: Duration) -> Result<Self, Error> {
        let tenths = delay.as_nanos().div_ceil(Self::UNIT.as_nanos());
        u8::try_from(tenths)
            .map(Self)
            .map_err(|_| Error::StepDelayRange)
    }
}

impl Default for StepDelay {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Most text bytes an [`Identification`] holds (the terminating 0 not counted).
pub const IDENTIFICATION_CAPACITY: usize = 32;

/// Port 0x01: the identification string, "terminated with 0". Held in a fixed buffer so
/// decoding never allocates.
#[derive(serde::Serialize, serde::Deserialize, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Identification {
    bytes: [u8; IDENTIFICATION_CAPACITY],
    len: u8,
}

impl Identification {
    /// The string of an SPI_motor board as the datasheet's example shows it.
    pub const SPI_MOTOR: &'static [u8] = b"spi_motor";

    /// An identification from its text (without the terminator).
    ///
    /// # Errors
    /// [`Error::InvalidIdentification`] when longer than [`IDENTIFICATION_CAPACITY`] or
    /// containing a 0 byte (which would end it early on the wire).
    pub fn new(text: &[u8]) -> Result<Self, Error> {
        if text.len() > IDENTIFICATION_CAPACITY || text.contains(&0) {
            return Err(Error::InvalidIdentification);
        }
        let mut bytes = [0; IDENTIFICATION_CAPACITY];
        let len = u8::try_from(text.len()).map_err(|_| Error::InvalidIdentification)?;
        bytes
            .get_mut(..text.len())
            .ok_or(Error::InvalidIdentification)?
            .copy_from_slice(text);
        Ok(Self { bytes, len })
    }

    /// The text bytes, without the terminator.
    pub fn as_bytes(&self) -> &[u8] {
        self.bytes.get(..usize::from(self.len)).unwrap_or(&[])
    }

    /// The text when it is valid UTF-8.
    pub fn as_str(&self) -> Option<&str> {
        core::str::from_utf8(self.as_bytes()).ok()
    }

    /// Bytes on the wire: the text and its terminating 0.
    pub fn wire_len(&self) -> usize {
        usize::from(self.len) + 1
    }
}

impl Default for Identification {
    fn default() -> Self {
        let mut bytes = [0; IDENTIFICATION_CAPACITY];
        for (dst, src) in bytes.iter_mut().zip(Self::SPI_MOTOR) {
            *dst = *src;
        }
        let len = Self::SPI_MOTOR.len().min(IDENTIFICATION_CAPACITY);
        Self {
            bytes,
            len: u8::try_from(len).unwrap_or(0),
        }
    }
}

impl core::fmt::Debug for Identification {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "Identification(\"{}\")", self.as_bytes().escape_ascii())
    }
}

/// Port 0x02: "read eeprom (serial number)". The datasheet gives no width; like every
/// other multi-byte value of the board it is read here as 4 bytes little-endian.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct SerialNumber(pub u32);

impl SerialNumber {
    /// Bytes on the wire.
    pub const LEN: usize = 4;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identification_rejects_zero_and_overlong_text() {
        assert_eq!(
            Identification::new(b"spi\0motor"),
            Err(Error::InvalidIdentification)
        );
        assert_eq!(
            Identification::new(&[b'a'; IDENTIFICATION_CAPACITY + 1]),
            Err(Error::InvalidIdentification)
        );
        let full = Identification::new(&[b'a'; IDENTIFICATION_CAPACITY]).unwrap();
        assert_eq!(full.wire_len(), IDENTIFICATION_CAPACITY + 1);
        assert_eq!(Identification::default().as_bytes(), b"spi_motor");
        assert_eq!(
            format!("{:?}", Identification::new(b"a\x01").unwrap()),
            "Identification(\"a\\x01\")"
        );
    }

    #[test]
    fn step_delay_units() {
        assert_eq!(StepDelay::from_tenths_ms(1).duration(), StepDelay::UNIT);
        assert_eq!(
            StepDelay::from_tenths_ms(255).duration(),
            Duration::from_micros(25_500)
        );
        assert_eq!(StepDelay::at_least(Duration::ZERO), Ok(StepDelay(0)));
    }
}
