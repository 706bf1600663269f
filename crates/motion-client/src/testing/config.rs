//! What the fake server serves: [`FakeConfig`] and its parts.

use motion_ipc::{Capabilities, CommandKind, DeviceModel, EstopCategory, ParamOwner, SignalKind};

/// One simulated axis.
#[derive(Debug, Clone)]
pub struct FakeAxis {
    /// Name.
    pub name: String,
    /// Unit.
    pub unit: String,
    /// Index of its device in [`FakeConfig::devices`].
    pub device: usize,
    /// Soft limits.
    pub min: f64,
    /// Soft limits.
    pub max: f64,
    /// Units/s.
    pub max_velocity: f64,
    /// Units/s².
    pub max_accel: f64,
    /// The smallest nonzero velocity of a velocity goal or search its "board" represents,
    /// units/s (0: no floor; slower velocities are refused as by the server).
    pub min_velocity: f64,
    /// The smallest velocity of a position profile its "board" represents, units/s.
    pub min_profile_velocity: f64,
    /// The smallest acceleration its "board" represents, units/s² (0: no floor).
    pub min_accel: f64,
    /// Accepted command kinds.
    pub capabilities: Capabilities,
    /// Units; 0 = not supervised (only described: the fake never raises it by itself).
    pub following_error: f64,
    /// × max_velocity; 0 = not supervised (described only).
    pub overspeed_factor: f64,
    /// Units; 0 = not supervised (described only).
    pub home_max_travel: f64,
    /// What an e-stop or a fault does to it.
    pub estop: EstopCategory,
    /// Distance from a target that counts as arrived, units (the least distance a velocity
    /// goal must keep from a soft limit, as on the server).
    pub position_tolerance: f64,
}

impl FakeAxis {
    /// An axis of device 0 accepting every command kind, unit "mm", not supervised.
    pub fn new(name: &str, min: f64, max: f64, max_velocity: f64) -> Self {
        Self {
            name: name.to_owned(),
            unit: "mm".to_owned(),
            device: 0,
            min,
            max,
            max_velocity,
            max_accel: max_velocity * 10.0,
            min_velocity: 0.0,
            min_profile_velocity: 0.0,
            min_accel: 0.0,
            capabilities: CommandKind::ALL
                .iter()
                .fold(Capabilities::NONE, |caps, kind| caps.with(*kind)),
            following_error: 0.0,
            overspeed_factor: 0.0,
            home_max_travel: 0.0,
            estop: EstopCategory::Hold,
            position_tolerance: 0.01,
        }
    }

    /// Without `kind` in its capabilities.
    #[must_use]
    pub fn without(mut self, kind: CommandKind) -> Self {
        self.capabilities = Capabilities(self.capabilities.0 & !(1 << kind as u32));
        self
    }
}

/// One simulated board.
#[derive(Debug, Clone)]
pub struct FakeDevice {
    /// Name.
    pub name: String,
    /// Model.
    pub model: DeviceModel,
    /// Link name.
    pub link: String,
    /// Firmware text it reports once online.
    pub firmware: String,
}

impl FakeDevice {
    /// A device of `model` on link "fake-link".
    pub fn new(name: &str, model: DeviceModel, firmware: &str) -> Self {
        Self {
            name: name.to_owned(),
            model,
            link: "fake-link".to_owned(),
            firmware: firmware.to_owned(),
        }
    }
}

/// One simulated signal.
#[derive(Debug, Clone)]
pub struct FakeSignal {
    /// Name.
    pub name: String,
    /// Index of its device.
    pub device: usize,
    /// The board's pin name.
    pub pin: String,
    /// Kind.
    pub kind: SignalKind,
    /// Unit of an analogue value.
    pub unit: String,
    /// Analogue: value = raw × scale + offset.
    pub scale: f64,
    /// Analogue offset.
    pub offset: f64,
    /// Raw full scale.
    pub full_scale: f64,
    /// Digital: logical value is the inverse of the level.
    pub invert: bool,
    /// Digital output: the state the e-stop puts it in.
    pub safe: Option<bool>,
}

