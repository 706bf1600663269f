//! Taking in client commands: identity, validation and goals.

use motion_drivers::{Goal, GoalError, GoalKind};
use motion_ipc::{
    AxisMode, ClientId, CommandKind, CommandReply, CommandRequest, DeviceState, FaultCode, Reason,
    SCHEMA_VERSION, Target,
};

use crate::Engine;
use crate::axis::Axis;

/// Where the engine takes commands from and sends its answers to. motiond implements it
/// over the iceoryx2 request-response server; tests over a queue. The engine calls
/// [`reply`](Self::reply) exactly once after each request [`next_request`](Self::next_request)
/// returned, before asking for the next one.
pub trait CommandPort {
    /// The next pending request, if any.
    fn next_request(&mut self) -> Option<CommandRequest>;
    /// The answer to the request most recently returned by `next_request`.
    fn reply(&mut self, reply: CommandReply);
    /// Who sent the request most recently returned by `next_request`, as the transport
    /// knows it: the sender's iceoryx2 node (`Some(ClientId::NONE)` when the transport
    /// could not tell). `None` (the default) is for in-process ports without a transport
    /// identity: the request's own `client` field is then taken as is.
    fn sender(&self) -> Option<ClientId> {
        None
    }
}

/// Requests taken in one step at most; the rest wait for the next tick.
pub const MAX_COMMANDS_PER_STEP: usize = 64;

/// Search velocity of a home command that gives none, as a fraction of max_velocity.
pub const HOME_FRACTION_OF_MAX: f64 = 0.25;

impl Engine {
    /// Validates and applies one request from `sender` (see [`CommandPort::sender`]); the
    /// answer says whether it was accepted.
    pub(crate) fn apply_command(
        &mut self,
        request: &CommandRequest,
        sender: Option<ClientId>,
    ) -> Reason {
        if request.schema_version != SCHEMA_VERSION {
            return Reason::SchemaMismatch;
        }
        let Ok(kind) = request.kind() else {
            return Reason::UnknownKind;
        };
        if request.values.iter().any(|value| !value.is_finite()) {
            return Reason::NotFinite;
        }
        let client = match sender {
            None => request.client,
            Some(node) if request.client.is_none() || request.client == node => node,
            Some(_) => return Reason::IdentityMismatch,
        };
        self.renew_claims(client);
        let Ok(target) = request.target() else {
            return Reason::UnknownTarget;
        };
        if target == Target::Signal {
            return self.signal_command(kind, request.axis as usize, client, request.values[0]);
        }
        match kind {
            CommandKind::EStop => {
                self.estop_all();
                return Reason::Accepted;
            }
            CommandKind::Reset => return self.reset(),
            CommandKind::Stop if request.axis == CommandRequest::ALL_AXES => {
                for index in 0..self.axes.len() {
                    self.stop_axis(index, false);
                }
                return Reason::Accepted;
            }
            CommandKind::Off if request.axis == CommandRequest::ALL_AXES => {
                return self.off_all(client);
            }
            CommandKind::SetOutput => return Reason::UnknownTarget,
            _ => {}
        }
        let index = request.axis as usize;
        let Some(axis) = self.axes.get(index) else {
            return Reason::UnknownAxis;
        };
        match kind {
            CommandKind::Claim | CommandKind::Release if client.is_none() => {
                return Reason::NoClientId;
            }
            CommandKind::Claim => {
                if axis.claimed_by_other(client) {
                    return Reason::ClaimedByOther;
                }
                let now = self.now;
                let axis = &mut self.axes[index];
                axis.claimed_by = client;
                axis.claim_renewed_at = now;
                return Reason::Accepted;
            }
            CommandKind::Release => {
                if axis.claimed_by != client {
                    return Reason::NotClaimed;
                }
                self.axes[index].claimed_by = ClientId::NONE;
                return Reason::Accepted;
            }
            // Anyone may stop any axis, claimed or not, e-stop or not.
            CommandKind::Stop => {
                self.stop_axis(index, false);
                return Reason::Accepted;
            }
            // Off is safe from the board's point of view but not always for the machine (a
            // vertical axis falls): claims apply; e-stop and faults do not stop it.
            CommandKind::Off => {
                if axis.claimed_by_other(client) {
                    return Reason::ClaimedByOther;
                }
                if !axis.capabilities.supports(CommandKind::Off) {
                    return Reason::Unsupported;
                }
                return match self.off_axis(index) {
                    Ok(()) => Reason::Accepted,
                    Err(error) => self.goal_error_reason(index, error),
                };
            }
            _ => {}
        }
        if self.shutting_down {
            return Reason::ShuttingDown;
        }
        if self.estop {
            return Reason::EstopLatched;
        }
        if axis.claimed_by_other(client) {
            return Reason::ClaimedByOther;
        }
        if !axis.capabilities.supports(kind) {
            return Reason::Unsupported;
        }
        match self.device_state_of(index) {
            DeviceState::Starting => return Reason::DeviceStarting,
            DeviceState::Offline if !self.device_link_up(axis.device) => return Reason::LinkDown,
            DeviceState::Offline => return Reason::DeviceOffline,
            DeviceState::Online | DeviceState::Faulted => {}
        }
        let beyond_limit = match axis.fault_code() {
            None => false,
            Some(FaultCode::LimitExceeded) => true,
            Some(FaultCode::LinkDown) => return Reason::LinkDown,
            Some(_) => return Reason::AxisFaulted,
        };
        let (goal, mode, target, deadman) = match goal_of(axis, kind, request.values) {
            Ok(goal) => goal,
            Err(reason) => return reason,
        };
        if beyond_limit && !heads_back_inside(axis, &goal, target) {
            return Reason::AxisFaulted;
        }
        let (bus, slot, channel) = (axis.bus, axis.slot, axis.channel);
        let now = self.now;
        let result = match self.buses[bus].driver_mut(slot) {
            Some(driver) => driver.set_goal(now, channel, goal),
            None => Err(GoalError::Offline),
        };
        if let Err(error) = result {
            return self.goal_error_reason(index, error);
        }
        let timeout = self.config.command_timeout;
        let axis = &mut self.axes[index];
        let position = axis.position();
        axis.mode = mode;
        axis.target = target;
        axis.goal_owner = client;
        axis.deadman_expired = false;
        axis.deadman_at = (deadman && !timeout.is_zero()).then(|| now + timeout);
        axis.move_start = position;
        axis.arrived = false;
        axis.off_after_stop = false;
        axis.switched_off = false;
        axis.home_travel = 0.0;
        axis.home_last = position;
        axis.home_referenced = axis.referenced();
        if kind == CommandKind::SetPosition {
            axis.position_set = true;
        }
        Reason::Accepted
    }

