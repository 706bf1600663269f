//! Planning: lines, trajectories through points, and every refusal.

use motion_trajectory::{AxisLimits, Path, PathError, Points, Tolerances};

const WIDE: AxisLimits = AxisLimits {
    min: -1000.0,
    max: 1000.0,
    max_velocity: 1000.0,
    max_accel: 10000.0,
};

fn close(a: f64, b: f64, tolerance: f64) -> bool {
    (a - b).abs() <= tolerance * (1.0 + a.abs().max(b.abs()))
}

/// Position, velocity, acceleration of every axis at `t`, and the point index.
fn at(path: &Path, t: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>, usize) {
    let n = path.axes();
    let (mut p, mut v, mut a) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let point = path.sample(t, &mut p, &mut v, &mut a);
    (p, v, a, point)
}

#[test]
fn a_lines_axes_start_and_arrive_together() {
    let limits = [WIDE; 3];
    let mut path = Path::new(3, 0);
    let (start, target) = ([0.0, 1.0, 2.0], [10.0, -4.0, 2.0]);
    path.plan_line(&start, &target, &limits, 1.0, 1.0).unwrap();
    assert!(!path.is_empty() && path.duration() > 0.0);
    let (p, v, a, point) = at(&path, 0.0);
    assert_eq!((p, point), (start.to_vec(), 0));
    assert!(v.iter().all(|&v| v == 0.0) && a[0] > 0.0 && a[1] < 0.0 && a[2] == 0.0);
    let (p, v, a, _) = at(&path, path.duration());
    assert_eq!((p, v, a), (target.to_vec(), vec![0.0; 3], vec![0.0; 3]));
    assert_eq!(path.end(), &target);
    // Every moving axis is at the same fraction of its move at every instant.
    for k in 0..=100 {
        let t = path.duration() * k as f64 / 100.0;
        let (p, _, _, _) = at(&path, t);
        let s0 = (p[0] - start[0]) / (target[0] - start[0]);
        let s1 = (p[1] - start[1]) / (target[1] - start[1]);
        assert!(close(s0, s1, 1e-12), "t {t}: {s0} {s1}");
        assert!((0.0..=1.0 + 1e-12).contains(&s0));
        assert_eq!(p[2], 2.0, "an axis with no move stays put");
    }
}

#[test]
fn the_slowest_axis_sets_a_lines_time() {
    // Axis 0: Δ 10, 5 u/s, 10 u/s²: s' ≤ 0.5, s'' ≤ 1. Axis 1: Δ 2, 0.5 u/s, 100 u/s²:
    // s' ≤ 0.25, s'' ≤ 50. So s' ≤ 0.25 (axis 1), s'' ≤ 1 (axis 0): ramps of 0.25 s,
    // cruise 1/0.25 - 0.25/1 = 3.75 s, 4.25 s in all.
    let limits = [
        AxisLimits {
            max_velocity: 5.0,
            max_accel: 10.0,
            ..WIDE
        },
        AxisLimits {
            max_velocity: 0.5,
            max_accel: 100.0,
            ..WIDE
        },
    ];
    let mut path = Path::new(2, 0);
    path.plan_line(&[0.0, 0.0], &[10.0, 2.0], &limits, 1.0, 1.0)
        .unwrap();
    assert!(close(path.duration(), 4.25, 1e-14), "{}", path.duration());
    let (_, v, a, _) = at(&path, 2.0);
    assert!(close(v[0], 2.5, 1e-14) && close(v[1], 0.5, 1e-14), "{v:?}");
    assert_eq!(a, vec![0.0, 0.0]);
    let (_, _, a, _) = at(&path, 0.1);
    assert!(close(a[0], 10.0, 1e-14) && close(a[1], 2.0, 1e-14), "{a:?}");
    // Axis 1 at its velocity limit, axis 0 at its acceleration limit: no headroom.
    assert!(close(path.max_feed(), 1.0, 1e-12), "{}", path.max_feed());
    // At half the velocity: s' ≤ 0.125: 0.125 + 8 - 0.125 + 0.125 = 8.125 s.
    path.plan_line(&[0.0, 0.0], &[10.0, 2.0], &limits, 0.5, 1.0)
        .unwrap();
    assert!(close(path.duration(), 8.125, 1e-14), "{}", path.duration());
    assert!(
        close(path.max_feed(), 1.0, 1e-12),
        "acceleration still binds"
    );
}

