//! A planned path: piecewise quintics per axis, planned from a line or from points, checked
//! exactly against the axes' limits, and sampled at any path time.

use crate::line::Profile;
use crate::points::{Kind, Start};
use crate::polynomial::{Span, cubic_hermite, eval, quintic_hermite};
use crate::segments::{Checker, Segments, feed_limit};
use crate::spline::Spline;
use crate::{AxisLimits, MAX_AXES, PathError, Points, Tolerances, check_limits};

/// What the segments between points are made from.
struct Build<'a> {
    points: &'a Points<'a>,
    kind: Kind,
    /// The velocities at the points of a spline through positions (three points or more).
    spline: &'a Spline,
    start_velocity: &'a [f64],
    lead_in: bool,
}

impl<'a> Build<'a> {
    /// Writes the segment from point k−1 to point k (k ≥ 1) of every axis. For a spline's
    /// last segment, the one before it must be written already.
    fn segment(&self, segments: &mut Segments, k: usize) {
        let points = self.points;
        let (n, axes) = (points.len(), segments.axes);
        let slot = usize::from(self.lead_in) + k - 1;
        let span = Span::new(segments.lengths[slot]);
        let stride = points.stride;
        let row = |values: &'a [f64], i: usize| -> &'a [f64] { &values[i * stride..][..axes] };
        let (p0, p1) = (row(points.positions, k - 1), row(points.positions, k));
        let (before, out) = segments.coeffs.split_at_mut(slot * axes);
        let out = &mut out[..axes];
        match (self.kind, points.velocities, points.accelerations) {
            (Kind::Accelerations, Some(v), Some(a)) => {
                let (v0, v1, a0, a1) = (row(v, k - 1), row(v, k), row(a, k - 1), row(a, k));
                for (j, c) in out.iter_mut().enumerate() {
                    *c = quintic_hermite([p0[j], v0[j], a0[j]], [p1[j], v1[j], a1[j]], &span);
                }
            }
            (Kind::Velocities, Some(v), _) => {
                let (v0, v1) = (row(v, k - 1), row(v, k));
                for (j, c) in out.iter_mut().enumerate() {
                    *c = cubic_hermite(p0[j], v0[j], p1[j], v1[j], &span);
                }
            }
            _ if n == 2 => {
                for (j, c) in out.iter_mut().enumerate() {
                    let v0 = if self.lead_in {
                        0.0
                    } else {
                        self.start_velocity[j]
                    };
                    *c = quintic_hermite([p0[j], v0, 0.0], [p1[j], 0.0, 0.0], &span);
                }
            }
            _ if k < n - 1 => {
                let m = |i: usize, j: usize| self.spline.velocity(i, j);
                for (j, c) in out.iter_mut().enumerate() {
                    *c = cubic_hermite(p0[j], m(k - 1, j), p1[j], m(k, j), &span);
                }
            }
            _ => {
                // The last: a quintic from the last cubic's end to rest.
                let cubics = &before[(slot - 1) * axes..];
                let h = segments.lengths[slot - 1];
                for (j, c) in out.iter_mut().enumerate() {
                    let a = eval(&cubics[j], h)[2];
                    let m = self.spline.velocity(k - 1, j);
                    *c = quintic_hermite([p0[j], m, a], [p1[j], 0.0, 0.0], &span);
                }
            }
        }
    }
}

/// A planned path for `axes` axes: piecewise polynomials (every segment stored as a quintic
/// per axis, c0..c5 in local time; lower-order segments have zero high coefficients), at most
/// `2 · max_points + 3` segments (a blended trajectory: a straight segment and a blend per
/// point).
///
/// Every buffer is sized in [`Path::new`]; planning and sampling never allocate. A path is
/// planned into a second set of buffers and swapped in only when it passed every check, so a
/// refused plan leaves the previous path untouched.
///
/// Serialized (the engine's state snapshot, `path_serde.rs`) as its sizes and the segments
/// in use; the planning scratch (the spline's solve, the checker's bounds) is not state.
pub struct Path {
    pub(crate) axes: usize,
    pub(crate) max_points: usize,
    pub(crate) active: Segments,
    pub(crate) draft: Segments,
    spline: Spline,
    /// Bounds on each segment and axis's |velocity| and |acceleration| (`Checker`).
    bounds: Vec<[f64; 2]>,
}

