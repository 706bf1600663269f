//! A QSB served alone by `motion-sim`: `--variant s|d|m`, `--seed`; `--baud` sets the rate
//! it starts at (its BAUD RATE command has the same rates).

use crate::sim::{QsbSim, QsbSimConfig, Variant};
use motion_board::{SimBoard, StandaloneError, StandaloneHelp, StandaloneSim};
use motion_drivers::Model;

/// `motion-sim --help` on the QSB.
pub(crate) const HELP: StandaloneHelp = StandaloneHelp {
    summary: "US Digital QSB-S/-D/-M, ASCII over USB serial, 230400 baud",
    options: "--variant s|d|m",
    examples: "\
motion-sim --model qsb --pty --link /tmp/qsb
    prints the pty path (first line of stdout) and links /tmp/qsb to it. Talk to it:
      screen /tmp/qsb 230400          (type R14 then Enter; Ctrl-A k quits)
      python3 -c \"import os,time; f=os.open('/tmp/qsb',os.O_RDWR); os.write(f,b'R14\\r\\n'); time.sleep(0.1); print(os.read(f,64))\"",
};

/// The simulated QSB `options` ask for.
pub(crate) fn simulate(options: &StandaloneSim) -> Result<SimBoard, StandaloneError> {
    options.refuse(Model::QSB, &["address", "drive"])?;
    let mut config = QsbSimConfig::default();
    let variants = [
        ("s", Variant::S),
        ("S", Variant::S),
        ("qsb-s", Variant::S),
        ("d", Variant::D),
        ("D", Variant::D),
        ("qsb-d", Variant::D),
        ("m", Variant::M),
        ("M", Variant::M),
        ("qsb-m", Variant::M),
    ];
    config.variant = options.choice(
        Model::QSB,
        "variant",
        &variants,
        config.variant,
        "use s, d or m",
    )?;
    if let Some(rate) = options.baud {
        let Some(selected) = qsb::BaudRate::ALL
            .iter()
            .copied()
            .find(|r| r.bits_per_second() == rate)
        else {
            return Err(StandaloneError::Invalid {
                option: "baud",
                message: format!(
                    "--baud {rate}: a QSB runs at 9600, 19200, 38400, 56000, 115200, 128000, 230400 or 256000"
                ),
            });
        };
        config.baud = selected;
    }
    if let Some(seed) = options.seed {
        config.seed = seed;
    }
    Ok(SimBoard::Stream(Box::new(QsbSim::new(config))))
}
