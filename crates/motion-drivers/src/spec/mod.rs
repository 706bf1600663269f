//! The neutral description a driver is built from: [`DriverSpec`].
//!
//! The server validates its config file and fills one [`DriverSpec`] per `[[device]]`: plain
//! numbers in axis units (or counts where the config gives counts), the enums of this
//! module, and the model's machine keys ([`DeviceMachine`], [`AxisMachine`]) — no protocol
//! type. Each board's `<Board>DriverConfig::from_spec` turns it into the driver's config
//! (the unit conversions and protocol encodings live there, next to the driver), and its
//! `params` says what the driver made of it, key by key, for `motionctl list`.
//!
//! A [`SpecError`] names the key (relative to its `[[device]]` or, with a channel, to the
//! axis on that channel) whose value the board cannot take; the server's validation refuses
//! such values first, with file, line and column.

mod keys;

use crate::driver::Model;
use crate::pin::{Pin, SignalKind};

pub use keys::{AxisMachine, DeviceMachine, MachineKeys};

/// What a qq2drv channel's IN pin is wired to (datasheet packet 14 Input Mode).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum HomeInputKind {
    /// A home switch: acts while active.
    Home,
    /// The encoder index: acts while active and A = B = 0.
    Index,
    /// An edge: acts on the inactive-to-active transition.
    Edge,
}

/// Which way a reference search runs, in axis units (after `counts_per_unit`'s sign).
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub enum Direction {
    /// Towards decreasing positions (the default: the switch sits at `min`).
    #[default]
    Negative,
    /// Towards increasing positions.
    Positive,
}

impl Direction {
    /// The config name.
    pub const fn id(self) -> &'static str {
        match self {
            Self::Negative => "negative",
            Self::Positive => "positive",
        }
    }
}

/// A qq2drv channel's IN pin as a home input (`home = { input = "index", ... }`).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq)]
pub struct HomeInput {
    /// What the pin is wired to.
    pub kind: HomeInputKind,
    /// The pin is active high (default true).
    pub active_high: bool,
    /// Packet 14 Spacing: the hysteresis between a positive-end and a negative-end trigger
    /// when two end-stops (or a rotary sensor) share the input, units; `None`: a single
    /// end-stop (Spacing 0).
    pub spacing: Option<f64>,
}

/// How an axis homes: the general `home` table with every default resolved. Every axis has
/// one; a board that cannot home ignores it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HomeSpec {
    /// Search direction (qsb `home_direction`, tmcpack `reference.side`: left = negative).
    pub direction: Direction,
    /// A search that travels farther than this from where it started fails with
    /// `HomeFailed`, units (> 0). Default: 1.25 × (max − min), the Trinamic manual's 5/4 of
    /// the drive range.
    pub max_travel: f64,
    /// The position the axis takes at the switch or index, units (qsb `home_offset`).
    pub position: f64,
    /// qq2drv: what the channel's IN pin is wired to; `None`: the channel cannot home.
    pub input: Option<HomeInput>,
}

/// One axis on the device: where it is and what it may do, in axis units.
#[derive(Debug, Clone, PartialEq)]
pub struct DriverAxis {
    /// The board channel it drives.
    pub channel: usize,
    /// Its unit (`"mm"`, `"deg"`).
    pub unit: String,
    /// Counts (the board's own position unit) per axis unit; negative when the board counts
    /// down as the axis moves up.
    pub counts_per_unit: f64,
    /// Soft limit, units.
    pub min: f64,
    /// Soft limit, units.
    pub max: f64,
    /// Velocity limit, units/s.
    pub max_velocity: f64,
    /// Acceleration limit, units/s².
    pub max_accel: f64,
    /// How it homes.
    pub home: HomeSpec,
    /// The model's axis keys.
    pub machine: AxisMachine,
}

impl DriverAxis {
    /// Its velocity and acceleration limits in counts (times `|counts_per_unit|`).
    pub fn limits(&self) -> AxisLimits {
        let scale = self.counts_per_unit.abs();
        AxisLimits {
            max_velocity: self.max_velocity * scale,
            max_accel: self.max_accel * scale,
        }
    }
}

