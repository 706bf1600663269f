//! Hold and resume of one axis's own position move (`Hold` / `Resume` with
//! `Target::Axis`; a group's feed hold is `group/`).
//!
//! | the axis | hold | resume |
//! |---|---|---|
//! | on a board that pauses its own move (`Driver::pause_line`: the QSB-M's COMMAND 6 "Pause the motor using the MD ACCEL rate", while its drive runs the move) | the board decelerates at the move's acceleration and keeps the rest of the move | `Driver::resume_line` (COMMAND 7 "Resume motor operation if previously stopped using the Motor Pause command"); a board that cannot resume it (its pause not answered yet) gets the move again |
//! | any other board, `RampPosition` | a stop at the move's acceleration (`Goal::Stop`) | the same `RampPosition` — target, velocity, acceleration — from where the axis stands |
//! | any other board, `Position` (the board's own controller) | a stop at `max_accel` | the same `Position` target |
//! | velocity, power, homing, holding, off, a move that arrived | refused: `NotMoving` | – |
//!
//! While held the axis is `stopping`, then `hold` at the position it came to rest, flagged
//! `HELD`; its following-error rule is the hold's. Anything else given to the axis — a
//! stop, a goal, an e-stop, a fault, its group — forgets the held move; a `Resume` without
//! one is refused with `NotMoving`. The resumed move belongs to the client that resumed
//! it. The held move is the axis's own state (`axis::HeldMove`).

use motion_drivers::{Driver, Goal};
use motion_ipc::rules::Motion;
use motion_ipc::{AxisMode, ClientId, Reason};

use crate::Engine;
use crate::axis::HeldMove;

impl<D: Driver> Engine<D> {
    /// `Hold` of axis `index` (accepted by the rulebook).
    pub(crate) fn hold_axis(&mut self, index: usize) -> Reason {
        let now = self.now;
        let axis = &self.axes[index];
        if axis.held.is_some() {
            return Reason::Accepted;
        }
        let arrived = axis.arrived
            || (!axis.state.moving && (axis.position() - axis.target).abs() <= axis.tolerance);
        let motion = match axis.mode {
            _ if arrived => return Reason::NotMoving,
            AxisMode::RampPosition => Motion::RampPosition {
                target: axis.target,
                velocity: axis.move_velocity,
                accel: axis.move_accel,
            },
            AxisMode::Position => Motion::Position {
                target: axis.target,
            },
            _ => return Reason::NotMoving,
        };
        let decel = match motion {
            Motion::RampPosition { accel, .. } => accel,
            _ => axis.max_accel,
        };
        let decel = axis.magnitude_to_counts(decel);
        let (bus, slot, channel) = (axis.bus, axis.slot, axis.channel);
        let Some(driver) = self.buses[bus].driver_mut(slot) else {
            return Reason::DeviceOffline;
        };
        let by_board = driver.pause_line(now, channel).unwrap_or(false);
        if !by_board {
            if let Err(error) = driver.set_goal(now, channel, Goal::Stop { decel }) {
                return self.goal_error_reason(index, error);
            }
            self.goal_set(index);
        }
        let axis = &mut self.axes[index];
        axis.mode = AxisMode::Stopping;
        axis.target = axis.position();
        axis.arrived = true;
        axis.deadman_at = None;
        axis.off_after_stop = false;
        axis.held = Some(HeldMove { motion, by_board });
        Reason::Accepted
    }

    /// `Resume` of axis `index` by `client` (accepted by the rulebook).
    pub(crate) fn resume_axis(&mut self, index: usize, client: ClientId) -> Reason {
        let now = self.now;
        let axis = &self.axes[index];
        let Some(held) = axis.held else {
            return Reason::NotMoving;
        };
        let goal = crate::command::goal_of(axis, held.motion);
        let (bus, slot, channel) = (axis.bus, axis.slot, axis.channel);
        let Some(driver) = self.buses[bus].driver_mut(slot) else {
            return Reason::DeviceOffline;
        };
        let by_board = held.by_board && driver.resume_line(now, channel).unwrap_or(false);
        if !by_board {
            if let Err(error) = driver.set_goal(now, channel, goal) {
                return self.goal_error_reason(index, error);
            }
            self.goal_set(index);
        }
        let axis = &mut self.axes[index];
        let position = axis.position();
        axis.mode = held.motion.mode();
        axis.target = held.motion.target().unwrap_or(position);
        axis.goal_owner = client;
        axis.move_start = position;
        axis.arrived = false;
        axis.held = None;
        Reason::Accepted
    }

    /// A held move lives only while its axis stops and holds: any other mode forgot it.
    pub(crate) fn forget_stale_holds(&mut self) {
        for axis in &mut self.axes {
            if !matches!(axis.mode, AxisMode::Stopping | AxisMode::Hold) || axis.group.is_some() {
                axis.held = None;
            }
        }
    }
}