#[test]
fn a_short_line_is_triangular_a_long_one_trapezoidal() {
    // Δ 1, 10 u/s, 4 u/s²: 10² ≥ 4, triangular: peak √4 = 2 at 0.5 s, 1 s in all.
    let limits = [AxisLimits {
        max_velocity: 10.0,
        max_accel: 4.0,
        ..WIDE
    }];
    let mut path = Path::new(1, 0);
    path.plan_line(&[0.0], &[1.0], &limits, 1.0, 1.0).unwrap();
    assert!(close(path.duration(), 1.0, 1e-14));
    let (p, v, _, _) = at(&path, 0.5);
    assert!(
        close(v[0], 2.0, 1e-14) && close(p[0], 0.5, 1e-14),
        "{p:?} {v:?}"
    );
    let (_, _, a, _) = at(&path, 0.4999);
    assert!(close(a[0], 4.0, 1e-14));
    let (_, _, a, _) = at(&path, 0.5001);
    assert!(
        close(a[0], -4.0, 1e-14),
        "no cruise: straight into deceleration"
    );
    // Δ 100: reaches 10 u/s after 2.5 s and 12.5 u, cruises 75 u in 7.5 s: 12.5 s in all.
    path.plan_line(&[0.0], &[100.0], &limits, 1.0, 1.0).unwrap();
    assert!(close(path.duration(), 12.5, 1e-14), "{}", path.duration());
    let (_, v, a, _) = at(&path, 5.0);
    assert!(close(v[0], 10.0, 1e-14) && a[0] == 0.0);
}

#[test]
fn a_zero_length_line_is_a_path_of_duration_0() {
    let mut path = Path::new(2, 0);
    path.plan_line(&[1.0, 2.0], &[1.0, 2.0], &[WIDE; 2], 1.0, 1.0)
        .unwrap();
    assert!(!path.is_empty());
    assert_eq!(path.duration(), 0.0);
    assert_eq!(path.max_feed(), f64::INFINITY);
    let (p, v, _, _) = at(&path, 0.0);
    assert_eq!((p, v), (vec![1.0, 2.0], vec![0.0, 0.0]));
    path.clear();
    assert!(path.is_empty());
}

/// Three points of two axes with velocities and accelerations, the last at rest.
const TIMES: [f64; 3] = [0.5, 1.0, 1.8];
const POSITIONS: [f64; 6] = [1.0, -1.0, 1.4, -0.6, 2.0, 0.0];
const VELOCITIES: [f64; 6] = [0.5, 0.2, 1.0, 0.8, 0.0, 0.0];
const ACCELERATIONS: [f64; 6] = [0.0, 1.0, -2.0, 0.5, 0.0, 0.0];

fn plan(
    path: &mut Path,
    points: &Points<'_>,
    limits: &[AxisLimits],
    start: [f64; 2],
) -> Result<(), PathError> {
    path.plan_points(
        &start,
        &[0.0; 2],
        &[0.0; 2],
        points,
        limits,
        &Tolerances {
            start: &[1e-6; 2],
            path: &[0.0; 2],
        },
    )
}

/// Checks that `path` passes every point at its time (positions always; velocities and
/// accelerations when given).
fn passes_points(path: &Path, points: &Points<'_>, tolerance: f64) {
    for (i, &t) in points.times.iter().enumerate() {
        let (p, v, a, point) = at(path, t);
        assert_eq!(point, (i + 1).min(points.len() - 1), "at point {i}");
        for j in 0..2 {
            let k = i * points.stride + j;
            assert!(
                close(p[j], points.positions[k], tolerance),
                "point {i} axis {j}: {p:?}"
            );
            if let Some(velocities) = points.velocities {
                assert!(
                    close(v[j], velocities[k], tolerance),
                    "point {i} axis {j}: {v:?}"
                );
            }
            if let Some(accelerations) = points.accelerations {
                assert!(
                    close(a[j], accelerations[k], 1e-8),
                    "point {i} axis {j}: {a:?}"
                );
            }
        }
    }
}

