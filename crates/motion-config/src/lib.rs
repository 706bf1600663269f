//! motiond's config (docs/ARCHITECTURE.md "Config contract"): finding the file, loading and
//! validating it, the validated description the server is built from, the drivers and
//! simulated links its boards become ([`boards`]), and the directories it names that must
//! be the server's own ([`private_dir`]). Used by motiond, its black box replay, the bench
//! and the tests alike: no server in it.
//!
//! Every mistake — unknown key, wrong type, missing key, duplicate name, unknown link or
//! device, a channel the model does not have, a value out of range, a link type the model
//! cannot use — is reported with file, line, column and key, all of them at once, and
//! nothing is opened.
#![warn(missing_docs)]

pub mod boards;
mod error;
mod given;
pub mod locate;
pub mod private_dir;
mod raw;
mod validate;

use core::time::Duration;
use std::path::{Path, PathBuf};

use motion_drivers::{LinkKind, Model, Pin, PinInfo, SignalKind};
use motion_engine::{AxisConfig, BusConfig, DeviceConfig, EngineConfig, GroupConfig, SignalConfig};

pub use error::{ConfigError, ConfigIssue};
pub use given::{GivenKeys, Owner};
/// The machine description in the drivers' neutral terms (`motion_drivers::spec`): the
/// home table and the machine keys (each model's own types are its board crate's), as
/// validated here.
pub use motion_drivers::spec::{
    AxisMachine, DeviceMachine, Direction, HomeInput, HomeInputKind, HomeSpec,
};

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
    /// SCHED_FIFO priority of the links' I/O threads (`None`: the normal policy). Unless
    /// given, one below `rt_priority` when that is set: the tick preempts them, and they
    /// preempt everything that is not real-time, so a queued command reaches the wire and
    /// a reply reaches the ring without waiting for a core behind ordinary work.
    pub io_rt_priority: Option<u8>,
    /// Core the tick thread is pinned to.
    pub cpu: Option<usize>,
    /// Core the links' I/O threads are pinned to (`None`: any core). On a machine with an
    /// isolated core for the server (`isolcpus`), the tick's `cpu`: the I/O threads then
    /// never wake on, or preempt, the clients' cores. Not the default: on a core the
    /// scheduler also gives to ordinary work, a client that lands there waits behind the
    /// tick and every I/O thread (measured: a busy-polling client's frame delivery p50
    /// from 12 µs to 38 µs on the 2-core development machine).
    pub io_cpu: Option<usize>,
    /// mlockall after the services exist.
    pub lock_memory: bool,
    /// Client limit of the iceoryx2 services (subscribers, clients, nodes).
    pub max_clients: u32,
    /// Consecutive overruns after which every axis is stopped (0: never).
    pub max_consecutive_overruns: u32,
    /// How often dead client nodes are looked for.
    pub liveness_check: Duration,
    /// A claim not renewed by a command of its owner within this time ends (zero: never).
    pub claim_lease: Duration,
    /// Seconds of ticks the black box keeps (0: no black box).
    pub blackbox_seconds: u32,
    /// Save the black box on a clean exit too.
    pub blackbox_on_exit: bool,
    /// Where black box files are written (`<state_dir>/blackbox` unless given); a
    /// directory of the server's user that no one else may write (crate::private_dir).
    pub blackbox_dir: PathBuf,
    /// How many of this server's black box files (`<name>-<ms>-<reason>.mcap`, of the
    /// server's user) `blackbox_dir` keeps: the newest by the time in their name; older
    /// ones are removed after each save, never the file just saved nor another server's.
    pub blackbox_keep: u32,
    /// Where the server keeps what must survive its restart: the axes of devices with
    /// `power_down = "restore"` it last saw referenced and at rest
    /// (`<state_dir>/<name>.references.toml`, motiond's `references`) and the key that
    /// authenticates them (`motiond.key`, motiond's `secret`). Unless given,
    /// [`default_state_dir`]; a directory of the server's user that no one else may write
    /// (crate::private_dir).
    pub state_dir: PathBuf,
}

