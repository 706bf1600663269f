//! Trajectories through positions alone whose exact spline exceeds a limit: blended at the
//! points (straight segments, parabolic blends) within every limit and every axis's path
//! tolerance, keeping the times of the points and ending exactly at the last point, at rest;
//! refused, naming the point and the axis, when that is impossible.

mod support;

use motion_trajectory::{AxisLimits, Path, PathError, Points, Tolerances};
use proptest::prelude::*;
use support::{ANALYTIC_SLACK, follow};

/// 10 units/s, 200 units/s².
const LIMIT: AxisLimits = AxisLimits {
    min: -100.0,
    max: 100.0,
    max_velocity: 10.0,
    max_accel: 200.0,
};

/// Two axes: axis 0 out at 9.5 units/s and back (its spline from rest overshoots 10 units/s),
/// axis 1 still, then a step of 2 units between points 2 and 3.
const TIMES: [f64; 5] = [0.0, 1.0, 2.0, 3.0, 4.0];
const POSITIONS: [f64; 10] = [0.0, 0.0, 9.5, 0.0, 19.0, 0.0, 9.5, 2.0, 0.0, 2.0];

fn points<'a>(times: &'a [f64], positions: &'a [f64]) -> Points<'a> {
    Points {
        times,
        positions,
        velocities: None,
        accelerations: None,
        stride: 2,
    }
}

fn plan(
    path: &mut Path,
    points: &Points<'_>,
    limits: &[AxisLimits],
    path_tolerance: &[f64],
) -> Result<(), PathError> {
    let axes = path.axes();
    let zero = vec![0.0; axes];
    path.plan_points(
        &zero,
        &zero,
        &zero,
        points,
        limits,
        &Tolerances {
            start: &zero,
            path: path_tolerance,
        },
    )
}

/// Samples `path` every 0.1 ms: within every limit (analytic), position and velocity
/// continuous (no step anywhere: the change over each step is what the velocity and
/// acceleration limits allow), every point passed at its time within the tolerance (the
/// first and the last exactly), the end exactly at the last point, at rest. Returns the
/// largest distance at an interior point.
fn check_blended(
    path: &Path,
    points: &Points<'_>,
    limits: &[AxisLimits],
    tolerance: &[f64],
) -> f64 {
    let axes = path.axes();
    let n = points.len();
    assert_eq!(path.duration(), points.times[n - 1]);
    let (mut p, mut v, mut a) = (vec![0.0; axes], vec![0.0; axes], vec![0.0; axes]);
    let (mut p0, mut v0) = (vec![0.0; axes], vec![0.0; axes]);
    let step = 1e-4;
    let steps = (path.duration() / step).ceil() as usize;
    path.sample(0.0, &mut p0, &mut v0, &mut a);
    for k in 1..=steps {
        let t = (k as f64 * step).min(path.duration());
        let dt = t - (k - 1) as f64 * step;
        path.sample(t, &mut p, &mut v, &mut a);
        for (j, l) in limits.iter().enumerate() {
            assert!(
                p[j] >= l.min && p[j] <= l.max,
                "t {t} axis {j}: position {}",
                p[j]
            );
            let (vmax, amax) = (
                l.max_velocity * (1.0 + ANALYTIC_SLACK),
                l.max_accel * (1.0 + ANALYTIC_SLACK),
            );
            assert!(v[j].abs() <= vmax, "t {t} axis {j}: velocity {}", v[j]);
            assert!(a[j].abs() <= amax, "t {t} axis {j}: acceleration {}", a[j]);
            assert!(
                (p[j] - p0[j]).abs() <= vmax * dt + 1e-9,
                "t {t} axis {j}: a position step {} → {}",
                p0[j],
                p[j]
            );
            assert!(
                (v[j] - v0[j]).abs() <= amax * dt + 1e-9,
                "t {t} axis {j}: a velocity step {} → {}",
                v0[j],
                v[j]
            );
        }
        p0.clone_from(&p);
        v0.clone_from(&v);
    }
    let mut largest: f64 = 0.0;
    for (i, &t) in points.times.iter().enumerate() {
        path.sample(t, &mut p, &mut v, &mut a);
        for j in 0..axes {
            let distance = (p[j] - points.position_of(i, j)).abs();
            if i == 0 || i == n - 1 {
                assert!(distance < 1e-9, "point {i} axis {j}: {distance} away");
            } else {
                assert!(
                    distance <= tolerance[j] + 1e-12,
                    "point {i} axis {j}: {distance} away, tolerance {}",
                    tolerance[j]
                );
                largest = largest.max(distance);
            }
        }
    }
    // The end: exactly the last point, at rest; just before it, almost there and slowing.
    path.sample(path.duration(), &mut p, &mut v, &mut a);
    assert_eq!(p, path.end());
    assert!(v.iter().chain(&a).all(|&x| x == 0.0));
    for (j, &p) in p.iter().enumerate() {
        assert_eq!(p, points.position_of(n - 1, j));
    }
    path.sample(path.duration() - 1e-6, &mut p, &mut v, &mut a);
    for (j, l) in limits.iter().enumerate() {
        assert!((p[j] - path.end()[j]).abs() < 1e-9, "axis {j}: {}", p[j]);
        assert!(
            v[j].abs() <= l.max_accel * 1e-6 * (1.0 + 1e-6),
            "axis {j}: {}",
            v[j]
        );
    }
    largest
}

