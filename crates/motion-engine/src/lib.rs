//! The deterministic tick of motiond.
//!
//! [`Engine::step`] takes the time, the client commands and what the links received, runs
//! the safety rules and writes one [`MotionFrame`] — no clock, no thread, no file, no
//! iceoryx2 call, no allocation after construction. The same inputs in the same ticks give
//! the same frames, so a run can be tested tick by tick and replayed bit for bit.
//!
//! One tick, as motiond drives it (docs/ARCHITECTURE.md "The tick"):
//! 1. [`Engine::handle_link_rx`] for every link with the bytes received since the last tick
//!    (and [`Engine::link_down`] / [`Engine::link_up`] for link events);
//! 2. [`Engine::step`]: drivers update their channels, commands are validated and answered
//!    exactly once through the [`CommandPort`], safety runs (deadman, soft limits, faults,
//!    e-stop), and the frame is written into the caller's (shared-memory) `&mut MotionFrame`;
//! 3. [`Engine::poll_link_transmit`] for every link until it returns `None`: the bytes the
//!    drivers want on the wire.
//!
//! ```
//! use core::time::Duration;
//! use motion_engine::{Engine, EngineConfig, CommandPort};
//! use motion_ipc::{CommandReply, CommandRequest, MotionFrame};
//!
//! struct NoCommands;
//! impl CommandPort for NoCommands {
//!     fn next_request(&mut self) -> Option<CommandRequest> { None }
//!     fn reply(&mut self, _: CommandReply) {}
//! }
//!
//! let config = EngineConfig {
//!     name: "empty".into(),
//!     tick_hz: 1000,
//!     command_timeout: Duration::from_millis(250),
//!     links: vec![],
//!     devices: vec![],
//!     axes: vec![],
//!     ..EngineConfig::default()
//! };
//! let mut engine: Engine = Engine::new(config, vec![]).expect("valid config");
//! let mut frame = MotionFrame::EMPTY;
//! engine.step(Duration::ZERO, &mut NoCommands, &mut frame);
//! engine.step(Duration::from_millis(1), &mut NoCommands, &mut frame);
//! assert_eq!(frame.tick, 1);
//! ```
#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod axis;
mod command;
mod commission;
mod config;
mod device;
mod frame;
mod group;
mod hold;
mod io;
mod safety;
mod signal;
mod supervision;

use core::time::Duration;

use motion_base::FixedQueue;
use motion_drivers::{Driver, LinkBus, LinkKind, MAX_SENDS_PER_STEP};
use motion_ipc::{ClientId, MotionFrame};

use crate::axis::Axis;
pub use crate::command::{CommandPort, HOME_FRACTION_OF_MAX, MAX_COMMANDS_PER_STEP};
pub use crate::config::{
    AxisConfig, BusConfig, DeviceConfig, EngineConfig, EngineConfigError, EstopCategory,
    GroupConfig, MAX_STREAM_BUFFER, SignalConfig, StreamLimit,
};
use crate::device::Device;
use crate::group::Group;
pub use crate::io::IO_STALL_LIMIT;
use crate::signal::Signal;
pub use crate::supervision::OVERSPEED_SAMPLES;

/// Counters since construction.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct EngineCounters {
    /// Requests answered.
    pub commands: u64,
    /// Requests refused.
    pub rejected: u64,
    /// Deadman expiries.
    pub deadman_stops: u64,
    /// Soft-limit stops of velocity and power goals.
    pub limit_stops: u64,
    /// Faults latched by the engine's supervision (following error, overspeed, limits,
    /// search travel, overruns).
    pub faults: u64,
}

/// The deterministic motion engine, over drivers of type `D`: the server's enum of the
/// registered boards' drivers (static dispatch, `motion_boards::AnyDriver`), or
/// `Box<dyn Driver>` (the default) in tests and tools.
#[derive(serde::Serialize, serde::Deserialize, Debug)]
pub struct Engine<D: Driver = Box<dyn Driver>> {
    config: EngineConfig,
    buses: Vec<LinkBus<D>>,
    /// Per device: where its driver is, and its readiness.
    devices: Vec<Device>,
    axes: Vec<Axis>,
    signals: Vec<Signal>,
    /// Per link: up (the shell reports down/up events).
    link_up: Vec<bool>,
    /// Per link: it has been open at least once ([`Engine::link_opening`] clears it until
    /// the first [`Engine::link_up`]). A link that never opened is not down: its boards are
    /// starting, and its drivers are not run.
    link_opened: Vec<bool>,
    /// Messages sent on each bus in the current tick.
    sends: Vec<usize>,
    tick: u64,
    started: bool,
    now: Duration,
    estop: bool,
    shutting_down: bool,
    counters: EngineCounters,
    /// Clients found dead lately: a request one of them sent just before it died may still
    /// be queued, and must not start a goal nobody will renew or stop.
    departed: FixedQueue<ClientId, DEPARTED_MEMORY>,
    /// Per link: the horizon the shell reported last (stamped links).
    heard: Vec<Option<Duration>>,
    /// CLOCK_MONOTONIC at engine time zero.
    clock_origin: Duration,
    /// Axis groups, config order.
    groups: Vec<Group>,
    /// What the answer to the request being applied names besides its reason.
    reply_detail: ReplyDetail,
    /// Per device: the address its config gives (a factory reset brings it back; a
    /// commissioned address replaces it in `config`).
    config_addresses: Vec<u32>,
}

