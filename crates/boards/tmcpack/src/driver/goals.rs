//! Goals and outputs: what a configured motor accepts, a goal becoming the motor's script
//! (the `channel` module), and which script's request goes next (stops first, then output
//! changes, then a `$50` line whose legs are out, then the other goals round-robin).

use super::channel::Channel;
use super::script::Step;
use super::wire::Pick;
use super::{Phase, TmcpackDriver};
use motion_drivers::{Driver, Goal, GoalError, GoalKind, GoalKinds, Pin};

/// The goals a configured motor takes.
pub(super) const CAPABILITIES: GoalKinds = GoalKinds::of(&[
    GoalKind::Off,
    GoalKind::Stop,
    GoalKind::Position,
    GoalKind::Velocity,
    GoalKind::RampPosition,
    GoalKind::Home,
    GoalKind::SetPosition,
]);

impl TmcpackDriver {
    pub(super) fn any_ready(&self) -> bool {
        self.io.outputs_pending
            || self.line_pick().is_some()
            || self.channels.iter().flatten().any(|c| self.may_send(c))
    }

    /// Whether `channel`'s next request may go now: a `$24` waits for a query after the
    /// last `$24` (a path's targets would otherwise take the line from the polls).
    fn may_send(&self, channel: &Channel) -> bool {
        match channel.current() {
            Some(Step::Send(tmcpack::Request::PiTarget { .. })) => !self.pi_since_poll,
            Some(Step::Send(_)) => true,
            _ => false,
        }
    }

    /// Stops first, then output changes, then the other goals round-robin.
    pub(super) fn pick_command(&mut self) -> Option<Pick> {
        let urgent = self.channels.iter().flatten().find(|c| c.urgent());
        if let Some(channel) = urgent
            && let Some(Step::Send(request)) = channel.current()
        {
            return Some(Pick {
                request,
                expect: None,
                channel: Some(usize::from(channel.motor)),
            });
        }
        if self.io.outputs_pending {
            return Some(Pick {
                request: self.io.outputs_request(),
                expect: None,
                channel: None,
            });
        }
        if let Some(line) = self.line_pick() {
            return Some(line);
        }
        for offset in 0..6 {
            let index = (self.next_command + offset) % 6;
            if let Some(Some(channel)) = self.channels.get(index)
                && self.may_send(channel)
                && let Some(Step::Send(request)) = channel.current()
            {
                self.next_command = (index + 1) % 6;
                return Some(Pick {
                    request,
                    expect: None,
                    channel: Some(index),
                });
            }
        }
        None
    }

    /// A goal for a configured motor of an online pack becomes the motor's script.
    pub(super) fn plan_goal(&mut self, channel: usize, goal: Goal) -> Result<(), GoalError> {
        if channel >= self.channel_count() {
            return Err(GoalError::NoSuchChannel(channel));
        }
        let phase = self.phase;
        let Some(Some(slot)) = self.channels.get_mut(channel) else {
            return Err(GoalError::Unsupported(goal.kind()));
        };
        match phase {
            Phase::Online => {
                slot.plan(goal)?;
                slot.goal_unsent = true;
                self.cancel_line_of(channel);
                Ok(())
            }
            Phase::Survey | Phase::Quiesce | Phase::Configure(_) | Phase::PowerDown => {
                Err(GoalError::Starting)
            }
            Phase::Down | Phase::Identify => Err(GoalError::Offline),
        }
    }

    /// A new level for a configured output of an online pack.
    pub(super) fn drive_output(&mut self, pin: Pin, high: bool) -> Result<(), GoalError> {
        if !self.io.config().outputs.contains(pin) {
            return Err(GoalError::NoSuchPin(pin));
        }
        match self.phase {
            Phase::Online => {}
            Phase::Survey | Phase::Quiesce | Phase::Configure(_) | Phase::PowerDown => {
                return Err(GoalError::Starting);
            }
            Phase::Down | Phase::Identify => return Err(GoalError::Offline),
        }
        if self.io.set(pin, high) {
            Ok(())
        } else {
            Err(GoalError::NoSuchPin(pin))
        }
    }
}
