//! The segments of a path, planned or being planned (per axis a quintic's coefficients
//! for each segment, where each starts, how long it lasts and which point it heads to:
//! [`Segments`]), and their exact check against the axes' limits, which also gives the
//! path's largest feed ([`Checker`]); the slack of those checks ([`SLACK`],
//! [`range_slack`]). The planners write the segments (`path.rs` from a line or points,
//! `blend.rs` its blends) and `Path` samples them.

use crate::polynomial::{Coeffs, Span, extremes, hull_bounds};
use crate::{AxisLimits, MAX_AXES, PathError, at_most};

/// The relative slack of the limit checks: a segment whose largest |velocity| is at most
/// `max_velocity · (1 + SLACK)` (and likewise the acceleration) is accepted.
pub(crate) const SLACK: f64 = 1e-9;

/// The rounding a position may have beyond a soft limit: `SLACK` of the axis's range (at
/// least of one unit), so that a path that starts or ends exactly at a limit is not refused
/// for 10⁻²³ of floating-point noise.
pub(crate) fn range_slack(limit: &AxisLimits) -> f64 {
    let span = limit.max - limit.min;
    if span.is_finite() {
        SLACK * span.max(1.0)
    } else {
        0.0
    }
}

/// The segments of one planned path (or of one being planned).
#[derive(Clone)]
pub(crate) struct Segments {
    pub(crate) axes: usize,
    pub(crate) count: usize,
    /// Segment s, axis j at `s * axes + j`.
    pub(crate) coeffs: Vec<Coeffs>,
    /// Path time at which each segment starts.
    pub(crate) starts: Vec<f64>,
    /// Each segment's duration.
    pub(crate) lengths: Vec<f64>,
    /// The point each segment heads to.
    pub(crate) heads: Vec<usize>,
    pub(crate) end: Vec<f64>,
    pub(crate) duration: f64,
    pub(crate) max_feed: f64,
    pub(crate) last_point: usize,
    pub(crate) planned: bool,
}

impl Segments {
    pub(crate) fn new(axes: usize, capacity: usize) -> Self {
        Self {
            axes,
            count: 0,
            coeffs: vec![[0.0; 6]; capacity * axes],
            starts: vec![0.0; capacity],
            lengths: vec![0.0; capacity],
            heads: vec![0; capacity],
            end: vec![0.0; axes],
            duration: 0.0,
            max_feed: f64::INFINITY,
            last_point: 0,
            planned: false,
        }
    }

    pub(crate) fn clear(&mut self) {
        self.count = 0;
        self.end.fill(0.0);
        self.duration = 0.0;
        self.max_feed = f64::INFINITY;
        self.last_point = 0;
        self.planned = false;
    }

    /// Appends a segment (its coefficients are written afterwards).
    pub(crate) fn push(&mut self, start: f64, length: f64, heads: usize) {
        let s = self.count;
        self.starts[s] = start;
        self.lengths[s] = length;
        self.heads[s] = heads;
        self.count += 1;
    }

    #[inline]
    pub(crate) fn coeffs(&self, segment: usize, axis: usize) -> &Coeffs {
        &self.coeffs[segment * self.axes + axis]
    }

    #[inline]
    pub(crate) fn coeffs_mut(&mut self, segment: usize, axis: usize) -> &mut Coeffs {
        &mut self.coeffs[segment * self.axes + axis]
    }

    /// The segment and local time at path time `t`; `None` at or past the end (and when
    /// nothing is planned).
    pub(crate) fn locate(&self, t: f64) -> Option<(usize, f64)> {
        let t = if t > 0.0 { t } else { 0.0 };
        let inside = self.planned && self.count > 0 && t < self.duration;
        if !inside {
            return None;
        }
        let segment = self.starts[..self.count]
            .partition_point(|&s| s <= t)
            .saturating_sub(1);
        Some((segment, t - self.starts[segment]))
    }
}

/// The largest feed at which velocity `v` and acceleration `a` (at feed 1) stay within `limit`.
pub(crate) fn feed_limit(v: f64, a: f64, limit: &AxisLimits) -> f64 {
    let by_velocity = if v != 0.0 {
        limit.max_velocity / v.abs()
    } else {
        f64::INFINITY
    };
    let by_accel = if a != 0.0 {
        (limit.max_accel / a.abs()).sqrt()
    } else {
        f64::INFINITY
    };
    by_velocity.min(by_accel)
}

