//! The simulated boards the bench serves, built through the board registry
//! (`motion_board::Board::simulate_standalone`, as the `motion-sim` tool builds them): the
//! bench picks a board by its model, not by its simulator's type. What stays board-specific
//! is on purpose: which message of each board's wire the rows time (`wire_board`).

use motion_base::Model;
use motion_board::{SimBoard, StandaloneSim};
use motion_link::sim::{SpiDevice, StreamDevice};

/// The SPI clock the simulated SPI boards count wire time at: the boards' 500 kHz.
const SPI_HZ: u32 = 500_000;

/// The simulated `model` with its defaults, at `address` and with `drive` where given.
fn simulated(model: Model, address: Option<u8>, drive: Option<&str>) -> Result<SimBoard, String> {
    let options = StandaloneSim {
        address,
        drive: drive.map(str::to_owned),
        spi_hz: SPI_HZ,
        ..StandaloneSim::default()
    };
    motion_boards::board(model)
        .simulate_standalone(&options)
        .map_err(|error| format!("simulate {model}: {error}"))
}

/// A simulated serial board: `model` with its defaults.
///
/// # Errors
/// `model` is an SPI board.
pub fn serial_board(model: Model) -> Result<Box<dyn StreamDevice>, String> {
    match simulated(model, None, None)? {
        SimBoard::Stream(device) => Ok(device),
        SimBoard::Spi(_) => Err(format!("{model} is an SPI board, not a serial one")),
    }
}

/// A simulated SPI board: `model` at `address`, driving `drive`, where given.
///
/// # Errors
/// `model` is a serial board, or refuses the address or drive.
pub fn spi_board(
    model: Model,
    address: Option<u8>,
    drive: Option<&str>,
) -> Result<Box<dyn SpiDevice>, String> {
    match simulated(model, address, drive)? {
        SimBoard::Spi(device) => Ok(device),
        SimBoard::Stream(_) => Err(format!("{model} is a serial board, not an SPI one")),
    }
}

#[cfg(test)]
mod tests {
    use super::{serial_board, spi_board};
    use motion_base::Model;

    #[test]
    fn boards_come_on_their_own_wire_only() {
        assert!(serial_board(Model::QSB).is_ok());
        assert!(serial_board(Model::TMCPACK).is_ok());
        assert!(serial_board(Model::QQ2DRV).is_err());
        assert!(spi_board(Model::QQ2DRV, None, None).is_ok());
        assert!(spi_board(Model::SPIMOTOR, Some(0x90), Some("stepper")).is_ok());
        assert!(
            spi_board(Model::SPIMOTOR, Some(0x91), None).is_err(),
            "odd address"
        );
        assert!(spi_board(Model::QSB, None, None).is_err());
    }
}
