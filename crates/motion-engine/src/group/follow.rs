//! Handing each board what it can follow of the path or the stream (`Driver::follow`):
//!
//! | style | sent | when |
//! |---|---|---|
//! | `Setpoints` (SPI_motor) | `Position` = the desired position now | every tick it changed |
//! | `Segments` (QuadQuad2Drv, Trinamic packs, the example board) | `RampPosition` to where the path will be a segment ahead (at least 1.5 braking distances), at the path's velocity plus the error over the feedback time | when the driver has acknowledged the last goal, and as long again after |
//! | `Velocity` (QSB) | `Velocity` = the path's velocity a segment ahead plus the position error over the feedback time; at the end a `RampPosition` to the path's end | likewise |
//!
//! A power stream hands every board its `Power` goal whatever its style. A segment is as
//! long as the driver takes to get a goal acknowledged (an average, between one tick and
//! [`MAX_LEAD`]); after each acknowledgement the link gets as long again for its own
//! traffic (polls, the encoder stream), so that following never starves the measurements
//! it is supervised by. A line a board runs itself (`lead.rs`) gets none while the board
//! runs it.

use core::time::Duration;

use motion_drivers::{Driver, Follow, Goal, GoalError};
use motion_ipc::{GroupAbort, PathKind, StreamMode};

use crate::Engine;
use crate::axis::Axis;
use crate::group::lead::Lead;
use crate::group::{Group, MAX_LEAD, Member};

/// A position error is fed back to a board over at least this long (or four segments, if
/// longer): gently enough not to overshoot on a slow link.
const FEEDBACK_TIME: Duration = Duration::from_millis(100);

/// A segment's target lies at least this many braking distances ahead (from the path's
/// speed at the axis's `max_accel`), so that a board's position ramp never brakes for it.
const BRAKE_MARGIN: f64 = 1.5;

/// A velocity within this many of the board's smallest steps that the board refuses is
/// sent as a stop (the conversion to the board's steps rounds down).
const SNAP_FLOORS: f64 = 4.0;

/// The least speed of a segment, as a fraction of `max_velocity` (the last approach to the
/// path's end, a held path): slow boards still get there.
const END_SPEED: f64 = 0.05;

impl<D: Driver> Engine<D> {
    /// Step 4c: every member of `group` gets its next goal if its board is ready for one.
    pub(crate) fn follow_group(&mut self, group: usize) {
        let now = self.now;
        let period = self.config.period();
        let count = self.groups[group].members.len();
        // Whether each member's driver still has a goal to acknowledge, as it was before
        // this tick's goals (two members on one board must not hold each other back).
        for slot in 0..count {
            let axis = &self.axes[self.groups[group].members[slot].axis];
            let pending = self.buses[axis.bus]
                .drivers()
                .get(axis.slot)
                .is_some_and(|driver| driver.goals_pending());
            self.groups[group].pending[slot] = pending;
        }
        for slot in 0..count {
            let g = &mut self.groups[group];
            let mut member = g.members[slot];
            let axis = &self.axes[member.axis];
            if member.led != Lead::No {
                // Its board runs the line itself.
                continue;
            }
            let goal = next_goal(g, slot, &mut member, axis, now, period);
            let Some(goal) = goal else {
                self.groups[group].members[slot] = member;
                continue;
            };
            let (bus, driver_slot, channel) = (axis.bus, axis.slot, axis.channel);
            let first = member.sent_at.is_none();
            let index = member.axis;
            let floor = axis.rate_to_counts(axis.min_velocity).abs() * SNAP_FLOORS;
            let result = match self.buses[bus].driver_mut(driver_slot) {
                Some(driver) => match (driver.set_goal(now, channel, goal), goal) {
                    // A velocity a few floors slow may convert to less than the board's
                    // smallest step: it stops instead.
                    (Err(GoalError::OutOfBoardRange(_)), Goal::Velocity { velocity, accel })
                        if velocity.abs() <= floor =>
                    {
                        member.last_velocity = 0.0;
                        driver.set_goal(
                            now,
                            channel,
                            Goal::Velocity {
                                velocity: 0.0,
                                accel,
                            },
                        )
                    }
                    (result, _) => result,
                },
                None => Err(GoalError::Offline),
            };
            if result.is_err() {
                self.abort_group(group, GroupAbort::GoalRefused, Some(index), 0.0, 0.0);
                return;
            }
            if first {
                self.goal_set(index);
            }
            member.sent_at = Some(now);
            member.acked_at = None;
            self.groups[group].members[slot] = member;
        }
    }
}

