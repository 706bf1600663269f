//! The validated description an [`Engine`](crate::Engine) is built from.
//!
//! motiond's config loader turns the TOML file into this (with file/line errors); tests
//! build it directly. Construction checks what the engine itself relies on and reports a
//! typed [`EngineConfigError`].

use core::time::Duration;

use motion_drivers::{LinkKind, Pin, SignalKind};
use motion_ipc::{MAX_AXES, MAX_DEVICES, MAX_GROUP_AXES, MAX_GROUPS, MAX_LINKS, MAX_SIGNALS};

/// One link as the engine sees it: a named bus of drivers, stream or SPI (the transport
/// that carries it is `motion_link::LinkConfig`, opened by motiond).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, PartialEq)]
pub struct BusConfig {
    /// Link name (config `[[link]] name`).
    pub name: String,
    /// Stream or SPI.
    pub kind: LinkKind,
}

/// One board on a link.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, PartialEq)]
pub struct DeviceConfig {
    /// Device name.
    pub name: String,
    /// Index into [`EngineConfig::links`].
    pub link: usize,
    /// Bus address (0 when the model has none).
    pub address: u32,
}

/// One axis: a channel of a device, with units and limits.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, PartialEq)]
pub struct AxisConfig {
    /// Axis name.
    pub name: String,
    /// Unit of positions.
    pub unit: String,
    /// Index into [`EngineConfig::devices`].
    pub device: usize,
    /// Channel (motor number) on the device.
    pub channel: usize,
    /// Device counts per unit (non-zero, finite; negative reverses the direction).
    pub counts_per_unit: f64,
    /// Lower soft limit, units.
    pub min: f64,
    /// Upper soft limit, units.
    pub max: f64,
    /// Velocity limit, units/s (> 0).
    pub max_velocity: f64,
    /// Acceleration limit, units/s² (> 0).
    pub max_accel: f64,
    /// Distance from the target within which a position goal counts as reached, units
    /// (> 0).
    pub position_tolerance: f64,
    /// How far the measured position may be from where the axis should be (the held
    /// target, the segment of a move, the soft limits) before the axis faults, units;
    /// 0 disables the check.
    pub following_error: f64,
    /// A measured speed above `overspeed_factor × max_velocity` for three fresh samples in
    /// a row faults the axis; 0 disables the check.
    pub overspeed_factor: f64,
    /// What an e-stop (and a fault) does to this axis.
    pub estop: EstopCategory,
    /// A reference search that travels this far from where it started faults the axis
    /// (`HomeFailed`), units; 0 disables the check.
    pub home_max_travel: f64,
}

impl Default for AxisConfig {
    /// A 1:1 axis on channel 0 of device 0 with limits ±1000 units, 100 units/s,
    /// 1000 units/s², supervision off and e-stop category `Hold`. For tests and examples:
    /// override what matters with struct update syntax.
    fn default() -> Self {
        Self {
            name: String::new(),
            unit: "mm".into(),
            device: 0,
            channel: 0,
            counts_per_unit: 1.0,
            min: -1000.0,
            max: 1000.0,
            max_velocity: 100.0,
            max_accel: 1000.0,
            position_tolerance: 2.0,
            following_error: 0.0,
            overspeed_factor: 0.0,
            estop: EstopCategory::Hold,
            home_max_travel: 0.0,
        }
    }
}

/// What an e-stop does to an axis: the stop categories of IEC 60204-1.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub enum EstopCategory {
    /// Category 2: decelerate and hold, energised (default; the right choice for an axis
    /// that gravity would move, e.g. a vertical axis).
    #[default]
    Hold,
    /// Category 1: decelerate, then de-energise.
    StopOff,
    /// Category 0: de-energise at once (the motor coasts).
    Off,
}

impl EstopCategory {
    /// The config name (`estop = "stop-off"`).
    pub const fn id(self) -> &'static str {
        match self {
            Self::Hold => "hold",
            Self::StopOff => "stop-off",
            Self::Off => "off",
        }
    }
}