impl core::fmt::Debug for Path {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Path")
            .field("axes", &self.axes)
            .field("max_points", &self.max_points)
            .field("segments", &self.active.count)
            .field("duration", &self.active.duration)
            .field("max_feed", &self.active.max_feed)
            .field("end", &self.active.end)
            .finish()
    }
}

impl Path {
    /// An empty path for `axes` axes (1 ..= [`MAX_AXES`]) and trajectories of up to
    /// `max_points` points: the only allocation.
    ///
    /// # Panics
    /// When `axes` is 0 or more than [`MAX_AXES`].
    pub fn new(axes: usize, max_points: usize) -> Self {
        assert!(
            (1..=MAX_AXES).contains(&axes),
            "a path has 1 to {MAX_AXES} axes, not {axes}"
        );
        // A blended path: a lead-in or a start blend, n − 1 straight segments, n − 2 blends
        // and the end blend.
        let capacity = 2 * max_points + 3;
        Self {
            axes,
            max_points,
            active: Segments::new(axes, capacity),
            draft: Segments::new(axes, capacity),
            spline: Spline::new(max_points, axes),
            bounds: vec![[0.0; 2]; capacity * axes],
        }
    }

    /// The number of axes.
    pub fn axes(&self) -> usize {
        self.axes
    }

    /// The most points [`Path::plan_points`] accepts.
    pub fn max_points(&self) -> usize {
        self.max_points
    }

    /// Whether no path is planned (after [`Path::new`] or [`Path::clear`]). A planned path of
    /// duration 0 (a zero-length line) is not empty.
    pub fn is_empty(&self) -> bool {
        !self.active.planned
    }

    /// Forgets the path: empty, duration 0, `end()` all zeros.
    pub fn clear(&mut self) {
        self.active.clear();
    }

    /// Seconds at feed 1 (0 when empty).
    pub fn duration(&self) -> f64 {
        self.active.duration
    }

    /// The final positions (one per axis; zeros when empty).
    pub fn end(&self) -> &[f64] {
        &self.active.end
    }

    /// The largest feed (time-scale factor) at which the whole path keeps every axis within the
    /// limits it was planned with: the minimum over segments and axes of
    /// min(max_velocity / max|v|, √(max_accel / max|a|)), computed exactly when planned;
    /// `f64::INFINITY` for a path that does not move (and an empty one).
    pub fn max_feed(&self) -> f64 {
        self.active.max_feed
    }

