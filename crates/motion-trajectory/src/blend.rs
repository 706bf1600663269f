//! A trajectory through positions alone whose exact spline exceeds a limit: straight segments
//! between the points with parabolic blends at them (linear segments with parabolic blends
//! through via points), keeping the times of the points.
//!
//! Every axis moves at its segment's velocity Δp/Δt between the blends. At an interior point
//! i the blend is centred on tᵢ and lasts bᵢ = maxⱼ |Δvⱼ| / max_accelⱼ — the shortest that
//! keeps every axis within its acceleration limit, the same for every axis of the group so
//! that they all pass the point at tᵢ — and the path passes the point at |Δvⱼ|·bᵢ/8 from it,
//! which must be within the axis's path tolerance.
//!
//! The ends keep the group's state and the goal:
//! - with a lead-in (times[0] > 0) the lead-in quintic arrives at point 0 with the first
//!   segment's velocity and acceleration 0: the path passes point 0 exactly;
//! - without one it starts at point 0 with the start velocity w and blends, from t₀ over b₀,
//!   into a straight segment that passes point 1 at t₁ (a blend centred on a virtual corner at
//!   t₀ + b₀/2, p₀ + w·b₀/2);
//! - it arrives at the last point exactly, at rest: the last straight segment heads to a
//!   virtual corner at (tₙ₋₁ − bₙ₋₁/2, pₙ₋₁) and the blend centred there ends at tₙ₋₁ with
//!   velocity 0.
//!
//! Both end blends are the shortest within every axis's acceleration limit: a segment of
//! duration h that covers d (d − w·h from a start velocity w) with one end blend of duration
//! b needs |d| / ((h − b/2)·b), so b = h − √(h² − 2|d|/max_accel) (two points without a
//! lead-in: one duration at both ends, found by bisection). Every segment is then checked
//! exactly like any other path (`Checker`): velocities, accelerations, positions.

use crate::points::{Points, Start};
use crate::polynomial::{Span, quintic_hermite};
use crate::segments::{Checker, SLACK, Segments};
use crate::{AxisLimits, PathError, at_most};

/// The blend durations at the ends and the anchors the straight segments go through.
struct Plan<'a> {
    points: &'a Points<'a>,
    limits: &'a [AxisLimits],
    start: &'a Start<'a>,
    n: usize,
    /// The blend at point 0 (0 with a lead-in) and the axis that sets it.
    first: (f64, usize),
    /// The blend to rest at the last point and the axis that sets it.
    last: (f64, usize),
}

impl Plan<'_> {
    /// The time of the corner the straight segments meet at point i.
    fn time(&self, i: usize) -> f64 {
        let t = self.points.times[i];
        if i == 0 {
            t + 0.5 * self.first.0
        } else if i == self.n - 1 {
            t - 0.5 * self.last.0
        } else {
            t
        }
    }

    /// The position of the corner the straight segments meet at point i.
    fn position(&self, i: usize, axis: usize) -> f64 {
        let p = self.points.position(i, axis);
        if i == 0 {
            p + 0.5 * self.first.0 * self.start.velocity[axis]
        } else {
            p
        }
    }

    /// The velocity of straight segment k (from point k−1 to point k, 1 ≤ k ≤ n−1); before it
    /// (k = 0) the start velocity, after it (k = n) 0.
    fn velocity(&self, k: usize, axis: usize) -> f64 {
        if k == 0 {
            self.start.velocity[axis]
        } else if k >= self.n {
            0.0
        } else {
            let dt = self.time(k) - self.time(k - 1);
            (self.position(k, axis) - self.position(k - 1, axis)) / dt
        }
    }

    /// The blend at point i (its duration, 0 for none) and the axis that sets it.
    fn width(&self, i: usize) -> (f64, usize) {
        if i == 0 {
            return self.first;
        }
        if i == self.n - 1 {
            return self.last;
        }
        let mut widest = (0.0, 0);
        for (axis, limit) in self.limits.iter().enumerate() {
            let change = (self.velocity(i + 1, axis) - self.velocity(i, axis)).abs();
            let b = change / limit.max_accel;
            if b > widest.0 {
                widest = (b, axis);
            }
        }
        widest
    }
}

