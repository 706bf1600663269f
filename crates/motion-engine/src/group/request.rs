//! Group requests (`target = Group`): claims of every member at once, run a path, hold,
//! resume, feed, cancel, stop. Each answer names the axis (and the point, the figure and
//! the limit) at fault through the engine's reply detail.

use motion_drivers::{Driver, Follow};
use motion_ipc::{
    ClientId, CommandKind, CommandRequest, DeviceState, FaultCode, GroupAbort, GroupMotion,
    GroupPath, MAX_GROUP_AXES, MAX_PATH_POINTS, PathFlags, PathKind, Reason, SCHEMA_VERSION,
};
use motion_trajectory::{PathError, Points, Tolerances};

use crate::command::CommandPort;
use crate::group::lead::Lead;
use crate::{Engine, ReplyDetail};

/// The largest path id a request carries exactly (`values[0]` is an f64).
const MAX_PATH_ID: f64 = 9_007_199_254_740_992.0;

/// Velocities and accelerations of a line's end when it replaces a moving path: at rest.
static AT_REST: [f64; MAX_GROUP_AXES] = [0.0; MAX_GROUP_AXES];

/// A line that replaces a moving path is planned as a trajectory of one point this much
/// longer than the same line from rest, longer still (by the same factor) while a limit
/// is broken, at most this many times.
const REPLACE_STRETCH: f64 = 1.5;
const REPLACE_TRIES: usize = 8;

impl<D: Driver> Engine<D> {
    /// One request addressed to group `request.axis` from `client`.
    pub(crate) fn apply_group_command(
        &mut self,
        request: &CommandRequest,
        client: ClientId,
        port: &mut dyn CommandPort,
    ) -> Reason {
        let Ok(kind) = request.kind() else {
            return Reason::UnknownKind;
        };
        match kind {
            CommandKind::EStop => {
                self.estop_all();
                return Reason::Accepted;
            }
            CommandKind::Reset => return self.reset(),
            _ => {}
        }
        let index = request.axis as usize;
        if index >= self.groups.len() {
            return Reason::UnknownGroup;
        }
        match kind {
            CommandKind::Claim => self.claim_group(index, client),
            CommandKind::Release => self.release_group(index, client),
            CommandKind::Stop => {
                self.stop_group(index, GroupAbort::Stopped);
                Reason::Accepted
            }
            CommandKind::Run => self.run_group(index, client, request.values[0], port),
            CommandKind::Stream => self.start_stream(index, client, request.values[0]),
            CommandKind::Cancel if self.streaming(index) => {
                if let Some(refused) = self.claimed_by_other(index, client) {
                    return refused;
                }
                self.cancel_stream(index);
                Reason::Accepted
            }
            CommandKind::Hold | CommandKind::Resume | CommandKind::Feed
                if self.streaming(index) =>
            {
                Reason::Unsupported
            }
            CommandKind::Hold => self.hold_group(index, client, false),
            CommandKind::Cancel => self.hold_group(index, client, true),
            CommandKind::Resume => self.resume_group(index, client),
            CommandKind::Feed => self.feed_group(index, client, request.values[0]),
            _ => Reason::UnknownTarget,
        }
    }

    /// Whether the group's stream runs.
    fn streaming(&self, group: usize) -> bool {
        let g = &self.groups[group];
        g.motion.active() && g.kind == PathKind::Stream
    }

    /// The first member axis claimed by a client other than `client`, with its holder.
    pub(crate) fn claimed_member(
        &self,
        group: usize,
        client: ClientId,
    ) -> Option<(usize, ClientId)> {
        self.groups[group].members.iter().find_map(|member| {
            let holder = self.axes[member.axis].claimed_by;
            (!holder.is_none() && holder != client).then_some((member.axis, holder))
        })
    }

    /// `ClaimedByOther`, naming the axis and its holder, when a member axis is claimed by
    /// a client other than `client`.
    pub(crate) fn claimed_by_other(&mut self, group: usize, client: ClientId) -> Option<Reason> {
        let (axis, holder) = self.claimed_member(group, client)?;
        Some(self.refuse_at(Reason::ClaimedByOther, axis, holder))
    }

    pub(crate) fn refuse_at(&mut self, reason: Reason, axis: usize, holder: ClientId) -> Reason {
        self.reply_detail = ReplyDetail {
            at_axis: Some(axis),
            holder,
            ..ReplyDetail::NONE
        };
        reason
    }

