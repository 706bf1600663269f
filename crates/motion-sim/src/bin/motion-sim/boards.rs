//! Builds the board models the command line asks for and puts them on their wires.

use anyhow::{Result, bail};
use motion_link::sim::{Duplex, SimLimits, SimLink, SpiBus, SpiDevice, StreamBus, StreamDevice};
use motion_sim::spimotor::{Drive, SpimotorSim, SpimotorSimConfig};

use crate::cli::{BoardSpec, ModelId};

/// A built model, on the wire its board uses.
#[allow(dead_code)] // Stream: until the serial models are in this build
pub enum Board {
    /// A serial board.
    Stream(Box<dyn StreamDevice>),
    /// An SPI board.
    Spi(Box<dyn SpiDevice>),
}

/// One line describing `spec`, for the log.
pub fn describe(spec: &BoardSpec) -> String {
    let mut text = spec.model.as_str().to_owned();
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

/// The board's own line rate, for serial boards.
pub fn native_baud(model: ModelId) -> u32 {
    match model {
        ModelId::Tmcpack => 19_200,
        _ => 230_400,
    }
}

fn refuse_option(spec: &BoardSpec, option: &str, given: bool) -> Result<()> {
    if given {
        bail!("--model {} has no --{option}", spec.model.as_str());
    }
    Ok(())
}

/// Builds one model.
pub fn build(spec: &BoardSpec) -> Result<Board> {
    match spec.model {
        ModelId::Spimotor => {
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
        ModelId::Qq2drv | ModelId::Tmcpack | ModelId::Qsb => {
            bail!("the {} model is not in this build yet", spec.model.as_str())
        }
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