    /// Off for every axis `client` may command (claims of others are skipped); boards that
    /// cannot de-energise are left as they are.
    fn off_all(&mut self, client: ClientId) -> Reason {
        let mut skipped = false;
        for index in 0..self.axes.len() {
            let axis = &self.axes[index];
            if axis.claimed_by_other(client) {
                skipped = true;
                continue;
            }
            if axis.capabilities.supports(CommandKind::Off) {
                let _ = self.off_axis(index);
            }
        }
        if skipped {
            Reason::ClaimedByOther
        } else {
            Reason::Accepted
        }
    }

    /// The reason for a goal the driver refused.
    fn goal_error_reason(&self, index: usize, error: GoalError) -> Reason {
        match error {
            GoalError::Unsupported(_) | GoalError::NoSuchPin(_) => Reason::Unsupported,
            GoalError::NoSuchChannel(_) => Reason::UnknownAxis,
            GoalError::OutOfBoardRange(GoalKind::Velocity | GoalKind::Home) => {
                Reason::VelocityLimit
            }
            GoalError::OutOfBoardRange(_) => Reason::OutOfRange,
            GoalError::Starting => Reason::DeviceStarting,
            GoalError::Offline => {
                let device = self.axes.get(index).map_or(usize::MAX, |axis| axis.device);
                if self.device_link_up(device) {
                    Reason::DeviceOffline
                } else {
                    Reason::LinkDown
                }
            }
        }
    }

    /// Renews the claim leases of `client`.
    fn renew_claims(&mut self, client: ClientId) {
        if client.is_none() {
            return;
        }
        let now = self.now;
        for axis in self.axes.iter_mut().filter(|a| a.claimed_by == client) {
            axis.claim_renewed_at = now;
        }
        for signal in self.signals.iter_mut().filter(|s| s.claimed_by == client) {
            signal.claim_renewed_at = now;
        }
    }

    /// Ends claims whose lease ran out.
    pub(crate) fn expire_claims(&mut self) {
        let lease = self.config.claim_lease;
        if lease.is_zero() {
            return;
        }
        let now = self.now;
        for axis in &mut self.axes {
            if !axis.claimed_by.is_none() && now.saturating_sub(axis.claim_renewed_at) > lease {
                axis.claimed_by = ClientId::NONE;
            }
        }
        for signal in &mut self.signals {
            if !signal.claimed_by.is_none() && now.saturating_sub(signal.claim_renewed_at) > lease {
                signal.claimed_by = ClientId::NONE;
            }
        }
    }

    /// Takes in at most [`MAX_COMMANDS_PER_STEP`] requests and answers each once.
    pub(crate) fn take_commands(&mut self, port: &mut dyn CommandPort) {
        for _ in 0..MAX_COMMANDS_PER_STEP {
            let Some(request) = port.next_request() else {
                break;
            };
            let reason = self.apply_command(&request, port.sender());
            self.counters.commands += 1;
            if reason != Reason::Accepted {
                self.counters.rejected += 1;
            }
            port.reply(CommandReply::to(&request, reason, self.tick));
        }
    }
}

