//! Feed override and feed hold as time scaling: path time τ advances by feed·dt each tick,
//! and the feed changes no faster than every axis's acceleration limit allows.
//!
//! Along a path p(τ) followed at feed f = dτ/dt, an axis's velocity is p'·f and its
//! acceleration p''·f² + p'·ḟ. With f ≤ the path's `max_feed`, |p''|·f² ≤ max_accel
//! everywhere, so ḟ = 0 is always allowed: the feed can always be held, and a hold (target 0)
//! lowers it at the most negative ḟ the axes allow. Where an axis already decelerates at its
//! limit (the end of a line at full feed) the feed cannot drop at all and the group rides the
//! path's own deceleration; every path ends at rest, where p' = 0 bounds nothing, so a hold
//! always reaches feed 0 in finite time.
//!
//! Each step chooses the new feed F (ḟ = (F − f)/dt constant over the tick, τ advancing by
//! (f + F)/2·dt) so that the acceleration is within the limits at both ends of the tick — at
//! its start (τ, f; linear in F, solved in closed form) and at its end (τ + (f + F)/2·dt, F)
//! — and on both sides of every segment boundary the tick crosses (where the feed is
//! √(f² + 2ḟ·Δτ)). The start gives a candidate F; when the later instants refuse it, F is
//! searched between f (always allowed) and the candidate by regula falsi (Illinois) on the
//! largest relative excess over the limits, keeping the allowed end. Within a segment between
//! those instants the polynomials are smooth, so what is left is a discretisation error of the
//! order of the change over one tick.

use crate::segments::SLACK;
use crate::{AxisLimits, Path};

/// The largest feed override: 150 %.
pub const MAX_FEED_OVERRIDE: f64 = 1.5;

/// Steps at most of the search for the new feed when the end of the tick refuses the
/// candidate (it usually ends within a handful).
const SEARCH_STEPS: usize = 60;

/// The search stops when the allowed feed is within this much (relative) of a limit.
const SEARCH_TOLERANCE: f64 = 1e-9;

/// Feed override and hold: path time τ advances by feed·dt each tick.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq)]
pub struct TimeScale {
    tau: f64,
    feed: f64,
    target: f64,
    feed_rate: f64,
}

impl Default for TimeScale {
    fn default() -> Self {
        Self::new()
    }
}

/// A feed as [`TimeScale`] keeps it: within 0 ..= 1.5, NaN as 0 (hold).
fn clamp_feed(feed: f64) -> f64 {
    if feed > 0.0 {
        feed.min(MAX_FEED_OVERRIDE)
    } else {
        0.0
    }
}

/// τ after a tick of `dt` from feed `f` to feed `next`.
#[inline]
fn advance(tau: f64, f: f64, next: f64, dt: f64, duration: f64) -> f64 {
    (tau + 0.5 * (f + next) * dt).min(duration)
}

/// How far velocity `v` and acceleration `a` at feed 1 exceed `limit` at feed `feed` while
/// the feed changes at `rate`, relative to the limits (≤ 0: within; NaN: not finite).
#[inline]
fn excess(v: f64, a: f64, feed: f64, rate: f64, limit: &AxisLimits) -> f64 {
    let accel = (a * feed * feed + v * rate).abs() / limit.max_accel - (1.0 + SLACK);
    let velocity = (v * feed).abs() / limit.max_velocity - (1.0 + SLACK);
    larger(accel, velocity)
}

/// The larger of two excesses; NaN (not finite) wins.
#[inline]
fn larger(a: f64, b: f64) -> f64 {
    if a.is_nan() || b > a { b } else { a }
}

impl TimeScale {
    /// τ = 0, feed 1, target 1.
    pub fn new() -> Self {
        Self {
            tau: 0.0,
            feed: 1.0,
            target: 1.0,
            feed_rate: 0.0,
        }
    }