    /// Claims every member axis for `client`, or none.
    fn claim_group(&mut self, group: usize, client: ClientId) -> Reason {
        if client.is_none() {
            return Reason::NoClientId;
        }
        if let Some(refused) = self.claimed_by_other(group, client) {
            return refused;
        }
        let now = self.now;
        for member in &self.groups[group].members {
            let axis = &mut self.axes[member.axis];
            axis.claimed_by = client;
            axis.claim_renewed_at = now;
        }
        Reason::Accepted
    }

    /// Gives back `client`'s claims on the member axes.
    fn release_group(&mut self, group: usize, client: ClientId) -> Reason {
        if client.is_none() {
            return Reason::NoClientId;
        }
        let mut released = false;
        for member in &self.groups[group].members {
            let axis = &mut self.axes[member.axis];
            if axis.claimed_by == client {
                axis.claimed_by = ClientId::NONE;
                released = true;
            }
        }
        if released {
            Reason::Accepted
        } else {
            Reason::NotClaimed
        }
    }

    /// Why a motion of `group` for `client` cannot start now (the first member at fault).
    pub(crate) fn members_refuse(&mut self, group: usize, client: ClientId) -> Option<Reason> {
        if self.shutting_down {
            return Some(Reason::ShuttingDown);
        }
        if self.estop {
            return Some(Reason::EstopLatched);
        }
        if let Some(refused) = self.claimed_by_other(group, client) {
            return Some(refused);
        }
        let members = self.groups[group].members.len();
        for slot in 0..members {
            let member = self.groups[group].members[slot];
            let index = member.axis;
            let axis = &self.axes[index];
            let busy = axis.group.is_some_and(|other| other != group)
                || (axis.group.is_none() && axis.state.moving);
            let needs = match member.follow {
                Follow::Setpoints => CommandKind::Position,
                Follow::Segments => CommandKind::RampPosition,
                Follow::Velocity => CommandKind::Velocity,
            };
            // Velocity following ends with a position move to the path's end.
            let supported = axis.capabilities.supports(needs)
                && (member.follow != Follow::Velocity
                    || axis.capabilities.supports(CommandKind::RampPosition));
            let reason = match self.device_state_of(index) {
                DeviceState::Starting => Some(Reason::DeviceStarting),
                DeviceState::Offline if !self.device_link_up(axis.device) => Some(Reason::LinkDown),
                DeviceState::Offline => Some(Reason::DeviceOffline),
                _ if axis.fault.is_some_and(|f| f.code == FaultCode::LinkDown) => {
                    Some(Reason::LinkDown)
                }
                _ if axis.fault.is_some() => Some(Reason::AxisFaulted),
                // No measurement yet: still starting; one that stopped coming: offline.
                _ if axis.stale && axis.refreshed_at.is_none() => Some(Reason::DeviceStarting),
                _ if axis.stale => Some(Reason::DeviceOffline),
                _ if busy => Some(Reason::GroupBusy),
                _ if !supported => Some(Reason::Unsupported),
                _ => None,
            };
            if let Some(reason) = reason {
                return Some(self.refuse_at(reason, index, ClientId::NONE));
            }
        }
        None
    }

    /// Plans the path `id` that `client` published and starts it (or replaces the
    /// running one from where the path has the group now).
    fn run_group(
        &mut self,
        group: usize,
        client: ClientId,
        id: f64,
        port: &mut dyn CommandPort,
    ) -> Reason {
        if client.is_none() {
            return Reason::NoClientId;
        }
        if !((0.0..=MAX_PATH_ID).contains(&id) && id.fract() == 0.0) {
            return Reason::PathLayout;
        }
        if let Some(reason) = self.members_refuse(group, client) {
            return reason;
        }
        if self.streaming(group) {
            let axis = self.groups[group].members[0].axis;
            return self.refuse_at(Reason::GroupBusy, axis, ClientId::NONE);
        }
        let id = id as u64;
        let Some(path) = port.take_path(client, id) else {
            return Reason::NoPath;
        };
        if path.group as usize != group {
            return Reason::NoPath;
        }
        if path.schema_version != SCHEMA_VERSION {
            return Reason::SchemaMismatch;
        }
        let count = self.groups[group].members.len();
        let points = path.point_count as usize;
        let kind = path.kind();
        if path.axis_count as usize != count
            || points == 0
            || points > MAX_PATH_POINTS
            || !matches!(kind, Ok(PathKind::Line | PathKind::Trajectory))
        {
            return Reason::PathLayout;
        }
        let kind = kind.unwrap_or(PathKind::Line);
        let replacing = self.groups[group].motion.active();
        let planned = self.plan(group, kind, path);
        if let Err(error) = planned {
            return self.path_refused(group, error);
        }
        self.start_motion_of(group, client, id, kind);
        if kind == PathKind::Line && !replacing {
            let feed = self.groups[group].scale.feed();
            self.groups[group].led_feed = feed;
            self.lead_line(group, feed);
        }
        Reason::Accepted
    }

