//! The math of coordinated motion for an axis group (up to [`MAX_AXES`] axes, on any boards):
//! what the engine's deterministic 1 kHz tick needs to move a group together — pure, no
//! clock, no I/O, no allocation after construction.
//!
//! 1. [`Path::plan_line`]: a synchronized straight line in joint space, every axis on one
//!    trapezoidal (or triangular) profile, so they start and arrive together;
//! 2. [`Path::plan_points`]: a time-parameterised trajectory through the [`Points`] a client
//!    sent (positions, optionally velocities and accelerations), with a lead-in from the
//!    group's current state: quintic Hermite, cubic Hermite, or a C2 spline through positions
//!    — blended at the points instead (straight segments, parabolic blends within every
//!    axis's `max_accel` and its path tolerance, [`Tolerances`]) when that spline exceeds a
//!    limit; every segment checked exactly (analytic extrema, not sampling) against each
//!    axis's [`AxisLimits`], a refusal ([`PathError`]) naming the point and the axis;
//! 3. [`TimeScale`]: feed override (0–150 %) and feed hold (to rest along the path, within the
//!    axes' acceleration limits) and resume, as a path time advanced by feed·dt each tick.
//!
//! A [`Path`] is sized once ([`Path::new`]) and planned and sampled in place.
//!
//! Choices worth knowing:
//! - every path ends at rest. A spline through positions only is C2 cubics with a last
//!   quintic segment, so that it arrives with velocity 0 and acceleration 0
//!   ([`Path::plan_points`]); a blended one arrives on a last parabolic blend, exactly at
//!   the last point;
//! - a trajectory through positions alone passes its points exactly when its spline fits
//!   the limits; otherwise the path passes each interior point at |Δv|·blend/8 per axis, the
//!   blend as short as the group's acceleration limits allow, at the point's time;
//! - the limit checks are exact per segment (analytic extrema), with a relative slack of
//!   10⁻⁹; the Bernstein hull of a segment settles most segments without root finding;
//! - [`TimeScale`] keeps the accelerations within the limits at both ends of every tick and at
//!   the segment boundaries it crosses, not only at the tick's start, so the positions it
//!   produces stay within the limits when finite-differenced too.
//!
//! ```
//! use motion_trajectory::{AxisLimits, Path, TimeScale};
//!
//! let limits = [AxisLimits { min: -100.0, max: 100.0, max_velocity: 10.0, max_accel: 50.0 }; 2];
//! let mut path = Path::new(2, 64);
//! path.plan_line(&[0.0, 0.0], &[20.0, 5.0], &limits, 1.0, 1.0)?;
//! // Axis 0 travels farther: it sets the time (20 units at 10/s, ramps of 0.2 s).
//! assert!((path.duration() - 2.2).abs() < 1e-12);
//!
//! // Follow it at 1 kHz; hold halfway, then resume.
//! let mut feed = TimeScale::new();
//! let (mut p, mut v, mut a) = ([0.0; 2], [0.0; 2], [0.0; 2]);
//! let mut ticks = 0;
//! while !feed.finished(&path) {
//!     if ticks == 1000 { feed.set_target(0.0) }
//!     if ticks == 1500 { assert!(feed.at_rest()); feed.set_target(1.0) }
//!     feed.step(&path, &limits, 0.001);
//!     feed.sample(&path, &mut p, &mut v, &mut a);
//!     assert!(v[0].abs() <= 10.0 + 1e-9 && a[0].abs() <= 50.0 + 1e-6);
//!     ticks += 1;
//! }
//! assert_eq!(p, [20.0, 5.0]);
//! # Ok::<(), motion_trajectory::PathError>(())
//! ```
#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod blend;
mod error;
mod line;
mod path;
mod path_serde;
mod points;
mod polynomial;
mod segments;
mod spline;
mod time_scale;

pub use error::PathError;
pub use path::Path;
pub use path_serde::scratch as serde_scratch_path;
pub use points::{Points, Tolerances};
pub use time_scale::{MAX_FEED_OVERRIDE, TimeScale};

/// The most axes in a group.
pub const MAX_AXES: usize = 16;

/// Limits of one axis, in its units.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq)]
pub struct AxisLimits {
    /// The lowest position.
    pub min: f64,
    /// The highest position.
    pub max: f64,
    /// The largest |velocity|, units/s (finite, > 0).
    pub max_velocity: f64,
    /// The largest |acceleration|, units/s² (finite, > 0).
    pub max_accel: f64,
}

impl AxisLimits {
    /// Whether the limits can be planned with: min ≤ max (neither NaN; infinite is fine),
    /// `max_velocity` and `max_accel` finite and positive.
    pub fn is_usable(&self) -> bool {
        self.min <= self.max
            && self.max_velocity.is_finite()
            && self.max_velocity > 0.0
            && self.max_accel.is_finite()
            && self.max_accel > 0.0
    }
}

/// [`PathError::BadLimits`] for the first axis whose limits are not usable.
fn check_limits(limits: &[AxisLimits]) -> Result<(), PathError> {
    match limits.iter().position(|l| !l.is_usable()) {
        Some(axis) => Err(PathError::BadLimits { axis }),
        None => Ok(()),
    }
}

/// `x <= limit`, false when either is NaN: a check written with it refuses a NaN.
#[inline]
fn at_most(x: f64, limit: f64) -> bool {
    x <= limit
}