/// The goal member `slot` of `g` gets now, if any.
fn next_goal(
    g: &mut Group,
    slot: usize,
    member: &mut Member,
    axis: &Axis,
    now: Duration,
    period: Duration,
) -> Option<Goal> {
    let desired = g.position[slot];
    let stream = g.kind == PathKind::Stream;
    if stream && g.stream.mode == StreamMode::Power {
        let power = g.power[slot];
        if member.sent_at.is_some() && power == member.last_velocity {
            return None;
        }
        member.last_velocity = power;
        return Some(Goal::Power { fraction: power });
    }
    if member.follow == Follow::Setpoints {
        if member.sent_at.is_some() && desired == member.last_target {
            return None;
        }
        member.last_target = desired;
        return Some(Goal::Position {
            counts: axis.to_counts(desired),
        });
    }
    if let (Some(sent), None) = (member.sent_at, member.acked_at)
        && !g.pending[slot]
    {
        // Acknowledged: that is a segment's length, and the link gets as long again for
        // its own traffic before the next goal.
        let took = now.saturating_sub(sent).clamp(period, MAX_LEAD);
        member.lead = (member.lead * 3 + took) / 4;
        member.acked_at = Some(now);
        member.next_at = now + took;
    }
    let waiting = member.sent_at.is_some() && member.acked_at.is_none();
    if waiting || now < member.next_at {
        return None;
    }
    let lead = member.lead.as_secs_f64();
    // Where the board is now (its last measurement carried forward).
    let since = axis
        .refreshed_at
        .map_or(0.0, |at| now.saturating_sub(at).as_secs_f64());
    let measured = axis.position() + axis.velocity() * since;
    let feedback = (member.lead * 4).max(FEEDBACK_TIME).as_secs_f64();
    let floor = axis.min_profile_velocity.max(axis.max_velocity * END_SPEED);
    let finished = if stream {
        g.stream.finishing
    } else {
        g.scale.finished(&g.path) || (g.scale.at_rest() && g.scale.target() == 0.0)
    };
    if finished {
        if member.end_sent && member.last_target == desired {
            return None;
        }
        member.end_sent = true;
        member.last_target = desired;
        let velocity = ((desired - measured).abs() / feedback)
            .max(floor)
            .min(axis.max_velocity);
        return Some(Goal::RampPosition {
            counts: axis.to_counts(desired),
            velocity: axis.magnitude_to_counts(velocity),
            accel: axis.magnitude_to_counts(axis.max_accel),
        });
    }
    member.end_sent = false;
    // A position ramp brakes to stop at its target: a segment's target lies at least a
    // braking distance ahead, or the board crawls.
    let speed = g.velocity[slot].abs();
    // A goal reaches the board about a segment after it is handed over (the
    // acknowledgement's time) and acts until the next one, a segment later: the board is
    // given where the path will be two segments ahead — for a position ramp at least a
    // braking distance ahead, or it brakes for its target.
    let ahead = 2.0 * lead + period.as_secs_f64();
    let reach = if member.follow == Follow::Segments {
        (speed / (2.0 * axis.max_accel) * BRAKE_MARGIN).max(ahead)
    } else {
        ahead
    };
    let (target, path_velocity) = if stream {
        let velocity = g.velocity[slot];
        let target = (desired + velocity * reach).clamp(axis.min, axis.max);
        (target, velocity)
    } else {
        let ahead = g.scale.time() + g.scale.feed() * reach;
        g.path.sample(
            ahead,
            &mut g.then,
            &mut g.then_velocity,
            &mut g.then_acceleration,
        );
        (g.then[slot], g.then_velocity[slot] * g.scale.feed())
    };
    if member.follow == Follow::Segments {
        if member.sent_at.is_some() && target == member.last_target {
            // The board is on its way there already.
            member.next_at = now;
            return None;
        }
        member.last_target = target;
        let along = (desired - measured) * (target - desired).signum();
        let velocity = (path_velocity.abs().max(speed) + along / feedback)
            .max(floor)
            .min(axis.max_velocity);
        return Some(Goal::RampPosition {
            counts: axis.to_counts(target),
            velocity: axis.magnitude_to_counts(velocity),
            accel: axis.magnitude_to_counts(axis.max_accel),
        });
    }
    let mut velocity = path_velocity + (desired - measured) / feedback;
    velocity = velocity.clamp(-axis.max_velocity, axis.max_velocity);
    if velocity.abs() < axis.min_velocity {
        velocity = 0.0;
    }
    if velocity == member.last_velocity {
        // The board runs at it already.
        member.next_at = now;
        return None;
    }
    member.last_velocity = velocity;
    member.last_target = desired;
    Some(Goal::Velocity {
        velocity: axis.rate_to_counts(velocity),
        accel: axis.magnitude_to_counts(axis.max_accel),
    })
}
