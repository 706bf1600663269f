//! The command rulebook: which [`CommandRequest`] the server accepts, and why it refuses the
//! others — one pure function used by the engine (`motion-engine`) and by the in-process fake
//! server of `motion-client::testing`, so that client tests run against the server's rules,
//! not a copy of them.
//!
//! The server asks [`identify`] who sent a request (from the transport, never the payload
//! alone), then [`judge`] what the request means given the [`Facts`] of the moment. The
//! verdict is either a refusal with its [`Reason`] or what to do; doing it (and a board
//! refusing the resulting goal) is the caller's part. The order of the checks is part of
//! the contract: a client sees the first rule a request breaks.
//!
//! ```
//! use motion_ipc::rules::{self, AxisFacts, Facts, SignalFacts, Verdict};
//! use motion_ipc::{ClientId, CommandKind, CommandRequest, Reason};
//!
//! struct One(AxisFacts);
//! impl Facts for One {
//!     fn estop(&self) -> bool { false }
//!     fn shutting_down(&self) -> bool { false }
//!     fn axis(&self, index: usize) -> Option<AxisFacts> { (index == 0).then_some(self.0) }
//!     fn signal(&self, _: usize) -> Option<SignalFacts> { None }
//! }
//! let facts = One(AxisFacts::test_axis(-100.0, 100.0, 50.0, 500.0));
//! let client = ClientId::from_u128(7);
//! let request = CommandRequest::new(client, 1, 0, CommandKind::Position).with_values([200.0, 0.0, 0.0]);
//! assert_eq!(rules::judge(&request, client, &facts), Verdict::Refused(Reason::OutOfRange));
//! ```

use crate::{
    AxisMode, Capabilities, ClientId, CommandKind, CommandRequest, DeviceState, FaultCode, Reason,
    SCHEMA_VERSION, SignalKind, Target,
};

/// Search velocity of a home command that gives none, as a fraction of `max_velocity`.
pub const HOME_FRACTION_OF_MAX: f64 = 0.25;

/// What the rules need to know about one axis at the moment a request is judged.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AxisFacts {
    /// Soft limits, units.
    pub min: f64,
    /// Soft limits, units.
    pub max: f64,
    /// Units/s.
    pub max_velocity: f64,
    /// Units/s².
    pub max_accel: f64,
    /// The smallest nonzero velocity of a velocity goal or a search its board represents,
    /// units/s (0: no floor): a slower velocity would be rounded to nothing or up to the
    /// board's step.
    pub min_velocity: f64,
    /// The smallest velocity of a position profile (`RampPosition`) its board represents,
    /// units/s (0: no floor).
    pub min_profile_velocity: f64,
    /// The smallest acceleration its board represents, units/s² (0: no floor).
    pub min_accel: f64,
    /// The command kinds its board accepts.
    pub capabilities: Capabilities,
    /// The client holding its claim ([`ClientId::NONE`]: none).
    pub claimed_by: ClientId,
    /// Its device's state.
    pub device: DeviceState,
    /// Whether its device's link is up (an offline device on a down link is `LinkDown`).
    pub link_up: bool,
    /// The latched fault ([`FaultCode::None`]: none).
    pub fault: FaultCode,
    /// The measured position, units, and whether it is fresh (a stale position cannot tell
    /// whether a velocity heads into a limit).
    pub position: f64,
    /// Whether `position` is fresh.
    pub position_fresh: bool,
    /// The position tolerance, units (the least distance a velocity goal must keep from a
    /// soft limit).
    pub tolerance: f64,
    /// Whether a group's motion owns the axis (moving, holding or held): its own motion
    /// commands are refused with [`Reason::GroupBusy`] (stops are not).
    pub group_motion: bool,
}

