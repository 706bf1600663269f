//! A group's straight line run by the pack itself ([`Driver::lead_line`]).
//!
//! Manual 8.7, `$50` "Start multi-dimensional linear Interpolation": "Coordinated movement
//! with multiple motors to a target position. The motors have to stand still before
//! execution. All motors reach the target position at the same time. The target position
//! has to be set for each motor (with command `$26`) before. The axis, which, regarding its
//! position distance, is the fastest, will be automatically used as a master." So:
//! - every leg's motor must be at rest (inactive, nothing queued), or the line is not taken
//!   and the engine follows it with segments;
//! - each leg's script is `$14` (vmax, amax) and `$26` (its target); once every one of them
//!   is out and the engine starts the line (with the group's other boards), one `$50` with
//!   the legs' mask starts them together;
//! - the master sets the line's pace: the leg with the highest velocity gets its own
//!   velocity (to the nearest unit, within the axis's limit) and acceleration; every other
//!   leg gets a vmax at least one unit above its share, so that whichever reading of
//!   "fastest" the firmware takes (the highest velocity, or the longest time at its vmax),
//!   the master is that leg, and the line keeps the engine's time law;
//! - a line of one leg is a plain ramp: `$14`, `$26`, and `$23` for the start (manual 8.4).
//!
//! A goal set on a leg's motor before the start went out (a stop, the group's following
//! taking over) cancels the line. After it, the motors ramp as the pack interpolates;
//! `$26` on the fly shortens or lengthens the master's ramp ("Modifies the target position
//! without influencing the operation mode"), which is how the engine takes the line over
//! for a hold or a feed change (docs/ARCHITECTURE.md "Coordinated motion").

use motion_base::counts_to_i32;
use motion_drivers::{Driver, GoalError, GoalKind, LineLeg};
use tmcpack::{MAX_VELOCITY, MotorMask, Request};

use super::wire::Pick;
use super::{Phase, TmcpackDriver};

/// A line prepared: its legs' `$14` / `$26` go out, then it waits for the start.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct PackLine {
    pub mask: MotorMask,
    pub targets: [i32; 6],
    /// The engine started it: its `$50` (or one leg's `$23`) goes once the legs are out.
    pub started: bool,
}

impl PackLine {
    /// What starts it: `$50` for several motors, `$23` with the target for one.
    pub fn request(&self) -> Request {
        let single = (0..6u8)
            .find(|&m| self.mask.has(m))
            .filter(|&m| MotorMask::single(m) == self.mask);
        match single {
            Some(motor) => Request::StartRamp {
                motor,
                target: self.targets.get(usize::from(motor)).copied().unwrap_or(0),
            },
            None => Request::Interpolate { mask: self.mask },
        }
    }
}

impl TmcpackDriver {
    /// [`Driver::lead_line`](motion_drivers::Driver::lead_line) for this pack.
    pub(super) fn prepare_line(&mut self, legs: &[LineLeg]) -> Result<bool, GoalError> {
        let range = GoalError::OutOfBoardRange(GoalKind::RampPosition);
        if legs.is_empty() || self.line.is_some() {
            return Ok(false);
        }
        match self.phase {
            Phase::Online => {}
            Phase::Survey | Phase::Quiesce | Phase::Configure(_) | Phase::PowerDown => {
                return Err(GoalError::Starting);
            }
            Phase::Down | Phase::Identify => return Err(GoalError::Offline),
        }
        let mut mask = 0u8;
        let mut master = None;
        let mut fastest = f64::NEG_INFINITY;
        for (index, leg) in legs.iter().enumerate() {
            let Some(Some(channel)) = self.channels.get(leg.channel) else {
                return Err(GoalError::NoSuchChannel(leg.channel));
            };
            let bit = 1u8 << leg.channel;
            if leg.channel >= self.channel_count() || mask & bit != 0 {
                return Err(GoalError::NoSuchChannel(leg.channel));
            }
            mask |= bit;
            let usable = |rate: f64| rate.is_finite() && rate > 0.0;
            if !usable(leg.velocity) || !usable(leg.accel) {
                return Err(range);
            }
            if !channel.at_rest() {
                return Ok(false);
            }
            let units = leg.velocity / channel.scale.hz;
            if units > fastest {
                fastest = units;
                master = Some(index);
            }
        }
        // Every leg checked before any script changes: all or none.
        let mut plans = [(0usize, 0i32, 0u16, 0u16); 6];
        for (index, (leg, plan)) in legs.iter().zip(plans.iter_mut()).enumerate() {
            let Some(Some(channel)) = self.channels.get(leg.channel) else {
                return Err(GoalError::NoSuchChannel(leg.channel));
            };
            let target = counts_to_i32(leg.counts).ok_or(range)?;
            let scale = channel.scale;
            let units = leg.velocity / scale.hz;
            let limit = f64::from(scale.vmax.max(1));
            let vmax = if Some(index) == master {
                units.round().clamp(1.0, limit)
            } else {
                (units.ceil() + 1.0).clamp(1.0, limit)
            };
            let amax = scale.amax(leg.accel).ok_or(range)?;
            if vmax > f64::from(MAX_VELOCITY) {
                return Err(range);
            }
            if Some(index) == master
                && !leg.represented_within(vmax * scale.hz, f64::from(amax) * scale.floor().accel)
            {
                // The pack's units are too coarse for this line's pace: the engine follows.
                return Ok(false);
            }
            *plan = (leg.channel, target, vmax as u16, amax);
        }
        let mut targets = [0i32; 6];
        for &(index, target, vmax, amax) in plans.iter().take(legs.len()) {
            if let Some(Some(channel)) = self.channels.get_mut(index) {
                channel.plan_leg(target, vmax, amax)?;
                channel.goal_unsent = true;
            }
            if let Some(slot) = targets.get_mut(index) {
                *slot = target;
            }
        }
        self.line = Some(PackLine {
            mask: MotorMask::from_bits_retain(mask),
            targets,
            started: false,
        });
        Ok(true)
    }

    /// Whether the line prepared waits only for its start (every leg's script is out).
    pub(super) fn line_prepared(&self) -> bool {
        self.line
            .is_some_and(|line| !line.started && !self.legs_pending(line))
    }

    fn legs_pending(&self, line: PackLine) -> bool {
        self.channels
            .iter()
            .flatten()
            .any(|c| line.mask.has(c.motor) && c.pending())
    }

    /// The line's start, once the engine started it and every leg's script is out.
    pub(super) fn line_pick(&self) -> Option<Pick> {
        let line = self.line.filter(|line| line.started)?;
        (!self.legs_pending(line)).then_some(Pick {
            request: line.request(),
            expect: None,
            channel: None,
        })
    }

    /// The line's start went out with sequence number `seq`: its motors ramp to their
    /// targets.
    pub(super) fn on_line_sent(&mut self, seq: u64) {
        let Some(line) = self.line.take() else {
            return;
        };
        for channel in self.channels.iter_mut().flatten() {
            if line.mask.has(channel.motor)
                && let Some(&target) = line.targets.get(usize::from(channel.motor))
            {
                channel.on_line_started(target, seq);
            }
        }
    }

    /// A goal on `channel` ends a line that has not started (its `$50` is not sent).
    pub(super) fn cancel_line_of(&mut self, channel: usize) {
        if self
            .line
            .is_some_and(|line| u8::try_from(channel).is_ok_and(|motor| line.mask.has(motor)))
        {
            self.line = None;
        }
    }
}