/// One named board I/O pin.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, PartialEq)]
pub struct SignalConfig {
    /// Signal name.
    pub name: String,
    /// Unit of an analogue value ("" for digital).
    pub unit: String,
    /// Index into [`EngineConfig::devices`].
    pub device: usize,
    /// The pin (index into the device model's pin table).
    pub pin: Pin,
    /// The pin's name on the board ("ttlio1").
    pub pin_name: String,
    /// What it is used as (the pin must support it).
    pub kind: SignalKind,
    /// Digital: the logical value is the inverse of the electrical level.
    pub invert: bool,
    /// Analogue: value = raw × scale + offset.
    pub scale: f64,
    /// Analogue: value = raw × scale + offset.
    pub offset: f64,
    /// Raw full scale (ADC counts; 1 for digital), for clients.
    pub full_scale: f64,
    /// Digital output: the logical value an e-stop sets; `None`: left alone.
    pub safe: Option<bool>,
}

/// The largest `stream_buffer`, ticks: a group's setpoint queue holds twice that (a
/// playout that far behind, setpoints that far ahead), reserved when the engine is built.
pub const MAX_STREAM_BUFFER: u32 = 1000;

/// What a group does with a streamed setpoint beyond an axis's limits (`stream_limit`).
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub enum StreamLimit {
    /// Clamp it to the limit, count it and flag it in the frame.
    Clamp,
    /// Stop the group and end the stream (the default: a safety function never quietly
    /// changes what was asked).
    #[default]
    Abort,
}

impl StreamLimit {
    /// The config name (`stream_limit = "clamp"`).
    pub const fn id(self) -> &'static str {
        match self {
            Self::Clamp => "clamp",
            Self::Abort => "abort",
        }
    }
}

/// One axis group (`[[group]]`): axes of any boards and links that move together.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, PartialEq)]
pub struct GroupConfig {
    /// Group name.
    pub name: String,
    /// Indices into [`EngineConfig::axes`], in the group's order (the order of every
    /// position list a client sends for the group); no axis twice.
    pub axes: Vec<usize>,
    /// Per member axis (same order): the largest |desired − measured| while the group
    /// moves before the group aborts, in the axis's unit; 0 disables the check.
    pub path_tolerance: Vec<f64>,
    /// Per member axis: how close to the end of its path the axis must come, in its unit
    /// (> 0).
    pub goal_tolerance: Vec<f64>,
    /// How long after the path's end every axis may take to come within its
    /// `goal_tolerance` before the group faults (`GoalTolerance`).
    pub goal_time_tolerance: Duration,
    /// What a streamed setpoint beyond a limit does.
    pub stream_limit: StreamLimit,
    /// Ticks without a new streamed setpoint after which the group stops (the deadman
    /// rule of streaming); > 0.
    pub stream_timeout: u32,
    /// Ticks ahead a streamed setpoint may be addressed and wait; > 0.
    pub stream_buffer: u32,
}

impl Default for GroupConfig {
    /// An empty group with the documented defaults: path check off, goal tolerance 1 unit,
    /// 1 s goal time, streams abort beyond a limit, time out after 20 ticks and buffer 3.
    fn default() -> Self {
        Self {
            name: String::new(),
            axes: Vec::new(),
            path_tolerance: Vec::new(),
            goal_tolerance: Vec::new(),
            goal_time_tolerance: Duration::from_secs(1),
            stream_limit: StreamLimit::Abort,
            stream_timeout: 20,
            stream_buffer: 3,
        }
    }
}

/// Everything the engine needs to know.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, PartialEq)]
pub struct EngineConfig {
    /// Instance name.
    pub name: String,
    /// Tick rate, 1..=20000 Hz.
    pub tick_hz: u32,
    /// Deadman for velocity and power goals; zero disables it.
    pub command_timeout: Duration,
    /// Links in config order.
    pub links: Vec<BusConfig>,
    /// Devices in config order; the engine gets one driver per device, same order.
    pub devices: Vec<DeviceConfig>,
    /// Axes in config order; this is the order of axes in every frame.
    pub axes: Vec<AxisConfig>,
    /// Signals in config order; this is the order of signals in every frame.
    pub signals: Vec<SignalConfig>,
    /// Axis groups in config order; this is the order of groups in every frame.
    pub groups: Vec<GroupConfig>,
    /// A claim not renewed by a command of its owner within this time ends; zero: claims
    /// last as long as their owner is connected.
    pub claim_lease: Duration,
}

impl Default for EngineConfig {
    /// An empty 1 kHz engine with a 250 ms deadman and no claim lease.
    fn default() -> Self {
        Self {
            name: String::new(),
            tick_hz: 1000,
            command_timeout: Duration::from_millis(250),
            links: Vec::new(),
            devices: Vec::new(),
            axes: Vec::new(),
            signals: Vec::new(),
            groups: Vec::new(),
            claim_lease: Duration::ZERO,
        }
    }
}