/// `[server] blackbox_dir`'s default under the state directory.
pub const BLACKBOX_SUBDIR: &str = "blackbox";

/// `[server] state_dir`'s default, from the process's environment:
/// [`crate::private_dir::default_state_dir`] (`$STATE_DIRECTORY`, `/var/lib/motiond` for
/// root or its owner, the user's `$XDG_STATE_HOME/motiond` or `~/.local/state/motiond`,
/// `/tmp/motiond-state-<uid>`).
pub fn default_state_dir() -> PathBuf {
    crate::private_dir::default_state_dir()
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
    /// The SPI socket contract of docs/ARCHITECTURE.md.
    SpiSocket {
        /// Unix socket path.
        path: PathBuf,
    },
    /// In-process simulated wire to the devices' models.
    Sim {
        /// Line rate of a serial wire, or SPI clock of an SPI wire.
        rate: u32,
    },
    /// A Linux SocketCAN interface (CAN 2.0A frames; `type = "socketcan"`).
    SocketCan {
        /// The network interface, e.g. `can0`.
        interface: String,
        /// The bus's bit rate (the interface's, set with `ip link`), bits per second.
        bitrate: u32,
    },
    /// In-process simulated CAN bus to the devices' models (`type = "sim-can"`).
    SimCan {
        /// Bit rate, bits per second.
        bitrate: u32,
    },
}

impl Transport {
    /// Whether the link carries CAN frames (`socketcan`, `sim-can`).
    pub const fn is_can(&self) -> bool {
        matches!(self, Self::SocketCan { .. } | Self::SimCan { .. })
    }

    /// The link's rate: baud of a serial line, SPI clock, CAN bit rate; `None` for an SPI
    /// socket (its peer sets the clock).
    pub const fn rate(&self) -> Option<u32> {
        match *self {
            Self::Serial { baud, .. } => Some(baud),
            Self::Spidev { speed_hz, .. } => Some(speed_hz),
            Self::Sim { rate } => Some(rate),
            Self::SocketCan { bitrate, .. } | Self::SimCan { bitrate } => Some(bitrate),
            Self::SpiSocket { .. } => None,
        }
    }
}

/// Who runs a link's transfers (`[[link]] io`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum IoMode {
    /// An I/O thread of its own (`io = "thread"`): serial links; spidev and sim links by
    /// default.
    Thread,
    /// The tick thread itself (`io = "tick"`), after publishing the frame: at most `budget`
    /// of wire time a tick (the first message of a tick always goes); the MISO bytes are
    /// taken at the start of the next tick. SPI socket links by default.
    Tick {
        /// Wire time a tick may spend (`io_budget_us`; default a quarter of the period).
        budget: Duration,
    },
}

impl IoMode {
    /// The `io` keyword.
    pub const fn keyword(self) -> &'static str {
        match self {
            Self::Thread => "thread",
            Self::Tick { .. } => "tick",
        }
    }
}

/// `[[link]]`, validated.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LinkSpec {
    /// Link name.
    pub name: String,
    /// Transport.
    pub transport: Transport,
    /// Stream or SPI (from the transport and the models on it).
    pub kind: LinkKind,
    /// Who runs its transfers.
    pub io: IoMode,
}

impl LinkSpec {
    /// Bytes, or CAN frames (`socketcan`, `sim-can`).
    pub fn framing(&self) -> motion_drivers::LinkFraming {
        if self.transport.is_can() {
            motion_drivers::LinkFraming::Can
        } else {
            motion_drivers::LinkFraming::Bytes
        }
    }

    /// The SPI clock a transfer of this link holds its caller for, bits per second:
    /// spidev's `speed_hz`, an SPI sim link's rate; `None` where a write only queues (an
    /// SPI socket: its peer clocks the bus) or on a stream link.
    pub fn spi_bit_rate(&self) -> Option<u32> {
        match (self.kind, &self.transport) {
            (LinkKind::Spi, Transport::Spidev { speed_hz, .. }) => Some(*speed_hz),
            (LinkKind::Spi, Transport::Sim { rate }) => Some(*rate),
            _ => None,
        }
    }
}

