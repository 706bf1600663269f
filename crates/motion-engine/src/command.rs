//! Taking in client commands: validation and goals.

use motion_drivers::{Goal, GoalError, GoalKind};
use motion_ipc::{AxisMode, CommandKind, CommandReply, CommandRequest, Reason, SCHEMA_VERSION};

use crate::Engine;

/// Where the engine takes commands from and sends its answers to. motiond implements it
/// over the iceoryx2 request-response server; tests over a queue. The engine calls
/// [`reply`](Self::reply) exactly once after each request [`next_request`](Self::next_request)
/// returned, before asking for the next one.
pub trait CommandPort {
    /// The next pending request, if any.
    fn next_request(&mut self) -> Option<CommandRequest>;
    /// The answer to the request most recently returned by `next_request`.
    fn reply(&mut self, reply: CommandReply);
}

/// Requests taken in one step at most; the rest wait for the next tick.
pub const MAX_COMMANDS_PER_STEP: usize = 64;

impl Engine {
    /// Validates and applies one request; the answer says whether it was accepted.
    pub(crate) fn apply_command(&mut self, request: &CommandRequest) -> Reason {
        if request.schema_version != SCHEMA_VERSION {
            return Reason::SchemaMismatch;
        }
        let Ok(kind) = request.kind() else {
            return Reason::UnknownKind;
        };
        if request.values.iter().any(|value| !value.is_finite()) {
            return Reason::NotFinite;
        }
        match kind {
            CommandKind::EStop => {
                self.estop_all();
                return Reason::Accepted;
            }
            CommandKind::Reset => return self.reset(),
            CommandKind::Stop if request.axis == CommandRequest::ALL_AXES => {
                for index in 0..self.axes.len() {
                    self.stop_axis(index, None);
                }
                return Reason::Accepted;
            }
            _ => {}
        }
        let index = request.axis as usize;
        let Some(axis) = self.axes.get(index) else {
            return Reason::UnknownAxis;
        };
        let client = request.client;
        match kind {
            CommandKind::Claim | CommandKind::Release if client.is_none() => {
                return Reason::NoClientId;
            }
            CommandKind::Claim => {
                if axis.claimed_by_other(client) {
                    return Reason::ClaimedByOther;
                }
                self.axes[index].claimed_by = client;
                return Reason::Accepted;
            }
            CommandKind::Release => {
                if axis.claimed_by != client {
                    return Reason::NotClaimed;
                }
                self.axes[index].claimed_by = motion_ipc::ClientId::NONE;
                return Reason::Accepted;
            }
            // Anyone may stop any axis, claimed or not, e-stop or not.
            CommandKind::Stop => {
                self.stop_axis(index, None);
                return Reason::Accepted;
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
        if let Some(fault) = axis.fault {
            return if fault == motion_ipc::FaultCode::LinkDown {
                Reason::LinkDown
            } else {
                Reason::AxisFaulted
            };
        }
        let [v0, v1, v2] = request.values;
        let or_max = |value: f64, max: f64| if value == 0.0 { max } else { value };
        let (goal, mode, target, deadman) = match kind {
            CommandKind::Power => {
                if v0.abs() > 1.0 {
                    return Reason::PowerLimit;
                }
                if heads_into_limit(axis, v0, axis.max_accel) {
                    return Reason::OutOfRange;
                }
                (Goal::Power { fraction: v0 }, AxisMode::Power, v0, true)
            }
            CommandKind::Position => {
                if v0 < axis.min || v0 > axis.max {
                    return Reason::OutOfRange;
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
                    return Reason::VelocityLimit;
                }
                if accel <= 0.0 || accel > axis.max_accel {
                    return Reason::AccelLimit;
                }
                if heads_into_limit(axis, v0, accel) {
                    return Reason::OutOfRange;
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
                    return Reason::OutOfRange;
                }
                if velocity <= 0.0 || velocity > axis.max_velocity {
                    return Reason::VelocityLimit;
                }
                if accel <= 0.0 || accel > axis.max_accel {
                    return Reason::AccelLimit;
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
                    return Reason::VelocityLimit;
                }
                let goal = Goal::Home {
                    velocity: axis.magnitude_to_counts(velocity),
                };
                (goal, AxisMode::Homing, axis.position(), false)
            }
            CommandKind::SetPosition => {
                if v0 < axis.min || v0 > axis.max {
                    return Reason::OutOfRange;
                }
                let goal = Goal::SetPosition {
                    counts: axis.to_counts(v0),
                };
                (goal, AxisMode::Hold, v0, false)
            }
            CommandKind::Stop
            | CommandKind::Claim
            | CommandKind::Release
            | CommandKind::EStop
            | CommandKind::Reset => return Reason::UnknownKind,
        };
        let (bus, slot, channel) = (axis.bus, axis.slot, axis.channel);
        let now = self.now;
        let result = match self.buses[bus].driver_mut(slot) {
            Some(driver) => driver.set_goal(now, channel, goal),
            None => Err(GoalError::Offline),
        };
        if let Err(error) = result {
            return match error {
                GoalError::Unsupported(_) => Reason::Unsupported,
                GoalError::NoSuchChannel(_) => Reason::UnknownAxis,
                GoalError::OutOfBoardRange(GoalKind::Velocity | GoalKind::Home) => {
                    Reason::VelocityLimit
                }
                GoalError::OutOfBoardRange(_) => Reason::OutOfRange,
                GoalError::Offline | GoalError::Starting | GoalError::NoSuchPin(_) => {
                    Reason::LinkDown
                }
            };
        }
        let timeout = self.config.command_timeout;
        let axis = &mut self.axes[index];
        axis.mode = mode;
        axis.target = target;
        axis.goal_owner = client;
        axis.deadman_expired = false;
        axis.deadman_at = (deadman && !timeout.is_zero()).then(|| now + timeout);
        if kind == CommandKind::SetPosition {
            axis.position_set = true;
        }
        Reason::Accepted
    }

    /// Takes in at most [`MAX_COMMANDS_PER_STEP`] requests and answers each once.
    pub(crate) fn take_commands(&mut self, port: &mut dyn CommandPort) {
        for _ in 0..MAX_COMMANDS_PER_STEP {
            let Some(request) = port.next_request() else {
                break;
            };
            let reason = self.apply_command(&request);
            self.counters.commands += 1;
            if reason != Reason::Accepted {
                self.counters.rejected += 1;
            }
            port.reply(CommandReply::to(&request, reason, self.tick));
        }
    }
}

/// Whether a velocity (or power, by its sign) goal of `velocity` could not stop before the
/// soft limit it heads for, from where the axis is now.
fn heads_into_limit(axis: &crate::axis::Axis, velocity: f64, accel: f64) -> bool {
    if axis.stale {
        return false;
    }
    let reach = velocity * velocity / (2.0 * accel);
    let position = axis.position();
    (velocity > 0.0 && position + reach.max(axis.tolerance) >= axis.max)
        || (velocity < 0.0 && position - reach.max(axis.tolerance) <= axis.min)
}

/// Search velocity of a home command that gives none, as a fraction of max_velocity.
pub const HOME_FRACTION_OF_MAX: f64 = 0.25;
