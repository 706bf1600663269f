//! The fake's axis groups: paths received on `paths`, group commands judged (with the
//! server's rulebook for what each member axis must allow), motions interpolated linearly.

use motion_ipc::rules::{self, Facts, Verdict};
use motion_ipc::{
    AxisFlags, AxisMode, ClientId, CommandKind, CommandRequest, DeviceState, FaultCode, GroupAbort,
    GroupInfo, GroupMotion, GroupPath, GroupState, MAX_GROUP_AXES, MAX_PATH_POINTS, PathFlags,
    PathKind, Reason, SCHEMA_VERSION, ServerInfo, Target, write_text,
};

use super::Model;
use super::judged::Judged;
use super::stream::SimStream;
use crate::testing::config::FakeGroup;

/// A path as received, compact (only its valid points).
#[derive(Debug, Clone)]
pub(in crate::testing) struct StoredPath {
    sender: ClientId,
    schema_version: u32,
    kind: u32,
    id: u64,
    group: u32,
    point_count: u32,
    axis_count: u32,
    flags: PathFlags,
    scales: (f64, f64),
    times: Vec<f64>,
    /// Point-major, `axes` per point (axes clamped to MAX_GROUP_AXES).
    positions: Vec<f64>,
    velocities: Vec<f64>,
}

impl StoredPath {
    pub(in crate::testing) fn new(sender: ClientId, path: &GroupPath) -> Self {
        let points = (path.point_count as usize).min(MAX_PATH_POINTS);
        let axes = (path.axis_count as usize).min(MAX_GROUP_AXES);
        let rows = |values: &[f64]| -> Vec<f64> {
            (0..points)
                .flat_map(|p| values[p * MAX_GROUP_AXES..p * MAX_GROUP_AXES + axes].to_vec())
                .collect()
        };
        Self {
            sender,
            schema_version: path.schema_version,
            kind: path.kind,
            id: path.id,
            group: path.group,
            point_count: path.point_count,
            axis_count: path.axis_count,
            flags: path.flags(),
            scales: (path.velocity_scale, path.accel_scale),
            times: path.times[..points].to_vec(),
            positions: rows(&path.positions),
            velocities: rows(&path.velocities),
        }
    }
}

/// A running motion: where each member is at each time (linear in between).
#[derive(Debug, Clone, Default)]
struct Plan {
    times: Vec<f64>,
    points: Vec<Vec<f64>>,
    /// Index into `points` of the path's point 0 (1 when the start was prepended).
    first: usize,
}

impl Plan {
    fn at(&self, time: f64) -> (Vec<f64>, usize) {
        let next = self
            .times
            .iter()
            .position(|t| *t > time)
            .unwrap_or(self.times.len());
        if next == 0 {
            return (self.points[0].clone(), 0);
        }
        if next >= self.times.len() {
            return (
                self.points[self.points.len() - 1].clone(),
                self.times.len() - 1,
            );
        }
        let (t0, t1) = (self.times[next - 1], self.times[next]);
        let share = ((time - t0) / (t1 - t0)).clamp(0.0, 1.0);
        let here = self.points[next - 1]
            .iter()
            .zip(&self.points[next])
            .map(|(a, b)| a + (b - a) * share)
            .collect();
        (here, next)
    }
}

/// One simulated group.
#[derive(Debug, Clone)]
pub(in crate::testing) struct SimGroup {
    pub(super) config: FakeGroup,
    pub(super) state: GroupState,
    plan: Plan,
    pub(super) stream: SimStream,
}

impl SimGroup {
    pub(in crate::testing) fn new(config: &FakeGroup) -> Self {
        Self {
            config: config.clone(),
            state: GroupState::IDLE,
            plan: Plan::default(),
            stream: SimStream::default(),
        }
    }

    pub(super) fn motion(&self) -> GroupMotion {
        self.state.motion().unwrap_or_default()
    }
}