/// The shortest blend at one end of a segment of duration `h` within every axis's
/// acceleration limit, when axis j must cover `d(j)` beyond what its velocity at the far end
/// carries it; refused at `point` when the whole segment is too short.
fn end_blend(
    limits: &[AxisLimits],
    h: f64,
    d: impl Fn(usize) -> f64,
    point: usize,
) -> Result<(f64, usize), PathError> {
    let mut widest = (0.0, 0);
    for (axis, limit) in limits.iter().enumerate() {
        let d = d(axis).abs();
        let x = 2.0 * d / limit.max_accel;
        if x == 0.0 {
            continue;
        }
        let b = x / (h + (h * h - x).sqrt());
        // NaN (x > h²), or a figure too small or large to time.
        if !(b > 0.0 && b <= h) {
            return Err(PathError::AccelLimit {
                point,
                axis,
                value: 2.0 * d / (h * h),
                limit: limit.max_accel,
            });
        }
        if b > widest.0 {
            widest = (b, axis);
        }
    }
    Ok(widest)
}

/// Two points without a lead-in: one blend duration b at both ends of the single segment (from
/// the start velocity, to rest), the shortest found by bisection within (0, h/2].
fn both_ends(plan: &Plan<'_>) -> Result<(f64, usize), PathError> {
    let points = plan.points;
    let h = points.times[1] - points.times[0];
    // The largest acceleration relative to its limit, the axis and its acceleration.
    let need = |b: f64| {
        let mut worst = (0.0, 0, 0.0);
        for (axis, limit) in plan.limits.iter().enumerate() {
            let w = plan.start.velocity[axis];
            let d = points.position(1, axis) - points.position(0, axis);
            let u = (d - 0.5 * w * b) / (h - b);
            let a = (u - w).abs().max(u.abs()) / b;
            let ratio = a / limit.max_accel;
            if !at_most(ratio, worst.0) {
                worst = (ratio, axis, a);
            }
        }
        worst
    };
    let moves = (0..plan.limits.len()).any(|axis| {
        plan.start.velocity[axis] != 0.0 || points.position(1, axis) != points.position(0, axis)
    });
    if !moves {
        return Ok((0.0, 0));
    }
    let (ratio, axis, value) = need(0.5 * h);
    if !at_most(ratio, 1.0) {
        return Err(PathError::AccelLimit {
            point: 1,
            axis,
            value,
            limit: plan.limits[axis].max_accel,
        });
    }
    let (mut low, mut high) = (0.0, 0.5 * h);
    for _ in 0..100 {
        let middle = 0.5 * (low + high);
        if !(middle > low && middle < high) {
            break;
        }
        if need(middle).0 <= 1.0 {
            high = middle;
        } else {
            low = middle;
        }
    }
    Ok((high, need(high).1))
}