#[test]
fn quintic_hermite_reproduces_positions_velocities_and_accelerations() {
    let points = Points {
        times: &TIMES,
        positions: &POSITIONS,
        velocities: Some(&VELOCITIES),
        accelerations: Some(&ACCELERATIONS),
        stride: 2,
    };
    let mut path = Path::new(2, 8);
    plan(&mut path, &points, &[WIDE; 2], [0.0, 0.0]).unwrap();
    assert_eq!(path.duration(), 1.8);
    assert_eq!(path.end(), &[2.0, 0.0]);
    passes_points(&path, &points, 1e-10);
    // The lead-in starts at the start state and heads to point 0.
    let (p, v, a, point) = at(&path, 0.0);
    assert_eq!(
        (p, v, a, point),
        (vec![0.0; 2], vec![0.0; 2], vec![0.0; 2], 0)
    );
    assert_eq!(at(&path, 0.25).3, 0);
}

#[test]
fn cubic_hermite_reproduces_positions_and_velocities() {
    let points = Points {
        times: &TIMES,
        positions: &POSITIONS,
        velocities: Some(&VELOCITIES),
        accelerations: None,
        stride: 2,
    };
    let mut path = Path::new(2, 8);
    plan(&mut path, &points, &[WIDE; 2], [0.0, 0.0]).unwrap();
    passes_points(&path, &points, 1e-10);
    // The lead-in meets point 0 with the acceleration the first cubic leaves it with.
    let (_, _, before, _) = at(&path, 0.5 - 1e-9);
    let (_, _, after, _) = at(&path, 0.5);
    assert!(close(before[0], after[0], 1e-6), "{before:?} {after:?}");
}

#[test]
fn a_spline_through_positions_passes_every_point_and_ends_at_rest() {
    let positions = [0.0, 0.0, 1.0, 2.0, 3.0, 1.0, 2.0, -1.0, 2.5, 0.5];
    let times = [0.0, 0.4, 1.0, 1.5, 2.5];
    let points = Points {
        times: &times,
        positions: &positions,
        velocities: None,
        accelerations: None,
        stride: 2,
    };
    let mut path = Path::new(2, 8);
    for start_velocity in [0.0, 0.7] {
        path.plan_points(
            &[0.0, 0.0],
            &[start_velocity, 0.0],
            &[0.0; 2],
            &points,
            &[WIDE; 2],
            &Tolerances {
                start: &[0.0; 2],
                path: &[0.0; 2],
            },
        )
        .unwrap();
        passes_points(&path, &points, 1e-10);
        // No lead-in: it leaves point 0 with the start velocity.
        assert!(close(at(&path, 0.0).1[0], start_velocity, 1e-12));
        let (p, v, a, _) = at(&path, 2.5 - 1e-9);
        assert!(
            v.iter().chain(&a).all(|x| x.abs() < 1e-6),
            "{p:?} {v:?} {a:?}"
        );
        // C2 at the inner points.
        for &t in &times[1..4] {
            let (_, v0, a0, _) = at(&path, t - 1e-9);
            let (_, v1, a1, _) = at(&path, t);
            for j in 0..2 {
                assert!(
                    close(v0[j], v1[j], 1e-6) && close(a0[j], a1[j], 1e-6),
                    "t {t}"
                );
            }
        }
    }
    // With a lead-in: zero acceleration at point 0 (the natural condition).
    let times = [0.3, 0.7, 1.3, 1.8, 2.8];
    let points = Points {
        times: &times,
        ..points
    };
    plan(&mut path, &points, &[WIDE; 2], [0.5, 0.5]).unwrap();
    passes_points(&path, &points, 1e-10);
    let (_, _, a, _) = at(&path, 0.3);
    assert!(a.iter().all(|a| a.abs() < 1e-9), "{a:?}");
}

#[test]
fn two_points_and_one_point() {
    let mut path = Path::new(2, 4);
    let points = Points {
        times: &[0.2, 1.0],
        positions: &[1.0, 1.0, 2.0, 0.0],
        velocities: None,
        accelerations: None,
        stride: 2,
    };
    plan(&mut path, &points, &[WIDE; 2], [0.0, 0.0]).unwrap();
    passes_points(&path, &points, 1e-10);
    let (_, v, a, _) = at(&path, 0.2);
    assert_eq!(
        (v, a),
        (vec![0.0; 2], vec![0.0; 2]),
        "after a lead-in: at rest at point 0"
    );
    // One point at time 0 where the group is: a path of duration 0 that stays there.
    let one = Points {
        times: &[0.0],
        positions: &[0.5, 0.5],
        ..points
    };
    plan(&mut path, &one, &[WIDE; 2], [0.5, 0.5]).unwrap();
    assert_eq!(path.duration(), 0.0);
    assert_eq!(at(&path, 0.0).0, vec![0.5, 0.5]);
    // One point later: just the lead-in, ending at rest.
    let one = Points {
        times: &[1.0],
        ..one
    };
    plan(&mut path, &one, &[WIDE; 2], [0.0, 0.0]).unwrap();
    let (p, v, a, point) = at(&path, 1.0 - 1e-9);
    assert!(
        close(p[0], 0.5, 1e-8) && v[0].abs() < 1e-6 && a[0].abs() < 1e-4,
        "{p:?} {v:?} {a:?}"
    );
    assert_eq!(point, 0);
}

