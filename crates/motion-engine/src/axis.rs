//! One axis as the engine runs it: units, limits, goal bookkeeping and safety state.

use core::time::Duration;

use motion_drivers::{ChannelState, DeviceFault, GoalKind, GoalKinds};
use motion_ipc::{AxisMode, Capabilities, ClientId, CommandKind, FaultCode};

use crate::config::AxisConfig;

/// Runtime state of one axis. Plain data; the engine drives it.
#[derive(Debug, Clone)]
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
    pub tolerance: f64,
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
    /// Last refresh instant seen from the driver, and the tick it was seen in.
    pub refreshed_at: Option<Duration>,
    pub last_refresh_tick: u64,
    /// Fault latched by the engine (cleared when the driver clears it and data is fresh).
    pub fault: Option<FaultCode>,
    /// When the fault was latched: it clears only on data refreshed after this instant.
    pub fault_at: Duration,
    pub deadman_expired: bool,
    pub estopped: bool,
    pub stale: bool,
    /// Position was declared by set-position (counts as referenced).
    pub position_set: bool,
    /// Last state reported by the driver.
    pub state: ChannelState,
}

impl Axis {
    pub fn new(config: &AxisConfig, bus: usize, slot: usize, goals: GoalKinds) -> Self {
        Self {
            bus,
            slot,
            channel: config.channel,
            counts_per_unit: config.counts_per_unit,
            min: config.min,
            max: config.max,
            max_velocity: config.max_velocity,
            max_accel: config.max_accel,
            tolerance: config.position_tolerance,
            capabilities: capabilities_of(goals),
            mode: AxisMode::Off,
            target: 0.0,
            goal_owner: ClientId::NONE,
            deadman_at: None,
            claimed_by: ClientId::NONE,
            refreshed_at: None,
            last_refresh_tick: 0,
            fault: None,
            fault_at: Duration::ZERO,
            deadman_expired: false,
            estopped: false,
            stale: true,
            position_set: false,
            state: ChannelState::UNKNOWN,
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

    /// Whether a client other than `client` holds a claim.
    pub fn claimed_by_other(&self, client: ClientId) -> bool {
        !self.claimed_by.is_none() && self.claimed_by != client
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
        )
    }

    /// Distance needed to stop from the current velocity at max deceleration, units.
    pub fn stopping_distance(&self) -> f64 {
        let velocity = self.velocity();
        velocity * velocity / (2.0 * self.max_accel)
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
    for (goal, kinds) in [
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
