//! The SPI_motor as a motiond board ([`SpimotorBoard`]): an SPI board driving one stepper
//! or two brushed motors; boards on one SPI bus share it, told apart by their address
//! (SPI_motor "Motor protocol": even addresses 2..=254), SPI mode 0 at 500 kHz. Its driver
//! is [`driver`], its simulator [`sim`], its machine keys [`machine_keys`]. The board has
//! no I/O pins of its own.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod driver;
mod keys;
pub mod machine_keys;
pub mod sim;
mod standalone;

use motion_board::keys::{DeviceContext, KeyIssues, KeyTable, key_names};
use motion_board::{
    AddressKey, Board, DeviceKeys, LinkFacts, SimBoard, StandaloneError, StandaloneHelp,
    StandaloneSim, TypedBoard,
};
use motion_drivers::spec::{DeviceMachine, DriverSpec};
use motion_drivers::{Model, PinInfo};

use driver::{PINS, SpimotorDriver, SpimotorDriverConfig};
pub use machine_keys::{SpiDrive, SpimotorDeviceKeys};
use sim::{Drive, SpimotorSim, SpimotorSimConfig};

/// The SPI_motor.
#[derive(Debug, Clone, Copy)]
pub struct SpimotorBoard;

impl Board for SpimotorBoard {
    fn model(&self) -> Model {
        Model::SPIMOTOR
    }

    fn link(&self) -> LinkFacts {
        LinkFacts {
            shared: true,
            default_rate: 500_000,
            spi_mode: 0,
            host_frame: None,
        }
    }

    fn channel_count(&self, machine: &DeviceMachine) -> usize {
        match machine.get_or_default::<SpimotorDeviceKeys>().drive {
            SpiDrive::Stepper => 1,
            SpiDrive::Brushed => 2,
        }
    }

    fn pins(&self, _machine: &DeviceMachine) -> &'static [PinInfo] {
        PINS
    }

    fn device_key_names(&self) -> &'static [&'static str] {
        key_names::<keys::RawDevice>()
    }

    fn address(&self) -> Option<AddressKey> {
        Some(AddressKey {
            default: 0x90,
            check: keys::check_address,
        })
    }

    fn cannot_home(&self) -> Option<&'static str> {
        Some("an SPI_motor has no reference input, so its axes cannot home")
    }

    fn device_keys(
        &self,
        keys: &KeyTable<'_>,
        ctx: &DeviceContext,
        issues: &mut dyn KeyIssues,
    ) -> Option<DeviceKeys> {
        keys::device_keys(issues, ctx, keys)
    }

    fn simulate(&self, spec: &DriverSpec, seed: u64) -> SimBoard {
        SimBoard::Spi(Box::new(SpimotorSim::new(SpimotorSimConfig {
            address: spec.address as u8,
            drive: match spec.machine.get_or_default::<SpimotorDeviceKeys>().drive {
                SpiDrive::Stepper => Drive::Stepper,
                SpiDrive::Brushed => Drive::Brushed,
            },
            seed,
            ..SpimotorSimConfig::default()
        })))
    }
}

impl TypedBoard for SpimotorBoard {
    type Config = SpimotorDriverConfig;
    type Driver = SpimotorDriver;
    const NEW_DRIVER: fn(SpimotorDriverConfig) -> SpimotorDriver = SpimotorDriver::new;
    const STANDALONE_HELP: StandaloneHelp = standalone::HELP;
    const SIMULATE_STANDALONE: fn(&StandaloneSim) -> Result<SimBoard, StandaloneError> =
        standalone::simulate;
}
