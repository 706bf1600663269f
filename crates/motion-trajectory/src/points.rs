//! The points of a trajectory as a client sent them, and the checks that need no polynomial.

use crate::{AxisLimits, PathError, at_most};

/// Points as a client sent them, borrowed from a shared-memory sample: point i, axis j is
/// `positions[i * stride + j]` (stride = 16 in the contract; only the first `axes` used).
///
/// The slices may be longer than the points need (a fixed-size sample): only the first
/// `(times.len() - 1) * stride + axes` values are read.
#[derive(Debug, Clone, Copy)]
pub struct Points<'a> {
    /// Seconds from the start of the trajectory, one per point: `times[0] >= 0`, then strictly
    /// increasing. `times[0] > 0` plans a lead-in from the start state to point 0.
    pub times: &'a [f64],
    /// Positions, `stride` values per point.
    pub positions: &'a [f64],
    /// Velocities, same layout; `None`: positions only (a C2 spline through them, or blended
    /// at them when the spline exceeds a limit).
    pub velocities: Option<&'a [f64]>,
    /// Accelerations, same layout; only with `velocities` (quintic Hermite segments).
    pub accelerations: Option<&'a [f64]>,
    /// Values per point in each slice (≥ the number of axes).
    pub stride: usize,
}

/// How the segments between points are made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    /// A C2 cubic spline through the positions.
    Positions,
    /// Cubic Hermite segments.
    Velocities,
    /// Quintic Hermite segments.
    Accelerations,
}

/// How far a trajectory may be from its points, one value per axis of the group.
#[derive(Debug, Clone, Copy)]
pub struct Tolerances<'a> {
    /// How far point 0 may be from the start position when its time is 0 (no lead-in):
    /// [`PathError::StartMismatch`] beyond it.
    pub start: &'a [f64],
    /// How far a trajectory through positions alone may pass each point when its exact spline
    /// would exceed a limit and it is blended at the points instead (the group's
    /// `path_tolerance`): [`PathError::BlendTolerance`] beyond it. 0 (or NaN) allows no
    /// blend at a point where the velocity changes.
    pub path: &'a [f64],
}

/// The start state of the group, how far point 0 may be from it without a lead-in, and how
/// far a blended path may pass the points.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Start<'a> {
    pub position: &'a [f64],
    pub velocity: &'a [f64],
    pub acceleration: &'a [f64],
    pub tolerance: &'a [f64],
    pub path_tolerance: &'a [f64],
}

impl Points<'_> {
    /// The number of points.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    pub(crate) fn kind(&self) -> Kind {
        match (self.velocities, self.accelerations) {
            (None, _) => Kind::Positions,
            (Some(_), None) => Kind::Velocities,
            (Some(_), Some(_)) => Kind::Accelerations,
        }
    }

    #[inline]
    pub(crate) fn position(&self, point: usize, axis: usize) -> f64 {
        self.positions[point * self.stride + axis]
    }

    /// The velocity sent for the point, 0 when none was.
    #[inline]
    pub(crate) fn velocity(&self, point: usize, axis: usize) -> f64 {
        self.velocities
            .map_or(0.0, |v| v[point * self.stride + axis])
    }

    /// The acceleration sent for the point, 0 when none was.
    #[inline]
    pub(crate) fn acceleration(&self, point: usize, axis: usize) -> f64 {
        self.accelerations
            .map_or(0.0, |a| a[point * self.stride + axis])
    }

    /// Every check that needs no polynomial, in this order: count, layout, limits, the start
    /// state finite, times, each point's values finite and within range (point by point),
    /// rest at the last point, and the start when point 0's time is 0.
    pub(crate) fn check(
        &self,
        axes: usize,
        capacity: usize,
        limits: &[AxisLimits],
        start: &Start<'_>,
    ) -> Result<(), PathError> {
        let count = self.len();
        if count == 0 {
            return Err(PathError::NoPoints);
        }
        if count > capacity {
            return Err(PathError::TooManyPoints { count, capacity });
        }
        let need = (count - 1)
            .checked_mul(self.stride)
            .and_then(|n| n.checked_add(axes))
            .ok_or(PathError::BadLayout)?;
        let fits = |values: Option<&[f64]>| values.is_none_or(|v| v.len() >= need);
        if self.stride < axes
            || !fits(Some(self.positions))
            || !fits(self.velocities)
            || !fits(self.accelerations)
            || (self.accelerations.is_some() && self.velocities.is_none())
            || limits.len() != axes
            || start.position.len() != axes
            || start.velocity.len() != axes
            || start.acceleration.len() != axes
            || start.tolerance.len() != axes
            || start.path_tolerance.len() != axes
        {
            return Err(PathError::BadLayout);
        }
        crate::check_limits(limits)?;
        for axis in 0..axes {
            let state = [
                start.position[axis],
                start.velocity[axis],
                start.acceleration[axis],
            ];
            if !state.iter().all(|x| x.is_finite()) {
                return Err(PathError::NotFinite { point: 0, axis });
            }
        }
        let mut before = 0.0;
        for (point, &time) in self.times.iter().enumerate() {
            let increasing = if point == 0 {
                time >= 0.0
            } else {
                time > before
            };
            if !time.is_finite() || !increasing {
                return Err(PathError::TimesNotIncreasing { point });
            }
            before = time;
        }
        for point in 0..count {
            let base = point * self.stride;
            let positions = &self.positions[base..][..axes];
            let velocities = self.velocities.map(|v| &v[base..][..axes]);
            let accelerations = self.accelerations.map(|a| &a[base..][..axes]);
            for (axis, (limit, &value)) in limits.iter().zip(positions).enumerate() {
                let finite = value.is_finite()
                    && velocities.is_none_or(|v| v[axis].is_finite())
                    && accelerations.is_none_or(|a| a[axis].is_finite());
                if !finite {
                    return Err(PathError::NotFinite { point, axis });
                }
                let slack = crate::segments::range_slack(limit);
                if !(value >= limit.min - slack && value <= limit.max + slack) {
                    return Err(PathError::OutOfRange {
                        point,
                        axis,
                        value,
                        min: limit.min,
                        max: limit.max,
                    });
                }
            }
        }
        // At rest at the end: zero, but for rounding (10⁻⁹ of the axis's limits).
        let last = count - 1;
        for (axis, limit) in limits.iter().enumerate().take(axes) {
            let value = self.velocity(last, axis);
            if value.abs() > crate::segments::SLACK * limit.max_velocity {
                return Err(PathError::VelocityLimit {
                    point: last,
                    axis,
                    value,
                    limit: 0.0,
                });
            }
            let value = self.acceleration(last, axis);
            if value.abs() > crate::segments::SLACK * limit.max_accel {
                return Err(PathError::AccelLimit {
                    point: last,
                    axis,
                    value,
                    limit: 0.0,
                });
            }
        }
        if self.times[0] == 0.0 {
            for axis in 0..axes {
                let distance = (self.position(0, axis) - start.position[axis]).abs();
                let tolerance = start.tolerance[axis];
                if !at_most(distance, tolerance) {
                    return Err(PathError::StartMismatch {
                        axis,
                        distance,
                        tolerance,
                    });
                }
            }
        }
        Ok(())
    }
}
