//! An SPI_motor served alone by `motion-sim`: `--address` (even), `--drive
//! stepper|brushed`, `--seed`.

use crate::sim::{Drive, SpimotorSim, SpimotorSimConfig};
use motion_board::{SimBoard, StandaloneError, StandaloneHelp, StandaloneSim};
use motion_drivers::Model;

/// `motion-sim --help` on the SPI_motor.
pub(crate) const HELP: StandaloneHelp = StandaloneHelp {
    summary: "SPI_motor, SPI, default address 0x90",
    options: "--address, --drive stepper|brushed",
    examples: "\
motion-sim --model spimotor --address 0x90 --model spimotor --address 0x92 --drive brushed --spi-socket /tmp/motors.sock",
};

/// The simulated board `options` ask for.
pub(crate) fn simulate(options: &StandaloneSim) -> Result<SimBoard, StandaloneError> {
    options.refuse(Model::SPIMOTOR, &["variant"])?;
    let mut config = SpimotorSimConfig::default();
    if let Some(address) = options.address {
        if address & 1 != 0 {
            return Err(StandaloneError::Invalid {
                option: "address",
                message: format!(
                    "spimotor --address 0x{address:02x}: an SPI_motor address is even \
                     (bit 0 is the read flag); did you mean 0x{:02x}?",
                    address & 0xFE
                ),
            });
        }
        config.address = address;
    }
    config.drive = options.choice(
        Model::SPIMOTOR,
        "drive",
        &[("stepper", Drive::Stepper), ("brushed", Drive::Brushed)],
        Drive::Stepper,
        "use stepper or brushed",
    )?;
    if let Some(seed) = options.seed {
        config.seed = seed;
    }
    Ok(SimBoard::Spi(Box::new(SpimotorSim::new(config))))
}