impl Model {
    /// The groups of `info`.
    pub(super) fn group_info(&self, info: &mut ServerInfo) {
        info.group_count = self.groups.len() as u32;
        for (sim, out) in self.groups.iter().zip(info.groups.iter_mut()) {
            *out = GroupInfo::EMPTY;
            write_text(&mut out.name, &sim.config.name);
            out.axis_count = sim.config.axes.len().min(MAX_GROUP_AXES) as u32;
            out.goal_time_tolerance = sim.config.goal_time_tolerance;
            out.stream_timeout = sim.config.stream_timeout;
            out.stream_buffer = sim.config.stream_buffer;
            for (slot, axis) in out.axes.iter_mut().zip(&sim.config.axes) {
                *slot = *axis as u32;
            }
            for (slot, value) in out
                .path_tolerance
                .iter_mut()
                .zip(&sim.config.path_tolerance)
            {
                *slot = *value;
            }
            for (slot, value) in out
                .goal_tolerance
                .iter_mut()
                .zip(&sim.config.goal_tolerance)
            {
                *slot = *value;
            }
        }
    }

    /// Keeps a path received on `paths` (the newest of an id per sender wins).
    pub(in crate::testing) fn store_path(&mut self, path: StoredPath) {
        self.paths
            .retain(|old| !(old.sender == path.sender && old.id == path.id));
        self.paths.push(path);
        if self.paths.len() > 64 {
            self.paths.remove(0);
        }
    }

    /// Whether axis `axis` follows an active group motion.
    pub(super) fn in_group_motion(&self, axis: usize) -> bool {
        self.groups
            .iter()
            .any(|g| g.motion().active() && g.config.axes.contains(&axis))
    }

    /// Ends group `index`'s active motion with `abort`; its axes hold where they are.
    pub(super) fn abort_group(
        &mut self,
        index: usize,
        abort: GroupAbort,
        axis: Option<usize>,
        figures: (f64, f64),
    ) {
        let Some(group) = self.groups.get_mut(index) else {
            return;
        };
        if !group.motion().active() {
            return;
        }
        group.state.motion = GroupMotion::Aborted as u8;
        group.state.abort = abort as u8;
        if group.state.stream == motion_ipc::StreamState::Streaming as u8 {
            group.state.stream = motion_ipc::StreamState::Aborted as u8;
        }
        group.state.abort_axis = axis.map_or(u32::MAX, |a| a as u32);
        (group.state.abort_value, group.state.abort_limit) = figures;
        group.state.owner = ClientId::NONE;
        group.state.feed = 0.0;
        for member in group.config.axes.clone() {
            if let Some((_, sim)) = self.axes.get_mut(member) {
                sim.state.mode = AxisMode::Hold as u8;
                sim.state.velocity = 0.0;
                sim.state.target = sim.state.position;
            }
        }
    }

    /// Aborts every active group motion that axis `axis` (or, with `None`, any axis) is in.
    pub(super) fn abort_groups_of(&mut self, axis: Option<usize>, abort: GroupAbort) {
        for index in 0..self.groups.len() {
            let member = axis.is_none_or(|a| self.groups[index].config.axes.contains(&a));
            if member {
                self.abort_group(index, abort, axis, (0.0, 0.0));
            }
        }
    }

    /// A group request (`target` = group), from `client`, judged in the engine's order
    /// (`motion-engine`'s `group/request.rs`; `rulebook_parity.rs` in that crate sends both
    /// the same table).
    pub(super) fn apply_group(&mut self, request: &CommandRequest, client: ClientId) -> Judged {
        let Ok(kind) = request.kind() else {
            return Reason::UnknownKind.into();
        };
        if matches!(kind, CommandKind::EStop | CommandKind::Reset) {
            // As on an axis: every axis, whatever the group.
            let mut every = *request;
            every.target = Target::Axis as u32;
            every.axis = CommandRequest::ALL_AXES;
            return self.validate_and_apply(&every, client).into();
        }
        let index = request.axis as usize;
        let Some(group) = self.groups.get(index) else {
            return Reason::UnknownGroup.into();
        };
        let members = group.config.axes.clone();
        let value = request.values[0];
        match kind {
            CommandKind::Claim => self.claim_group(index, client),
            CommandKind::Release => self.release_group(index, client),
            CommandKind::Stop => {
                self.abort_group(index, GroupAbort::Stopped, None, (0.0, 0.0));
                for member in members {
                    let (axis, sim) = &mut self.axes[member];
                    Self::stop(axis, sim);
                }
                Reason::Accepted.into()
            }
            CommandKind::Run => self.run(index, value, client),
            CommandKind::Stream => self.start_stream(index, value, client),
            CommandKind::Cancel if self.streaming(index) => {
                if let Some(refused) = self.claimed_by_other(index, client) {
                    return refused;
                }
                self.cancel_stream(index)
            }
            CommandKind::Hold | CommandKind::Resume | CommandKind::Feed
                if self.streaming(index) =>
            {
                Reason::Unsupported.into()
            }
            CommandKind::Hold | CommandKind::Resume | CommandKind::Feed | CommandKind::Cancel => {
                self.steer(index, kind, value, client)
            }
            _ => Reason::UnknownTarget.into(),
        }
    }