    /// Plans `path` into the group's spare path from where the group is (or where its
    /// running path has it), then makes it the running one.
    fn plan(&mut self, group: usize, kind: PathKind, path: &GroupPath) -> Result<(), PathError> {
        let feed_now = self.groups[group].scale.feed();
        let active = self.groups[group].motion.active();
        let g = &mut self.groups[group];
        let count = g.members.len();
        if active {
            // From the running path's state, in path time at the feed it runs at now.
            g.scale.sample(
                &g.path,
                &mut g.position,
                &mut g.velocity,
                &mut g.acceleration,
            );
            let per_feed = if feed_now > 0.0 { 1.0 / feed_now } else { 0.0 };
            for slot in 0..count {
                g.velocity[slot] *= per_feed;
                g.acceleration[slot] *= per_feed * per_feed;
            }
        } else {
            for (slot, member) in g.members.iter().enumerate() {
                g.position[slot] = self.axes[member.axis].position();
            }
            g.velocity.fill(0.0);
            g.acceleration.fill(0.0);
        }
        for slot in 0..count {
            // The start tolerance of a trajectory whose first point is at time 0.
            g.then[slot] = g.config.path_tolerance[slot].max(g.config.goal_tolerance[slot]);
        }
        let moving = g.velocity.iter().any(|v| *v != 0.0);
        let scale = |value: f64| if value == 0.0 { 1.0 } else { value };
        match kind {
            PathKind::Line if !moving => g.spare.plan_line(
                &g.position,
                &path.positions[..count],
                &g.limits,
                scale(path.velocity_scale),
                scale(path.accel_scale),
            )?,
            PathKind::Line => {
                g.spare.plan_line(
                    &g.position,
                    &path.positions[..count],
                    &g.limits,
                    scale(path.velocity_scale),
                    scale(path.accel_scale),
                )?;
                let mut duration = g.spare.duration().max(1e-3) * REPLACE_STRETCH;
                let mut result = Err(PathError::NoPoints);
                for _ in 0..REPLACE_TRIES {
                    let times = [duration];
                    let points = Points {
                        times: &times,
                        positions: &path.positions[..count],
                        velocities: Some(&AT_REST[..count]),
                        accelerations: Some(&AT_REST[..count]),
                        stride: count,
                    };
                    result = g.spare.plan_points(
                        &g.position,
                        &g.velocity,
                        &g.acceleration,
                        &points,
                        &g.limits,
                        &Tolerances {
                            start: &g.then,
                            path: &g.config.path_tolerance,
                        },
                    );
                    if !matches!(
                        result,
                        Err(PathError::VelocityLimit { .. } | PathError::AccelLimit { .. })
                    ) {
                        break;
                    }
                    duration *= REPLACE_STRETCH;
                }
                result?;
            }
            _ => {
                let n = path.point_count as usize;
                let flags = path.flags();
                let values = n * MAX_GROUP_AXES;
                let velocities = flags.contains(PathFlags::VELOCITIES);
                let points = Points {
                    times: &path.times[..n],
                    positions: &path.positions[..values],
                    velocities: velocities.then(|| &path.velocities[..values]),
                    accelerations: (velocities && flags.contains(PathFlags::ACCELERATIONS))
                        .then(|| &path.accelerations[..values]),
                    stride: MAX_GROUP_AXES,
                };
                g.spare.plan_points(
                    &g.position,
                    &g.velocity,
                    &g.acceleration,
                    &points,
                    &g.limits,
                    &Tolerances {
                        start: &g.then,
                        path: &g.config.path_tolerance,
                    },
                )?;
            }
        }
        core::mem::swap(&mut g.path, &mut g.spare);
        if active {
            g.scale.restart(feed_now);
            g.scale.set_target(g.feed_set);
        } else {
            g.scale.restart(g.feed_set);
        }
        Ok(())
    }