impl AxisFacts {
    /// A healthy, unclaimed axis at 0 on an online device, accepting every motion kind:
    /// for examples and tests.
    pub fn test_axis(min: f64, max: f64, max_velocity: f64, max_accel: f64) -> Self {
        let mut capabilities = Capabilities::NONE;
        for kind in CommandKind::ALL {
            capabilities = capabilities.with(kind);
        }
        Self {
            min,
            max,
            max_velocity,
            max_accel,
            min_velocity: 0.0,
            min_profile_velocity: 0.0,
            min_accel: 0.0,
            capabilities,
            claimed_by: ClientId::NONE,
            device: DeviceState::Online,
            link_up: true,
            fault: FaultCode::None,
            position: 0.0,
            position_fresh: true,
            tolerance: 0.01,
            group_motion: false,
        }
    }

    /// Whether a client other than `client` holds the claim.
    pub fn claimed_by_other(&self, client: ClientId) -> bool {
        !self.claimed_by.is_none() && self.claimed_by != client
    }
}

/// What the rules need to know about one signal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SignalFacts {
    /// Input or output.
    pub kind: SignalKind,
    /// The client holding its claim ([`ClientId::NONE`]: none).
    pub claimed_by: ClientId,
    /// Its device's state.
    pub device: DeviceState,
    /// Whether its device's link is up.
    pub link_up: bool,
}

/// The server's state as the rules see it.
pub trait Facts {
    /// Whether the e-stop is latched.
    fn estop(&self) -> bool;
    /// Whether the server is stopping for good (SIGTERM).
    fn shutting_down(&self) -> bool;
    /// Axis `index`, if configured.
    fn axis(&self, index: usize) -> Option<AxisFacts>;
    /// Signal `index`, if configured.
    fn signal(&self, index: usize) -> Option<SignalFacts>;
}

/// A motion goal in axis units, as the rules accepted it.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq)]
pub enum Motion {
    /// Open-loop drive, fraction of full power −1..=1.
    Power {
        /// Fraction of full power, −1..=1.
        fraction: f64,
    },
    /// Go to `target` at the axis's limits.
    Position {
        /// Target, units.
        target: f64,
    },
    /// Run at `velocity` (units/s), reached at the axis's `max_accel`.
    Velocity {
        /// Velocity, units/s.
        velocity: f64,
        /// The axis's `max_accel`, units/s².
        accel: f64,
    },
    /// Run at `velocity`, reached at `accel` (units/s²).
    RampVelocity {
        /// Velocity, units/s.
        velocity: f64,
        /// Acceleration, units/s².
        accel: f64,
    },
    /// Go to `target` with a trapezoidal profile.
    RampPosition {
        /// Target, units.
        target: f64,
        /// Profile velocity, units/s.
        velocity: f64,
        /// Profile acceleration, units/s².
        accel: f64,
    },
    /// Reference search at `velocity` (units/s, > 0).
    Home {
        /// Search velocity, units/s.
        velocity: f64,
    },
    /// Declare the present position to be `target`.
    SetPosition {
        /// The position the axis is now at, units.
        target: f64,
    },
}

impl Motion {
    /// The axis mode the goal puts the axis in.
    pub fn mode(&self) -> AxisMode {
        match self {
            Self::Power { .. } => AxisMode::Power,
            Self::Position { .. } => AxisMode::Position,
            Self::Velocity { .. } => AxisMode::Velocity,
            Self::RampVelocity { .. } => AxisMode::RampVelocity,
            Self::RampPosition { .. } => AxisMode::RampPosition,
            Self::Home { .. } => AxisMode::Homing,
            Self::SetPosition { .. } => AxisMode::Hold,
        }
    }

    /// The frame's `target` for the goal: the position, the velocity or the power fraction
    /// (`None` for a search, whose target is where the axis is).
    pub fn target(&self) -> Option<f64> {
        match *self {
            Self::Power { fraction } => Some(fraction),
            Self::Position { target }
            | Self::RampPosition { target, .. }
            | Self::SetPosition { target } => Some(target),
            Self::Velocity { velocity, .. } | Self::RampVelocity { velocity, .. } => Some(velocity),
            Self::Home { .. } => None,
        }
    }