    /// `ClaimedByOther`, naming the member and its holder, when a member of group `index`
    /// is claimed by a client other than `client`.
    pub(super) fn claimed_by_other(&self, index: usize, client: ClientId) -> Option<Judged> {
        self.groups[index].config.axes.iter().find_map(|&member| {
            let holder = self.axes[member].1.state.claimed_by;
            (!holder.is_none() && holder != client).then(|| {
                let mut judged = Judged::at(Reason::ClaimedByOther, None, member, 0.0, 0.0);
                judged.holder = holder;
                judged
            })
        })
    }

    /// Claims every member for `client`, or none.
    fn claim_group(&mut self, index: usize, client: ClientId) -> Judged {
        if client.is_none() {
            return Reason::NoClientId.into();
        }
        if let Some(refused) = self.claimed_by_other(index, client) {
            return refused;
        }
        for member in self.groups[index].config.axes.clone() {
            self.axes[member].1.state.claimed_by = client;
        }
        Reason::Accepted.into()
    }

    /// Gives back `client`'s claims on the members; `NotClaimed` when it held none.
    fn release_group(&mut self, index: usize, client: ClientId) -> Judged {
        if client.is_none() {
            return Reason::NoClientId.into();
        }
        let mut released = false;
        for member in self.groups[index].config.axes.clone() {
            let state = &mut self.axes[member].1.state;
            if state.claimed_by == client {
                state.claimed_by = ClientId::NONE;
                released = true;
            }
        }
        if released {
            Reason::Accepted.into()
        } else {
            Reason::NotClaimed.into()
        }
    }

    /// Why the members of group `index` cannot start a motion of `client` now, as the
    /// engine's `members_refuse`: shutdown, e-stop, another client's claim, then per member
    /// its board's state, its fault, stale data, or a motion of its own.
    pub(super) fn members_refuse(&self, index: usize, client: ClientId) -> Option<Judged> {
        if self.shutting_down() {
            return Some(Reason::ShuttingDown.into());
        }
        if self.estop() {
            return Some(Reason::EstopLatched.into());
        }
        if let Some(refused) = self.claimed_by_other(index, client) {
            return Some(refused);
        }
        for &member in &self.groups[index].config.axes {
            let Some(facts) = self.axis(member) else {
                continue; // not an axis of this machine: the group's config never names one
            };
            let other_group = self.groups.iter().enumerate().any(|(other, g)| {
                other != index && g.motion().active() && g.config.axes.contains(&member)
            });
            let moving = self.axes[member].1.state.flags & AxisFlags::MOVING.0 != 0;
            let reason = match facts.device {
                DeviceState::Starting => Some(Reason::DeviceStarting),
                DeviceState::Offline if !facts.link_up => Some(Reason::LinkDown),
                DeviceState::Offline => Some(Reason::DeviceOffline),
                _ if facts.fault == FaultCode::LinkDown => Some(Reason::LinkDown),
                _ if facts.fault != FaultCode::None => Some(Reason::AxisFaulted),
                _ if !facts.position_fresh => Some(Reason::DeviceOffline),
                _ if other_group || (!facts.group_motion && moving) => Some(Reason::GroupBusy),
                _ => None,
            };
            if let Some(reason) = reason {
                return Some(Judged::at(reason, None, member, 0.0, 0.0));
            }
        }
        None
    }

    /// Hold, resume, feed, cancel of a path (a stream's are handled before).
    fn steer(&mut self, index: usize, kind: CommandKind, value: f64, client: ClientId) -> Judged {
        let members = self.groups[index].config.axes.clone();
        if kind == CommandKind::Feed && !(0.0..=1.5).contains(&value) {
            return Judged::at(Reason::OutOfRange, None, members[0], value, 1.5);
        }
        if let Some(refused) = self.claimed_by_other(index, client) {
            return refused;
        }
        if kind == CommandKind::Resume && self.estop() {
            return Reason::EstopLatched.into();
        }
        let active = self.groups[index].motion().active();
        let state = &mut self.groups[index].state;
        match kind {
            CommandKind::Feed => {
                // For the running path and the next, moving or not.
                state.feed_set = value;
                return Reason::Accepted.into();
            }
            _ if !active => return Reason::NotMoving.into(),
            CommandKind::Hold => state.motion = GroupMotion::Holding as u8,
            CommandKind::Resume => state.motion = GroupMotion::Moving as u8,
            _ => self.abort_group(index, GroupAbort::Cancelled, None, (0.0, 0.0)),
        }
        Reason::Accepted.into()
    }