    /// τ = 0, feed = target = `feed` (clamped to 0 ..= 1.5): a new path starts at the set
    /// feed, capped by the path's `max_feed` at the next [`TimeScale::step`].
    pub fn restart(&mut self, feed: f64) {
        let feed = clamp_feed(feed);
        *self = Self {
            tau: 0.0,
            feed,
            target: feed,
            feed_rate: 0.0,
        };
    }

    /// The feed to move to: 0 holds, 1 is the planned speed; clamped to 0 ..= 1.5 (NaN: 0).
    pub fn set_target(&mut self, feed: f64) {
        self.target = clamp_feed(feed);
    }

    /// The feed set by [`TimeScale::set_target`].
    pub fn target(&self) -> f64 {
        self.target
    }

    /// The current (effective) feed.
    pub fn feed(&self) -> f64 {
        self.feed
    }

    /// The rate of change of the feed over the last step (ḟ, per second).
    pub fn feed_rate(&self) -> f64 {
        self.feed_rate
    }

    /// Path time τ.
    pub fn time(&self) -> f64 {
        self.tau
    }

    /// Whether the feed is 0 (held).
    pub fn at_rest(&self) -> bool {
        self.feed == 0.0
    }

    /// Whether τ reached the path's duration.
    pub fn finished(&self, path: &Path) -> bool {
        self.tau >= path.duration()
    }

    /// One tick of `dt` seconds (nothing when `dt` is not positive and finite): the effective
    /// target is min(target, `path.max_feed()`) (a feed above `max_feed` is cut to it first);
    /// the feed moves toward it at the largest rate ḟ that keeps every axis's acceleration
    /// p''·f² + p'·ḟ within ±max_accel and |p'·f| within max_velocity (module docs: at the
    /// tick's start, its end, and across segment boundaries; axes with p' = 0 give no bound on
    /// ḟ); τ += (old + new feed)/2 · dt, clamped to the duration. A hold snaps to exactly 0.
    /// No allocation.
    ///
    /// # Panics
    /// When `limits` has fewer entries than the path has axes.
    pub fn step(&mut self, path: &Path, limits: &[AxisLimits], dt: f64) {
        if !(dt > 0.0 && dt.is_finite()) {
            return;
        }
        let limits = &limits[..path.axes()];
        let cap = path.max_feed();
        if self.feed > cap {
            self.feed = cap;
        }
        let (tau, f) = (self.tau, self.feed);
        let goal = self.target.min(cap);
        let next = if goal == f {
            f
        } else {
            let (low, high) = start_interval(path, limits, tau, f, dt);
            let candidate = if goal > f {
                goal.min(high)
            } else {
                goal.max(low)
            };
            let excess_at = |next: f64| end_excess(path, limits, tau, f, next, dt);
            let over = if candidate == f {
                0.0
            } else {
                excess_at(candidate)
            };
            if over <= 0.0 {
                candidate
            } else {
                search(f, candidate, over, excess_at)
            }
        };
        self.feed_rate = (next - f) / dt;
        self.tau = advance(tau, f, next, dt, path.duration());
        self.feed = next;
    }

    /// The time-scaled state at the current τ: position p(τ), velocity p'·feed, acceleration
    /// p''·feed² + p'·ḟ (ḟ of the last step). Returns [`Path::sample`]'s point index.
    ///
    /// # Panics
    /// When a slice is shorter than the number of axes.
    pub fn sample(
        &self,
        path: &Path,
        position: &mut [f64],
        velocity: &mut [f64],
        acceleration: &mut [f64],
    ) -> usize {
        let point = path.sample(self.tau, position, velocity, acceleration);
        let f = self.feed;
        for (v, a) in velocity[..path.axes()]
            .iter_mut()
            .zip(&mut acceleration[..path.axes()])
        {
            *a = *a * f * f + *v * self.feed_rate;
            *v *= f;
        }
        point
    }
}

