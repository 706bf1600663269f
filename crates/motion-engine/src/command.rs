//! Taking in client commands: identity, validation and goals.

use motion_drivers::Driver;
use motion_drivers::{Goal, GoalError, GoalKind};
use motion_ipc::rules::{self, AxisFacts, Facts, Motion, SignalFacts, Verdict};
use motion_ipc::{
    ClientId, CommandKind, CommandReply, CommandRequest, DeviceState, FaultCode, GroupPath, Reason,
    Target,
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
    /// The newest path with id `id` that `client` (the transport's identity of the request
    /// being applied) published on `paths`, taken: a path runs once. `None` (the default)
    /// when there is none.
    fn take_path(&mut self, client: ClientId, id: u64) -> Option<&GroupPath> {
        let _ = (client, id);
        None
    }
}

/// Requests taken in one step at most; the rest wait for the next tick.
pub const MAX_COMMANDS_PER_STEP: usize = 64;

/// Search velocity of a home command that gives none, as a fraction of max_velocity.
pub const HOME_FRACTION_OF_MAX: f64 = rules::HOME_FRACTION_OF_MAX;

/// The engine's state as the rulebook sees it.
impl<D: Driver> Facts for Engine<D> {
    fn estop(&self) -> bool {
        self.estop
    }

    fn shutting_down(&self) -> bool {
        self.shutting_down
    }

    fn axis(&self, index: usize) -> Option<AxisFacts> {
        let axis = self.axes.get(index)?;
        Some(AxisFacts {
            min: axis.min,
            max: axis.max,
            max_velocity: axis.max_velocity,
            max_accel: axis.max_accel,
            min_velocity: axis.min_velocity,
            min_profile_velocity: axis.min_profile_velocity,
            min_accel: axis.min_accel,
            capabilities: axis.capabilities,
            claimed_by: axis.claimed_by,
            device: self.device_state_of(index),
            link_up: self.device_link_up(axis.device),
            fault: axis.fault_code().unwrap_or(FaultCode::None),
            position: axis.position(),
            position_fresh: !axis.stale,
            tolerance: axis.tolerance,
            group_motion: axis.group.is_some(),
        })
    }

    fn signal(&self, index: usize) -> Option<SignalFacts> {
        let signal = self.signals.get(index)?;
        let device = signal.config.device;
        Some(SignalFacts {
            kind: signal.config.kind,
            claimed_by: signal.claimed_by,
            device: self
                .devices
                .get(device)
                .map_or(DeviceState::Offline, |d| d.state),
            link_up: self.device_link_up(device),
        })
    }
}

impl<D: Driver> Engine<D> {
    /// Validates (the rulebook, [`motion_ipc::rules`]) and applies one request from `sender`
    /// (see [`CommandPort::sender`]); the answer says whether it was accepted.
    pub(crate) fn apply_command(
        &mut self,
        request: &CommandRequest,
        port: &mut dyn CommandPort,
    ) -> Reason {
        let client = match rules::identify(request, port.sender()) {
            Ok(client) => client,
            Err(reason) => return reason,
        };
        if !client.is_none()
            && self.departed.position(|gone| *gone == client).is_some()
            && !matches!(
                request.kind(),
                Ok(CommandKind::Stop | CommandKind::EStop | CommandKind::Off)
            )
        {
            // Sent by a client already found dead (its request was still queued): the
            // identity is no longer a live client's. Stops still count.
            return Reason::IdentityMismatch;
        }
        self.renew_claims(client);
        if request.target == Target::Group as u32 {
            return self.apply_group_command(request, client, port);
        }
        if request.target == Target::Device as u32 {
            return self.apply_device_command(request, client);
        }
        match rules::judge(request, client, &*self) {
            Verdict::Refused(reason) => reason,
            Verdict::EStop => {
                self.estop_all();
                Reason::Accepted
            }
            Verdict::Reset => self.reset(),
            Verdict::StopAll => {
                for index in 0..self.axes.len() {
                    self.stop_axis(index, false);
                }
                Reason::Accepted
            }
            Verdict::OffAll => self.off_all(client),
            Verdict::ClaimAxis(index) => {
                let now = self.now;
                let axis = &mut self.axes[index];
                axis.claimed_by = client;
                axis.claim_renewed_at = now;
                Reason::Accepted
            }
            Verdict::ReleaseAxis(index) => {
                self.axes[index].claimed_by = ClientId::NONE;
                Reason::Accepted
            }
            Verdict::StopAxis(index) => {
                self.stop_axis(index, false);
                Reason::Accepted
            }
            Verdict::OffAxis(index) => match self.off_axis(index) {
                Ok(()) => Reason::Accepted,
                Err(error) => self.goal_error_reason(index, error),
            },
            Verdict::Move { axis, motion } => self.start_motion(axis, client, motion, request),
            Verdict::ClaimSignal(index) => {
                let now = self.now;
                let signal = &mut self.signals[index];
                signal.claimed_by = client;
                signal.claim_renewed_at = now;
                Reason::Accepted
            }
            Verdict::ReleaseSignal(index) => {
                self.signals[index].claimed_by = ClientId::NONE;
                Reason::Accepted
            }
            Verdict::SetOutput { signal, on } => self.set_output(signal, on),
            Verdict::SetValue { signal, value } => self.set_value(signal, value),
            Verdict::HoldAxis(index) => self.hold_axis(index),
            Verdict::ResumeAxis(index) => self.resume_axis(index, client),
        }
    }

