//! Builds the board models the command line asks for and puts them on their wires.

use anyhow::{Result, bail};
use motion_link::sim::{Duplex, SimLimits, SimLink, SpiBus, SpiDevice, StreamBus, StreamDevice};
use motion_sim::qq2drv::{Qq2drvSim, Qq2drvSimConfig};
use motion_sim::qsb::{QsbSim, QsbSimConfig, Variant as QsbVariant};
use motion_sim::spimotor::{Drive, SpimotorSim, SpimotorSimConfig};
use motion_sim::tmcpack::{TmcpackSim, TmcpackSimConfig};
use tmcpack::Variant as PackVariant;

use motion_base::Model;

use crate::cli::BoardSpec;

/// A built model, on the wire its board uses.
pub enum Board {
    /// A serial board.
    Stream(Box<dyn StreamDevice>),
    /// An SPI board.
    Spi(Box<dyn SpiDevice>),
}

/// One line describing `spec`, for the log.
pub fn describe(spec: &BoardSpec) -> String {
    let mut text = spec.model.id().to_owned();
    if let Some(a) = spec.address {
        text.push_str(&format!(" address {a} (0x{a:02x})"));
    }
    if let Some(v) = &spec.variant {
        text.push_str(&format!(" variant {v}"));
    }
    if let Some(d) = &spec.drive {
        text.push_str(&format!(" drive {d}"));
    }
    if let Some(s) = spec.seed {
        text.push_str(&format!(" seed {s}"));
    }
    text
}

fn refuse_option(spec: &BoardSpec, option: &str, given: bool) -> Result<()> {
    if given {
        bail!("--model {} has no --{option}", spec.model.id());
    }
    Ok(())
}

/// Builds one model. `baud` is the pty's rate when `--baud` was given: a QSB is set to
/// start at it (its BAUD RATE command has the same rates); a pack always starts at its
/// factory 19200 baud, as after power-up.
pub fn build(spec: &BoardSpec, baud: Option<u32>, spi_hz: u32) -> Result<Board> {
    match spec.model {
        Model::QSB => {
            refuse_option(spec, "address", spec.address.is_some())?;
            refuse_option(spec, "drive", spec.drive.is_some())?;
            let mut config = QsbSimConfig::default();
            config.variant = match spec.variant.as_deref() {
                None => config.variant,
                Some("s" | "S" | "qsb-s") => QsbVariant::S,
                Some("d" | "D" | "qsb-d") => QsbVariant::D,
                Some("m" | "M" | "qsb-m") => QsbVariant::M,
                Some(other) => bail!("qsb --variant {other}: use s, d or m"),
            };
            if let Some(rate) = baud {
                let Some(selected) = qsb::BaudRate::ALL
                    .iter()
                    .copied()
                    .find(|r| r.bits_per_second() == rate)
                else {
                    bail!(
                        "--baud {rate}: a QSB runs at 9600, 19200, 38400, 56000, 115200, 128000, 230400 or 256000"
                    );
                };
                config.baud = selected;
            }
            if let Some(seed) = spec.seed {
                config.seed = seed;
            }
            Ok(Board::Stream(Box::new(QsbSim::new(config))))
        }
        Model::TMCPACK => {
            refuse_option(spec, "drive", spec.drive.is_some())?;
            let mut config = TmcpackSimConfig::default();
            if let Some(address) = spec.address {
                config.address = address;
            }
            config.variant = match spec.variant.as_deref() {
                None | Some("sixpack") => PackVariant::SixPack,
                Some("quadpack") => PackVariant::QuadPack,
                Some(other) => bail!("tmcpack --variant {other}: use sixpack or quadpack"),
            };
            if let Some(seed) = spec.seed {
                config.seed = seed;
            }
            Ok(Board::Stream(Box::new(TmcpackSim::new(config))))
        }
        Model::QQ2DRV => {
            refuse_option(spec, "address", spec.address.is_some())?;
            refuse_option(spec, "variant", spec.variant.is_some())?;
            refuse_option(spec, "drive", spec.drive.is_some())?;
            let mut config = Qq2drvSimConfig {
                spi_clock_hz: spi_hz,
                ..Qq2drvSimConfig::default()
            };
            if let Some(seed) = spec.seed {
                config.seed = seed;
            }
            Ok(Board::Spi(Box::new(Qq2drvSim::new(config))))
        }
        Model::SPIMOTOR => {
            refuse_option(spec, "variant", spec.variant.is_some())?;
            let mut config = SpimotorSimConfig::default();
            if let Some(address) = spec.address {
                if address & 1 != 0 {
                    bail!(
                        "spimotor --address 0x{address:02x}: an SPI_motor address is even \
                         (bit 0 is the read flag); did you mean 0x{:02x}?",
                        address & 0xFE
                    );
                }
                config.address = address;
            }
            config.drive = match spec.drive.as_deref() {
                None | Some("stepper") => Drive::Stepper,
                Some("brushed") => Drive::Brushed,
                Some(other) => bail!("spimotor --drive {other}: use stepper or brushed"),
            };
            if let Some(seed) = spec.seed {
                config.seed = seed;
            }
            Ok(Board::Spi(Box::new(SpimotorSim::new(config))))
        }
        other => bail!("motion-sim has no model of {other}"),
    }
}

/// Puts the serial boards on one wire (a bus when there are several: an RS-485 pair, half
/// duplex) at `baud`.
pub fn stream_link(mut devices: Vec<Box<dyn StreamDevice>>, baud: u32) -> SimLink {
    let single = if devices.len() == 1 {
        devices.pop()
    } else {
        None
    };
    let (device, duplex): (Box<dyn StreamDevice>, Duplex) = match single {
        Some(device) => (device, Duplex::Full),
        None => {
            let mut bus = StreamBus::new();
            for d in devices {
                bus.push(d);
            }
            (Box::new(bus), Duplex::Half)
        }
    };
    SimLink::stream_with("pty", baud, duplex, device)
}

/// Puts the SPI boards on one bus (shared chip select) clocked at `speed_hz`.
pub fn spi_link(mut devices: Vec<Box<dyn SpiDevice>>, speed_hz: u32) -> SimLink {
    let single = if devices.len() == 1 {
        devices.pop()
    } else {
        None
    };
    let device: Box<dyn SpiDevice> = match single {
        Some(device) => device,
        None => {
            let mut bus = SpiBus::new();
            for d in devices {
                bus.push(d);
            }
            Box::new(bus)
        }
    };
    let limits = SimLimits {
        max_transaction: usize::from(u16::MAX),
        to_host: 2 * usize::from(u16::MAX),
        ..SimLimits::default()
    };
    SimLink::spi("spi-socket", speed_hz, device).with_limits(limits)
}