    /// `Run` of path `id` from `client` on group `index`.
    fn run(&mut self, index: usize, id: f64, client: ClientId) -> Judged {
        if client.is_none() {
            return Reason::NoClientId.into();
        }
        // An exact path id (values[0] is an f64: integers up to 2^53).
        if !((0.0..=9_007_199_254_740_992.0).contains(&id) && id.fract() == 0.0) {
            return Reason::PathLayout.into();
        }
        if let Some(refused) = self.members_refuse(index, client) {
            return refused;
        }
        if self.streaming(index) {
            let first = self.groups[index].config.axes[0];
            return Judged::at(Reason::GroupBusy, None, first, 0.0, 0.0);
        }
        let found = self
            .paths
            .iter()
            .rposition(|path| path.sender == client && path.id as f64 == id);
        let Some(found) = found else {
            return Reason::NoPath.into();
        };
        let path = self.paths.remove(found);
        let members = self.groups[index].config.axes.clone();
        if self.groups[index].motion().active() {
            return Judged::at(Reason::GroupBusy, None, members[0], 0.0, 0.0);
        }
        let kind = PathKind::try_from(path.kind);
        let points = path.point_count as usize;
        let scale_ok = |s: f64| s.is_finite() && (0.0..=1.0).contains(&s);
        let layout_ok = path.schema_version == SCHEMA_VERSION
            && path.group as usize == index
            && path.axis_count as usize == members.len()
            && (1..=MAX_PATH_POINTS).contains(&points)
            && match kind {
                Ok(PathKind::Line) => {
                    points == 1 && scale_ok(path.scales.0) && scale_ok(path.scales.1)
                }
                Ok(PathKind::Trajectory) => true,
                _ => false,
            };
        if !layout_ok {
            return Reason::PathLayout.into();
        }
        let line = kind == Ok(PathKind::Line);
        let axes = members.len();
        if !line {
            let mut previous = None;
            for (point, &time) in path.times.iter().enumerate() {
                if !time.is_finite() || time < 0.0 || previous.is_some_and(|p| time <= p) {
                    let mut judged = Judged::from(Reason::PathTimes);
                    judged.at_point = point as u32;
                    judged.value = time;
                    judged.limit = previous.unwrap_or(0.0);
                    return judged;
                }
                previous = Some(time);
            }
        }
        for point in 0..points {
            for (slot, &member) in members.iter().enumerate() {
                let (axis, _) = &self.axes[member];
                let position = path.positions[point * axes + slot];
                if !position.is_finite() {
                    return Judged::at(Reason::NotFinite, Some(point), member, position, 0.0);
                }
                if position < axis.min || position > axis.max {
                    let limit = if position < axis.min {
                        axis.min
                    } else {
                        axis.max
                    };
                    return Judged::at(Reason::OutOfRange, Some(point), member, position, limit);
                }
                if path.flags.contains(PathFlags::VELOCITIES) {
                    let velocity = path.velocities[point * axes + slot];
                    if velocity.abs() > axis.max_velocity {
                        let (value, limit) = (velocity.abs(), axis.max_velocity);
                        return Judged::at(
                            Reason::VelocityLimit,
                            Some(point),
                            member,
                            value,
                            limit,
                        );
                    }
                }
            }
        }
        for (slot, &member) in members.iter().enumerate() {
            let target = path.positions[slot];
            let request = axis_request(client, member, CommandKind::RampPosition, target);
            if let Verdict::Refused(reason) = rules::judge(&request, client, &*self) {
                let mut judged = Judged::at(reason, None, member, 0.0, 0.0);
                if reason == Reason::ClaimedByOther {
                    judged.holder = self.axes[member].1.state.claimed_by;
                }
                return judged;
            }
        }
        let start: Vec<f64> = members
            .iter()
            .map(|&m| self.axes[m].1.state.position)
            .collect();
        let point_rows: Vec<Vec<f64>> = path.positions.chunks(axes).map(<[f64]>::to_vec).collect();
        let plan = if line {
            let end = point_rows[0].clone();
            let scale = |s: f64| if s == 0.0 { 1.0 } else { s };
            let duration = members
                .iter()
                .zip(start.iter().zip(&end))
                .map(|(&m, (a, b))| {
                    (b - a).abs() / (self.axes[m].0.max_velocity * scale(path.scales.0))
                })
                .fold(1.0 / f64::from(self.tick_hz), f64::max);
            Plan {
                times: vec![0.0, duration],
                points: vec![start, end],
                first: 1,
            }
        } else {
            let mut plan = Plan {
                times: path.times.clone(),
                points: point_rows,
                first: 0,
            };
            if path.times[0] > 0.0 {
                plan.times.insert(0, 0.0);
                plan.points.insert(0, start);
                plan.first = 1;
            } else {
                let tolerance = &self.groups[index].config.goal_tolerance;
                for (slot, &member) in members.iter().enumerate() {
                    let distance = (plan.points[0][slot] - start[slot]).abs();
                    let allowed = tolerance.get(slot).copied().unwrap_or(0.05);
                    if distance > allowed {
                        return Judged::at(Reason::PathStart, Some(0), member, distance, allowed);
                    }
                }
            }
            plan
        };
        let group = &mut self.groups[index];
        let feed_set = group.state.feed_set;
        group.state = GroupState {
            owner: client,
            path_id: path.id,
            time: 0.0,
            duration: plan.times.last().copied().unwrap_or(0.0),
            feed: feed_set,
            feed_set,
            point: 0,
            motion: GroupMotion::Moving as u8,
            kind: kind.map_or(0, |k| k as u8),
            ..GroupState::IDLE
        };
        group.plan = plan;
        for member in members {
            self.axes[member].1.state.mode = AxisMode::Group as u8;
        }
        Reason::Accepted.into()
    }

