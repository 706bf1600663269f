//! One axis as the engine runs it: units, limits, goal bookkeeping and safety state.

use core::time::Duration;

use motion_drivers::{ChannelState, DeviceFault, GoalKind, GoalKinds, RateFloor};
use motion_ipc::rules::Motion;
use motion_ipc::{AxisMode, Capabilities, ClientId, CommandKind, FaultCode};

use crate::config::{AxisConfig, EstopCategory};

/// A latched fault: its code, who raised it, and the figure and tolerance it broke.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq)]
pub(crate) struct Fault {
    pub code: FaultCode,
    /// Raised by the engine's supervision (cleared only by a reset once its cause is
    /// gone) rather than reported by the driver (cleared when the driver clears it).
    pub by_engine: bool,
    /// The measured figure (units, units/s), 0 when none.
    pub value: f64,
    /// The tolerance or limit it broke, 0 when none.
    pub limit: f64,
    /// When it was latched.
    pub at: Duration,
}

/// A position move held by `Hold`.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq)]
pub(crate) struct HeldMove {
    /// The goal to continue (`Position` or `RampPosition`), in axis units.
    pub motion: Motion,
    /// The board paused the move itself: [`Driver::resume_line`](motion_drivers::Driver::resume_line)
    /// continues it.
    pub by_board: bool,
}

/// Runtime state of one axis. Plain data; the engine drives it.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone)]
pub(crate) struct Axis {
    /// Link (bus) index and driver index within that bus.
    pub bus: usize,
    pub slot: usize,
    pub channel: usize,
    pub counts_per_unit: f64,
    pub min: f64,
    pub max: f64,
    pub max_velocity: f64,
    pub max_accel: f64,
    /// The smallest nonzero velocity (units/s; of a velocity goal or search, and of a
    /// position profile) and acceleration (units/s²) the axis's board represents
    /// ([`motion_drivers::Driver::rate_floor`]); 0: none.
    pub min_velocity: f64,
    pub min_profile_velocity: f64,
    pub min_accel: f64,
    pub tolerance: f64,
    pub following_error: f64,
    pub overspeed_factor: f64,
    pub estop: EstopCategory,
    pub home_max_travel: f64,
    /// Index of the axis's device.
    pub device: usize,
    pub capabilities: Capabilities,
    /// What the engine is doing with the axis.
    pub mode: AxisMode,
    /// Position target (position modes) or velocity target (velocity modes), units.
    pub target: f64,
    /// The client whose goal the axis is executing (NONE for engine goals).
    pub goal_owner: ClientId,
    /// Deadman expiry of a velocity/power goal.
    pub deadman_at: Option<Duration>,
    pub claimed_by: ClientId,
    /// When the claim was last renewed by a command of its owner (claim lease).
    pub claim_renewed_at: Duration,
    /// Last refresh instant seen from the driver, and the tick it was seen in.
    pub refreshed_at: Option<Duration>,
    pub last_refresh_tick: u64,
    /// Fresh data arrived from the board in this step.
    pub fresh: bool,
    /// When supervision last looked at a fresh sample.
    pub last_sample_at: Duration,
    /// The latched fault.
    pub fault: Option<Fault>,
    /// Position where the current position goal started, units.
    pub move_start: f64,
    /// The current position goal has been reached once (the hold rule applies from then on).
    pub arrived: bool,
    /// Velocity (units/s) and acceleration (units/s²) of the last `RampPosition` goal.
    pub move_velocity: f64,
    pub move_accel: f64,
    /// The position move `Hold` brought to rest, which `Resume` continues.
    pub held: Option<HeldMove>,
    /// Fresh samples in a row above the overspeed limit.
    pub overspeed_samples: u8,
    /// Reference search: distance travelled so far, units; last position seen.
    pub home_travel: f64,
    pub home_last: f64,
    /// Reference search of an axis that was already referenced when it started.
    pub home_referenced: bool,
    /// Stop-off category in progress: de-energise once the stop has come to rest.
    pub off_after_stop: bool,
    /// The axis was de-energised on purpose (`off`, a stop category): a board that comes
    /// back online gets it switched off again, not a holding stop.
    pub switched_off: bool,
    pub deadman_expired: bool,
    pub estopped: bool,
    pub stale: bool,
    /// Position was declared by set-position (counts as referenced).
    pub position_set: bool,
    /// Last state reported by the driver.
    pub state: ChannelState,
    /// Tick in which the current goal was handed to the driver.
    pub goal_tick: u64,
    /// Tick and engine time at which its first request was written.
    pub goal_wire: Option<(u64, Duration)>,
    /// The group whose motion owns the axis (mode `Group`), if any.
    pub group: Option<usize>,
    /// While a group owns it: the path's position (units) and velocity (units/s) now.
    pub path_position: f64,
    pub path_velocity: f64,
}