    /// Whether the goal lives only while its client renews it (the deadman).
    pub fn needs_renewal(&self) -> bool {
        matches!(
            self,
            Self::Power { .. } | Self::Velocity { .. } | Self::RampVelocity { .. }
        )
    }
}

/// What a request means, once judged.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Verdict {
    /// Refused, for this reason; nothing changes.
    Refused(Reason),
    /// Latch the e-stop.
    EStop,
    /// Clear the e-stop, deadman expiries and the faults whose cause is gone; claims and
    /// running goals stay.
    Reset,
    /// Stop every axis.
    StopAll,
    /// Off for every axis the client may command and whose board can de-energise; the
    /// answer is `ClaimedByOther` when an axis was skipped for a claim ([`off_all_skips`]).
    OffAll,
    /// Claim axis `.0` for the client.
    ClaimAxis(usize),
    /// End the client's claim of axis `.0`.
    ReleaseAxis(usize),
    /// Stop axis `.0` (anyone may, claimed or not, e-stop or not).
    StopAxis(usize),
    /// De-energise axis `.0`.
    OffAxis(usize),
    /// Give axis `axis` the goal `motion`.
    Move {
        /// Axis index.
        axis: usize,
        /// The goal.
        motion: Motion,
    },
    /// Claim signal `.0` for the client.
    ClaimSignal(usize),
    /// End the client's claim of signal `.0`.
    ReleaseSignal(usize),
    /// Set output `signal` to `on` (logical level).
    SetOutput {
        /// Signal index.
        signal: usize,
        /// Logical level.
        on: bool,
    },
    /// Set the value of signal `signal` (a trigger's compare position, in the signal's
    /// unit).
    SetValue {
        /// Signal index.
        signal: usize,
        /// The value, in the signal's unit.
        value: f64,
    },
    /// Bring the position move of axis `.0` to rest and keep it (`Hold` with
    /// [`Target::Axis`]); whether it has one is the engine's to say
    /// ([`Reason::NotMoving`]).
    HoldAxis(usize),
    /// Continue the held move of axis `.0` (`Resume` with [`Target::Axis`]).
    ResumeAxis(usize),
}

/// Who sent `request`: the transport's identity `sender` when there is one (a payload
/// `client` that names someone else is refused), else the payload's own `client` (in-process
/// ports). Checks first the schema version, the kind and that every value is finite.
pub fn identify(request: &CommandRequest, sender: Option<ClientId>) -> Result<ClientId, Reason> {
    if request.schema_version != SCHEMA_VERSION {
        return Err(Reason::SchemaMismatch);
    }
    if request.kind().is_err() {
        return Err(Reason::UnknownKind);
    }
    if request.values.iter().any(|value| !value.is_finite()) {
        return Err(Reason::NotFinite);
    }
    match sender {
        None => Ok(request.client),
        Some(node) if request.client.is_none() || request.client == node => Ok(node),
        Some(_) => Err(Reason::IdentityMismatch),
    }
}