    /// Straight line in joint space from `start` (at rest) to `target` (at rest): every axis on
    /// the same scalar profile s(t) in [0, 1] (trapezoidal, or triangular when short), so every
    /// axis starts and arrives at the same instant; the slowest axis sets the time:
    /// s' ≤ minᵢ(velocity_scale·vmaxᵢ/|Δᵢ|), s'' ≤ minᵢ(accel_scale·amaxᵢ/|Δᵢ|). Axes with Δ = 0
    /// stay put. A zero-length move is a valid path of duration 0.
    ///
    /// Refused: a scale not in (0, 1] ([`PathError::BadScale`]), slices whose length is not
    /// the number of axes ([`PathError::BadLayout`]), unusable limits, a start or target that
    /// is not finite ([`PathError::NotFinite`], point 0), a target outside min..max
    /// ([`PathError::OutOfRange`], point 0). The start may be outside the range (a line
    /// that brings an axis back into it); the line stays between start and target.
    pub fn plan_line(
        &mut self,
        start: &[f64],
        target: &[f64],
        limits: &[AxisLimits],
        velocity_scale: f64,
        accel_scale: f64,
    ) -> Result<(), PathError> {
        let in_unit = |x: f64| x > 0.0 && x <= 1.0;
        if !in_unit(velocity_scale) || !in_unit(accel_scale) {
            return Err(PathError::BadScale);
        }
        let axes = self.axes;
        if start.len() != axes || target.len() != axes || limits.len() != axes {
            return Err(PathError::BadLayout);
        }
        check_limits(limits)?;
        for axis in 0..axes {
            if !start[axis].is_finite() || !target[axis].is_finite() {
                return Err(PathError::NotFinite { point: 0, axis });
            }
        }
        for (axis, limit) in limits.iter().enumerate() {
            let value = target[axis];
            if !(value >= limit.min && value <= limit.max) {
                return Err(PathError::OutOfRange {
                    point: 0,
                    axis,
                    value,
                    min: limit.min,
                    max: limit.max,
                });
            }
        }
        let (mut rate, mut accel) = (f64::INFINITY, f64::INFINITY);
        for (axis, limit) in limits.iter().enumerate() {
            let distance = (target[axis] - start[axis]).abs();
            if distance > 0.0 {
                rate = rate.min(velocity_scale * limit.max_velocity / distance);
                accel = accel.min(accel_scale * limit.max_accel / distance);
            }
        }
        let draft = &mut self.draft;
        draft.clear();
        draft.end.copy_from_slice(target);
        draft.planned = true;
        // No axis moves (or only by amounts too small to time): a path of duration 0.
        if rate.is_finite() && accel.is_finite() {
            let profile = Profile::new(rate, accel);
            let Profile {
                peak,
                ramp_time,
                cruise_time,
                ramp_distance,
                ..
            } = profile;
            draft.push(0.0, ramp_time, 0);
            if cruise_time > 0.0 {
                draft.push(ramp_time, cruise_time, 0);
            }
            draft.push(ramp_time + cruise_time, ramp_time, 0);
            let decel = draft.count - 1;
            let mut max_feed = f64::INFINITY;
            for (axis, limit) in limits.iter().enumerate() {
                let (p0, delta) = (start[axis], target[axis] - start[axis]);
                *draft.coeffs_mut(0, axis) = [p0, 0.0, 0.5 * accel * delta, 0.0, 0.0, 0.0];
                if cruise_time > 0.0 {
                    *draft.coeffs_mut(1, axis) =
                        [p0 + ramp_distance * delta, peak * delta, 0.0, 0.0, 0.0, 0.0];
                }
                *draft.coeffs_mut(decel, axis) = [
                    p0 + (1.0 - ramp_distance) * delta,
                    peak * delta,
                    -0.5 * accel * delta,
                    0.0,
                    0.0,
                    0.0,
                ];
                max_feed = max_feed.min(feed_limit(peak * delta, accel * delta, limit));
            }
            draft.duration = profile.duration();
            draft.max_feed = max_feed;
        }
        core::mem::swap(&mut self.active, &mut self.draft);
        Ok(())
    }

