//! Configuration of a simulated SPI_motor board.

use core::time::Duration;

use spimotor::{Address, Identification, SerialNumber};

/// What is connected to the board's two H-bridges.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Drive {
    /// One stepper motor: a single axis on channel 0 (ports 0x10, 0x40–0x44).
    #[default]
    Stepper,
    /// Two brushed DC motors: channel 0 = motor A (ports 0x20–0x22), channel 1 = motor B
    /// (ports 0x30–0x32).
    Brushed,
}

impl Drive {
    /// Number of motor channels the drive exposes.
    pub const fn channels(self) -> usize {
        match self {
            Self::Stepper => 1,
            Self::Brushed => 2,
        }
    }
}

/// Physics of one brushed DC motor driven by a PWM H-bridge (both motors share it).
///
/// The speed follows a first-order lag towards `intensity / 255 × no_load_speed` in the
/// commanded direction; a stop brakes it towards zero with the same time constant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BrushedMotorConfig {
    /// Shaft speed at intensity 255 without load, revolutions per second (6000 rpm = 100).
    pub no_load_speed: f64,
    /// Mechanical time constant of the speed response.
    pub time_constant: Duration,
    /// Relative spread of the reached speed: each spin command draws a factor uniformly
    /// from `1 ± speed_noise` (load and supply variation) from the seeded generator.
    pub speed_noise: f64,
}

impl Default for BrushedMotorConfig {
    fn default() -> Self {
        Self {
            no_load_speed: 100.0,
            time_constant: Duration::from_millis(30),
            speed_noise: 0.02,
        }
    }
}

/// Everything that makes one simulated board differ from another.
#[derive(Debug, Clone, PartialEq)]
pub struct SpimotorSimConfig {
    /// SPI address as the even byte form (0x90 answers to 0x90 and 0x91). Bit 0 is
    /// ignored. This is the address in the board's EEPROM at start; the address-change
    /// sequence moves it.
    pub address: u8,
    /// Stepper (one axis) or two brushed motors.
    pub drive: Drive,
    /// Seed of the generator behind every random effect of the model.
    pub seed: u64,
    /// What port 0x01 returns. At most [`spimotor::IDENTIFICATION_CAPACITY`] bytes are
    /// kept, up to the first NUL.
    pub identification: String,
    /// What port 0x02 returns (the serial number in the board's EEPROM).
    pub serial: u32,
    /// Physics of motors A and B (drive [`Drive::Brushed`]).
    pub brushed: BrushedMotorConfig,
}

impl Default for SpimotorSimConfig {
    fn default() -> Self {
        Self {
            address: Address::DEFAULT.get(),
            drive: Drive::Stepper,
            seed: 0,
            identification: String::from("spi_motor"),
            serial: 0x0000_0001,
            brushed: BrushedMotorConfig::default(),
        }
    }
}

impl SpimotorSimConfig {
    /// The identification as the protocol type: cut at the first NUL and to capacity.
    pub(super) fn wire_identification(&self) -> Identification {
        let bytes = self.identification.as_bytes();
        let end = bytes
            .iter()
            .position(|&b| b == 0)
            .unwrap_or(bytes.len())
            .min(spimotor::IDENTIFICATION_CAPACITY);
        Identification::new(bytes.get(..end).unwrap_or(&[])).unwrap_or_default()
    }

    /// The serial number as the protocol type.
    pub(super) fn wire_serial(&self) -> SerialNumber {
        SerialNumber(self.serial)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identification_is_cut_at_nul_and_capacity() {
        let with = |s: &str| SpimotorSimConfig {
            identification: s.into(),
            ..Default::default()
        };
        assert_eq!(
            with("spi_motor").wire_identification().as_bytes(),
            b"spi_motor"
        );
        assert_eq!(with("ab\0cd").wire_identification().as_bytes(), b"ab");
        let long = "x".repeat(100);
        assert_eq!(
            with(&long).wire_identification().as_bytes().len(),
            spimotor::IDENTIFICATION_CAPACITY
        );
        assert_eq!(SpimotorSimConfig::default().address, 0x90);
        assert_eq!(Drive::default(), Drive::Stepper);
    }
}
