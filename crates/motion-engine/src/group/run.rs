//! One tick of every group: what interfered with its axes, the path's time, its desired
//! state, supervision against the path and the goal, and the end of its motion.

use motion_drivers::Driver;
use motion_ipc::{AxisMode, ClientId, FaultCode, GroupAbort, GroupMotion, PathKind, StreamState};

use crate::Engine;
use crate::group::lead::{Arming, LEAD_DRIFT, Lead};

impl<D: Driver> Engine<D> {
    /// Step 4b (after the commands and the safety rules): every group with a motion.
    pub(crate) fn run_groups(&mut self) {
        for group in 0..self.groups.len() {
            if !self.groups[group].motion.active() {
                continue;
            }
            if let Some((reason, axis)) = self.interference(group) {
                self.abort_group(group, reason, axis, 0.0, 0.0);
                continue;
            }
            if self.groups[group].kind == PathKind::Stream {
                self.stream_tick(group);
                if self.groups[group].motion.active() {
                    self.follow_group(group);
                }
                if self.groups[group].stream.finishing {
                    self.end_of_path(group);
                }
                continue;
            }
            if self.line_started(group) {
                self.advance_group(group);
            }
            self.follow_group(group);
            if self.groups[group].motion.active() {
                self.supervise_group(group);
            }
            if self.groups[group].motion.active() {
                self.end_of_path(group);
            }
        }
    }

    /// Something outside the group's motion took one of its axes: a stop, an off, a fault,
    /// the e-stop, a shutdown (each leaves the axis without its group), or a claim that
    /// passed to someone else.
    fn interference(&self, group: usize) -> Option<(GroupAbort, Option<usize>)> {
        let g = &self.groups[group];
        for member in &g.members {
            let axis = &self.axes[member.axis];
            if axis.group != Some(group) || axis.mode != AxisMode::Group {
                let reason = if self.shutting_down {
                    GroupAbort::ShuttingDown
                } else if self.estop {
                    GroupAbort::EStop
                } else if axis.fault.is_some() {
                    GroupAbort::AxisFault
                } else {
                    GroupAbort::Stopped
                };
                return Some((reason, Some(member.axis)));
            }
            if axis.fault.is_some() {
                return Some((GroupAbort::AxisFault, Some(member.axis)));
            }
            let holder = axis.claimed_by;
            // Claimed by another client, or no longer by the owner who claimed it.
            if holder != g.owner && (g.claimed || !holder.is_none()) {
                return Some((GroupAbort::ClaimLost, Some(member.axis)));
            }
        }
        None
    }

    /// The path's time moves on by the feed; the desired state of every member.
    fn advance_group(&mut self, group: usize) {
        let now = self.now;
        let dt = self.config.period().as_secs_f64();
        let g = &mut self.groups[group];
        g.scale.step(&g.path, &g.limits, dt);
        g.point = g.scale.sample(
            &g.path,
            &mut g.position,
            &mut g.velocity,
            &mut g.acceleration,
        ) as u32;
        g.history.push(now, g.scale.time());
        for (slot, member) in g.members.iter().enumerate() {
            let axis = &mut self.axes[member.axis];
            axis.path_position = g.position[slot];
            axis.path_velocity = g.velocity[slot];
        }
        if g.motion == GroupMotion::Holding && g.scale.at_rest() {
            g.motion = GroupMotion::Held;
        }
        if g.motion == GroupMotion::Held && g.cancelling {
            self.finish_group(group, GroupMotion::Aborted, GroupAbort::Cancelled);
        }
    }