/// What an answer names besides its reason: the axis (config index) and the point at
/// fault, the claim holder, the figure and the limit ([`motion_ipc::CommandReply`]).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq)]
pub(crate) struct ReplyDetail {
    pub at_point: Option<usize>,
    pub at_axis: Option<usize>,
    pub holder: ClientId,
    pub value: f64,
    pub limit: f64,
}

impl ReplyDetail {
    pub const NONE: Self = Self {
        at_point: None,
        at_axis: None,
        holder: ClientId::NONE,
        value: 0.0,
        limit: 0.0,
    };
}

/// Dead clients remembered (the oldest is forgotten first; node ids are never reused).
const DEPARTED_MEMORY: usize = 64;

impl<D: Driver> Engine<D> {
    /// Builds the engine from a validated description and one driver per device (same
    /// order as `config.devices`).
    pub fn new(config: EngineConfig, drivers: Vec<D>) -> Result<Self, EngineConfigError> {
        config::validate(&config, drivers.len())?;
        let mut per_link: Vec<Vec<D>> = config.links.iter().map(|_| Vec::new()).collect();
        let mut devices = Vec::with_capacity(drivers.len());
        for (device, driver) in config.devices.iter().zip(drivers) {
            devices.push(Device::new(device.link, per_link[device.link].len()));
            per_link[device.link].push(driver);
        }
        let mut axes = Vec::with_capacity(config.axes.len());
        for axis in &config.axes {
            let (bus, slot) = (devices[axis.device].bus, devices[axis.device].slot);
            let driver = &per_link[bus][slot];
            if axis.channel >= driver.channel_count() {
                return Err(EngineConfigError::NoSuchChannel {
                    axis: axis.name.clone(),
                    device: config.devices[axis.device].name.clone(),
                    channel: axis.channel,
                    count: driver.channel_count(),
                });
            }
            let goals = driver.capabilities(axis.channel);
            if axis.estop != EstopCategory::Hold && !goals.contains(motion_drivers::GoalKind::Off) {
                return Err(EngineConfigError::BadAxisValue {
                    axis: axis.name.clone(),
                    what: "estop = \"stop-off\" or \"off\" needs a board that can de-energise the motor; this one cannot (use \"hold\")",
                });
            }
            let floor = driver.rate_floor(axis.channel);
            axes.push(Axis::new(axis, bus, slot, goals, floor));
        }
        let signals = config
            .signals
            .iter()
            .map(|signal| {
                let device = &devices[signal.device];
                Signal::new(signal.clone(), device.bus, device.slot)
            })
            .collect();
        let groups = config
            .groups
            .iter()
            .map(|group| {
                let members = group
                    .axes
                    .iter()
                    .map(|&index| {
                        let axis = &axes[index];
                        let follow = per_link[axis.bus][axis.slot].follow(axis.channel);
                        let limits = motion_trajectory::AxisLimits {
                            min: axis.min,
                            max: axis.max,
                            max_velocity: axis.max_velocity,
                            max_accel: axis.max_accel,
                        };
                        (index, follow, limits)
                    })
                    .collect();
                Group::new(group.clone(), members)
            })
            .collect();
        let buses: Vec<LinkBus<D>> = config
            .links
            .iter()
            .zip(per_link)
            .map(|(link, drivers)| LinkBus::new(link.kind, drivers))
            .collect();
        Ok(Self {
            sends: vec![0; buses.len()],
            heard: vec![None; buses.len()],
            clock_origin: Duration::ZERO,
            link_up: vec![true; buses.len()],
            link_opened: vec![true; buses.len()],
            buses,
            devices,
            axes,
            signals,
            tick: 0,
            started: false,
            now: Duration::ZERO,
            estop: false,
            shutting_down: false,
            counters: EngineCounters::default(),
            departed: FixedQueue::new(),
            groups,
            reply_detail: ReplyDetail::NONE,
            config_addresses: config.devices.iter().map(|d| d.address).collect(),
            config,
        })
    }