/// Plans the blended path through `points` (at least two, positions only, checked by
/// `Points::check`) into `draft`, checking every segment with a `Checker` over `bounds` and
/// every interior point against the axes' path tolerances.
pub(crate) fn plan(
    draft: &mut Segments,
    bounds: &mut [[f64; 2]],
    points: &Points<'_>,
    limits: &[AxisLimits],
    start: &Start<'_>,
) -> Result<(), PathError> {
    let (n, times) = (points.len(), points.times);
    let lead_in = times[0] > 0.0;
    let mut plan = Plan {
        points,
        limits,
        start,
        n,
        first: (0.0, 0),
        last: (0.0, 0),
    };
    if n == 2 && !lead_in {
        let both = both_ends(&plan)?;
        plan.first = both;
        plan.last = both;
    } else {
        let h = times[n - 1] - times[n - 2];
        let d = |axis: usize| points.position(n - 1, axis) - points.position(n - 2, axis);
        plan.last = end_blend(limits, h, d, n - 1)?;
        if !lead_in {
            let h = times[1] - times[0];
            let d = |axis: usize| {
                points.position(1, axis) - points.position(0, axis) - start.velocity[axis] * h
            };
            plan.first = end_blend(limits, h, d, 1)?;
        }
    }

    // A straight segment over an axis's velocity limit: no blend helps.
    for k in 1..n {
        for (axis, limit) in limits.iter().enumerate() {
            let value = plan.velocity(k, axis);
            if !at_most(value.abs(), limit.max_velocity * (1.0 + SLACK)) {
                return Err(PathError::VelocityLimit {
                    point: k,
                    axis,
                    value,
                    limit: limit.max_velocity,
                });
            }
        }
    }

    draft.clear();
    draft.planned = true;
    draft.duration = times[n - 1];
    draft.last_point = n - 1;
    for (axis, end) in draft.end.iter_mut().enumerate() {
        *end = points.position(n - 1, axis);
    }
    let axes = draft.axes;
    let mut checker = Checker::new(limits, bounds);
    if lead_in {
        draft.push(0.0, times[0], 0);
        let span = Span::new(times[0]);
        for axis in 0..axes {
            let from = [
                start.position[axis],
                start.velocity[axis],
                start.acceleration[axis],
            ];
            let to = [points.position(0, axis), plan.velocity(1, axis), 0.0];
            *draft.coeffs_mut(0, axis) = quintic_hermite(from, to, &span);
        }
        checker.check(draft, 0)?;
    } else if plan.first.0 > 0.0 {
        let b = plan.first.0;
        blend(draft, &plan, 0, times[0], times[0] + b, 1);
        checker.check(draft, draft.count - 1)?;
    }
    for k in 1..n {
        let (before, after) = (plan.width(k - 1).0, plan.width(k));
        let (t0, t1) = (plan.time(k - 1), plan.time(k));
        // The straight segment between the blends.
        let (from, to) = (t0 + 0.5 * before, t1 - 0.5 * after.0);
        if !at_most(0.5 * before + 0.5 * after.0, t1 - t0) {
            // The blends overlap: name the longer one, with the acceleration it would need to
            // fit within the segment.
            let (longer, axis) = if after.0 >= before {
                (k, after.1)
            } else {
                (k - 1, plan.width(k - 1).1)
            };
            let change = (plan.velocity(longer + 1, axis) - plan.velocity(longer, axis)).abs();
            return Err(PathError::AccelLimit {
                point: k,
                axis,
                value: change / (t1 - t0),
                limit: limits[axis].max_accel,
            });
        }
        if to > from {
            let s = draft.count;
            draft.push(from, to - from, k);
            for axis in 0..axes {
                let u = plan.velocity(k, axis);
                let p = plan.position(k - 1, axis) + u * (from - t0);
                *draft.coeffs_mut(s, axis) = [p, u, 0.0, 0.0, 0.0, 0.0];
            }
            checker.check(draft, s)?;
        }
        if after.0 > 0.0 {
            let b = after.0;
            if k < n - 1 {
                for axis in 0..axes {
                    let change = plan.velocity(k + 1, axis) - plan.velocity(k, axis);
                    let distance = change.abs() * b / 8.0;
                    let tolerance = start.path_tolerance[axis];
                    if !at_most(distance, tolerance) {
                        return Err(PathError::BlendTolerance {
                            point: k,
                            axis,
                            distance,
                            tolerance,
                            blend: b,
                            by_axis: after.1,
                        });
                    }
                }
            }
            let end = if k == n - 1 {
                times[n - 1]
            } else {
                t1 + 0.5 * b
            };
            blend(draft, &plan, k, to, end, k);
            checker.check(draft, draft.count - 1)?;
        }
    }
    draft.max_feed = checker.max_feed(draft);
    Ok(())
}

/// Appends the blend at point i, from path time `from` to `to`, heading to point `heads`:
/// from the velocity before the point to the one after it at a constant acceleration, tangent
/// to the straight segments (or the start state, or rest) on both sides.
fn blend(draft: &mut Segments, plan: &Plan<'_>, i: usize, from: f64, to: f64, heads: usize) {
    let s = draft.count;
    draft.push(from, to - from, heads);
    let b = plan.width(i).0;
    for axis in 0..draft.axes {
        let (before, after) = (plan.velocity(i, axis), plan.velocity(i + 1, axis));
        // Tangent to the segment before at half the blend before its corner (point 0: the
        // point itself).
        let p = if i == 0 {
            plan.points.position(0, axis)
        } else {
            plan.position(i, axis) - 0.5 * b * before
        };
        *draft.coeffs_mut(s, axis) = [p, before, 0.5 * (after - before) / b, 0.0, 0.0, 0.0];
    }
}