/// The goal, mode, target and deadman flag of a motion request, or why it is refused.
fn goal_of(
    axis: &Axis,
    kind: CommandKind,
    [v0, v1, v2]: [f64; 3],
) -> Result<(Goal, AxisMode, f64, bool), Reason> {
    let or_max = |value: f64, max: f64| if value == 0.0 { max } else { value };
    Ok(match kind {
        CommandKind::Power => {
            if v0.abs() > 1.0 {
                return Err(Reason::PowerLimit);
            }
            if heads_into_limit(axis, v0, axis.max_accel) {
                return Err(Reason::OutOfRange);
            }
            (Goal::Power { fraction: v0 }, AxisMode::Power, v0, true)
        }
        CommandKind::Position => {
            if v0 < axis.min || v0 > axis.max {
                return Err(Reason::OutOfRange);
            }
            let goal = Goal::Position {
                counts: axis.to_counts(v0),
            };
            (goal, AxisMode::Position, v0, false)
        }
        CommandKind::Velocity | CommandKind::RampVelocity => {
            let accel = if kind == CommandKind::Velocity {
                axis.max_accel
            } else {
                or_max(v1, axis.max_accel)
            };
            if v0.abs() > axis.max_velocity {
                return Err(Reason::VelocityLimit);
            }
            if accel <= 0.0 || accel > axis.max_accel {
                return Err(Reason::AccelLimit);
            }
            if heads_into_limit(axis, v0, accel) {
                return Err(Reason::OutOfRange);
            }
            let goal = Goal::Velocity {
                velocity: axis.rate_to_counts(v0),
                accel: axis.magnitude_to_counts(accel),
            };
            let mode = if kind == CommandKind::Velocity {
                AxisMode::Velocity
            } else {
                AxisMode::RampVelocity
            };
            (goal, mode, v0, true)
        }
        CommandKind::RampPosition => {
            let velocity = or_max(v1, axis.max_velocity);
            let accel = or_max(v2, axis.max_accel);
            if v0 < axis.min || v0 > axis.max {
                return Err(Reason::OutOfRange);
            }
            if velocity <= 0.0 || velocity > axis.max_velocity {
                return Err(Reason::VelocityLimit);
            }
            if accel <= 0.0 || accel > axis.max_accel {
                return Err(Reason::AccelLimit);
            }
            let goal = Goal::RampPosition {
                counts: axis.to_counts(v0),
                velocity: axis.magnitude_to_counts(velocity),
                accel: axis.magnitude_to_counts(accel),
            };
            (goal, AxisMode::RampPosition, v0, false)
        }
        CommandKind::Home => {
            let velocity = or_max(v0, axis.max_velocity * HOME_FRACTION_OF_MAX);
            if velocity <= 0.0 || velocity > axis.max_velocity {
                return Err(Reason::VelocityLimit);
            }
            let goal = Goal::Home {
                velocity: axis.magnitude_to_counts(velocity),
            };
            (goal, AxisMode::Homing, axis.position(), false)
        }
        CommandKind::SetPosition => {
            if v0 < axis.min || v0 > axis.max {
                return Err(Reason::OutOfRange);
            }
            let goal = Goal::SetPosition {
                counts: axis.to_counts(v0),
            };
            (goal, AxisMode::Hold, v0, false)
        }
        CommandKind::Stop
        | CommandKind::Off
        | CommandKind::Claim
        | CommandKind::Release
        | CommandKind::EStop
        | CommandKind::Reset
        | CommandKind::SetOutput => return Err(Reason::UnknownKind),
    })
}

/// Whether a velocity (or power, by its sign) goal of `velocity` could not stop before the
/// soft limit it heads for, from where the axis is now.
fn heads_into_limit(axis: &Axis, velocity: f64, accel: f64) -> bool {
    if axis.stale {
        return false;
    }
    let reach = velocity * velocity / (2.0 * accel);
    let position = axis.position();
    (velocity > 0.0 && position + reach.max(axis.tolerance) >= axis.max)
        || (velocity < 0.0 && position - reach.max(axis.tolerance) <= axis.min)
}

/// For an axis beyond a soft limit (`LimitExceeded` latched): whether `goal` brings it back
/// inside (a position target within the limits, a velocity or power towards them, a
/// set-position within them). Nothing else is accepted until a reset.
fn heads_back_inside(axis: &Axis, goal: &Goal, target: f64) -> bool {
    let position = axis.position();
    let inward =
        |sign: f64| (position > axis.max && sign < 0.0) || (position < axis.min && sign > 0.0);
    match goal {
        Goal::Position { .. } | Goal::RampPosition { .. } | Goal::SetPosition { .. } => {
            (axis.min..=axis.max).contains(&target)
        }
        // `target` is the requested velocity (units/s) or power fraction, sign as the axis
        // counts positions.
        Goal::Velocity { .. } | Goal::Power { .. } => inward(target),
        Goal::Off | Goal::Stop { .. } | Goal::Home { .. } => false,
    }
}
