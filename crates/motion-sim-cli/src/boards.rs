//! Builds the boards the command line asks for, through the registry
//! (`motion_boards::by_id`: each board takes its own options), and puts them on their
//! wires.

use anyhow::Result;
use motion_board::{SimBoard, StandaloneSim};
use motion_link::sim::{Duplex, SimLimits, SimLink, SpiBus, SpiDevice, StreamBus, StreamDevice};

use crate::cli::BoardSpec;

/// One line describing `spec`, for the log.
pub fn describe(spec: &BoardSpec) -> String {
    let mut text = spec.board.model().id().to_owned();
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

/// Builds one board. `baud` is the pty's rate when `--baud` was given (a board that can
/// start at another rate is set to start at it), `spi_hz` the socket's SPI clock.
pub fn build(spec: &BoardSpec, baud: Option<u32>, spi_hz: u32) -> Result<SimBoard> {
    let options = StandaloneSim {
        address: spec.address,
        variant: spec.variant.clone(),
        drive: spec.drive.clone(),
        seed: spec.seed,
        baud,
        spi_hz,
    };
    Ok(spec.board.simulate_standalone(&options)?)
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

#[cfg(test)]
mod tests {
    use super::build;
    use crate::cli;

    /// The first error building the boards of `args`, as the tool prints it.
    fn refusal(args: &str) -> String {
        let options =
            cli::parse(std::iter::once("motion-sim").chain(args.split_whitespace())).unwrap();
        let cli = &options.cli;
        options
            .boards
            .iter()
            .find_map(|spec| build(spec, cli.baud, cli.spi_hz).err())
            .map(|error| format!("{error:#}"))
            .unwrap_or_default()
    }

    #[test]
    fn each_board_takes_its_own_options_and_refuses_the_others() {
        for (args, message) in [
            (
                "--model qq2drv --address 1 --spi-socket /tmp/s",
                "--model qq2drv has no --address",
            ),
            (
                "--model qsb --drive stepper --pty",
                "--model qsb has no --drive",
            ),
            (
                "--model tmcpack --variant hexpack --pty",
                "tmcpack --variant hexpack: use sixpack or quadpack",
            ),
            (
                "--model spimotor --address 0x91 --spi-socket /tmp/s",
                "spimotor --address 0x91: an SPI_motor address is even (bit 0 is the read flag); \
                 did you mean 0x90?",
            ),
            (
                "--model qsb --pty --baud 1234",
                "--baud 1234: a QSB runs at 9600, 19200",
            ),
            (
                "--model example --variant x --pty",
                "--model example has no --variant",
            ),
        ] {
            let got = refusal(args);
            assert!(got.starts_with(message), "{args}: {got}");
        }
        for args in [
            "--model tmcpack --address 2 --variant quadpack --seed 3 --pty",
            "--model spimotor --address 0x92 --drive brushed --spi-socket /tmp/s",
            "--model qsb --variant d --pty --baud 115200",
            "--model qq2drv --seed 9 --spi-socket /tmp/s",
            "--model example --seed 1 --pty",
        ] {
            assert_eq!(refusal(args), "", "{args}");
        }
    }
}