impl EngineConfig {
    /// The tick period.
    pub fn period(&self) -> Duration {
        Duration::from_nanos(1_000_000_000 / u64::from(self.tick_hz.max(1)))
    }
}

/// A description the engine cannot run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EngineConfigError {
    /// `tick_hz` outside 1..=20000.
    #[error("tick_hz {0} is outside 1..=20000")]
    TickRate(u32),
    /// More links, devices or axes than the shared-memory contract can carry.
    #[error("{what}: {count} configured, at most {max} are supported")]
    TooMany {
        /// "links", "devices" or "axes".
        what: &'static str,
        /// How many were configured.
        count: usize,
        /// The limit.
        max: usize,
    },
    /// A device names a link index that does not exist.
    #[error("device `{device}` refers to link #{link}, which does not exist")]
    UnknownLink {
        /// Device name.
        device: String,
        /// The bad index.
        link: usize,
    },
    /// An axis (or signal) names a device index that does not exist.
    #[error("axis or signal `{axis}` refers to device #{device}, which does not exist")]
    UnknownDevice {
        /// Axis name.
        axis: String,
        /// The bad index.
        device: usize,
    },
    /// The number of drivers differs from the number of devices.
    #[error("{drivers} drivers were given for {devices} devices")]
    DriverCount {
        /// Drivers given.
        drivers: usize,
        /// Devices configured.
        devices: usize,
    },
    /// An axis names a channel its device does not have.
    #[error("axis `{axis}`: device `{device}` has no channel {channel} (it has {count})")]
    NoSuchChannel {
        /// Axis name.
        axis: String,
        /// Device name.
        device: String,
        /// The bad channel.
        channel: usize,
        /// Channels the device has.
        count: usize,
    },
    /// Two axes drive the same channel.
    #[error("axes `{first}` and `{second}` both drive channel {channel} of device `{device}`")]
    SharedChannel {
        /// First axis.
        first: String,
        /// Second axis.
        second: String,
        /// Device name.
        device: String,
        /// The channel.
        channel: usize,
    },
    /// Two items of one kind share a name.
    #[error("two {what} are called `{name}`")]
    DuplicateName {
        /// "links", "devices" or "axes".
        what: &'static str,
        /// The name.
        name: String,
    },
    /// A group is invalid.
    #[error("group `{group}`: {what}")]
    BadGroup {
        /// Group name.
        group: String,
        /// What is wrong.
        what: &'static str,
    },
    /// A numeric axis parameter is invalid.
    #[error("axis `{axis}`: {what}")]
    BadAxisValue {
        /// Axis name.
        axis: String,
        /// What is wrong.
        what: &'static str,
    },
}

