//! The US Digital QSB as a motiond board ([`QsbBoard`]): a USB serial encoder interface
//! (the -M also drives a stepper), alone on its virtual COM port, which starts at 230400
//! baud; "The commands and responses are sent in RS-232 format over a virtual COM port
//! connection through the USB" (QSB command list, Communications), so its bytes reach the
//! host at the end of each 1 ms full-speed USB frame. Its driver is [`driver`], its
//! simulator [`sim`], its machine keys [`machine_keys`].
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod driver;
pub mod machine_keys;
pub mod sim;
mod standalone;

use core::time::Duration;

mod keys;

use motion_board::keys::{DeviceContext, KeyIssues, KeyTable, key_names};
use motion_board::machine::MachineView;
use motion_board::{
    Board, DeviceKeys, LinkFacts, SimBoard, StandaloneError, StandaloneHelp, StandaloneSim,
    TypedBoard,
};
use motion_drivers::spec::{DeviceMachine, DriverSpec};
use motion_drivers::{Model, PinInfo};

use driver::{QsbDriver, QsbDriverConfig, pins};
pub use machine_keys::{QsbDeviceKeys, QsbInputMode, QsbVariant, TriggerSources};
use sim::{DriveEnable, QsbSim, QsbSimConfig, Variant};

/// A full-speed USB device is polled once per 1 ms frame.
pub const USB_FRAME: Duration = Duration::from_millis(1);

/// The QSB.
#[derive(Debug, Clone, Copy)]
pub struct QsbBoard;

impl Board for QsbBoard {
    fn model(&self) -> Model {
        Model::QSB
    }

    fn link(&self) -> LinkFacts {
        LinkFacts {
            shared: false,
            default_rate: 230_400,
            spi_mode: 0,
            host_frame: Some(USB_FRAME),
        }
    }

    fn channel_count(&self, _machine: &DeviceMachine) -> usize {
        1
    }

    fn pins(&self, machine: &DeviceMachine) -> &'static [PinInfo] {
        pins(machine.get_or_default::<QsbDeviceKeys>().variant.into())
    }

    fn product_name(&self, machine: &DeviceMachine) -> &'static str {
        machine.get_or_default::<QsbDeviceKeys>().variant.id()
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

    fn cross_check(&self, machine: &MachineView<'_>, issues: &mut dyn KeyIssues) {
        keys::cross_check(issues, machine);
    }

    /// The variant, the encoder's counts per motor step (in the configured `count_mode`),
    /// and the external stepper driver's
    /// enable line where `enable_output` says it is wired. (The index is the encoder's,
    /// once per revolution of the model's 500-cycle encoder: a home search finds it within
    /// 2000 counts.)
    fn simulate(&self, spec: &DriverSpec, seed: u64) -> SimBoard {
        let keys = spec.machine.get_or_default::<QsbDeviceKeys>();
        let drive_enable = keys.enable_output.map(|bit| DriveEnable {
            bit,
            active_high: keys.enable_active_high.unwrap_or(false),
        });
        let counts_per_step = keys.counts_per_step;
        let counts_per_step =
            counts_per_step.unwrap_or_else(|| QsbDriverConfig::default().counts_per_step);
        // counts_per_step is in the configured count mode's counts; the model's encoder
        // turns in quadrature cycles.
        let per_cycle = f64::from(
            driver::CounterSetup {
                count: keys.count_mode.unwrap_or_default(),
                ..driver::CounterSetup::default()
            }
            .mdr0()
            .counts_per_cycle(),
        );
        SimBoard::Stream(Box::new(QsbSim::new(QsbSimConfig {
            variant: match keys.variant {
                QsbVariant::M => Variant::M,
                QsbVariant::S => Variant::S,
                QsbVariant::D => Variant::D,
            },
            seed,
            drive_enable,
            cycles_per_step: counts_per_step / per_cycle,
            ..QsbSimConfig::default()
        })))
    }
}

impl TypedBoard for QsbBoard {
    type Config = QsbDriverConfig;
    type Driver = QsbDriver;
    const NEW_DRIVER: fn(QsbDriverConfig) -> QsbDriver = QsbDriver::new;
    const STANDALONE_HELP: StandaloneHelp = standalone::HELP;
    const SIMULATE_STANDALONE: fn(&StandaloneSim) -> Result<SimBoard, StandaloneError> =
        standalone::simulate;
}