    /// A trajectory from the current state (`start_position` / `start_velocity` /
    /// `start_acceleration`, one value per axis) through `points`.
    ///
    /// - Lead-in: when `times[0] > 0`, a quintic from the start state to point 0 over
    ///   `times[0]` seconds (matching position, velocity and acceleration at both ends; point
    ///   0's velocity and acceleration are those the path has when it leaves point 0). When
    ///   `times[0] == 0` there is no lead-in: point 0 must be within
    ///   `tolerances.start[axis]` of `start_position` ([`PathError::StartMismatch`]) and the
    ///   path starts at point 0's values.
    /// - Between points: with velocities and accelerations, quintic Hermite (C2); with
    ///   velocities only, cubic Hermite (C1: the acceleration jumps at the points, and to 0 at
    ///   the end); positions only, a C2 spline through the points: cubics, except for a last
    ///   quintic segment so that it ends at rest with velocity 0 and acceleration 0 (the
    ///   conditions and the solve: `spline.rs`). Its velocity at point 0 is the start
    ///   velocity without a lead-in, and its acceleration at point 0 is 0 with one.
    /// - Positions only, when that spline exceeds a limit (velocity, acceleration or range,
    ///   the lead-in's included): blended at the points instead (`blend.rs`). Straight
    ///   segments between the points, each axis at its segment's Δp/Δt, with a parabolic
    ///   blend centred on each interior point, as short as every axis's `max_accel` allows
    ///   and the same for every axis, so that the points' times are kept; an axis whose
    ///   velocity changes by Δv passes the point at |Δv|·blend/8, which must be within
    ///   `tolerances.path[axis]` ([`PathError::BlendTolerance`], naming the point and the
    ///   axis). The lead-in arrives at point 0 with the first segment's velocity; without
    ///   one, a blend from the start velocity leaves point 0; a last blend arrives exactly at
    ///   the last point, at rest. Blends that do not fit between their neighbours, or ends
    ///   too short for `max_accel`, are [`PathError::AccelLimit`]; a straight segment over
    ///   `max_velocity` is [`PathError::VelocityLimit`]. The blended path is C1 (the
    ///   acceleration steps at the ends of the blends) and goes through the same exact
    ///   checks; the spline, when it fits, is kept (it passes the points exactly).
    /// - The last point ends at rest: with velocities its velocity must be 0 (else
    ///   [`PathError::VelocityLimit`] at the last point, limit 0), with accelerations its
    ///   acceleration too ([`PathError::AccelLimit`], limit 0).
    ///
    /// Checked before anything changes (a refused plan leaves the previous path untouched):
    /// the layout, the limits, finite values, increasing times, every point within min..max,
    /// and on every segment, exactly (analytic extrema, not sampling), the largest |velocity|
    /// and |acceleration| against the limits (relative slack 10⁻⁹) and the position against
    /// min..max. The start state must be finite, and the lead-in must stay within min..max
    /// too. Refusals name the point and the axis. `tolerances` holds one value per axis in
    /// each slice ([`PathError::BadLayout`] otherwise).
    pub fn plan_points(
        &mut self,
        start_position: &[f64],
        start_velocity: &[f64],
        start_acceleration: &[f64],
        points: &Points<'_>,
        limits: &[AxisLimits],
        tolerances: &Tolerances<'_>,
    ) -> Result<(), PathError> {
        let start = Start {
            position: start_position,
            velocity: start_velocity,
            acceleration: start_acceleration,
            tolerance: tolerances.start,
            path_tolerance: tolerances.path,
        };
        points.check(self.axes, self.max_points, limits, &start)?;
        match self.plan_exact(points, limits, &start) {
            Err(
                PathError::VelocityLimit { .. }
                | PathError::AccelLimit { .. }
                | PathError::OutOfRange { .. },
            ) if points.kind() == Kind::Positions && points.len() >= 2 => {
                crate::blend::plan(&mut self.draft, &mut self.bounds, points, limits, &start)?;
            }
            exact => exact?,
        }
        core::mem::swap(&mut self.active, &mut self.draft);
        Ok(())
    }

