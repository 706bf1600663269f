//! A Trinamic pack served alone by `motion-sim`: `--address`, `--variant sixpack|quadpack`,
//! `--seed`. A pack always starts at its factory 19200 baud, as after power-up, whatever
//! `--baud` the pty runs at.

use crate::sim::{TmcpackSim, TmcpackSimConfig};
use motion_board::{SimBoard, StandaloneError, StandaloneHelp, StandaloneSim};
use motion_drivers::Model;
use tmcpack::Variant;

/// `motion-sim --help` on the pack.
pub(crate) const HELP: StandaloneHelp = StandaloneHelp {
    summary: "Trinamic SIXpack/QUADpack, 9-byte frames, 19200 baud",
    options: "--address, --variant sixpack|quadpack",
    examples: "\
motion-sim --model tmcpack --address 1 --model tmcpack --address 2 --variant quadpack --pty
    two packs on one RS-485 bus. Unit info ($43) of pack 1, 9-byte request:
      python3 -c \"import os,time,sys; f=os.open(sys.argv[1],os.O_RDWR); os.write(f,bytes([1,0x43,0xFE,0,0,0,0,0,0])); time.sleep(0.1); print(os.read(f,64).hex())\" /dev/pts/N",
};

/// The simulated pack `options` ask for.
pub(crate) fn simulate(options: &StandaloneSim) -> Result<SimBoard, StandaloneError> {
    options.refuse(Model::TMCPACK, &["drive"])?;
    let mut config = TmcpackSimConfig::default();
    if let Some(address) = options.address {
        config.address = address;
    }
    config.variant = options.choice(
        Model::TMCPACK,
        "variant",
        &[
            ("sixpack", Variant::SixPack),
            ("quadpack", Variant::QuadPack),
        ],
        Variant::SixPack,
        "use sixpack or quadpack",
    )?;
    if let Some(seed) = options.seed {
        config.seed = seed;
    }
    Ok(SimBoard::Stream(Box::new(TmcpackSim::new(config))))
}
