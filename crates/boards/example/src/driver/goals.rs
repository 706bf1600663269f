//! Goals in steps turned into the one request that carries each: the conversions to the
//! board's integer fields and their ranges.

use motion_drivers::{Goal, GoalError, GoalKind, GoalKinds};

use super::AxisLimits;
use crate::codec::{MAX_ACCEL, MAX_SPEED, Request};

/// What every channel accepts.
pub(super) const KINDS: GoalKinds = GoalKinds::of(&[
    GoalKind::Off,
    GoalKind::Stop,
    GoalKind::Position,
    GoalKind::Velocity,
    GoalKind::RampPosition,
    GoalKind::SetPosition,
]);

/// A position, steps.
fn steps(value: f64, kind: GoalKind) -> Result<i32, GoalError> {
    let rounded = value.round();
    if rounded.is_finite() && rounded >= f64::from(i32::MIN) && rounded <= f64::from(i32::MAX) {
        Ok(rounded as i32)
    } else {
        Err(GoalError::OutOfBoardRange(kind))
    }
}

/// A speed or acceleration in `1..=max`: rounded, raised to the board's floor of 1 (the
/// engine refuses goals below [`RateFloor`](motion_drivers::RateFloor)), capped at `max` (the
/// board is never faster than asked).
fn rate(value: f64, max: u32, kind: GoalKind) -> Result<u32, GoalError> {
    if !value.is_finite() || value <= 0.0 {
        return Err(GoalError::OutOfBoardRange(kind));
    }
    Ok(value.round().clamp(1.0, f64::from(max)) as u32)
}

/// The request that carries `goal` on `channel` (whose axis has `limits`).
pub(super) fn request(channel: u8, goal: Goal, limits: AxisLimits) -> Result<Request, GoalError> {
    let kind = goal.kind();
    Ok(match goal {
        Goal::Off => Request::Off { channel },
        Goal::Stop { decel } => Request::Stop {
            channel,
            decel: rate(decel, MAX_ACCEL, kind)?,
        },
        Goal::Position { counts } => Request::Move {
            channel,
            target: steps(counts, kind)?,
            speed: rate(limits.max_velocity, MAX_SPEED, kind)?,
            accel: rate(limits.max_accel, MAX_ACCEL, kind)?,
        },
        Goal::RampPosition {
            counts,
            velocity,
            accel,
        } => Request::Move {
            channel,
            target: steps(counts, kind)?,
            speed: rate(velocity, MAX_SPEED, kind)?,
            accel: rate(accel, MAX_ACCEL, kind)?,
        },
        Goal::Velocity { velocity, accel } => {
            let rounded = velocity.round();
            if !rounded.is_finite() || rounded.abs() > f64::from(MAX_SPEED) {
                return Err(GoalError::OutOfBoardRange(kind));
            }
            Request::Jog {
                channel,
                velocity: rounded as i32,
                accel: rate(accel, MAX_ACCEL, kind)?,
            }
        }
        Goal::SetPosition { counts } => Request::SetPosition {
            channel,
            position: steps(counts, kind)?,
        },
        Goal::Power { .. } | Goal::Home { .. } => return Err(GoalError::Unsupported(kind)),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn goals_become_one_request_each_in_whole_steps() {
        let limits = AxisLimits {
            max_velocity: 2500.4,
            max_accel: 30_000.0,
        };
        assert_eq!(
            request(1, Goal::Position { counts: 99.6 }, limits),
            Ok(Request::Move {
                channel: 1,
                target: 100,
                speed: 2500,
                accel: 30_000
            })
        );
        let ramp = Goal::RampPosition {
            counts: -5.0,
            velocity: 90_000.0,
            accel: 0.2,
        };
        // Capped at the board's fastest, raised to its floor.
        assert_eq!(
            request(0, ramp, limits),
            Ok(Request::Move {
                channel: 0,
                target: -5,
                speed: MAX_SPEED,
                accel: 1
            })
        );
        let jog = Goal::Velocity {
            velocity: -60_000.0,
            accel: 1.0,
        };
        assert_eq!(
            request(0, jog, limits),
            Err(GoalError::OutOfBoardRange(GoalKind::Velocity))
        );
        for bad in [f64::NAN, f64::INFINITY, 1e12] {
            assert_eq!(
                request(0, Goal::Position { counts: bad }, limits),
                Err(GoalError::OutOfBoardRange(GoalKind::Position)),
                "{bad}"
            );
        }
        assert_eq!(
            request(0, Goal::Stop { decel: f64::NAN }, limits),
            Err(GoalError::OutOfBoardRange(GoalKind::Stop))
        );
        assert_eq!(
            request(0, Goal::Home { velocity: 1.0 }, limits),
            Err(GoalError::Unsupported(GoalKind::Home))
        );
        assert!(!KINDS.contains(GoalKind::Power));
    }
}
