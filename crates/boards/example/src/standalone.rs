//! The AS-2 served alone by `motion-sim` (no config file): `--seed` only (it has no
//! address, variant or drive); the pty runs at its 115200 baud unless `--baud` says
//! otherwise.

use core::time::Duration;

use motion_board::{SimBoard, StandaloneError, StandaloneHelp, StandaloneSim};

use crate::MODEL;
use crate::sim::{ExampleSim, ExampleSimConfig};

/// `motion-sim --help` on the AS-2.
pub(crate) const HELP: StandaloneHelp = StandaloneHelp {
    summary: "AS-2 ASCII stepper (worked example), 2 channels, 115200 baud",
    options: "",
    examples: "\
motion-sim --model example --pty --link /tmp/as2
    the worked example board (crates/boards/example/README.md). Talk to it:
      screen /tmp/as2 115200          (type ? then Enter: the firmware version)",
};

/// The simulated AS-2 `options` ask for, with the jitter it has on a `type = "sim"` link.
pub(crate) fn simulate(options: &StandaloneSim) -> Result<SimBoard, StandaloneError> {
    options.refuse(MODEL, &["address", "variant", "drive"])?;
    let defaults = ExampleSimConfig::default();
    Ok(SimBoard::Stream(Box::new(ExampleSim::new(
        ExampleSimConfig {
            jitter: Duration::from_micros(100),
            seed: options.seed.unwrap_or(defaults.seed),
            ..defaults
        },
    ))))
}
