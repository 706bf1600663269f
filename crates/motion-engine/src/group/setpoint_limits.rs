//! The limits a streamed setpoint is judged by, on the client's own time law.
//!
//! A setpoint says where a member axis is to be (or how fast it is to go) at its own tick,
//! `for_tick`. Its velocity and acceleration are finite differences of consecutive applied
//! setpoints over their `for_tick`s — never over the ticks in which they arrived or were
//! applied — so a client whose setpoints reach the server a tick late, or several in one
//! tick, is judged on exactly the path it sent:
//!
//! - velocity over the span from the previous setpoint: `v = Δposition / (Δfor_tick · period)`;
//! - acceleration between the two spans' midpoints: `a = Δv / ((span + previous span) / 2)`
//!   (the first setpoint of a stream: `Δv / span`, from rest).
//!
//! Pure functions of the previous step and the setpoint: no engine state, no clock.

use motion_trajectory::AxisLimits;

/// What a member axis's path was after the previous setpoint applied.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Previous {
    /// The path's position, units.
    pub position: f64,
    /// The velocity the previous setpoint asked for (units/s; 0 at the stream's start).
    pub velocity: f64,
    /// The span that velocity was judged over, s (0 before the stream's first setpoint).
    pub span: f64,
}

/// A setpoint within the limits, or clamped to them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Step {
    /// Where the path goes, units.
    pub position: f64,
    /// The velocity it asks for (what the next setpoint's acceleration is judged from).
    pub velocity: f64,
    /// Whether anything was clamped.
    pub clamped: bool,
}

/// A setpoint beyond a limit under `stream_limit = "abort"`: the figure and the limit it
/// broke (the axis's unit, per s, per s²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Breach {
    pub figure: f64,
    pub limit: f64,
}

/// The span the acceleration from `previous` to a step of `span` is judged over.
fn accel_span(previous: &Previous, span: f64) -> f64 {
    if previous.span > 0.0 {
        (span + previous.span) / 2.0
    } else {
        span
    }
}

/// A position setpoint `value` for `span` seconds after the previous one.
pub(crate) fn judge_position(
    previous: &Previous,
    value: f64,
    span: f64,
    limits: &AxisLimits,
    clamp: bool,
) -> Result<Step, Breach> {
    let target = value.clamp(limits.min, limits.max);
    let mut clamped = false;
    if target != value {
        if !clamp {
            let limit = if value < limits.min {
                limits.min
            } else {
                limits.max
            };
            return Err(Breach {
                figure: value,
                limit,
            });
        }
        clamped = true;
    }
    let wanted = (target - previous.position) / span;
    let reach = limits.max_accel * accel_span(previous, span);
    let velocity = wanted
        .clamp(-limits.max_velocity, limits.max_velocity)
        .clamp(previous.velocity - reach, previous.velocity + reach);
    if velocity != wanted {
        if !clamp {
            return Err(if wanted.abs() > limits.max_velocity {
                Breach {
                    figure: wanted,
                    limit: limits.max_velocity,
                }
            } else {
                Breach {
                    figure: (wanted - previous.velocity) / accel_span(previous, span),
                    limit: limits.max_accel,
                }
            });
        }
        clamped = true;
    }
    let position = if velocity == wanted {
        // Exactly what was asked, not re-derived through the velocity.
        target
    } else {
        previous.position + velocity * span
    };
    Ok(Step {
        position,
        velocity,
        clamped,
    })
}

/// A velocity setpoint `value` for `span` seconds after the previous one; `position` is
/// where the path is now, `period` a tick: the velocity must let the axis stop before a
/// soft limit from where it will be after this tick.
pub(crate) fn judge_velocity(
    previous: &Previous,
    value: f64,
    span: f64,
    period: f64,
    limits: &AxisLimits,
    clamp: bool,
) -> Result<Step, Breach> {
    let reach = limits.max_accel * accel_span(previous, span);
    let mut velocity = value
        .clamp(-limits.max_velocity, limits.max_velocity)
        .clamp(previous.velocity - reach, previous.velocity + reach);
    let mut clamped = false;
    if velocity != value {
        if !clamp {
            return Err(if value.abs() > limits.max_velocity {
                Breach {
                    figure: value,
                    limit: limits.max_velocity,
                }
            } else {
                Breach {
                    figure: (value - previous.velocity) / accel_span(previous, span),
                    limit: limits.max_accel,
                }
            });
        }
        clamped = true;
    }
    let next = previous.position + velocity * period;
    // A velocity that would carry the axis past a soft limit before it could stop there.
    let stop = velocity * velocity / (2.0 * limits.max_accel);
    let beyond = (velocity > 0.0 && next + stop > limits.max)
        || (velocity < 0.0 && next - stop < limits.min);
    if beyond {
        if !clamp {
            return Err(Breach {
                figure: next,
                limit: if velocity > 0.0 {
                    limits.max
                } else {
                    limits.min
                },
            });
        }
        clamped = true;
        velocity = 0.0;
    }
    Ok(Step {
        position: if beyond { previous.position } else { next },
        velocity,
        clamped,
    })
}