/// `Points::position` is the crate's: the tests read the layout themselves.
trait PositionOf {
    fn position_of(&self, point: usize, axis: usize) -> f64;
}

impl PositionOf for Points<'_> {
    fn position_of(&self, point: usize, axis: usize) -> f64 {
        self.positions[point * self.stride + axis]
    }
}

#[test]
fn a_spline_over_the_velocity_limit_is_blended_within_every_limit() {
    let limits = [LIMIT; 2];
    let tolerance = [0.5, 0.5];
    let points = points(&TIMES, &POSITIONS);
    let mut path = Path::new(2, 8);
    // The exact spline exceeds a limit: with no tolerance there is no blending either.
    let exact = plan(&mut path, &points, &limits, &[0.0; 2]);
    assert!(
        matches!(
            exact,
            Err(PathError::BlendTolerance {
                point: 1,
                axis: 0,
                ..
            })
        ),
        "{exact:?}"
    );
    assert!(path.is_empty());
    plan(&mut path, &points, &limits, &tolerance).unwrap();
    let largest = check_blended(&path, &points, &limits, &tolerance);
    // The turn at point 2: Δv = 19 units/s, a blend of 19/200 s, passed at 19·0.095/8.
    let (mut p, mut v, mut a) = ([0.0; 2], [0.0; 2], [0.0; 2]);
    path.sample(2.0, &mut p, &mut v, &mut a);
    assert!((19.0 - p[0] - 19.0 * 0.095 / 8.0).abs() < 1e-9, "{p:?}");
    assert!((largest - 19.0 * 0.095 / 8.0).abs() < 1e-9, "{largest}");
    // Axis 1 blends over the same interval, at its own lower acceleration.
    assert!((p[1] - 2.0 * 0.095 / 8.0).abs() < 1e-9, "{p:?}");
    assert!(
        (a[0] + 200.0).abs() < 1e-6 && (a[1] - 2.0 / 0.095).abs() < 1e-6,
        "{a:?}"
    );
    // Followed at feed 1 tick by tick, with a hold and a resume.
    let run = follow(&path, &limits, 1.0, &[(1500, 0.0)], 3000, 20_000);
    assert_eq!(run.end.as_slice(), path.end());
    assert_eq!(run.holds, 1);
}

#[test]
fn a_blend_after_a_lead_in_keeps_the_start_state() {
    let limits = [LIMIT; 2];
    let tolerance = [0.5, 0.5];
    let times = TIMES.map(|t| t + 0.5);
    let points = points(&times, &POSITIONS);
    let mut path = Path::new(2, 8);
    let (start, moving) = ([-1.0, 0.5], [2.0, -1.0]);
    path.plan_points(
        &start,
        &moving,
        &[0.0; 2],
        &points,
        &limits,
        &Tolerances {
            start: &[0.0; 2],
            path: &tolerance,
        },
    )
    .unwrap();
    let (mut p, mut v, mut a) = ([0.0; 2], [0.0; 2], [0.0; 2]);
    path.sample(0.0, &mut p, &mut v, &mut a);
    assert_eq!((p, v, a), (start, moving, [0.0; 2]));
    path.sample(2.5, &mut p, &mut v, &mut a);
    assert!(p[0] < 19.0 - 1e-3, "blended: {p:?}");
    // From 0.5 s on (after the lead-in) the same checks as without one.
    let largest = check_blended(&path, &points, &limits, &tolerance);
    assert!(largest > 0.0 && largest <= 0.5);
}

#[test]
fn a_spline_that_fits_stays_exact_through_the_points() {
    let limits = [LIMIT; 2];
    let times = TIMES.map(|t| 3.0 * t);
    let points = points(&times, &POSITIONS);
    let mut path = Path::new(2, 8);
    plan(&mut path, &points, &limits, &[0.5; 2]).unwrap();
    let (mut p, mut v, mut a) = ([0.0; 2], [0.0; 2], [0.0; 2]);
    for (i, &t) in times.iter().enumerate() {
        path.sample(t, &mut p, &mut v, &mut a);
        for j in 0..2 {
            assert!(
                (p[j] - POSITIONS[2 * i + j]).abs() < 1e-9,
                "point {i}: {p:?}"
            );
        }
    }
    // C2: a spline's acceleration has no step at an interior point.
    let (mut before, mut after) = ([0.0; 2], [0.0; 2]);
    path.sample(6.0 - 1e-9, &mut p, &mut v, &mut before);
    path.sample(6.0 + 1e-9, &mut p, &mut v, &mut after);
    assert!((before[0] - after[0]).abs() < 1e-5, "{before:?} {after:?}");
}