/// Judges `request` from `client` (as [`identify`] found it) against `facts`.
pub fn judge(request: &CommandRequest, client: ClientId, facts: &impl Facts) -> Verdict {
    use Verdict::Refused;
    let Ok(kind) = request.kind() else {
        return Refused(Reason::UnknownKind);
    };
    let Ok(target) = request.target() else {
        return Refused(Reason::UnknownTarget);
    };
    let index = request.axis as usize;
    if target == Target::Signal {
        return judge_signal(kind, index, client, request.values[0], facts);
    }
    if target == Target::Group {
        // A group's requests depend on its paths and its motion's state, which only the
        // engine holds (`motion-engine`'s `group` module judges them); a server without
        // groups has none to find.
        return Refused(Reason::UnknownGroup);
    }
    if target == Target::Device {
        // Commissioning depends on the devices' boards, which only the engine holds
        // (`motion-engine`'s `commission` module judges it); a server without devices has
        // none to find.
        return Refused(Reason::UnknownDevice);
    }
    match kind {
        CommandKind::EStop => return Verdict::EStop,
        CommandKind::Reset if facts.shutting_down() => return Refused(Reason::ShuttingDown),
        CommandKind::Reset => return Verdict::Reset,
        CommandKind::Stop if request.axis == CommandRequest::ALL_AXES => return Verdict::StopAll,
        CommandKind::Off if request.axis == CommandRequest::ALL_AXES => return Verdict::OffAll,
        CommandKind::SetOutput
        | CommandKind::Run
        | CommandKind::Feed
        | CommandKind::Cancel
        | CommandKind::Stream
        | CommandKind::Commission => return Refused(Reason::UnknownTarget),
        _ => {}
    }
    let Some(axis) = facts.axis(index) else {
        return Refused(Reason::UnknownAxis);
    };
    match kind {
        CommandKind::Claim | CommandKind::Release if client.is_none() => {
            return Refused(Reason::NoClientId);
        }
        CommandKind::Claim if axis.claimed_by_other(client) => {
            return Refused(Reason::ClaimedByOther);
        }
        CommandKind::Claim => return Verdict::ClaimAxis(index),
        CommandKind::Release if axis.claimed_by != client => return Refused(Reason::NotClaimed),
        CommandKind::Release => return Verdict::ReleaseAxis(index),
        CommandKind::Stop => return Verdict::StopAxis(index),
        // Off is safe for the board but not always for the machine (a vertical axis falls):
        // claims apply; e-stop and faults do not stop it.
        CommandKind::Off if axis.claimed_by_other(client) => {
            return Refused(Reason::ClaimedByOther);
        }
        CommandKind::Off if !axis.capabilities.supports(kind) => {
            return Refused(Reason::Unsupported);
        }
        CommandKind::Off => return Verdict::OffAxis(index),
        _ => {}
    }
    if facts.shutting_down() {
        return Refused(Reason::ShuttingDown);
    }
    if facts.estop() {
        return Refused(Reason::EstopLatched);
    }
    if axis.claimed_by_other(client) {
        return Refused(Reason::ClaimedByOther);
    }
    if axis.group_motion {
        return Refused(Reason::GroupBusy);
    }
    if !axis.capabilities.supports(kind) {
        return Refused(Reason::Unsupported);
    }
    if let Err(reason) = device_ready(axis.device, axis.link_up) {
        return Refused(reason);
    }
    let beyond_limit = match axis.fault {
        FaultCode::None => false,
        FaultCode::LimitExceeded if kind == CommandKind::Hold => false,
        FaultCode::LimitExceeded => true,
        FaultCode::LinkDown => return Refused(Reason::LinkDown),
        _ => return Refused(Reason::AxisFaulted),
    };
    match kind {
        CommandKind::Hold => return Verdict::HoldAxis(index),
        // A resumed move goes where it went: not out of a soft limit's fault.
        CommandKind::Resume if beyond_limit => return Refused(Reason::AxisFaulted),
        CommandKind::Resume => return Verdict::ResumeAxis(index),
        _ => {}
    }
    let motion = match motion_of(&axis, kind, request.values) {
        Ok(motion) => motion,
        Err(reason) => return Refused(reason),
    };
    if beyond_limit && !heads_back_inside(&axis, &motion) {
        return Refused(Reason::AxisFaulted);
    }
    Verdict::Move {
        axis: index,
        motion,
    }
}

/// Whether [`Verdict::OffAll`] skips `axis` for `client` (claimed by another).
pub fn off_all_skips(axis: &AxisFacts, client: ClientId) -> bool {
    axis.claimed_by_other(client)
}