/// A power setpoint `value` (a fraction of full power, −1..=1).
pub(crate) fn judge_power(value: f64, clamp: bool) -> Result<f64, Breach> {
    let power = value.clamp(-1.0, 1.0);
    if power != value && !clamp {
        return Err(Breach {
            figure: value,
            limit: 1.0,
        });
    }
    Ok(power)
}

#[cfg(test)]
mod tests {
    use super::*;

    const LIMITS: AxisLimits = AxisLimits {
        min: -100.0,
        max: 100.0,
        max_velocity: 50.0,
        max_accel: 500.0,
    };
    const MS: f64 = 0.001;

    fn at(position: f64, velocity: f64, span: f64) -> Previous {
        Previous {
            position,
            velocity,
            span,
        }
    }

    #[test]
    fn velocity_and_acceleration_are_taken_over_the_setpoints_own_spans() {
        // 10 units/s for a tick, then a setpoint two ticks on that keeps 10 units/s: no
        // acceleration, whatever tick it arrives in.
        let step = judge_position(&at(1.0, 10.0, MS), 1.02, 2.0 * MS, &LIMITS, false)
            .expect("within the limits");
        assert!((step.velocity - 10.0).abs() < 1e-9);
        assert_eq!(step.position, 1.02);
        assert!(!step.clamped);
        // The same step over one tick is 20 units/s: 10 units/s gained between the spans'
        // midpoints (1 ms apart) is 10 000 units/s², beyond 500.
        let breach = judge_position(&at(1.0, 10.0, MS), 1.02, MS, &LIMITS, false)
            .expect_err("beyond max_accel");
        assert_eq!(breach.limit, 500.0);
        assert!((breach.figure - 10_000.0).abs() < 1e-6, "{breach:?}");
    }

    #[test]
    fn the_midpoint_rule_for_uneven_spans() {
        // 10 units/s over 1 ms, then 10.9 units/s over 3 ms: the midpoints are 2 ms apart,
        // 450 units/s², within the limit; 11.4 units/s is 700 units/s², beyond it.
        let previous = at(0.0, 10.0, MS);
        let step = judge_position(&previous, 0.0327, 3.0 * MS, &LIMITS, false).expect("within");
        assert!((step.velocity - 10.9).abs() < 1e-9);
        let breach =
            judge_position(&previous, 0.0342, 3.0 * MS, &LIMITS, false).expect_err("beyond");
        assert!((breach.figure - 700.0).abs() < 1e-6, "{breach:?}");
    }

    #[test]
    fn clamping_keeps_each_limit_and_says_so() {
        let step = judge_position(&at(0.0, 0.0, MS), 1.0, MS, &LIMITS, true).expect("clamped");
        assert!(step.clamped);
        assert!((step.velocity - 0.5).abs() < 1e-12, "{step:?}");
        assert!((step.position - 0.0005).abs() < 1e-12);
        let step = judge_position(&at(99.999, 0.0, MS), 120.0, MS, &LIMITS, true).expect("clamped");
        assert!(step.clamped && step.position <= 100.0);
        let breach =
            judge_position(&at(0.0, 0.0, MS), -120.0, MS, &LIMITS, false).expect_err("beyond min");
        assert_eq!((breach.figure, breach.limit), (-120.0, -100.0));
        let breach = judge_position(&at(0.0, 49.9, MS), 0.0599, MS, &LIMITS, false)
            .expect_err("beyond max_velocity");
        assert_eq!(breach.limit, 50.0);
    }

    #[test]
    fn velocities_are_judged_by_their_spans_and_the_soft_limits() {
        let step =
            judge_velocity(&at(0.0, 10.0, MS), 10.5, MS, MS, &LIMITS, false).expect("500/s²");
        assert_eq!(step.velocity, 10.5);
        assert!((step.position - 0.0105).abs() < 1e-12);
        // Two ticks on, the spans' midpoints are 1.5 ms apart: 0.7 units/s more is 467
        // units/s², within; one tick on it is 700.
        let step =
            judge_velocity(&at(0.0, 10.0, MS), 10.7, 2.0 * MS, MS, &LIMITS, false).expect("within");
        assert_eq!(step.velocity, 10.7);
        assert!(judge_velocity(&at(0.0, 10.0, MS), 10.7, MS, MS, &LIMITS, false).is_err());
        // 40 units/s needs 1.6 units to stop: from 99 it would pass 100.
        let breach = judge_velocity(&at(99.0, 40.0, MS), 40.0, MS, MS, &LIMITS, false)
            .expect_err("past the soft limit");
        assert_eq!(breach.limit, 100.0);
        let step =
            judge_velocity(&at(99.0, 40.0, MS), 40.0, MS, MS, &LIMITS, true).expect("clamped");
        assert_eq!(
            (step.velocity, step.position, step.clamped),
            (0.0, 99.0, true)
        );
    }

    #[test]
    fn power_within_one() {
        assert_eq!(judge_power(0.5, false), Ok(0.5));
        assert_eq!(judge_power(1.5, true), Ok(1.0));
        assert_eq!(
            judge_power(-1.5, false),
            Err(Breach {
                figure: -1.5,
                limit: 1.0
            })
        );
    }
}