#[test]
fn a_blend_beyond_an_axis_tolerance_is_refused_naming_the_point_and_the_axis() {
    let limits = [LIMIT; 2];
    let points = points(&TIMES, &POSITIONS);
    let mut path = Path::new(2, 8);
    // Axis 0 sets the blend at point 2 (95 ms); axis 1's step of 2 units/s there passes it at
    // 2·0.095/8 ≈ 0.024.
    let error = plan(&mut path, &points, &limits, &[0.5, 0.01]).unwrap_err();
    let PathError::BlendTolerance {
        point,
        axis,
        distance,
        tolerance,
        blend,
        by_axis,
    } = error
    else {
        panic!("{error:?}");
    };
    assert_eq!((point, axis, by_axis, tolerance), (2, 1, 0, 0.01));
    assert!((blend - 0.095).abs() < 1e-12 && (distance - 0.02375).abs() < 1e-12);
    let message = error.to_string();
    assert!(
        message.starts_with("point 2, axis 1:") && message.contains("path tolerance 0.01"),
        "{message}"
    );
    assert!(path.is_empty());
}

#[test]
fn impossible_blends_are_refused_naming_the_point_and_the_axis() {
    let limits = [LIMIT; 2];
    let mut path = Path::new(2, 8);
    // The end: 0.4 units in 50 ms to rest needs 2·0.4/0.05² = 320 units/s² at least.
    let times = [0.0, 1.0, 1.05];
    let positions = [0.0, 0.0, 5.0, 0.0, 5.4, 0.0];
    let error = plan(&mut path, &points(&times, &positions), &limits, &[5.0; 2]);
    assert!(
        matches!(error, Err(PathError::AccelLimit { point: 2, axis: 0, value, limit: 200.0 })
            if (value - 320.0).abs() < 1e-9),
        "{error:?}"
    );
    // Blends that overlap: 9 → −5 units/s at point 1 needs 70 ms, −5 → −8.9 at point 2
    // 19.5 ms, but they are 20 ms apart.
    let times = [0.0, 1.0, 1.02, 2.02];
    let positions = [0.0, 0.0, 9.0, 0.0, 8.9, 0.0, 0.0, 0.0];
    let error = plan(&mut path, &points(&times, &positions), &limits, &[5.0; 2]);
    assert!(
        matches!(error, Err(PathError::AccelLimit { point: 2, axis: 0, value, limit: 200.0 }) if value > 200.0),
        "{error:?}"
    );
    // A straight segment over the velocity limit: no blend helps.
    let times = [0.0, 1.0, 2.0, 3.0];
    let positions = [0.0, 0.0, 5.0, 0.0, 17.0, 0.0, 20.0, 0.0];
    let error = plan(&mut path, &points(&times, &positions), &limits, &[5.0; 2]);
    assert!(
        matches!(
            error,
            Err(PathError::VelocityLimit {
                point: 2,
                axis: 0,
                limit: 10.0,
                ..
            })
        ),
        "{error:?}"
    );
    assert!(path.is_empty());
}

#[test]
fn two_points_without_a_lead_in_blend_at_both_ends() {
    // 9 units in 1 s: the quintic peaks at 1.875·9 units/s; a trapezoid of 2·(b/2) ramps
    // fits 10 units/s.
    let limits = [LIMIT; 2];
    let times = [0.0, 1.0];
    let positions = [0.0, 0.0, 9.0, -3.0];
    let points = points(&times, &positions);
    let mut path = Path::new(2, 8);
    plan(&mut path, &points, &limits, &[0.0; 2]).unwrap();
    check_blended(&path, &points, &limits, &[0.0; 2]);
    // And from a start velocity (a path replaced while moving, point 0 at time 0).
    path.plan_points(
        &[0.0; 2],
        &[4.0, 1.0],
        &[0.0; 2],
        &points,
        &limits,
        &Tolerances {
            start: &[0.0; 2],
            path: &[0.0; 2],
        },
    )
    .unwrap();
    let (mut p, mut v, mut a) = ([0.0; 2], [0.0; 2], [0.0; 2]);
    path.sample(0.0, &mut p, &mut v, &mut a);
    assert_eq!((p, v), ([0.0; 2], [4.0, 1.0]));
    check_blended(&path, &points, &limits, &[0.0; 2]);
}