impl FakeSignal {
    /// A digital signal (`DigitalIn` or `DigitalOut`).
    pub fn digital(name: &str, device: usize, pin: &str, kind: SignalKind) -> Self {
        Self {
            name: name.to_owned(),
            device,
            pin: pin.to_owned(),
            kind,
            unit: String::new(),
            scale: 1.0,
            offset: 0.0,
            full_scale: 1.0,
            invert: false,
            safe: None,
        }
    }

    /// An analogue input, value = raw × `scale` + `offset` in `unit`, 10-bit converter.
    pub fn analog(
        name: &str,
        device: usize,
        pin: &str,
        unit: &str,
        scale: f64,
        offset: f64,
    ) -> Self {
        Self {
            name: name.to_owned(),
            device,
            pin: pin.to_owned(),
            kind: SignalKind::AnalogIn,
            unit: unit.to_owned(),
            scale,
            offset,
            full_scale: 1023.0,
            invert: false,
            safe: None,
        }
    }
}

/// One machine parameter the fake publishes on its params service.
#[derive(Debug, Clone)]
pub struct FakeParam {
    /// Device or axis.
    pub owner: ParamOwner,
    /// Device or axis index.
    pub index: u16,
    /// The key as a config spells it.
    pub key: String,
    /// The value with unit.
    pub value: String,
    /// Whether "the config" set it.
    pub from_config: bool,
}

impl FakeParam {
    /// A parameter of `owner` `index`.
    pub fn new(owner: ParamOwner, index: u16, key: &str, value: &str, from_config: bool) -> Self {
        Self {
            owner,
            index,
            key: key.to_owned(),
            value: value.to_owned(),
            from_config,
        }
    }
}

/// One simulated axis group (`[[group]]`): axes that move together along lines and
/// trajectories (interpolated linearly by the fake; no path or goal supervision unless a test
/// aborts it with [`FakeControl::AbortGroup`](super::FakeControl::AbortGroup)).
#[derive(Debug, Clone)]
pub struct FakeGroup {
    /// Name.
    pub name: String,
    /// Member axes (indices into [`FakeConfig::axes`]), in the group's order.
    pub axes: Vec<usize>,
    /// Per member: path tolerance, units (described only).
    pub path_tolerance: Vec<f64>,
    /// Per member: goal tolerance, units; a trajectory's point at time 0 farther than this
    /// from where the axis is is refused with `PathStart`.
    pub goal_tolerance: Vec<f64>,
    /// Seconds (described only).
    pub goal_time_tolerance: f64,
    /// Ticks without a streamed setpoint before a stream goes stale and the group stops.
    pub stream_timeout: u32,
    /// Ticks ahead a streamed setpoint may be sent (further ahead: dropped as early).
    pub stream_buffer: u32,
}

impl FakeGroup {
    /// A group of `axes`, path tolerance 0.5 and goal tolerance 0.05 units each, goal time
    /// 0.5 s; a stream goes stale after 50 ticks without a setpoint and takes setpoints up
    /// to 3 ticks ahead.
    pub fn new(name: &str, axes: &[usize]) -> Self {
        Self {
            name: name.to_owned(),
            axes: axes.to_vec(),
            path_tolerance: vec![0.5; axes.len()],
            goal_tolerance: vec![0.05; axes.len()],
            goal_time_tolerance: 0.5,
            stream_timeout: 50,
            stream_buffer: 3,
        }
    }
}

/// What the fake server serves.
#[derive(Debug, Clone)]
pub struct FakeConfig {
    /// Instance name.
    pub name: String,
    /// Tick rate.
    pub tick_hz: u32,
    /// Deadman, ms (0 disables).
    pub command_timeout_ms: u32,
    /// Ports of each kind per service (frame subscribers, tick listeners, command clients,
    /// estop notifiers, info/stats/params subscribers), like `[server] max_clients`.
    pub max_clients: usize,
    /// Devices report `starting` for this many ticks after (re)start, and refuse goals.
    pub starting_ticks: u64,
    /// Publish the server description this many ticks after (re)start instead of at once,
    /// to test a client that learns of a restart from a frame or a reply first.
    pub info_delay_ticks: u64,
    /// Latch the e-stop on SIGUSR1 like the real server. Installs a process-wide handler:
    /// only for a test binary where no other fake runs meanwhile.
    pub latch_on_sigusr1: bool,
    /// Devices.
    pub devices: Vec<FakeDevice>,
    /// Axes.
    pub axes: Vec<FakeAxis>,
    /// Signals.
    pub signals: Vec<FakeSignal>,
    /// Machine parameters.
    pub params: Vec<FakeParam>,
    /// Axis groups (none in [`FakeConfig::demo`]; see [`FakeConfig::with_groups`]).
    pub groups: Vec<FakeGroup>,
}