fn device_ready(state: DeviceState, link_up: bool) -> Result<(), Reason> {
    match state {
        DeviceState::Starting => Err(Reason::DeviceStarting),
        DeviceState::Offline if !link_up => Err(Reason::LinkDown),
        DeviceState::Offline => Err(Reason::DeviceOffline),
        DeviceState::Online | DeviceState::Faulted => Ok(()),
    }
}

fn judge_signal(
    kind: CommandKind,
    index: usize,
    client: ClientId,
    value: f64,
    facts: &impl Facts,
) -> Verdict {
    use Verdict::Refused;
    let Some(signal) = facts.signal(index) else {
        return Refused(Reason::UnknownSignal);
    };
    let claimed_by_other = !signal.claimed_by.is_none() && signal.claimed_by != client;
    match kind {
        CommandKind::Claim | CommandKind::Release if client.is_none() => {
            Refused(Reason::NoClientId)
        }
        CommandKind::Claim if claimed_by_other => Refused(Reason::ClaimedByOther),
        CommandKind::Claim => Verdict::ClaimSignal(index),
        CommandKind::Release if signal.claimed_by != client => Refused(Reason::NotClaimed),
        CommandKind::Release => Verdict::ReleaseSignal(index),
        CommandKind::SetOutput
            if !matches!(signal.kind, SignalKind::DigitalOut | SignalKind::Trigger) =>
        {
            Refused(Reason::NotAnOutput)
        }
        CommandKind::SetOutput if facts.shutting_down() => Refused(Reason::ShuttingDown),
        CommandKind::SetOutput if facts.estop() => Refused(Reason::EstopLatched),
        CommandKind::SetOutput if claimed_by_other => Refused(Reason::ClaimedByOther),
        CommandKind::SetOutput => match device_ready(signal.device, signal.link_up) {
            Err(reason) => Refused(reason),
            // A trigger's compare position: any finite value (`identify` refused the
            // others); whether its board can hold it is the board's to say.
            Ok(()) if signal.kind == SignalKind::Trigger => Verdict::SetValue {
                signal: index,
                value,
            },
            // A digital output is 0 or 1; anything else (0.5, 2, −1, 5e-324) is no level.
            Ok(()) if value != 0.0 && value != 1.0 => Refused(Reason::OutOfRange),
            Ok(()) => Verdict::SetOutput {
                signal: index,
                on: value == 1.0,
            },
        },
        _ => Refused(Reason::UnknownKind),
    }
}