    /// Plans the segments through the points exactly (Hermite segments, or the spline) into
    /// the draft.
    fn plan_exact(
        &mut self,
        points: &Points<'_>,
        limits: &[AxisLimits],
        start: &Start<'_>,
    ) -> Result<(), PathError> {
        let axes = self.axes;
        let (start_position, start_velocity, start_acceleration) =
            (start.position, start.velocity, start.acceleration);
        let times = points.times;
        let n = points.len();
        let lead_in = times[0] > 0.0;
        let kind = points.kind();
        if kind == Kind::Positions && n >= 3 {
            let clamp = (!lead_in).then_some(start_velocity);
            self.spline
                .solve(times, |i, axis| points.position(i, axis), clamp);
        }

        let draft = &mut self.draft;
        draft.clear();
        draft.planned = true;
        draft.duration = times[n - 1];
        draft.last_point = n - 1;
        for (axis, end) in draft.end.iter_mut().enumerate() {
            *end = points.position(n - 1, axis);
        }
        if lead_in {
            draft.push(0.0, times[0], 0);
        }
        for k in 1..n {
            draft.push(times[k - 1], times[k] - times[k - 1], k);
        }
        let build = Build {
            points,
            kind,
            spline: &self.spline,
            start_velocity,
            lead_in,
        };
        let mut checker = Checker::new(limits, &mut self.bounds);
        // The segment that leaves point 0 comes first: the lead-in meets its start.
        let first = usize::from(lead_in);
        if n > 1 {
            build.segment(draft, 1);
        }
        if lead_in {
            for axis in 0..axes {
                let leave = if n > 1 {
                    eval(draft.coeffs(first, axis), 0.0)
                } else {
                    let p = points.position(0, axis);
                    [p, points.velocity(0, axis), points.acceleration(0, axis)]
                };
                let from = [
                    start_position[axis],
                    start_velocity[axis],
                    start_acceleration[axis],
                ];
                *draft.coeffs_mut(0, axis) = quintic_hermite(from, leave, &Span::new(times[0]));
            }
            checker.check(draft, 0)?;
        }
        for k in 1..n {
            if k > 1 {
                build.segment(draft, k);
            }
            checker.check(draft, first + k - 1)?;
        }
        draft.max_feed = checker.max_feed(draft);
        Ok(())
    }

    /// The state at path time `t` (clamped to 0 ..= duration) at feed 1: writes position,
    /// velocity and acceleration (the first `axes` values of each) and returns the index of
    /// the point the current segment heads to (0 during the lead-in; for a line: 0; a blend
    /// at a point: that point, until the blend ends). At or
    /// past the end: [`Path::end`], at rest, and the last point. An empty path gives `end()`
    /// (zeros), at rest, and 0.
    ///
    /// # Panics
    /// When a slice is shorter than the number of axes.
    pub fn sample(
        &self,
        t: f64,
        position: &mut [f64],
        velocity: &mut [f64],
        acceleration: &mut [f64],
    ) -> usize {
        let axes = self.axes;
        let (position, velocity, acceleration) = (
            &mut position[..axes],
            &mut velocity[..axes],
            &mut acceleration[..axes],
        );
        let s = &self.active;
        match s.locate(t) {
            None => {
                position.copy_from_slice(&s.end);
                velocity.fill(0.0);
                acceleration.fill(0.0);
                s.last_point
            }
            Some((segment, u)) => {
                for axis in 0..axes {
                    let [p, v, a] = eval(s.coeffs(segment, axis), u);
                    position[axis] = p;
                    velocity[axis] = v;
                    acceleration[axis] = a;
                }
                s.heads[segment]
            }
        }
    }

    /// The segment and local time at path time `t` (`None` at or past the end).
    pub(crate) fn locate(&self, t: f64) -> Option<(usize, f64)> {
        self.active.locate(t)
    }

    /// Position, velocity and acceleration of `axis` on `segment` at local time `u`.
    #[inline]
    pub(crate) fn state(&self, segment: usize, axis: usize, u: f64) -> [f64; 3] {
        eval(self.active.coeffs(segment, axis), u)
    }

    /// The number of segments.
    pub(crate) fn segments(&self) -> usize {
        self.active.count
    }

    /// Path time at which `segment` starts, and its duration.
    pub(crate) fn segment_span(&self, segment: usize) -> (f64, f64) {
        (self.active.starts[segment], self.active.lengths[segment])
    }

    /// The first segment that starts after path time `t` (`segments()` if none).
    pub(crate) fn segment_after(&self, t: f64) -> usize {
        self.active.starts[..self.active.count].partition_point(|&s| s <= t)
    }
}
