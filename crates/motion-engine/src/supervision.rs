//! Supervision of every axis on every fresh sample: following error, overspeed, soft
//! limits and reference-search travel. Pure arithmetic on the axis's state; a broken rule
//! latches a fault with the measured figure and the tolerance, and stops the axis with its
//! e-stop category at once.
//!
//! | rule | applies | fault |
//! |---|---|---|
//! | \|position − target\| > `following_error` | holding (`Hold`, or a position goal that arrived once) | `FollowingError` |
//! | position outside [start, target] widened by `following_error` | a position goal on its way | `FollowingError` |
//! | \|velocity\| > `overspeed_factor` × `max_velocity` on 3 fresh samples in a row | always | `Overspeed` |
//! | position beyond `min`/`max` by more than `following_error` | every mode but `Off` and a search; during a search of a referenced axis the tolerance is `home_max_travel` | `LimitExceeded` |
//! | distance of a search from where it started > `home_max_travel` | `Homing` | `HomeFailed` |
//!
//! `following_error = 0` turns off the following-error and limit rules, `overspeed_factor
//! = 0` the overspeed rule, `home_max_travel = 0` the travel rule.

use motion_drivers::Driver;
use motion_ipc::{AxisMode, DeviceState, FaultCode};

use crate::Engine;
use crate::axis::Axis;

/// Fresh samples in a row above the overspeed limit that fault the axis.
pub const OVERSPEED_SAMPLES: u8 = 3;

/// A broken rule: code, measured figure, tolerance.
type Broken = (FaultCode, f64, f64);

impl<D: Driver> Engine<D> {
    /// Step 2: every rule on every axis with fresh data from an online board.
    pub(crate) fn supervise(&mut self) {
        let now = self.now;
        for index in 0..self.axes.len() {
            if self.device_state_of(index) != DeviceState::Online {
                continue;
            }
            let axis = &mut self.axes[index];
            if axis.fault.is_some() || !axis.fresh || axis.stale {
                continue;
            }
            let elapsed = now.saturating_sub(axis.last_sample_at).as_secs_f64();
            if let Some((code, value, limit)) = check(axis, elapsed) {
                self.fault_axis(index, code, value, limit);
            }
            self.axes[index].last_sample_at = now;
        }
    }
}

fn check(axis: &mut Axis, elapsed: f64) -> Option<Broken> {
    overspeed(axis)
        .or_else(|| search_travel(axis, elapsed))
        .or_else(|| limits(axis))
        .or_else(|| following(axis))
}

fn overspeed(axis: &mut Axis) -> Option<Broken> {
    if axis.overspeed_factor <= 0.0 {
        return None;
    }
    let limit = axis.overspeed_factor * axis.max_velocity;
    let speed = axis.velocity().abs();
    if speed > limit {
        axis.overspeed_samples = axis.overspeed_samples.saturating_add(1);
    } else {
        axis.overspeed_samples = 0;
    }
    (axis.overspeed_samples >= OVERSPEED_SAMPLES).then_some((FaultCode::Overspeed, speed, limit))
}

/// How far the search has gone from where it started: the sum of the plausible steps
/// (a jump faster than twice the axis's velocity limit is the board setting its counter at
/// the trigger, not travel), signed, so that backing off a switch does not count twice.
fn search_travel(axis: &mut Axis, elapsed: f64) -> Option<Broken> {
    if axis.mode != AxisMode::Homing {
        return None;
    }
    let position = axis.position();
    let step = position - axis.home_last;
    axis.home_last = position;
    if step.abs() <= 2.0 * axis.max_velocity * elapsed + axis.tolerance {
        axis.home_travel += step;
    }
    let distance = axis.home_travel.abs();
    (axis.home_max_travel > 0.0 && distance > axis.home_max_travel).then_some((
        FaultCode::HomeFailed,
        distance,
        axis.home_max_travel,
    ))
}

fn limits(axis: &Axis) -> Option<Broken> {
    if axis.following_error <= 0.0 || axis.mode == AxisMode::Off {
        return None;
    }
    let tolerance = if axis.mode == AxisMode::Homing {
        if !axis.home_referenced || axis.home_max_travel <= 0.0 {
            return None;
        }
        axis.home_max_travel
    } else {
        axis.following_error
    };
    let position = axis.position();
    if position < axis.min - tolerance {
        Some((FaultCode::LimitExceeded, position, axis.min))
    } else if position > axis.max + tolerance {
        Some((FaultCode::LimitExceeded, position, axis.max))
    } else {
        None
    }
}

fn following(axis: &mut Axis) -> Option<Broken> {
    let tolerance = axis.following_error;
    if tolerance <= 0.0 {
        return None;
    }
    let position = axis.position();
    let from_target = (position - axis.target).abs();
    match axis.mode {
        AxisMode::Hold => {
            // Armed once the position was within the tolerance of the target (a
            // set-position takes a sample or two to show).
            if !axis.arrived {
                axis.arrived = from_target <= tolerance;
                return None;
            }
            (from_target > tolerance).then_some((FaultCode::FollowingError, from_target, tolerance))
        }
        AxisMode::Position | AxisMode::RampPosition => {
            if !axis.arrived && !axis.state.moving && from_target <= axis.tolerance {
                axis.arrived = true;
            }
            if axis.arrived {
                return (from_target > tolerance).then_some((
                    FaultCode::FollowingError,
                    from_target,
                    tolerance,
                ));
            }
            let low = axis.move_start.min(axis.target);
            let high = axis.move_start.max(axis.target);
            let outside = (low - position).max(position - high).max(0.0);
            (outside > tolerance).then_some((FaultCode::FollowingError, outside, tolerance))
        }
        _ => None,
    }
}