/// The goal of a motion request, or why it is refused. A value of 0 for an optional
/// velocity or acceleration means the axis's maximum.
fn motion_of(
    axis: &AxisFacts,
    kind: CommandKind,
    [v0, v1, v2]: [f64; 3],
) -> Result<Motion, Reason> {
    let or_max = |value: f64, max: f64| if value == 0.0 { max } else { value };
    let within = |position: f64| position >= axis.min && position <= axis.max;
    Ok(match kind {
        CommandKind::Power => {
            if v0.abs() > 1.0 {
                return Err(Reason::PowerLimit);
            }
            if heads_into_limit(axis, v0, axis.max_accel) {
                return Err(Reason::OutOfRange);
            }
            Motion::Power { fraction: v0 }
        }
        CommandKind::Position if !within(v0) => return Err(Reason::OutOfRange),
        CommandKind::Position => Motion::Position { target: v0 },
        CommandKind::Velocity | CommandKind::RampVelocity => {
            let accel = if kind == CommandKind::Velocity {
                axis.max_accel
            } else {
                or_max(v1, axis.max_accel)
            };
            if v0.abs() > axis.max_velocity || (v0 != 0.0 && v0.abs() < axis.min_velocity) {
                return Err(Reason::VelocityLimit);
            }
            if !accel_within(axis, accel) {
                return Err(Reason::AccelLimit);
            }
            if heads_into_limit(axis, v0, accel) {
                return Err(Reason::OutOfRange);
            }
            if kind == CommandKind::Velocity {
                Motion::Velocity {
                    velocity: v0,
                    accel,
                }
            } else {
                Motion::RampVelocity {
                    velocity: v0,
                    accel,
                }
            }
        }
        CommandKind::RampPosition => {
            let velocity = or_max(v1, axis.max_velocity);
            let accel = or_max(v2, axis.max_accel);
            if !within(v0) {
                return Err(Reason::OutOfRange);
            }
            if !speed_within(axis, velocity, axis.min_profile_velocity) {
                return Err(Reason::VelocityLimit);
            }
            if !accel_within(axis, accel) {
                return Err(Reason::AccelLimit);
            }
            Motion::RampPosition {
                target: v0,
                velocity,
                accel,
            }
        }
        CommandKind::Home => {
            let velocity = or_max(v0, axis.max_velocity * HOME_FRACTION_OF_MAX);
            if !speed_within(axis, velocity, axis.min_velocity) {
                return Err(Reason::VelocityLimit);
            }
            Motion::Home { velocity }
        }
        CommandKind::SetPosition if !within(v0) => return Err(Reason::OutOfRange),
        CommandKind::SetPosition => Motion::SetPosition { target: v0 },
        CommandKind::Stop
        | CommandKind::Off
        | CommandKind::Claim
        | CommandKind::Release
        | CommandKind::EStop
        | CommandKind::Reset
        | CommandKind::SetOutput
        | CommandKind::Run
        | CommandKind::Hold
        | CommandKind::Resume
        | CommandKind::Feed
        | CommandKind::Cancel
        | CommandKind::Stream
        | CommandKind::Commission => return Err(Reason::UnknownKind),
    })
}

/// Whether a speed (> 0) is within the axis's: at most `max_velocity`, at least `floor`
/// (the smallest its board represents for this kind of goal).
fn speed_within(axis: &AxisFacts, speed: f64, floor: f64) -> bool {
    speed > 0.0 && speed <= axis.max_velocity && speed >= floor
}

/// Whether an acceleration (> 0) is within the axis's: at most `max_accel`, at least the
/// smallest its board represents (a smaller one would be rounded up to the board's step:
/// harder than asked).
fn accel_within(axis: &AxisFacts, accel: f64) -> bool {
    accel > 0.0 && accel <= axis.max_accel && accel >= axis.min_accel
}

/// Whether a velocity (or power, by its sign) goal of `velocity` could not stop before the
/// soft limit it heads for, from where the axis is now.
fn heads_into_limit(axis: &AxisFacts, velocity: f64, accel: f64) -> bool {
    if !axis.position_fresh {
        return false;
    }
    let reach = velocity * velocity / (2.0 * accel);
    let position = axis.position;
    (velocity > 0.0 && position + reach.max(axis.tolerance) >= axis.max)
        || (velocity < 0.0 && position - reach.max(axis.tolerance) <= axis.min)
}

/// For an axis beyond a soft limit (`LimitExceeded` latched): whether `motion` brings it
/// back inside (a position target within the limits, a velocity or power towards them, a
/// set-position within them). Nothing else is accepted until a reset.
fn heads_back_inside(axis: &AxisFacts, motion: &Motion) -> bool {
    let position = axis.position;
    let inward =
        |sign: f64| (position > axis.max && sign < 0.0) || (position < axis.min && sign > 0.0);
    match *motion {
        Motion::Position { target }
        | Motion::RampPosition { target, .. }
        | Motion::SetPosition { target } => (axis.min..=axis.max).contains(&target),
        Motion::Velocity { velocity, .. } | Motion::RampVelocity { velocity, .. } => {
            inward(velocity)
        }
        Motion::Power { fraction } => inward(fraction),
        Motion::Home { .. } => false,
    }
}

#[cfg(test)]
mod tests;
