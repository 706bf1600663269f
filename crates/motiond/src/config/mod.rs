//! The config file (DESIGN.md "Config contract"): loading, validation, and the validated
//! description the server is built from.
//!
//! Every mistake — unknown key, wrong type, missing key, duplicate name, unknown link or
//! device, a channel the model does not have, a value out of range, a link type the model
//! cannot use — is reported with file, line, column and key, all of them at once, and
//! nothing is opened.

mod error;
mod raw;
mod validate;

use core::time::Duration;
use std::path::{Path, PathBuf};

use motion_drivers::{BusKind, Model};
use motion_engine::{AxisConfig, DeviceConfig, EngineConfig, LinkConfig};

pub use error::{ConfigError, ConfigIssue};

/// `[server]`.
#[derive(Debug, Clone, PartialEq)]
pub struct ServerSettings {
    /// Instance name; services are `motiond/<name>/…`.
    pub name: String,
    /// Tick rate, Hz.
    pub tick_hz: u32,
    /// Deadman for velocity and power goals (zero: disabled).
    pub command_timeout: Duration,
    /// SCHED_FIFO priority of the tick thread.
    pub rt_priority: Option<u8>,
    /// Core the tick thread is pinned to.
    pub cpu: Option<usize>,
    /// mlockall after the services exist.
    pub lock_memory: bool,
    /// Client limit of the iceoryx2 services (subscribers, clients, nodes).
    pub max_clients: u32,
    /// Consecutive overruns after which every axis is stopped (0: never).
    pub max_consecutive_overruns: u32,
    /// How often dead client nodes are looked for.
    pub liveness_check: Duration,
}

/// How a link reaches its devices.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Transport {
    /// A tty (RS-232, RS-485 adapter, USB CDC), 8N1.
    Serial {
        /// tty path.
        path: PathBuf,
        /// Line rate.
        baud: u32,
    },
    /// A Linux spidev device.
    Spidev {
        /// `/dev/spidevB.C`.
        path: PathBuf,
        /// SPI clock.
        speed_hz: u32,
        /// SPI mode 0..=3 (default per model: 1 for qq2drv, 0 for spimotor).
        mode: u8,
    },
    /// The SPI socket contract of DESIGN.md.
    SpiSocket {
        /// Unix socket path.
        path: PathBuf,
    },
    /// In-process simulated wire to the devices' models.
    Sim {
        /// Line rate of a serial wire, or SPI clock of an SPI wire.
        rate: u32,
    },
}

/// `[[link]]`, validated.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LinkSpec {
    /// Link name.
    pub name: String,
    /// Transport.
    pub transport: Transport,
    /// Stream or SPI (from the transport and the models on it).
    pub kind: BusKind,
}

/// Trinamic pack variant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PackVariant {
    /// SIXpack: 6 motors.
    Sixpack,
    /// QUADpack: 4 motors.
    Quadpack,
}

/// SPI_motor drive.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SpiDrive {
    /// One stepper, channel 0.
    Stepper,
    /// Two brushed motors: channels 0 = A, 1 = B.
    Brushed,
}

/// `[[device]]`, validated.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeviceSpec {
    /// Device name.
    pub name: String,
    /// Index into [`ServerConfig::links`].
    pub link: usize,
    /// Board model.
    pub model: Model,
    /// Bus address (tmcpack 0..=255, spimotor even 2..=254; 0 for the others).
    pub address: u32,
    /// tmcpack variant.
    pub variant: PackVariant,
    /// spimotor drive.
    pub drive: SpiDrive,
    /// Seed of the simulated model (sim links).
    pub sim_seed: u64,
}

impl DeviceSpec {
    /// Channels the device has as configured.
    pub fn channel_count(&self) -> usize {
        channel_count(self.model, self.variant, self.drive)
    }
}

/// Channels of a model (seeds: QuadQuad2Drv 4 DC motors; SIXpack 6 / QUADpack 4 steppers;
/// SPI_motor one stepper or two brushed motors; QSB one encoder (and the -M stepper on it)).
pub fn channel_count(model: Model, variant: PackVariant, drive: SpiDrive) -> usize {
    match (model, variant, drive) {
        (Model::Qq2drv, _, _) => 4,
        (Model::Tmcpack, PackVariant::Sixpack, _) => 6,
        (Model::Tmcpack, PackVariant::Quadpack, _) => 4,
        (Model::Spimotor, _, SpiDrive::Stepper) => 1,
        (Model::Spimotor, _, SpiDrive::Brushed) => 2,
        (Model::Qsb, _, _) => 1,
    }
}

/// What a qq2drv channel's IN pin is wired to (datasheet packet 14 Input Mode).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum HomeInputKind {
    /// A home switch: acts while active.
    Home,
    /// The encoder index: acts while active and A = B = 0.
    Index,
    /// An edge: acts on the inactive-to-active transition.
    Edge,
}

/// `home = { input = "index", ... }` of a qq2drv axis: how it homes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HomeSpec {
    /// What the pin is wired to.
    pub input: HomeInputKind,
    /// The pin is active high (default true).
    pub active_high: bool,
    /// The switch sits at the positive end: the search runs positive (default false).
    pub positive_end: bool,
    /// The position the axis takes at the trigger, units (default 0).
    pub position: f64,
}

/// A validated config file.
#[derive(Debug, Clone, PartialEq)]
pub struct ServerConfig {
    /// The file it came from.
    pub path: PathBuf,
    /// `[server]`.
    pub server: ServerSettings,
    /// `[[link]]`s in file order.
    pub links: Vec<LinkSpec>,
    /// `[[device]]`s in file order.
    pub devices: Vec<DeviceSpec>,
    /// `[[axis]]`s in file order, as the engine takes them.
    pub axes: Vec<AxisConfig>,
    /// Per axis (same order): its home input, for qq2drv axes that have one.
    pub homes: Vec<Option<HomeSpec>>,
}

impl ServerConfig {
    /// Reads and validates `path`.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let source =
            std::fs::read_to_string(path).map_err(|error| ConfigError::unreadable(path, &error))?;
        Self::parse(path, &source)
    }

    /// Validates `source` as if read from `path`.
    pub fn parse(path: &Path, source: &str) -> Result<Self, ConfigError> {
        validate::parse(source)
            .map_err(|issues| ConfigError {
                path: path.to_owned(),
                issues,
            })
            .map(|mut config| {
                config.path = path.to_owned();
                config
            })
    }

    /// The engine's description.
    pub fn engine_config(&self) -> EngineConfig {
        EngineConfig {
            name: self.server.name.clone(),
            tick_hz: self.server.tick_hz,
            command_timeout: self.server.command_timeout,
            links: self
                .links
                .iter()
                .map(|link| LinkConfig {
                    name: link.name.clone(),
                    kind: link.kind,
                })
                .collect(),
            devices: self
                .devices
                .iter()
                .map(|device| DeviceConfig {
                    name: device.name.clone(),
                    link: device.link,
                    address: device.address,
                })
                .collect(),
            axes: self.axes.clone(),
        }
    }
}