/// The new feeds F whose ḟ = (F − f)/dt keeps every axis's acceleration within its limit at
/// path time τ (the start of the tick), widened to contain f.
fn start_interval(path: &Path, limits: &[AxisLimits], tau: f64, f: f64, dt: f64) -> (f64, f64) {
    let (mut low, mut high) = (f64::NEG_INFINITY, f64::INFINITY);
    if let Some((segment, u)) = path.locate(tau) {
        for (axis, limit) in limits.iter().enumerate() {
            let [_, v, a] = path.state(segment, axis, u);
            if v == 0.0 {
                continue;
            }
            let bound_a = (-limit.max_accel - a * f * f) / v;
            let bound_b = (limit.max_accel - a * f * f) / v;
            low = low.max(f + bound_a.min(bound_b) * dt);
            high = high.min(f + bound_a.max(bound_b) * dt);
        }
    }
    (low.min(f), high.max(f))
}

/// The feed between `f` (allowed: its excess is taken as 0) and `bad` (excess `over` > 0 or
/// NaN) closest to `bad` whose excess is ≤ 0, to within [`SEARCH_TOLERANCE`]: regula falsi
/// with the Illinois modification, bisecting where the excess is not finite.
fn search(f: f64, bad: f64, over: f64, excess_at: impl Fn(f64) -> f64) -> f64 {
    let (mut good, mut bad) = (f, bad);
    let (mut e_good, mut e_bad) = (0.0f64.min(excess_at(f)), over);
    // Which end the last step moved (true: good), for the Illinois halving.
    let mut last_good = None;
    for _ in 0..SEARCH_STEPS {
        let secant = good + e_good * (bad - good) / (e_good - e_bad);
        let x = if secant.is_finite() && (secant - good) * (bad - secant) > 0.0 {
            secant
        } else {
            0.5 * (good + bad)
        };
        if x == good || x == bad || (bad - good).abs() <= SEARCH_TOLERANCE * bad.abs().max(f) {
            break;
        }
        let e = excess_at(x);
        if e <= 0.0 {
            good = x;
            e_good = e;
            if last_good == Some(true) {
                e_bad *= 0.5;
            }
            last_good = Some(true);
            if e >= -SEARCH_TOLERANCE {
                break;
            }
        } else {
            bad = x;
            e_bad = if e.is_finite() { e } else { f64::MAX };
            if last_good == Some(false) {
                e_good *= 0.5;
            }
            last_good = Some(false);
        }
    }
    good
}

/// The largest excess over the limits (relative; ≤ 0: within, NaN: not finite) of a tick
/// from feed `f` to feed `next`, at the end of the tick and on both sides of every segment
/// boundary it crosses.
fn end_excess(path: &Path, limits: &[AxisLimits], tau: f64, f: f64, next: f64, dt: f64) -> f64 {
    let mut worst = f64::NEG_INFINITY;
    let rate = (next - f) / dt;
    let duration = path.duration();
    let tau_end = advance(tau, f, next, dt, duration);
    // The feed where the tick reaches path time tau + distance.
    let feed_at = |distance: f64| (f * f + 2.0 * rate * distance).max(0.0).sqrt();
    if let Some((segment, u)) = path.locate(tau_end) {
        for (axis, limit) in limits.iter().enumerate() {
            let [_, v, a] = path.state(segment, axis, u);
            worst = larger(worst, excess(v, a, next, rate, limit));
        }
    }
    let segments = path.segments();
    let mut boundary = path.segment_after(tau);
    // Segment boundaries in (tau, tau_end], and the end of the path.
    while boundary <= segments {
        let (at, after) = if boundary < segments {
            (path.segment_span(boundary).0, Some(boundary))
        } else {
            (duration, None)
        };
        if boundary == 0 || at > tau_end || at <= tau {
            break;
        }
        let feed = feed_at(at - tau);
        let (_, length) = path.segment_span(boundary - 1);
        for (axis, limit) in limits.iter().enumerate() {
            let [_, v, a] = path.state(boundary - 1, axis, length);
            worst = larger(worst, excess(v, a, feed, rate, limit));
            if let Some(next_segment) = after {
                let [_, v, a] = path.state(next_segment, axis, 0.0);
                worst = larger(worst, excess(v, a, feed, rate, limit));
            }
        }
        boundary += 1;
    }
    worst
}
