//! Goals: what each channel accepts, and a goal handed to the stepper (`stepper.rs`) or
//! a brushed motor (`brushed.rs`); a newer goal drops the unsent writes of the one before.

use core::time::Duration;

use super::SpimotorDriver;
use super::wire::Op;
use motion_drivers::{Driver, Goal, GoalError, GoalKind, GoalKinds};

impl SpimotorDriver {
    /// The goals `channel` accepts: power, stop and off for a brushed motor; for the
    /// stepper every motion goal but `Home`, only stop, off and set-position while it cannot
    /// move.
    pub(super) fn kinds(&self, channel: usize) -> GoalKinds {
        if channel >= self.channel_count() {
            return GoalKinds::NONE;
        }
        if !self.is_stepper() {
            return GoalKinds::of(&[GoalKind::Off, GoalKind::Stop, GoalKind::Power]);
        }
        if self.stepper.can_move() {
            GoalKinds::of(&[
                GoalKind::Off,
                GoalKind::Stop,
                GoalKind::Position,
                GoalKind::Velocity,
                GoalKind::RampPosition,
                GoalKind::SetPosition,
            ])
        } else {
            GoalKinds::of(&[GoalKind::Off, GoalKind::Stop, GoalKind::SetPosition])
        }
    }

    /// A goal for the stepper or a brushed motor, if the channel takes it.
    pub(super) fn plan_goal(
        &mut self,
        now: Duration,
        channel: usize,
        goal: Goal,
    ) -> Result<(), GoalError> {
        if channel >= self.channel_count() {
            return Err(GoalError::NoSuchChannel(channel));
        }
        let kind = goal.kind();
        if !self.capabilities(channel).contains(kind) {
            return Err(GoalError::Unsupported(kind));
        }
        if !self.link_up {
            return Err(GoalError::Offline);
        }
        if self.is_stepper() {
            self.stepper_goal(now, goal)
        } else {
            self.brushed_goal(channel, goal)
        }
    }

    /// Drops the unsent goal ops of `channel` and recomputes the planned registers.
    pub(super) fn drop_goals(&mut self, channel: u8) {
        self.commands.retain(|queued| !queued.is_goal_of(channel));
        self.planned = self.written;
        let mut planned = self.written;
        for queued in self.commands.iter() {
            if let Op::Write(write) = queued.op {
                planned.apply(write);
            }
        }
        self.planned = planned;
    }
}