#[test]
fn max_feed_is_the_headroom_of_the_tightest_axis() {
    // A spline whose largest |v| and |a| are known only through the path: plan it loose,
    // then with limits at exactly the headroom found, it is accepted; a hair lower, refused.
    let points = Points {
        times: &TIMES,
        positions: &POSITIONS,
        velocities: Some(&VELOCITIES),
        accelerations: Some(&ACCELERATIONS),
        stride: 2,
    };
    let mut path = Path::new(2, 8);
    plan(&mut path, &points, &[WIDE; 2], [0.0, 0.0]).unwrap();
    let headroom = path.max_feed();
    assert!(headroom.is_finite() && headroom > 1.0);
    // Scaling both limits of both axes by k scales max_feed by... velocity k, acceleration √k.
    let k = 1.0 / headroom;
    let tight = [AxisLimits {
        max_velocity: WIDE.max_velocity * k,
        max_accel: WIDE.max_accel * k * k,
        ..WIDE
    }; 2];
    plan(&mut path, &points, &tight, [0.0, 0.0]).unwrap();
    assert!(close(path.max_feed(), 1.0, 1e-9), "{}", path.max_feed());
    let tighter = tight.map(|l| AxisLimits {
        max_velocity: l.max_velocity * (1.0 - 1e-6),
        max_accel: l.max_accel * (1.0 - 1e-6) * (1.0 - 1e-6),
        ..l
    });
    let error = plan(&mut path, &points, &tighter, [0.0, 0.0]).unwrap_err();
    assert!(
        matches!(
            error,
            PathError::VelocityLimit { .. } | PathError::AccelLimit { .. }
        ),
        "{error}"
    );
}

/// Floating-point noise is no reason to refuse: a last velocity of −2.9·10⁻¹⁵ is at rest,
/// and a path that starts exactly at a soft limit may round a hair beyond it (both seen by
/// the bench from computed trajectories); a real excess still is refused.
#[test]
fn rounding_at_rest_and_at_a_limit_is_not_refused() {
    let limits = [AxisLimits {
        min: 0.0,
        max: 100.0,
        max_velocity: 50.0,
        max_accel: 250.0,
    }; 2];
    let times = [1.0, 2.0];
    let positions = [10.0, 5.0, 20.0, 10.0];
    let velocities = [10.0, 5.0, -2.9e-15, 0.0];
    let points = Points {
        times: &times,
        positions: &positions,
        velocities: Some(&velocities),
        accelerations: None,
        stride: 2,
    };
    let mut path = Path::new(2, 16);
    plan(&mut path, &points, &limits, [0.0, 0.0]).expect("noise at rest is rest");
    let moving = [10.0, 5.0, 1e-3, 0.0];
    let points = Points {
        velocities: Some(&moving),
        ..points
    };
    assert!(matches!(
        plan(&mut path, &points, &limits, [0.0, 0.0]),
        Err(PathError::VelocityLimit {
            point: 1,
            axis: 0,
            ..
        })
    ));
    // A point a rounding beyond the limit is within it; one a micron beyond is not.
    let positions = [-1e-13, 5.0, 20.0, 10.0];
    let points = Points {
        times: &times,
        positions: &positions,
        velocities: None,
        accelerations: None,
        stride: 2,
    };
    plan(&mut path, &points, &limits, [0.0, 0.0]).expect("a rounding at the limit");
    let positions = [-1e-3, 5.0, 20.0, 10.0];
    let points = Points {
        positions: &positions,
        ..points
    };
    assert!(matches!(
        plan(&mut path, &points, &limits, [0.0, 0.0]),
        Err(PathError::OutOfRange { axis: 0, .. })
    ));
}