#[test]
fn nothing_finite_is_a_panic() {
    let limits = [LIMIT; 2];
    let mut path = Path::new(2, 8);
    for tolerance in [f64::NAN, -1.0, f64::INFINITY, 1e300] {
        let _ = plan(
            &mut path,
            &points(&TIMES, &POSITIONS),
            &limits,
            &[tolerance; 2],
        );
    }
    let huge = [0.0, 1e-300, 1e300];
    let positions = [0.0, 0.0, 100.0, -100.0, -100.0, 100.0];
    let _ = plan(&mut path, &points(&huge, &positions), &limits, &[1e300; 2]);
    let tiny = [0.0, 1e-300, 2e-300];
    let _ = plan(&mut path, &points(&tiny, &positions), &limits, &[1e300; 2]);
    // A tolerance slice of the wrong length.
    assert_eq!(
        plan(&mut path, &points(&TIMES, &POSITIONS), &limits, &[1.0]),
        Err(PathError::BadLayout)
    );
}

/// Hands out the random numbers of a case in order (each in [0, 1)).
struct Draw<'a>(std::slice::Iter<'a, f64>);

impl Draw<'_> {
    fn unit(&mut self) -> f64 {
        *self.0.next().expect("enough random numbers")
    }

    fn range(&mut self, low: f64, high: f64) -> f64 {
        low + (high - low) * self.unit()
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, ..ProptestConfig::default() })]

    /// Random points at up to 1.2 times an axis's velocity limit between them, random
    /// tolerances, with or without a lead-in and a start velocity: whatever is accepted
    /// stays within every limit, passes the points within the tolerances, ends at the last
    /// point at rest, and can be followed tick by tick.
    #[test]
    fn random_positions_are_blended_within_every_limit(
        axes in 1usize..=6,
        count in 2usize..=10,
        lead_in in any::<bool>(),
        numbers in prop::collection::vec(0.0f64..1.0, 400),
    ) {
        let mut draw = Draw(numbers.iter());
        let limits: Vec<AxisLimits> = (0..axes)
            .map(|_| AxisLimits {
                min: -100.0,
                max: 100.0,
                max_velocity: draw.range(1.0, 20.0),
                max_accel: draw.range(20.0, 500.0),
            })
            .collect();
        let tolerance: Vec<f64> = (0..axes).map(|_| draw.range(0.0, 1.0)).collect();
        let mut times = Vec::with_capacity(count);
        let mut t = if lead_in { draw.range(0.5, 1.5) } else { 0.0 };
        for _ in 0..count {
            times.push(t);
            t += draw.range(0.2, 1.5);
        }
        let stride = 16;
        let mut positions = vec![0.0; stride * count];
        for (j, l) in limits.iter().enumerate() {
            let mut p = draw.range(-50.0, 50.0);
            for i in 0..count {
                if i > 0 {
                    let pace = draw.range(-0.95, 0.95) * l.max_velocity;
                    p = (p + pace * (times[i] - times[i - 1])).clamp(l.min, l.max);
                }
                positions[i * stride + j] = p;
            }
        }
        let start_position: Vec<f64> = (0..axes)
            .map(|j| positions[j] + if lead_in { draw.range(-0.2, 0.2) } else { 0.0 })
            .collect();
        let start_velocity: Vec<f64> =
            limits.iter().map(|l| draw.range(-0.2, 0.2) * l.max_velocity).collect();
        let points = Points { times: &times, positions: &positions, velocities: None, accelerations: None, stride };
        let mut path = Path::new(axes, 10);
        let planned = path.plan_points(
            &start_position,
            &start_velocity,
            &vec![0.0; axes],
            &points,
            &limits,
            &Tolerances { start: &vec![0.0; axes], path: &tolerance },
        );
        match planned {
            Ok(()) => {
                // From point 0 on; the lead-in is any trajectory's.
                let mut p = vec![0.0; axes];
                let (mut v, mut a) = (p.clone(), p.clone());
                path.sample(0.0, &mut p, &mut v, &mut a);
                prop_assert_eq!(&p, &start_position);
                if !lead_in {
                    prop_assert_eq!(&v, &start_velocity);
                }
                check_blended(&path, &points, &limits, &tolerance);
                let run = follow(&path, &limits, 1.0, &[], 1, 1_000_000);
                prop_assert_eq!(run.end.as_slice(), path.end());
            }
            Err(error) => {
                prop_assert!(
                    matches!(
                        error,
                        PathError::VelocityLimit { .. }
                            | PathError::AccelLimit { .. }
                            | PathError::OutOfRange { .. }
                            | PathError::BlendTolerance { .. }
                    ),
                    "{}", error
                );
                prop_assert!(path.is_empty());
            }
        }
    }
}