    /// How many bytes more than now its serialized state (the black box's snapshot) may
    /// take, at the most: the groups' running paths at their longest trajectories (a
    /// group's spare path is scratch: its sizes only). Everything else is sized at
    /// start-up.
    pub fn snapshot_growth(&self) -> usize {
        self.groups
            .iter()
            .map(|group| group.path.serialized_bound())
            .sum()
    }

    /// The description the engine was built from.
    pub fn config(&self) -> &EngineConfig {
        &self.config
    }

    /// The tick of the last step (0 before and during the first).
    pub fn tick(&self) -> u64 {
        self.tick
    }

    /// Whether the e-stop is latched.
    pub fn estop_latched(&self) -> bool {
        self.estop
    }

    /// Counters since construction.
    pub fn counters(&self) -> EngineCounters {
        self.counters
    }

    /// The driver of device `index` (config order).
    pub fn driver(&self, device: usize) -> Option<&D> {
        let (bus, slot) = self.devices.get(device).map(|d| (d.bus, d.slot))?;
        self.buses.get(bus)?.drivers().get(slot)
    }

    /// Stream or SPI, per link.
    pub fn link_kind(&self, link: usize) -> Option<LinkKind> {
        self.buses.get(link).map(LinkBus::kind)
    }

    /// Bytes received on `link` since the last tick (call before [`step`](Self::step)),
    /// read by the link's I/O side at `arrived`. The drivers get them at the tick's `now`
    /// or at `arrived` if that is later: a tick that woke late (its `now` is its deadline)
    /// takes bytes that came after that deadline, and a driver told they came earlier than
    /// they did would time what follows them — a board's switch-over hold after its answer,
    /// the next request — from an instant before the answer ended, and talk over the board
    /// (docs/ARCHITECTURE.md "The tick's time and the wire's").
    pub fn handle_link_rx(&mut self, link: usize, now: Duration, arrived: Duration, bytes: &[u8]) {
        if let Some(bus) = self.buses.get_mut(link) {
            bus.handle_rx(now.max(arrived), bytes);
        }
    }

    /// `link` is not open yet (call before the first [`step`](Self::step); the shell
    /// opens links on their own threads): until its first [`link_up`](Self::link_up) its
    /// devices are `Starting` — commands to them are refused with `DeviceStarting`, never
    /// `LinkDown` — its drivers are not run and nothing is sent on it. Without this call a
    /// link counts as open from the start (a rig that moves bytes itself).
    pub fn link_opening(&mut self, link: usize) {
        if link < self.buses.len() {
            self.link_up[link] = false;
            self.link_opened[link] = false;
        }
    }

    /// `link` failed (unplugged, closed, I/O error): its axes fault and stop being driven.
    /// A link that never opened ([`link_opening`](Self::link_opening)) stays opening: its
    /// boards are still starting, not down.
    pub fn link_down(&mut self, link: usize, now: Duration) {
        if !self.link_opened.get(link).copied().unwrap_or(false) {
            return;
        }
        if let Some(bus) = self.buses.get_mut(link) {
            bus.link_down(now);
            self.link_up[link] = false;
        }
    }

    /// `link` is open (the first time, or again after it failed): its boards (re)start;
    /// axes stay stale until fresh data and need a new command.
    pub fn link_up(&mut self, link: usize, now: Duration) {
        if let Some(bus) = self.buses.get_mut(link) {
            bus.link_up(now);
            self.link_up[link] = true;
            self.link_opened[link] = true;
        }
    }

    /// The fault latched on axis `index` (config order): code, measured figure, tolerance.
    pub fn axis_fault(&self, index: usize) -> Option<(motion_ipc::FaultCode, f64, f64)> {
        let fault = self.axes.get(index)?.fault?;
        Some((fault.code, fault.value, fault.limit))
    }

    /// The readiness of device `index` (config order) as of the last step.
    pub fn device_state(&self, index: usize) -> Option<motion_ipc::DeviceState> {
        self.devices.get(index).map(|device| device.state)
    }