    /// Hands the accepted `motion` of axis `index` to its driver; the axis takes the goal
    /// once the driver accepted it.
    fn start_motion(
        &mut self,
        index: usize,
        client: ClientId,
        motion: Motion,
        request: &CommandRequest,
    ) -> Reason {
        let axis = &self.axes[index];
        let goal = goal_of(axis, motion);
        let target = motion.target().unwrap_or_else(|| axis.position());
        let (bus, slot, channel) = (axis.bus, axis.slot, axis.channel);
        let now = self.now;
        let result = match self.buses[bus].driver_mut(slot) {
            Some(driver) => driver.set_goal(now, channel, goal),
            None => Err(GoalError::Offline),
        };
        if let Err(error) = result {
            return self.goal_error_reason(index, error);
        }
        self.goal_set(index);
        let timeout = self.config.command_timeout;
        let axis = &mut self.axes[index];
        let position = axis.position();
        axis.mode = motion.mode();
        axis.target = target;
        axis.goal_owner = client;
        axis.deadman_expired = false;
        axis.deadman_at = (motion.needs_renewal() && !timeout.is_zero()).then(|| now + timeout);
        axis.move_start = position;
        axis.arrived = false;
        axis.off_after_stop = false;
        axis.switched_off = false;
        axis.held = None;
        if let Motion::RampPosition {
            velocity, accel, ..
        } = motion
        {
            axis.move_velocity = velocity;
            axis.move_accel = accel;
        }
        axis.home_travel = 0.0;
        axis.home_last = position;
        axis.home_referenced = axis.referenced();
        if request.kind() == Ok(CommandKind::SetPosition) {
            axis.position_set = true;
        }
        Reason::Accepted
    }

    /// Off for every axis `client` may command (claims of others are skipped); boards that
    /// cannot de-energise are left as they are.
    fn off_all(&mut self, client: ClientId) -> Reason {
        let mut skipped = false;
        for index in 0..self.axes.len() {
            let Some(facts) = Facts::axis(&*self, index) else {
                continue;
            };
            if rules::off_all_skips(&facts, client) {
                skipped = true;
                continue;
            }
            if facts.capabilities.supports(CommandKind::Off) {
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
    pub(crate) fn goal_error_reason(&self, index: usize, error: GoalError) -> Reason {
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
                if !self.device_link_opened(device) {
                    Reason::DeviceStarting
                } else if self.device_link_up(device) {
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
            self.reply_detail = crate::ReplyDetail::NONE;
            let reason = self.apply_command(&request, port);
            self.counters.commands += 1;
            if reason != Reason::Accepted {
                self.counters.rejected += 1;
            }
            let detail = self.reply_detail;
            let index = |value: Option<usize>| value.map_or(u32::MAX, |v| v as u32);
            let mut reply = CommandReply::to(&request, reason, self.tick)
                .at_axis(index(detail.at_axis), detail.holder);
            reply.at_point = index(detail.at_point);
            reply.value = detail.value;
            reply.limit = detail.limit;
            port.reply(reply);
        }
    }
}

/// The driver goal, in device counts, of an accepted motion.
pub(crate) fn goal_of(axis: &Axis, motion: Motion) -> Goal {
    match motion {
        Motion::Power { fraction } => Goal::Power { fraction },
        Motion::Position { target } => Goal::Position {
            counts: axis.to_counts(target),
        },
        Motion::Velocity { velocity, accel } | Motion::RampVelocity { velocity, accel } => {
            Goal::Velocity {
                velocity: axis.rate_to_counts(velocity),
                accel: axis.magnitude_to_counts(accel),
            }
        }
        Motion::RampPosition {
            target,
            velocity,
            accel,
        } => Goal::RampPosition {
            counts: axis.to_counts(target),
            velocity: axis.magnitude_to_counts(velocity),
            accel: axis.magnitude_to_counts(accel),
        },
        Motion::Home { velocity } => Goal::Home {
            velocity: axis.magnitude_to_counts(velocity),
        },
        Motion::SetPosition { target } => Goal::SetPosition {
            counts: axis.to_counts(target),
        },
    }
}