/// An axis's limits in its board's counts (the board's own position unit: steps,
/// quadrature transitions, microsteps), as a driver plans its moves with them.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq)]
pub struct AxisLimits {
    /// Velocity limit, counts/s.
    pub max_velocity: f64,
    /// Acceleration limit, counts/s².
    pub max_accel: f64,
}

/// One signal on one of the device's pins.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DriverSignal {
    /// The pin (index into the model's pin table for the device's variant).
    pub pin: Pin,
    /// What it is used as.
    pub kind: SignalKind,
}

/// A device on the same link (a shared bus divides its wire time among its devices).
#[derive(Debug, Clone, PartialEq)]
pub struct BusPeer {
    /// Its model.
    pub model: Model,
    /// Axes on it.
    pub axes: usize,
    /// Signals on its pins.
    pub signals: Vec<DriverSignal>,
    /// Its machine keys.
    pub machine: DeviceMachine,
}

/// A board driver's configuration made from the neutral description: one per board crate
/// (`<Board>DriverConfig`), where every driver starts — its unit conversions and protocol
/// encodings, and the machine parameters it reports.
pub trait FromSpec: Sized {
    /// The configuration of the device `spec` describes.
    ///
    /// # Errors
    /// A value of the spec the board cannot take (the config validator refuses such values
    /// first, with file, line and column), naming its key.
    fn from_spec(spec: &DriverSpec) -> Result<Self, SpecError>;

    /// One [`Param`] per machine parameter of the device and of its axes, with the value
    /// in effect.
    #[must_use]
    fn params(&self, spec: &DriverSpec) -> Vec<Param>;
}

/// One `[[device]]` as a driver needs it (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct DriverSpec {
    /// The device's name.
    pub name: String,
    /// Board model.
    pub model: Model,
    /// The line rate of its link: baud of a serial line, SPI clock, CAN bit rate; `None`:
    /// the link gives none (the driver's default applies).
    pub line_rate: Option<u32>,
    /// How its link frames messages: bytes, or CAN frames (`motion_base::CanRecord`, one
    /// a frame) on a `socketcan` or `sim-can` link.
    pub framing: motion_base::LinkFraming,
    /// Bus address (tmcpack 0..=255, spimotor even 2..=254; 0 for the others).
    pub address: u32,
    /// The model's device keys.
    pub machine: DeviceMachine,
    /// The axes on the device, in config order.
    pub axes: Vec<DriverAxis>,
    /// The signals on its pins, in config order.
    pub signals: Vec<DriverSignal>,
    /// Every device on its link, itself included, in config order.
    pub bus: Vec<BusPeer>,
}

impl DriverSpec {
    /// The (first) axis on `channel`, with its index in [`axes`](Self::axes).
    pub fn axis_on(&self, channel: usize) -> Option<(usize, &DriverAxis)> {
        self.axes
            .iter()
            .enumerate()
            .find(|(_, axis)| axis.channel == channel)
    }

    /// Velocity and acceleration limits of `channel` in counts, from the axis that drives
    /// it.
    pub fn channel_limits(&self, channel: usize) -> Option<AxisLimits> {
        self.axis_on(channel).map(|(_, axis)| axis.limits())
    }
}

/// A value of the spec the board cannot take.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SpecError {
    /// `None`: a key of the `[[device]]`; `Some(channel)`: a key of the axis on `channel`.
    pub channel: Option<usize>,
    /// The key, dotted into inline tables (`"current.standby"`).
    pub key: &'static str,
    /// What is wrong with its value.
    pub message: String,
}

impl core::fmt::Display for SpecError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self.channel {
            Some(channel) => write!(
                f,
                "the axis on channel {channel}: `{}`: {}",
                self.key, self.message
            ),
            None => write!(f, "`{}`: {}", self.key, self.message),
        }
    }
}

impl std::error::Error for SpecError {}

/// Whose parameter a [`Param`] is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamOwner {
    /// The `[[device]]`.
    Device,
    /// The axis at this index of [`DriverSpec::axes`].
    Axis(usize),
}

/// One effective machine parameter: the config key and the value the driver uses, with its
/// unit and its encoding on the wire (`"50 %"`, `"2 ms ($40)"`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Param {
    /// Device or axis.
    pub owner: ParamOwner,
    /// The config key, dotted into inline tables.
    pub key: &'static str,
    /// The effective value.
    pub value: String,
}