    /// One tick at `now`: drivers update, commands from `port` are answered, safety runs,
    /// and the frame for this tick is written into `frame`.
    pub fn step(&mut self, now: Duration, port: &mut dyn CommandPort, frame: &mut MotionFrame) {
        if self.started {
            self.tick += 1;
        }
        self.started = true;
        self.now = now;
        self.sends.fill(0);
        self.apply_io_stamps(now);
        for (bus, opened) in self.buses.iter_mut().zip(&self.link_opened) {
            if *opened {
                bus.handle_timeout(now);
            }
        }
        self.update_devices();
        self.update_from_drivers();
        self.update_signals();
        self.supervise();
        self.expire_claims();
        self.take_commands(port);
        self.run_safety();
        self.run_groups();
        self.forget_stale_holds();
        self.write_frame(frame);
    }

    /// Accounts for `ticks` missed deadlines (an overrun the shell skipped instead of
    /// running late ticks back to back), so that tick `k` keeps meaning `t0 + k·period`.
    pub fn skip_ticks(&mut self, ticks: u64) {
        self.tick += ticks;
    }

    /// The next message for `link`, written into `buf` (at least 256 bytes); `None` when
    /// the link has nothing to send this tick. On an SPI link each message is one
    /// transaction.
    #[must_use]
    pub fn poll_link_transmit(
        &mut self,
        link: usize,
        now: Duration,
        buf: &mut [u8],
    ) -> Option<usize> {
        if !self.link_opened.get(link).copied().unwrap_or(false) {
            // Nothing goes to a link that never opened (the drivers have not started).
            return None;
        }
        let sends = self.sends.get_mut(link)?;
        if *sends >= MAX_SENDS_PER_STEP {
            return None;
        }
        let bus = self.buses.get_mut(link)?;
        let (slot, transmit) = bus.poll_transmit(now, buf)?;
        *sends += 1;
        if !bus.stamped() {
            // Written as it is made.
            self.goal_on_wire(link, slot, transmit.goal_starts, now);
        }
        Some(transmit.len)
    }

    /// The earliest instant a driver has timed work (a reply timeout, a poll period).
    #[must_use]
    pub fn poll_timeout(&self) -> Option<Duration> {
        self.buses
            .iter()
            .zip(&self.link_opened)
            .filter(|(_, opened)| **opened)
            .filter_map(|(bus, _)| bus.poll_timeout())
            .min()
    }

    /// The client node `client` died (its process is gone without a word): its claims end
    /// and its goals are voided (the axes decelerate and hold).
    pub fn client_dead(&mut self, client: ClientId) {
        if client.is_none() {
            return;
        }
        self.abort_groups_of(client);
        self.release_claims_of(client);
        if self.departed.position(|gone| *gone == client).is_none() {
            self.departed.push_overwrite(client);
        }
        for index in 0..self.axes.len() {
            let axis = &mut self.axes[index];
            if axis.goal_owner != client {
                continue;
            }
            if axis.has_active_goal() {
                self.stop_axis(index, false);
            } else {
                axis.goal_owner = ClientId::NONE;
            }
        }
    }

    /// The claims of `client` end (it closed its command port or exited; its goals go on:
    /// a move sent by a command that exited right away still completes — but a group's
    /// motion or stream that it ran under its claim stops, as when it dies).
    pub fn release_claims_of(&mut self, client: ClientId) {
        if client.is_none() {
            return;
        }
        self.abort_claimed_groups_of(client);
        for axis in &mut self.axes {
            if axis.claimed_by == client {
                axis.claimed_by = ClientId::NONE;
            }
        }
        for signal in &mut self.signals {
            if signal.claimed_by == client {
                signal.claimed_by = ClientId::NONE;
            }
        }
    }

    /// The claim holders of every axis and signal (for the shell, which checks them against
    /// the nodes connected to the command service).
    pub fn claim_holders(&self) -> impl Iterator<Item = ClientId> + '_ {
        self.axes
            .iter()
            .map(|axis| axis.claimed_by)
            .chain(self.signals.iter().map(|signal| signal.claimed_by))
            .filter(|client| !client.is_none())
    }

    /// Latches the e-stop (as an `EStop` request does): for the shell's other e-stop paths
    /// (the `estop` event, SIGUSR1).
    pub fn estop(&mut self) {
        self.estop_all();
    }

    /// Whether every board has acknowledged its goals and no axis with a live link moves.
    pub fn all_at_rest(&self) -> bool {
        let drivers_settled = self
            .buses
            .iter()
            .flat_map(|bus| bus.drivers())
            .all(|driver| !driver.goals_pending() || !driver.status().online);
        drivers_settled
            && self
                .axes
                .iter()
                .all(|axis| !axis.state.moving || axis.fault.is_some())
    }
}