pub(crate) fn validate(
    config: &EngineConfig,
    driver_count: usize,
) -> Result<(), EngineConfigError> {
    if !(1..=20_000).contains(&config.tick_hz) {
        return Err(EngineConfigError::TickRate(config.tick_hz));
    }
    for (what, count, max) in [
        ("links", config.links.len(), MAX_LINKS),
        ("devices", config.devices.len(), MAX_DEVICES),
        ("axes", config.axes.len(), MAX_AXES),
        ("signals", config.signals.len(), MAX_SIGNALS),
        ("groups", config.groups.len(), MAX_GROUPS),
    ] {
        if count > max {
            return Err(EngineConfigError::TooMany { what, count, max });
        }
    }
    if driver_count != config.devices.len() {
        return Err(EngineConfigError::DriverCount {
            drivers: driver_count,
            devices: config.devices.len(),
        });
    }
    check_unique("links", config.links.iter().map(|l| l.name.as_str()))?;
    check_unique("devices", config.devices.iter().map(|d| d.name.as_str()))?;
    check_unique("axes", config.axes.iter().map(|a| a.name.as_str()))?;
    check_unique("signals", config.signals.iter().map(|s| s.name.as_str()))?;
    check_unique("groups", config.groups.iter().map(|g| g.name.as_str()))?;
    for group in &config.groups {
        validate_group(group, config.axes.len())?;
    }
    for signal in &config.signals {
        if signal.device >= config.devices.len() {
            return Err(EngineConfigError::UnknownDevice {
                axis: signal.name.clone(),
                device: signal.device,
            });
        }
        if !(signal.scale.is_finite() && signal.offset.is_finite()) {
            return Err(EngineConfigError::BadAxisValue {
                axis: signal.name.clone(),
                what: "a signal's scale and offset must be finite",
            });
        }
    }
    for device in &config.devices {
        if device.link >= config.links.len() {
            return Err(EngineConfigError::UnknownLink {
                device: device.name.clone(),
                link: device.link,
            });
        }
    }
    for (index, axis) in config.axes.iter().enumerate() {
        if axis.device >= config.devices.len() {
            return Err(EngineConfigError::UnknownDevice {
                axis: axis.name.clone(),
                device: axis.device,
            });
        }
        let bad = |what| EngineConfigError::BadAxisValue {
            axis: axis.name.clone(),
            what,
        };
        if !axis.counts_per_unit.is_finite() || axis.counts_per_unit == 0.0 {
            return Err(bad("counts_per_unit must be finite and not zero"));
        }
        if !(axis.min.is_finite() && axis.max.is_finite() && axis.min < axis.max) {
            return Err(bad("min and max must be finite with min < max"));
        }
        if !(axis.max_velocity.is_finite() && axis.max_velocity > 0.0) {
            return Err(bad("max_velocity must be finite and > 0"));
        }
        if !(axis.max_accel.is_finite() && axis.max_accel > 0.0) {
            return Err(bad("max_accel must be finite and > 0"));
        }
        if !(axis.position_tolerance.is_finite() && axis.position_tolerance > 0.0) {
            return Err(bad("position_tolerance must be finite and > 0"));
        }
        for (value, what) in [
            (
                axis.following_error,
                "following_error must be finite and >= 0",
            ),
            (
                axis.overspeed_factor,
                "overspeed_factor must be finite and >= 0",
            ),
            (
                axis.home_max_travel,
                "home_max_travel must be finite and >= 0",
            ),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(bad(what));
            }
        }
        if let Some(other) = config.axes[..index]
            .iter()
            .find(|other| other.device == axis.device && other.channel == axis.channel)
        {
            return Err(EngineConfigError::SharedChannel {
                first: other.name.clone(),
                second: axis.name.clone(),
                device: config.devices[axis.device].name.clone(),
                channel: axis.channel,
            });
        }
    }
    Ok(())
}

fn validate_group(group: &GroupConfig, axis_count: usize) -> Result<(), EngineConfigError> {
    let bad = |what| EngineConfigError::BadGroup {
        group: group.name.clone(),
        what,
    };
    if group.axes.is_empty() {
        return Err(bad("a group needs at least one axis"));
    }
    if group.axes.len() > MAX_GROUP_AXES {
        return Err(bad("a group holds at most 16 axes"));
    }
    if group.axes.iter().any(|axis| *axis >= axis_count) {
        return Err(bad("an axis index does not exist"));
    }
    for (index, axis) in group.axes.iter().enumerate() {
        if group.axes[..index].contains(axis) {
            return Err(bad("an axis appears twice"));
        }
    }
    if group.path_tolerance.len() != group.axes.len()
        || group.goal_tolerance.len() != group.axes.len()
    {
        return Err(bad("one path and one goal tolerance per axis"));
    }
    if !group
        .path_tolerance
        .iter()
        .all(|value| value.is_finite() && *value >= 0.0)
    {
        return Err(bad("path_tolerance must be finite and >= 0"));
    }
    if !group
        .goal_tolerance
        .iter()
        .all(|value| value.is_finite() && *value > 0.0)
    {
        return Err(bad("goal_tolerance must be finite and > 0"));
    }
    if group.stream_timeout == 0 || group.stream_buffer == 0 {
        return Err(bad("stream_timeout and stream_buffer must be > 0 ticks"));
    }
    if group.stream_buffer > MAX_STREAM_BUFFER {
        return Err(bad("stream_buffer must be at most 1000 ticks"));
    }
    Ok(())
}

fn check_unique<'a>(
    what: &'static str,
    names: impl Iterator<Item = &'a str> + Clone,
) -> Result<(), EngineConfigError> {
    for (index, name) in names.clone().enumerate() {
        if names.clone().take(index).any(|earlier| earlier == name) {
            return Err(EngineConfigError::DuplicateName {
                what,
                name: name.to_owned(),
            });
        }
    }
    Ok(())
}