/// The limit checks of a path being planned, segment by segment as they are built, and its
/// `max_feed`.
///
/// A segment passes at once when the hulls of its Bernstein coefficients (`hull_bounds`)
/// are within the limits; otherwise its exact extremes decide. Each segment and axis keeps
/// its bounds on |velocity| and |acceleration| — from the hulls, or exact — and
/// [`Checker::max_feed`] refines only those bounds that could exceed an axis's exact
/// largest |velocity| or |acceleration| over the path, so `max_feed` is exact at the cost of
/// a few exact extremes.
pub(crate) struct Checker<'a> {
    limits: &'a [AxisLimits],
    /// Segment s, axis j at `s * axes + j`: bounds on |velocity| and |acceleration|.
    bounds: &'a mut [[f64; 2]],
    /// Per axis, the largest bound on |velocity| and on |acceleration| so far, and the
    /// segment it belongs to.
    largest: [[(f64, usize); 2]; MAX_AXES],
}

impl<'a> Checker<'a> {
    pub(crate) fn new(limits: &'a [AxisLimits], bounds: &'a mut [[f64; 2]]) -> Self {
        Self {
            limits,
            bounds,
            largest: [[(0.0, 0); 2]; MAX_AXES],
        }
    }

    /// Checks every axis of `segment`; refusals name the point it heads to and the axis.
    pub(crate) fn check(&mut self, segments: &Segments, segment: usize) -> Result<(), PathError> {
        let t = segments.lengths[segment];
        let span = Span::new(t);
        let point = segments.heads[segment];
        let axes = segments.axes;
        let coeffs = &segments.coeffs[segment * axes..][..axes];
        let bounds = &mut self.bounds[segment * axes..][..axes];
        let each = self
            .limits
            .iter()
            .zip(coeffs)
            .zip(bounds)
            .zip(&mut self.largest);
        for (axis, (((limit, c), bound), largest)) in each.enumerate() {
            let (v_limit, a_limit) = (
                limit.max_velocity * (1.0 + SLACK),
                limit.max_accel * (1.0 + SLACK),
            );
            let slack = range_slack(limit);
            let (min, max) = (limit.min - slack, limit.max + slack);
            *bound = match hull_bounds(c, &span, min, max) {
                Some((v, a)) if v <= v_limit && a <= a_limit => [v, a],
                _ => {
                    let e = extremes(c, t, min, max);
                    if !at_most(e.velocity.abs(), v_limit) {
                        return Err(PathError::VelocityLimit {
                            point,
                            axis,
                            value: e.velocity,
                            limit: limit.max_velocity,
                        });
                    }
                    if !at_most(e.acceleration.abs(), a_limit) {
                        return Err(PathError::AccelLimit {
                            point,
                            axis,
                            value: e.acceleration,
                            limit: limit.max_accel,
                        });
                    }
                    if let Some(value) = e.outside {
                        return Err(PathError::OutOfRange {
                            point,
                            axis,
                            value,
                            min: limit.min,
                            max: limit.max,
                        });
                    }
                    [e.velocity.abs(), e.acceleration.abs()]
                }
            };
            for (largest, &bound) in largest.iter_mut().zip(bound.iter()) {
                if bound > largest.0 {
                    *largest = (bound, segment);
                }
            }
        }
        Ok(())
    }

    /// The exact largest feed of the checked `segments`: per axis, the exact largest
    /// |velocity| and |acceleration| over the path give min(max_velocity/|v|, √(max_accel/|a|)).
    pub(crate) fn max_feed(&self, segments: &Segments) -> f64 {
        let axes = segments.axes;
        let exact = |segment: usize, axis: usize| {
            let e = extremes(
                segments.coeffs(segment, axis),
                segments.lengths[segment],
                f64::NEG_INFINITY,
                f64::INFINITY,
            );
            [e.velocity.abs(), e.acceleration.abs()]
        };
        // Start from the segment with the largest bound (most likely the largest exact
        // figure), then refine every bound above the largest exact figure so far.
        let mut largest = [[0.0; 2]; MAX_AXES];
        for (axis, largest) in largest[..axes].iter_mut().enumerate() {
            for (which, largest) in largest.iter_mut().enumerate() {
                let (bound, segment) = self.largest[axis][which];
                if bound > 0.0 {
                    *largest = exact(segment, axis)[which];
                }
            }
        }
        let rows = self.bounds[..segments.count * axes].chunks_exact(axes);
        for (segment, row) in rows.enumerate() {
            for (axis, (bound, largest)) in row.iter().zip(&mut largest).enumerate() {
                if bound[0] > largest[0] || bound[1] > largest[1] {
                    let e = exact(segment, axis);
                    *largest = [largest[0].max(e[0]), largest[1].max(e[1])];
                }
            }
        }
        self.limits
            .iter()
            .zip(&largest)
            .map(|(limit, &[v, a])| feed_limit(v, a, limit))
            .fold(f64::INFINITY, f64::min)
    }
}