    /// Advances every active group by `dt` seconds of wall time.
    pub(super) fn step_groups(&mut self, dt: f64) {
        for index in 0..self.groups.len() {
            if self.streaming(index) {
                self.stream_tick(index, dt);
                continue;
            }
            let group = &mut self.groups[index];
            let motion = group.motion();
            if !motion.active() {
                continue;
            }
            group.state.feed = match motion {
                GroupMotion::Moving => group.state.feed_set,
                _ => 0.0,
            };
            if motion == GroupMotion::Holding {
                group.state.motion = GroupMotion::Held as u8;
            }
            group.state.time = (group.state.time + group.state.feed * dt).min(group.state.duration);
            let (desired, next) = group.plan.at(group.state.time);
            group.state.point = next.saturating_sub(group.plan.first) as u32;
            let done = group.state.time >= group.state.duration;
            let end = group.plan.points.last().cloned().unwrap_or_default();
            let members = group.config.axes.clone();
            if done {
                group.state.motion = GroupMotion::Done as u8;
                group.state.owner = ClientId::NONE;
            }
            for (slot, member) in members.into_iter().enumerate() {
                let sim = &mut self.axes[member].1;
                let here = desired.get(slot).copied().unwrap_or(sim.state.position);
                sim.state.velocity = if dt > 0.0 {
                    (here - sim.state.position) / dt
                } else {
                    0.0
                };
                sim.state.position = here;
                sim.state.desired_position = here;
                sim.state.desired_velocity = sim.state.velocity;
                sim.state.target = end.get(slot).copied().unwrap_or(here);
                if done {
                    sim.state.mode = AxisMode::Hold as u8;
                    sim.state.velocity = 0.0;
                    sim.state.desired_velocity = 0.0;
                }
            }
        }
    }

    /// The groups' states for the frame.
    pub(super) fn group_states(&self) -> impl Iterator<Item = GroupState> + '_ {
        self.groups.iter().map(|group| group.state)
    }
}

/// A request about one member axis, to ask the rulebook what that axis allows.
fn axis_request(client: ClientId, axis: usize, kind: CommandKind, value: f64) -> CommandRequest {
    let mut request =
        CommandRequest::new(client, 0, axis as u32, kind).with_values([value, 0.0, 0.0]);
    request.target = Target::Axis as u32;
    request
}