impl Axis {
    pub fn new(
        config: &AxisConfig,
        bus: usize,
        slot: usize,
        goals: GoalKinds,
        floor: RateFloor,
    ) -> Self {
        let per_unit = config.counts_per_unit.abs();
        let in_units = |counts: f64| {
            let units = counts / per_unit;
            if units.is_finite() && units > 0.0 {
                units
            } else {
                0.0
            }
        };
        Self {
            bus,
            slot,
            channel: config.channel,
            counts_per_unit: config.counts_per_unit,
            min: config.min,
            max: config.max,
            max_velocity: config.max_velocity,
            max_accel: config.max_accel,
            min_velocity: in_units(floor.velocity),
            min_profile_velocity: in_units(floor.profile_velocity),
            min_accel: in_units(floor.accel),
            tolerance: config.position_tolerance,
            following_error: config.following_error,
            overspeed_factor: config.overspeed_factor,
            estop: config.estop,
            home_max_travel: config.home_max_travel,
            device: config.device,
            capabilities: capabilities_of(goals),
            mode: AxisMode::Off,
            target: 0.0,
            goal_owner: ClientId::NONE,
            deadman_at: None,
            claimed_by: ClientId::NONE,
            claim_renewed_at: Duration::ZERO,
            refreshed_at: None,
            last_refresh_tick: 0,
            fresh: false,
            last_sample_at: Duration::ZERO,
            fault: None,
            move_start: 0.0,
            arrived: false,
            move_velocity: 0.0,
            move_accel: 0.0,
            held: None,
            overspeed_samples: 0,
            home_travel: 0.0,
            home_last: 0.0,
            home_referenced: false,
            off_after_stop: false,
            switched_off: false,
            deadman_expired: false,
            estopped: false,
            stale: true,
            position_set: false,
            state: ChannelState::UNKNOWN,
            goal_tick: 0,
            goal_wire: None,
            group: None,
            path_position: 0.0,
            path_velocity: 0.0,
        }
    }

    /// Units → counts.
    pub fn to_counts(&self, units: f64) -> f64 {
        units * self.counts_per_unit
    }

    /// Rates (velocity, acceleration magnitudes) units → counts, sign kept.
    pub fn rate_to_counts(&self, units: f64) -> f64 {
        units * self.counts_per_unit
    }

    /// Magnitudes (acceleration) units → counts, always positive.
    pub fn magnitude_to_counts(&self, units: f64) -> f64 {
        (units * self.counts_per_unit).abs()
    }

    /// Measured position in units.
    pub fn position(&self) -> f64 {
        self.state.position / self.counts_per_unit
    }

    /// Measured velocity in units/s.
    pub fn velocity(&self) -> f64 {
        self.state.velocity / self.counts_per_unit
    }

    /// Where the engine wants the axis now, units (the frame's `desired_position`).
    pub fn desired_position(&self) -> f64 {
        match self.mode {
            AxisMode::Group => self.path_position,
            AxisMode::Position | AxisMode::RampPosition | AxisMode::Hold => self.target,
            _ => self.position(),
        }
    }

    /// The velocity the engine wants now, units/s (the frame's `desired_velocity`).
    pub fn desired_velocity(&self) -> f64 {
        match self.mode {
            AxisMode::Group => self.path_velocity,
            AxisMode::Velocity | AxisMode::RampVelocity => self.target,
            _ => 0.0,
        }
    }

    /// A goal the client set that must be voided when its owner dies or a fault occurs.
    pub fn has_active_goal(&self) -> bool {
        matches!(
            self.mode,
            AxisMode::Power
                | AxisMode::Position
                | AxisMode::Velocity
                | AxisMode::RampPosition
                | AxisMode::RampVelocity
                | AxisMode::Homing
                | AxisMode::Group
        )
    }

    /// Distance needed to stop from the current velocity at max deceleration, units.
    pub fn stopping_distance(&self) -> f64 {
        let velocity = self.velocity();
        velocity * velocity / (2.0 * self.max_accel)
    }

    /// The latched fault's code.
    pub fn fault_code(&self) -> Option<FaultCode> {
        self.fault.map(|fault| fault.code)
    }

    /// Whether the axis has a reference (homed by the board, or its position was set).
    pub fn referenced(&self) -> bool {
        self.state.homed || self.position_set
    }
}

/// The command kinds an axis accepts, from the goals its driver supports.
pub(crate) fn capabilities_of(goals: GoalKinds) -> Capabilities {
    let mut caps = Capabilities::NONE
        .with(CommandKind::Stop)
        .with(CommandKind::Claim)
        .with(CommandKind::Release)
        .with(CommandKind::EStop)
        .with(CommandKind::Reset);
    if goals.contains(GoalKind::Position) || goals.contains(GoalKind::RampPosition) {
        // A position move to hold and resume (`hold.rs`): by the board's own pause, or
        // by a stop and the same goal again.
        caps = caps.with(CommandKind::Hold).with(CommandKind::Resume);
    }
    for (goal, kinds) in [
        (GoalKind::Off, &[CommandKind::Off][..]),
        (GoalKind::Power, &[CommandKind::Power][..]),
        (GoalKind::Position, &[CommandKind::Position][..]),
        (
            GoalKind::Velocity,
            &[CommandKind::Velocity, CommandKind::RampVelocity][..],
        ),
        (GoalKind::RampPosition, &[CommandKind::RampPosition][..]),
        (GoalKind::Home, &[CommandKind::Home][..]),
        (GoalKind::SetPosition, &[CommandKind::SetPosition][..]),
    ] {
        if goals.contains(goal) {
            for kind in kinds {
                caps = caps.with(*kind);
            }
        }
    }
    caps
}

/// The shared-memory fault code of a driver fault.
pub(crate) fn fault_code(fault: DeviceFault) -> FaultCode {
    match fault {
        DeviceFault::LinkDown => FaultCode::LinkDown,
        DeviceFault::NotResponding => FaultCode::BoardNotResponding,
        DeviceFault::Reset => FaultCode::BoardReset,
        DeviceFault::BoardError => FaultCode::BoardError,
        DeviceFault::Protocol => FaultCode::Protocol,
        DeviceFault::Overspeed => FaultCode::Overspeed,
        DeviceFault::LimitSwitch => FaultCode::LimitSwitch,
        DeviceFault::HomeFailed => FaultCode::HomeFailed,
    }
}