    /// The reply to a refused plan: the reason, the point, the axis, the figures.
    fn path_refused(&mut self, group: usize, error: PathError) -> Reason {
        let axis_of = |slot: usize| self.groups[group].members.get(slot).map(|m| m.axis);
        let (reason, point, axis, value, limit) = match error {
            PathError::TooManyPoints { .. }
            | PathError::NoPoints
            | PathError::BadLayout
            | PathError::BadScale
            | PathError::BadLimits { .. } => (Reason::PathLayout, None, None, 0.0, 0.0),
            PathError::NotFinite { point, axis } => {
                (Reason::NotFinite, Some(point), axis_of(axis), 0.0, 0.0)
            }
            PathError::TimesNotIncreasing { point } => {
                (Reason::PathTimes, Some(point), None, 0.0, 0.0)
            }
            PathError::OutOfRange {
                point,
                axis,
                value,
                min,
                max,
            } => {
                let limit = if value < min { min } else { max };
                (Reason::OutOfRange, Some(point), axis_of(axis), value, limit)
            }
            PathError::VelocityLimit {
                point,
                axis,
                value,
                limit,
            } => (
                Reason::VelocityLimit,
                Some(point),
                axis_of(axis),
                value,
                limit,
            ),
            PathError::AccelLimit {
                point,
                axis,
                value,
                limit,
            } => (Reason::AccelLimit, Some(point), axis_of(axis), value, limit),
            // The blends the axes' accelerations allow pass the point too far; the reply
            // carries the distance and the tolerance.
            PathError::BlendTolerance {
                point,
                axis,
                distance,
                tolerance,
                ..
            } => (
                Reason::BlendTolerance,
                Some(point),
                axis_of(axis),
                distance,
                tolerance,
            ),
            PathError::StartMismatch {
                axis,
                distance,
                tolerance,
            } => (
                Reason::PathStart,
                Some(0),
                axis_of(axis),
                distance,
                tolerance,
            ),
        };
        self.reply_detail = ReplyDetail {
            at_point: point,
            at_axis: axis,
            holder: ClientId::NONE,
            value,
            limit,
        };
        reason
    }

    /// The planned path starts: every member follows it from this tick.
    fn start_motion_of(&mut self, group: usize, client: ClientId, id: u64, kind: PathKind) {
        let now = self.now;
        for slot in 0..self.groups[group].members.len() {
            let end = self.groups[group].path.end()[slot];
            self.groups[group].position[slot] = end;
        }
        let claimed = self.take_members(group, client, kind);
        let g = &mut self.groups[group];
        // Until the path's time first moves, every member's desired state is its start.
        g.scale.sample(
            &g.path,
            &mut g.position,
            &mut g.velocity,
            &mut g.acceleration,
        );
        g.claimed = claimed;
        g.path_id = id;
        g.history.clear();
        g.history.push(now, 0.0);
    }

    /// Feed hold (`cancel`: then end the motion once at rest).
    fn hold_group(&mut self, group: usize, client: ClientId, cancel: bool) -> Reason {
        if let Some(refused) = self.claimed_by_other(group, client) {
            return refused;
        }
        let g = &mut self.groups[group];
        if !g.motion.active() {
            return Reason::NotMoving;
        }
        g.scale.set_target(0.0);
        g.cancelling |= cancel;
        if g.motion == GroupMotion::Moving {
            g.motion = GroupMotion::Holding;
        }
        self.pause_led(group);
        Reason::Accepted
    }

    /// Continues a held (or holding) path at the set feed.
    fn resume_group(&mut self, group: usize, client: ClientId) -> Reason {
        if let Some(refused) = self.claimed_by_other(group, client) {
            return refused;
        }
        if self.estop {
            return Reason::EstopLatched;
        }
        let g = &mut self.groups[group];
        if !g.motion.active() || g.cancelling {
            return Reason::NotMoving;
        }
        g.scale.set_target(g.feed_set);
        g.motion = GroupMotion::Moving;
        if g.feed_set == g.led_feed {
            self.resume_led(group);
        } else {
            self.follow_led(group);
        }
        // Members followed with goals get the moving path at once: the goal that held them
        // on the path (a QSB's position move of a step or two) is superseded, never waited
        // for while the path runs away.
        let now = self.now;
        for member in &mut self.groups[group].members {
            if member.led == Lead::No {
                member.restart(now);
            }
        }
        Reason::Accepted
    }

    /// The feed override, 0..=1.5: for the running path (unless held) and the next.
    fn feed_group(&mut self, group: usize, client: ClientId, feed: f64) -> Reason {
        if !(0.0..=1.5).contains(&feed) {
            return Reason::OutOfRange;
        }
        if let Some(refused) = self.claimed_by_other(group, client) {
            return refused;
        }
        let g = &mut self.groups[group];
        g.feed_set = feed;
        if g.motion == GroupMotion::Moving {
            g.scale.set_target(feed);
        }
        if feed != g.led_feed {
            // A board's line has one pace.
            self.follow_led(group);
        }
        Reason::Accepted
    }
}