/// `[[device]]`, validated.
#[derive(Debug, Clone, PartialEq)]
pub struct DeviceSpec {
    /// Device name.
    pub name: String,
    /// Index into [`ServerConfig::links`].
    pub link: usize,
    /// Board model.
    pub model: Model,
    /// Bus address (tmcpack 0..=255, spimotor even 2..=254; 0 for the others).
    pub address: u32,
    /// Seed of the simulated model (sim links).
    pub sim_seed: u64,
    /// The model's machine keys.
    pub machine: DeviceMachine,
    /// What its board keys say about its axes' reference searches (qsb `home_direction`,
    /// `home_max_travel`, `home_offset`).
    pub home_hints: motion_board::HomeHints,
}

impl DeviceSpec {
    /// Channels the device has as configured (its board's count for its variant).
    pub fn channel_count(&self) -> usize {
        motion_boards::board(self.model).channel_count(&self.machine)
    }

    /// The device's I/O pins (its board's pin table for its variant).
    pub fn pins(&self) -> &'static [PinInfo] {
        motion_boards::board(self.model).pins(&self.machine)
    }
}

/// Per axis (same order as [`ServerConfig::axes`]): what the engine's [`AxisConfig`] does not
/// carry.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisSpec {
    /// How the axis homes.
    pub home: HomeSpec,
    /// The model's machine keys.
    pub machine: AxisMachine,
}

/// `[[signal]]`, validated: a named board I/O pin.
#[derive(Debug, Clone, PartialEq)]
pub struct SignalSpec {
    /// Signal name.
    pub name: String,
    /// Index into [`ServerConfig::devices`].
    pub device: usize,
    /// What it is used as.
    pub kind: SignalKind,
    /// The pin (index into the device model's pin table).
    pub pin: Pin,
    /// The pin's config name (`"ttlio1"`).
    pub pin_name: String,
    /// Digital: the logical value is the inverse of the electrical level.
    pub invert: bool,
    /// Analogue: value = raw × scale + offset.
    pub scale: f64,
    /// Analogue: value = raw × scale + offset.
    pub offset: f64,
    /// Unit of the value ("V", "mm"; "" for digital).
    pub unit: String,
    /// Digital output: the logical value it takes on e-stop; `None`: left as it is.
    pub safe: Option<bool>,
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
    /// Per axis (same order): homing and machine keys.
    pub axis_specs: Vec<AxisSpec>,
    /// `[[signal]]`s in file order.
    pub signals: Vec<SignalSpec>,
    /// `[[group]]`s in file order, as the engine takes them.
    pub groups: Vec<GroupConfig>,
    /// Every key the file set, for telling configured values from defaults.
    pub given: GivenKeys,
    /// What works but is probably not what the user wants (printed at start and by
    /// `--check-config`), in file order.
    pub warnings: Vec<ConfigIssue>,
}

impl ServerConfig {
    /// Reads and validates `path`.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let bytes = std::fs::read(path).map_err(|error| ConfigError::unreadable(path, &error))?;
        let source = core::str::from_utf8(&bytes)
            .map_err(|error| ConfigError::not_utf8(path, &bytes, &error))?;
        Self::parse(path, source)
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
                .map(|link| BusConfig {
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
            signals: self
                .signals
                .iter()
                .map(|signal| SignalConfig {
                    name: signal.name.clone(),
                    unit: signal.unit.clone(),
                    device: signal.device,
                    pin: signal.pin,
                    pin_name: signal.pin_name.clone(),
                    kind: signal.kind,
                    invert: signal.invert,
                    scale: signal.scale,
                    offset: signal.offset,
                    full_scale: self.devices[signal.device]
                        .pins()
                        .get(usize::from(signal.pin.0))
                        .map_or(1.0, |pin| pin.full_scale),
                    safe: signal.safe,
                })
                .collect(),
            groups: self.groups.clone(),
            claim_lease: self.server.claim_lease,
        }
    }
}
