//! The driver config of an SPI_motor from the neutral [`DriverSpec`]: address, drive, its
//! link's clock, the axis limits and (stepper) the drive intensity and coils; and the
//! parameters that config gives the board, as `motionctl list` shows them.

use spimotor::{Address, Coils};

use super::{SpimotorDrive, SpimotorDriverConfig};
use crate::{SpiDrive, SpimotorDeviceKeys};
use motion_drivers::spec::{DriverSpec, FromSpec, Param, ParamOwner, SpecError};

impl From<SpiDrive> for SpimotorDrive {
    fn from(drive: SpiDrive) -> Self {
        match drive {
            SpiDrive::Stepper => Self::Stepper,
            SpiDrive::Brushed => Self::Brushed,
        }
    }
}

impl FromSpec for SpimotorDriverConfig {
    /// The driver configuration of the spimotor device `spec` describes: address, drive,
    /// its link's clock, the axis limits and (stepper) the drive intensity and coils.
    fn from_spec(spec: &DriverSpec) -> Result<Self, SpecError> {
        let address = Address::new(spec.address as u8).map_err(|_| SpecError {
            channel: None,
            key: "address",
            message: format!("{} is not an SPI_motor address", spec.address),
        })?;
        let mut driver = Self {
            address,
            drive: spec
                .machine
                .get_or_default::<SpimotorDeviceKeys>()
                .drive
                .into(),
            ..Self::default()
        };
        if let Some(speed) = spec.line_rate {
            driver.speed_hz = speed;
        }
        for (channel, limits) in driver.limits.iter_mut().enumerate() {
            if let Some(configured) = spec.channel_limits(channel) {
                *limits = configured;
            }
        }
        if let Some(keys) = spec.machine.get::<SpimotorDeviceKeys>() {
            if let Some(intensity) = keys.intensity {
                driver.stepper_intensity = intensity;
            }
            match keys.coils {
                Some(1) => driver.coils = Coils::One,
                Some(_) => driver.coils = Coils::Two,
                None => {}
            }
            if let Some(silence) = keys.silence {
                driver.silence = silence;
            }
        }
        Ok(driver)
    }

    /// The machine parameters of the device, as the driver uses them: `silence_ms`, and a
    /// stepper board's `intensity` (port 0x10) and `coils` (port 0x44).
    fn params(&self, spec: &DriverSpec) -> Vec<Param> {
        let silence = Param {
            owner: ParamOwner::Device,
            key: "silence_ms",
            value: format!("{} ms", self.silence.as_millis()),
        };
        if spec.machine.get_or_default::<SpimotorDeviceKeys>().drive != SpiDrive::Stepper {
            return vec![silence];
        }
        vec![
            silence,
            Param {
                owner: ParamOwner::Device,
                key: "intensity",
                value: format!(
                    "{} (0x{:02x} of 0xff)",
                    self.stepper_intensity, self.stepper_intensity
                ),
            },
            Param {
                owner: ParamOwner::Device,
                key: "coils",
                value: match self.coils {
                    Coils::One => "1 (port 0x44 ← 0x00)".to_owned(),
                    Coils::Two => "2 (port 0x44 ← 0x01)".to_owned(),
                },
            },
        ]
    }
}
