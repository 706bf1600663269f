//! The Trinamic SIXpack / QUADpack as a motiond board ([`TmcpackBoard`]): a serial board
//! (RS-232 or RS-485, manual 2) with six or four stepper channels; packs on one RS-485 bus
//! share the link, told apart by their address (manual 6.1); they start at the factory
//! 19200 baud (manual 7.2 `$40`). It speaks CAN 2.0A too (manual 6.2: a `socketcan` or
//! `sim-can` link, identifier = address << 3, 125 k / 250 k / 500 k / 1 Mbit/s by jumper).
//! Its driver is [`driver`], its simulator [`sim`], its machine keys [`machine_keys`].
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod driver;
mod keys;
pub mod machine_keys;
mod readings;
pub mod sim;
mod standalone;

use motion_board::keys::{AxisContext, DeviceContext, KeyIssues, KeyTable, key_names};
use motion_board::machine::MachineView;
use motion_board::{
    AddressKey, AxisKeys, Board, CanFacts, DeviceKeys, LinkFacts, SimBoard, StandaloneError,
    StandaloneHelp, StandaloneSim, TypedBoard,
};
use motion_drivers::spec::{DeviceMachine, DriverSpec, MachineKeys};
use motion_drivers::{Model, PinInfo};

use driver::{TmcpackDriver, TmcpackDriverConfig, pins};
pub use machine_keys::{
    CurrentKeys, PackVariant, PiKeys, PositionMode, PowerDownMode, ReadyOutputKeys, ReferenceKeys,
    TmcpackAxisKeys, TmcpackDeviceKeys,
};

/// The Trinamic pack.
#[derive(Debug, Clone, Copy)]
pub struct TmcpackBoard;

impl Board for TmcpackBoard {
    fn model(&self) -> Model {
        Model::TMCPACK
    }

    fn link(&self) -> LinkFacts {
        LinkFacts {
            shared: true,
            default_rate: 19_200,
            spi_mode: 0,
            // RS-232 or RS-485 (manual 2): a UART, whatever adapter the host uses.
            host_frame: None,
        }
    }

    /// Manual 6.2: "The integrated CAN-Controller supports the full-CAN-specifications 2.0A
    /// with 11 address bits", at the rate its jumpers JP1/JP2 select ("250 kbit/s
    /// (default)").
    fn can(&self) -> Option<CanFacts> {
        const BITRATES: [u32; 4] = [
            tmcpack::CanBitrate::ALL[0].bits_per_second(),
            tmcpack::CanBitrate::ALL[1].bits_per_second(),
            tmcpack::CanBitrate::ALL[2].bits_per_second(),
            tmcpack::CanBitrate::ALL[3].bits_per_second(),
        ];
        Some(CanFacts {
            bitrates: &BITRATES,
            default_bitrate: tmcpack::CAN_DEFAULT_BITRATE,
        })
    }

    fn channel_count(&self, machine: &DeviceMachine) -> usize {
        match machine.get_or_default::<TmcpackDeviceKeys>().variant {
            PackVariant::Sixpack => 6,
            PackVariant::Quadpack => 4,
        }
    }

    fn pins(&self, machine: &DeviceMachine) -> &'static [PinInfo] {
        pins(machine.get_or_default::<TmcpackDeviceKeys>().variant.into())
    }

    fn device_key_names(&self) -> &'static [&'static str] {
        key_names::<keys::RawDevice>()
    }

    fn axis_key_names(&self) -> &'static [&'static str] {
        key_names::<keys::RawAxis>()
    }

    fn address(&self) -> Option<AddressKey> {
        Some(AddressKey {
            default: 1,
            check: keys::check_address,
        })
    }

    fn device_keys(
        &self,
        keys: &KeyTable<'_>,
        ctx: &DeviceContext,
        issues: &mut dyn KeyIssues,
    ) -> Option<DeviceKeys> {
        keys::device_keys(issues, ctx, keys)
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
        SimBoard::Stream(Box::new(sim::machine::model(spec, seed)))
    }

    fn simulate_can(
        &self,
        spec: &DriverSpec,
        seed: u64,
    ) -> Option<Box<dyn motion_link::sim::CanDevice>> {
        Some(Box::new(sim::machine::model(spec, seed)))
    }
}

impl TypedBoard for TmcpackBoard {
    type Config = TmcpackDriverConfig;
    type Driver = TmcpackDriver;
    const NEW_DRIVER: fn(TmcpackDriverConfig) -> TmcpackDriver = TmcpackDriver::new;
    const STANDALONE_HELP: StandaloneHelp = standalone::HELP;
    const SIMULATE_STANDALONE: fn(&StandaloneSim) -> Result<SimBoard, StandaloneError> =
        standalone::simulate;
}
