//! Why a path was refused.

/// Why [`Path::plan_line`](crate::Path::plan_line) or
/// [`Path::plan_points`](crate::Path::plan_points) refused a path. Names the point index and
/// the axis index (within the group) where it can; a refused plan leaves the previous path
/// untouched.
///
/// For the limit variants, `point` is the index of the point that ENDS the segment where the
/// limit is exceeded: 0 is the lead-in from the start state to point 0.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum PathError {
    /// More points than the path was sized for ([`Path::new`](crate::Path::new)'s `max_points`).
    #[error(
        "{count} points, but this path holds at most {capacity}: send at most {capacity} points \
         (split a longer trajectory)"
    )]
    TooManyPoints {
        /// The number of points sent.
        count: usize,
        /// The most points the path holds.
        capacity: usize,
    },
    /// An empty trajectory.
    #[error("no points: a trajectory needs at least one point")]
    NoPoints,
    /// The slices do not fit the group: a stride smaller than the number of axes, position,
    /// velocity or acceleration slices too short for the points, accelerations without
    /// velocities, or a start state, limits or tolerance slice whose length is not the number
    /// of axes.
    #[error(
        "bad layout: the stride must be at least the number of axes, the position (velocity, \
         acceleration) slices must hold every point, accelerations need velocities, and the start \
         state, the limits and the tolerances need one value per axis"
    )]
    BadLayout,
    /// A position, velocity or acceleration (of a point, or of the start state: point 0) is NaN
    /// or infinite.
    #[error(
        "point {point}, axis {axis}: a value is not finite (NaN or infinite); send finite \
         positions, velocities and accelerations"
    )]
    NotFinite {
        /// The point (0 for the start state of the group).
        point: usize,
        /// The axis within the group.
        axis: usize,
    },
    /// A point's time is not finite, negative (point 0), or not after the previous point's.
    #[error(
        "point {point}: its time is not finite, negative or not after the previous point's; \
         times are seconds from the start of the trajectory, times[0] >= 0, then strictly \
         increasing"
    )]
    TimesNotIncreasing {
        /// The first point whose time is wrong.
        point: usize,
    },
    /// A point, or the path on the segment that ends at `point`, leaves the axis's range.
    #[error(
        "point {point}, axis {axis}: position {value} is outside the axis's range {min}..{max} \
         (at the point or on the way to it; point 0: the lead-in from the start); keep every \
         point, and the path between points, within the range"
    )]
    OutOfRange {
        /// The point (or the end of the segment) where it happens.
        point: usize,
        /// The axis within the group.
        axis: usize,
        /// The position outside the range (the extreme one on a segment).
        value: f64,
        /// The axis's lower limit.
        min: f64,
        /// The axis's upper limit.
        max: f64,
    },
    /// The path's velocity exceeds the axis's `max_velocity` on the segment that ends at
    /// `point`; a limit of 0 is the last point, whose velocity must be 0.
    #[error(
        "point {point}, axis {axis}: velocity {value} exceeds the limit {limit} on the segment \
         that ends at point {point} (point 0: the lead-in from the start state); give the points \
         more time or lower their velocities (a limit of 0: the last point, where a trajectory \
         must end at rest)"
    )]
    VelocityLimit {
        /// The point that ends the segment (0: the lead-in).
        point: usize,
        /// The axis within the group.
        axis: usize,
        /// The velocity of largest magnitude on the segment, signed.
        value: f64,
        /// The limit it exceeds.
        limit: f64,
    },
    /// The path's acceleration exceeds the axis's `max_accel` on the segment that ends at
    /// `point`; a limit of 0 is the last point, whose acceleration must be 0.
    #[error(
        "point {point}, axis {axis}: acceleration {value} exceeds the limit {limit} on the \
         segment that ends at point {point} (point 0: the lead-in from the start state); give \
         the points more time or smooth them (a limit of 0: the last point, where a trajectory \
         must end at rest)"
    )]
    AccelLimit {
        /// The point that ends the segment (0: the lead-in).
        point: usize,
        /// The axis within the group.
        axis: usize,
        /// The acceleration of largest magnitude on the segment, signed.
        value: f64,
        /// The limit it exceeds.
        limit: f64,
    },
    /// A trajectory through positions alone: its exact spline exceeds a limit, and the path
    /// blended at the points instead would pass `point` farther from it than the axis's path
    /// tolerance. The blend at a point is as short as every axis's `max_accel` allows (the
    /// same for every axis, so that they pass the point together): `blend` seconds, set by
    /// axis `by_axis`; an axis whose velocity changes by Δv passes at |Δv|·blend/8.
    #[error(
        "point {point}, axis {axis}: blended at the point, the path would pass it {distance} \
         away, beyond the axis's path tolerance {tolerance} (the blend lasts {blend} s, as \
         axis {by_axis}'s max_accel needs; the exact spline through the points exceeds a \
         limit); give the points more time, add points where the path turns, or send \
         velocities"
    )]
    BlendTolerance {
        /// The point (an interior one: the first and the last are passed exactly).
        point: usize,
        /// The axis within the group that would pass too far.
        axis: usize,
        /// How far it would pass the point.
        distance: f64,
        /// The axis's path tolerance.
        tolerance: f64,
        /// The blend's duration, seconds.
        blend: f64,
        /// The axis whose acceleration limit sets the blend's duration.
        by_axis: usize,
    },
    /// Point 0's time is 0 (no lead-in), but it is not where the axis is.
    #[error(
        "axis {axis}: point 0 is {distance} away from the current position (tolerance \
         {tolerance}) but its time is 0; start the trajectory at the current position, or give \
         point 0 a time > 0 for a lead-in"
    )]
    StartMismatch {
        /// The axis within the group.
        axis: usize,
        /// |point 0 − start position|.
        distance: f64,
        /// The tolerance it exceeds.
        tolerance: f64,
    },
    /// A velocity or acceleration scale of a line not in (0, 1].
    #[error("bad scale: a line's velocity and acceleration scales must be in (0, 1]")]
    BadScale,
    /// An axis's limits are unusable: `min > max`, a NaN, or `max_velocity` / `max_accel` not
    /// finite and positive.
    #[error(
        "axis {axis}: its limits are not usable; need min <= max (not NaN) and finite \
         max_velocity > 0 and max_accel > 0"
    )]
    BadLimits {
        /// The axis within the group.
        axis: usize,
    },
}