impl FakeConfig {
    /// The demo machine, 500 Hz, deadman 250 ms, 8 ports per service, devices online at
    /// once:
    /// - devices `pack` (tmcpack, axes `x`, `y`) and `aux` (qsb, axis `a`);
    /// - `x`, `y`: −100..100 mm, 50 mm/s, following error 0.5 mm, overspeed × 1.2, home
    ///   travel 250 mm; `x` stops with `stop-off`, `y` holds;
    /// - `a`: deg, no homing and no off;
    /// - signals `door` (digital-in, pack in0), `lamp` (digital-out, pack out0, safe off),
    ///   `pressure` (analog-in, aux ain0, 0.01 bar per count), `valve` (digital-out, aux
    ///   out1, inverted);
    /// - a few machine parameters, some from "the config", some defaults.
    pub fn demo(name: &str) -> Self {
        let mut x = FakeAxis::new("x", -100.0, 100.0, 50.0);
        x.following_error = 0.5;
        x.overspeed_factor = 1.2;
        x.home_max_travel = 250.0;
        x.estop = EstopCategory::StopOff;
        let mut y = x.clone();
        y.name = "y".to_owned();
        y.estop = EstopCategory::Hold;
        let mut a = FakeAxis::new("a", -180.0, 180.0, 90.0)
            .without(CommandKind::Home)
            .without(CommandKind::Off);
        a.unit = "deg".to_owned();
        a.device = 1;
        let mut lamp = FakeSignal::digital("lamp", 0, "out0", SignalKind::DigitalOut);
        lamp.safe = Some(false);
        let mut valve = FakeSignal::digital("valve", 1, "out1", SignalKind::DigitalOut);
        valve.invert = true;
        Self {
            name: name.to_owned(),
            tick_hz: 500,
            command_timeout_ms: 250,
            max_clients: 8,
            starting_ticks: 0,
            info_delay_ticks: 0,
            latch_on_sigusr1: false,
            devices: vec![
                FakeDevice::new("pack", DeviceModel::TMCPACK, "fake pack 1.0"),
                FakeDevice::new("aux", DeviceModel::QSB, "fake qsb 2.1"),
            ],
            axes: vec![x, y, a],
            signals: vec![
                FakeSignal::digital("door", 0, "in0", SignalKind::DigitalIn),
                lamp,
                FakeSignal::analog("pressure", 1, "ain0", "bar", 0.01, 0.0),
                valve,
            ],
            params: vec![
                FakeParam::new(ParamOwner::Device, 0, "address", "1", true),
                FakeParam::new(ParamOwner::Device, 0, "baud", "19200 baud", false),
                FakeParam::new(ParamOwner::Device, 1, "counts_per_step", "4", true),
                FakeParam::new(ParamOwner::Axis, 0, "current.run", "80 %", true),
                FakeParam::new(ParamOwner::Axis, 0, "current.standstill", "50 %", false),
                FakeParam::new(ParamOwner::Axis, 2, "microsteps", "64", false),
            ],
            groups: Vec::new(),
        }
    }

    /// The demo machine with two groups: `xy` (`x`, `y`) and `all` (`x`, `y`, `a`).
    #[must_use]
    pub fn with_groups(mut self) -> Self {
        self.groups = vec![
            FakeGroup::new("xy", &[0, 1]),
            FakeGroup::new("all", &[0, 1, 2]),
        ];
        self
    }

    /// The same with devices starting for `ticks` ticks after start.
    #[must_use]
    pub fn starting_for(mut self, ticks: u64) -> Self {
        self.starting_ticks = ticks;
        self
    }
}