    /// Every fresh measurement against where the path had the axis when its board
    /// measured it.
    fn supervise_group(&mut self, group: usize) {
        let count = self.groups[group].members.len();
        for slot in 0..count {
            let g = &mut self.groups[group];
            let member = g.members[slot];
            let tolerance = g.config.path_tolerance[slot];
            let axis = &self.axes[member.axis];
            if tolerance <= 0.0 || !axis.fresh || axis.stale {
                continue;
            }
            let Some(measured_at) = axis.refreshed_at else {
                continue;
            };
            let Some(tau) = g.history.at(measured_at) else {
                continue;
            };
            g.path.sample(
                tau,
                &mut g.then,
                &mut g.then_velocity,
                &mut g.then_acceleration,
            );
            let deviation = (g.then[slot] - axis.position()).abs();
            if member.led == Lead::Running && deviation > tolerance * LEAD_DRIFT {
                // A board running the line by itself drifts from the path (its rates in its
                // own units): the engine follows it with goals from now on.
                self.follow_led_board(group, member.axis);
            }
            if deviation > tolerance {
                let axis = member.axis;
                self.abort_group(
                    group,
                    GroupAbort::PathTolerance,
                    Some(axis),
                    deviation,
                    tolerance,
                );
                return;
            }
        }
    }

    /// At the path's end: done once every axis is within its goal tolerance; after
    /// `goal_time_tolerance` the axes that are not fault `GoalTolerance`.
    fn end_of_path(&mut self, group: usize) {
        let now = self.now;
        let g = &mut self.groups[group];
        let finishing = g.kind == PathKind::Stream && g.stream.finishing;
        if g.motion != GroupMotion::Moving || !(finishing || g.scale.finished(&g.path)) {
            return;
        }
        let ended_at = *g.ended_at.get_or_insert(now);
        // Settled: fresh, within the goal tolerance, and at rest.
        let mut missed = None;
        for (slot, member) in g.members.iter().enumerate() {
            let axis = &self.axes[member.axis];
            let end = if finishing {
                g.position[slot]
            } else {
                g.path.end()[slot]
            };
            let distance = (axis.position() - end).abs();
            let tolerance = g.config.goal_tolerance[slot];
            if axis.stale || distance > tolerance || axis.state.moving {
                missed.get_or_insert((member.axis, distance, tolerance));
            }
        }
        let Some((axis, distance, tolerance)) = missed else {
            self.finish_group(group, GroupMotion::Done, GroupAbort::None);
            return;
        };
        if now.saturating_sub(ended_at) <= g.config.goal_time_tolerance {
            return;
        }
        let count = g.members.len();
        for slot in 0..count {
            let g = &self.groups[group];
            let member = g.members[slot];
            let target = if finishing {
                g.position[slot]
            } else {
                g.path.end()[slot]
            };
            let goal = g.config.goal_tolerance[slot];
            let axis = &self.axes[member.axis];
            let distance = (axis.position() - target).abs();
            if axis.stale || distance > goal || axis.state.moving {
                self.fault_axis(member.axis, FaultCode::GoalTolerance, distance, goal);
            }
        }
        self.abort_group(
            group,
            GroupAbort::GoalTolerance,
            Some(axis),
            distance,
            tolerance,
        );
    }

    /// A motion of kind `kind` owned by `client` starts: every member becomes the group's
    /// (mode `group`, heading for the group's `position` of it: the path's end, or where
    /// a stream starts), its following starts afresh. Returns whether `client` holds every
    /// member's claim.
    pub(crate) fn take_members(&mut self, group: usize, client: ClientId, kind: PathKind) -> bool {
        let now = self.now;
        let mut claimed = true;
        for slot in 0..self.groups[group].members.len() {
            let g = &mut self.groups[group];
            let target = g.position[slot];
            let member = &mut g.members[slot];
            member.sent_at = None;
            member.acked_at = None;
            member.end_sent = false;
            member.next_at = now;
            member.last_velocity = f64::NAN;
            member.led = Lead::No;
            let axis = &mut self.axes[member.axis];
            claimed &= axis.claimed_by == client;
            let position = axis.position();
            axis.mode = AxisMode::Group;
            axis.group = Some(group);
            axis.goal_owner = client;
            axis.deadman_at = None;
            axis.deadman_expired = false;
            axis.arrived = false;
            axis.off_after_stop = false;
            axis.switched_off = false;
            axis.move_start = position;
            axis.target = target;
            axis.path_position = position;
            axis.path_velocity = 0.0;
        }
        let g = &mut self.groups[group];
        g.motion = GroupMotion::Moving;
        g.abort = GroupAbort::None;
        g.abort_axis = None;
        g.abort_value = 0.0;
        g.abort_limit = 0.0;
        g.owner = client;
        g.kind = kind;
        g.point = 0;
        g.cancelling = false;
        g.ended_at = None;
        g.arming = Arming::No;
        claimed
    }

