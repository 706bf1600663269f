//! The QuadQuad2Drv as a motiond board ([`Qq2drvBoard`]): an SPI board with four DC motor
//! channels under the board's own PID, alone on its link (its frames have no address),
//! SPI mode 1 at the datasheet's recommended 500 kHz ("We recommend clocking SPI up to
//! 500kHz", QuadQuad2Drv datasheet). Its driver is [`driver`], its simulator [`sim`],
//! its machine keys [`machine_keys`].
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod driver;
mod keys;
pub mod machine_keys;
pub mod sim;
mod standalone;

use motion_board::keys::{AxisContext, DeviceContext, KeyIssues, KeyTable, key_names};
use motion_board::machine::MachineView;
use motion_board::{
    AxisKeys, Board, DeviceKeys, LinkFacts, SimBoard, StandaloneError, StandaloneHelp,
    StandaloneSim, TypedBoard,
};
use motion_drivers::spec::{DeviceMachine, DriverSpec, MachineKeys};
use motion_drivers::{Model, PinInfo};

use driver::{PINS, Qq2drvDriver, Qq2drvDriverConfig};
pub use machine_keys::{PidKeys, Qq2drvAxisKeys, Qq2drvDeviceKeys};

/// The QuadQuad2Drv.
#[derive(Debug, Clone, Copy)]
pub struct Qq2drvBoard;

impl Board for Qq2drvBoard {
    fn model(&self) -> Model {
        Model::QQ2DRV
    }

    fn link(&self) -> LinkFacts {
        LinkFacts {
            shared: false,
            default_rate: 500_000,
            spi_mode: 1,
            host_frame: None,
        }
    }

    fn channel_count(&self, _machine: &DeviceMachine) -> usize {
        4
    }

    fn pins(&self, _machine: &DeviceMachine) -> &'static [PinInfo] {
        PINS
    }

    fn device_key_names(&self) -> &'static [&'static str] {
        key_names::<keys::RawDevice>()
    }

    fn device_keys(
        &self,
        keys: &KeyTable<'_>,
        ctx: &DeviceContext,
        issues: &mut dyn KeyIssues,
    ) -> Option<DeviceKeys> {
        keys::device_keys(issues, ctx, keys)
    }

    fn axis_key_names(&self) -> &'static [&'static str] {
        keys::AXIS_KEYS
    }

    fn axis_keys(
        &self,
        keys: &KeyTable<'_>,
        _device: &MachineKeys,
        ctx: &AxisContext<'_>,
        issues: &mut dyn KeyIssues,
    ) -> Option<AxisKeys> {
        keys::axis_keys(issues, ctx, keys)
    }

    fn cross_check(&self, machine: &MachineView<'_>, issues: &mut dyn KeyIssues) {
        keys::cross_check(issues, machine);
    }

    fn simulate(&self, spec: &DriverSpec, seed: u64) -> SimBoard {
        SimBoard::Spi(Box::new(sim::machine::model(spec, seed)))
    }
}

impl TypedBoard for Qq2drvBoard {
    type Config = Qq2drvDriverConfig;
    type Driver = Qq2drvDriver;
    const NEW_DRIVER: fn(Qq2drvDriverConfig) -> Qq2drvDriver = Qq2drvDriver::new;
    const STANDALONE_HELP: StandaloneHelp = standalone::HELP;
    const SIMULATE_STANDALONE: fn(&StandaloneSim) -> Result<SimBoard, StandaloneError> =
        standalone::simulate;
}
