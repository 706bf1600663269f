//! A QuadQuad2Drv served alone by `motion-sim`: `--seed` only; it counts wire time at the
//! socket's `--spi-hz`.

use crate::sim::{Qq2drvSim, Qq2drvSimConfig};
use motion_board::{SimBoard, StandaloneError, StandaloneHelp, StandaloneSim};
use motion_drivers::Model;

/// `motion-sim --help` on the QuadQuad2Drv.
pub(crate) const HELP: StandaloneHelp = StandaloneHelp {
    summary: "QuadQuad2Drv, SPI mode 1, 500 kHz",
    options: "SPI socket",
    examples: "\
motion-sim --model qq2drv --spi-socket /tmp/qq2drv.sock
    one transaction = u16 little-endian length + MOSI bytes; the answer is as many MISO
    bytes. Version request (packet 1) then filler to clock the reply out:
      python3 -c \"import socket; s=socket.socket(socket.AF_UNIX); s.connect('/tmp/qq2drv.sock'); s.send(bytes([4,0,2,4,1,249])); print(s.recv(4).hex()); s.send(bytes([16,0])+bytes(16)); print(s.recv(16).hex())\"",
};

/// The simulated board `options` ask for.
pub(crate) fn simulate(options: &StandaloneSim) -> Result<SimBoard, StandaloneError> {
    options.refuse(Model::QQ2DRV, &["address", "variant", "drive"])?;
    let mut config = Qq2drvSimConfig {
        spi_clock_hz: options.spi_hz,
        ..Qq2drvSimConfig::default()
    };
    if let Some(seed) = options.seed {
        config.seed = seed;
    }
    Ok(SimBoard::Spi(Box::new(Qq2drvSim::new(config))))
}