    /// The motion ends in order (done, or a cancel at rest): every member holds where the
    /// path left it.
    fn finish_group(&mut self, group: usize, motion: GroupMotion, abort: GroupAbort) {
        let g = &mut self.groups[group];
        g.motion = motion;
        g.abort = abort;
        for (slot, member) in g.members.iter().enumerate() {
            let axis = &mut self.axes[member.axis];
            if axis.group != Some(group) {
                continue;
            }
            axis.group = None;
            axis.mode = AxisMode::Hold;
            axis.target = g.position[slot];
            axis.arrived = true;
            axis.goal_owner = ClientId::NONE;
        }
        if abort == GroupAbort::Cancelled {
            // At rest on the path; a stop makes every board hold exactly where it is.
            for slot in 0..self.groups[group].members.len() {
                let axis = self.groups[group].members[slot].axis;
                self.stop_axis(axis, false);
            }
        }
    }

    /// Ends the group's motion early: every member still following it stops (its stop
    /// category; a stop command: a plain stop), and the frame says why.
    pub(crate) fn abort_group(
        &mut self,
        group: usize,
        reason: GroupAbort,
        axis: Option<usize>,
        value: f64,
        limit: f64,
    ) {
        let g = &mut self.groups[group];
        g.motion = GroupMotion::Aborted;
        g.abort = reason;
        g.abort_axis = axis;
        g.abort_value = value;
        g.abort_limit = limit;
        g.cancelling = false;
        if g.stream.state == StreamState::Streaming {
            g.stream.state = StreamState::Aborted;
            g.stream.clear();
        }
        for slot in 0..self.groups[group].members.len() {
            let index = self.groups[group].members[slot].axis;
            if self.axes[index].group != Some(group) {
                continue;
            }
            self.axes[index].group = None;
            match reason {
                GroupAbort::Stopped
                | GroupAbort::ClientDead
                | GroupAbort::ShuttingDown
                | GroupAbort::StreamStale => {
                    self.stop_axis(index, false);
                }
                _ => self.stop_by_category(index),
            }
        }
    }

    /// A stop of the group: its motion (if any) aborts, every member stops.
    pub(crate) fn stop_group(&mut self, group: usize, reason: GroupAbort) {
        if self.groups[group].motion.active() {
            self.abort_group(group, reason, None, 0.0, 0.0);
        }
        for slot in 0..self.groups[group].members.len() {
            let index = self.groups[group].members[slot].axis;
            self.stop_axis(index, false);
        }
    }

    /// The motions `client` ran end (it died): every member stops.
    pub(crate) fn abort_groups_of(&mut self, client: ClientId) {
        for group in 0..self.groups.len() {
            let g = &self.groups[group];
            if g.motion.active() && g.owner == client {
                self.abort_group(group, GroupAbort::ClientDead, None, 0.0, 0.0);
            }
        }
    }

    /// The motions `client` ran under its claim end (it left; its claims end with it).
    pub(crate) fn abort_claimed_groups_of(&mut self, client: ClientId) {
        for group in 0..self.groups.len() {
            let g = &self.groups[group];
            if g.motion.active() && g.owner == client && g.claimed {
                self.abort_group(group, GroupAbort::ClientDead, None, 0.0, 0.0);
            }
        }
    }
}
