//! Every refusal, naming the right point and axis; a refused plan leaves the path as it was.

use motion_trajectory::{AxisLimits, Path, PathError, Points, Tolerances};

const LIMIT: AxisLimits = AxisLimits {
    min: -10.0,
    max: 10.0,
    max_velocity: 5.0,
    max_accel: 50.0,
};
const LIMITS: [AxisLimits; 2] = [LIMIT; 2];

/// Plans `positions` (stride 2) at `times` from rest at `start`, lead-in if times[0] > 0.
fn plan_with(
    path: &mut Path,
    times: &[f64],
    positions: &[f64],
    velocities: Option<&[f64]>,
    accelerations: Option<&[f64]>,
    start: [f64; 2],
) -> Result<(), PathError> {
    let points = Points {
        times,
        positions,
        velocities,
        accelerations,
        stride: 2,
    };
    path.plan_points(
        &start,
        &[0.0; 2],
        &[0.0; 2],
        &points,
        &LIMITS,
        &Tolerances {
            start: &[0.01; 2],
            path: &[0.0; 2],
        },
    )
}

fn refusal(
    times: &[f64],
    positions: &[f64],
    velocities: Option<&[f64]>,
    accelerations: Option<&[f64]>,
) -> PathError {
    let mut path = Path::new(2, 8);
    let error = plan_with(
        &mut path,
        times,
        positions,
        velocities,
        accelerations,
        [0.0; 2],
    )
    .expect_err("refused");
    assert!(path.is_empty(), "a refused plan plans nothing");
    error
}

#[test]
fn too_many_points_and_none() {
    let mut path = Path::new(2, 2);
    let error = plan_with(&mut path, &[0.0, 1.0, 2.0], &[0.0; 6], None, None, [0.0; 2]);
    assert_eq!(
        error,
        Err(PathError::TooManyPoints {
            count: 3,
            capacity: 2
        })
    );
    assert_eq!(refusal(&[], &[], None, None), PathError::NoPoints);
}

#[test]
fn bad_layouts() {
    let times = [0.0, 1.0];
    let mut path = Path::new(2, 8);
    let points = Points {
        times: &times,
        positions: &[0.0; 4],
        velocities: None,
        accelerations: None,
        stride: 2,
    };
    let cases: [(Points<'_>, usize, usize, usize); 7] = [
        (
            Points {
                stride: 1,
                ..points
            },
            2,
            2,
            2,
        ),
        (
            Points {
                positions: &[0.0; 3],
                ..points
            },
            2,
            2,
            2,
        ),
        (
            Points {
                velocities: Some(&[0.0; 3]),
                ..points
            },
            2,
            2,
            2,
        ),
        (
            Points {
                accelerations: Some(&[0.0; 4]),
                ..points
            },
            2,
            2,
            2,
        ),
        (points, 1, 2, 2),
        (points, 2, 1, 2),
        (points, 2, 2, 3),
    ];
    for (i, (points, start, limits, tolerance)) in cases.into_iter().enumerate() {
        let error = path.plan_points(
            &vec![0.0; start],
            &[0.0; 2],
            &[0.0; 2],
            &points,
            &vec![LIMIT; limits],
            &Tolerances {
                start: &vec![0.0; tolerance],
                path: &[0.0; 2],
            },
        );
        assert_eq!(error, Err(PathError::BadLayout), "case {i}");
    }
    // The positions may be longer than the points need (a fixed-size sample), and the last
    // point needs only `axes` values, not a whole stride.
    let points = Points {
        positions: &[0.0; 18],
        stride: 16,
        ..points
    };
    path.plan_points(
        &[0.0; 2],
        &[0.0; 2],
        &[0.0; 2],
        &points,
        &LIMITS,
        &Tolerances {
            start: &[0.0; 2],
            path: &[0.0; 2],
        },
    )
    .unwrap();
    assert_eq!(
        path.plan_line(&[0.0], &[0.0, 1.0], &LIMITS, 1.0, 1.0),
        Err(PathError::BadLayout)
    );
}

#[test]
fn values_that_are_not_finite() {
    let mut positions = [0.0; 6];
    positions[2 * 2 + 1] = f64::NAN;
    assert_eq!(
        refusal(&[0.0, 1.0, 2.0], &positions, None, None),
        PathError::NotFinite { point: 2, axis: 1 }
    );
    let mut velocities = [0.0; 6];
    velocities[2] = f64::INFINITY;
    assert_eq!(
        refusal(&[0.0, 1.0, 2.0], &[0.0; 6], Some(&velocities), None),
        PathError::NotFinite { point: 1, axis: 0 }
    );
    let mut path = Path::new(2, 8);
    assert_eq!(
        plan_with(&mut path, &[1.0], &[0.0; 2], None, None, [0.0, f64::NAN]),
        Err(PathError::NotFinite { point: 0, axis: 1 }),
        "the start state counts as point 0"
    );
    assert_eq!(
        path.plan_line(&[0.0; 2], &[f64::NAN, 0.0], &LIMITS, 1.0, 1.0),
        Err(PathError::NotFinite { point: 0, axis: 0 })
    );
}

#[test]
fn times_that_do_not_increase() {
    let positions = [0.0; 6];
    for (times, point) in [
        ([0.1, 0.5, 0.5], 2),
        ([0.1, 0.5, 0.4], 2),
        ([-0.1, 0.5, 1.0], 0),
        ([0.0, f64::NAN, 1.0], 1),
        ([0.0, 1.0, f64::INFINITY], 2),
    ] {
        assert_eq!(
            refusal(&times, &positions, None, None),
            PathError::TimesNotIncreasing { point },
            "{times:?}"
        );
    }
}

#[test]
fn positions_out_of_range_at_a_point_on_a_segment_and_on_the_lead_in() {
    let error = refusal(
        &[0.0, 3.0, 6.0],
        &[0.0, 0.0, 1.0, 11.0, 1.0, 1.0],
        None,
        None,
    );
    assert_eq!(
        error,
        PathError::OutOfRange {
            point: 1,
            axis: 1,
            value: 11.0,
            min: -10.0,
            max: 10.0
        }
    );
    // Axis 1 leaves 9.5 at 3 u/s and must be back at rest at 9.5 two seconds later: it
    // overshoots 10 on the way to point 2.
    let error = refusal(
        &[0.0, 5.0, 7.0],
        &[0.0, 0.0, 0.0, 9.5, 0.0, 9.5],
        Some(&[0.0, 0.0, 0.0, 3.0, 0.0, 0.0]),
        None,
    );
    let PathError::OutOfRange {
        point: 2,
        axis: 1,
        value,
        ..
    } = error
    else {
        panic!("{error:?}");
    };
    // p(u) = 9.5 + 3u - 3u² + 0.75u³, v(u) = 3 - 6u + 2.25u²: zero at u = 2/3, where
    // p = 9.5 + 8/9.
    assert!((value - (9.5 + 8.0 / 9.0)).abs() < 1e-12, "{value}");
    // The start outside the range: the lead-in leaves it.
    let mut path = Path::new(2, 8);
    let error = plan_with(&mut path, &[5.0], &[0.0; 2], None, None, [0.0, -10.5]);
    assert!(
        matches!(error, Err(PathError::OutOfRange { point: 0, axis: 1, value, .. }) if value == -10.5),
        "{error:?}"
    );
    // A line's target.
    assert_eq!(
        path.plan_line(&[0.0; 2], &[0.0, -10.5], &LIMITS, 1.0, 1.0),
        Err(PathError::OutOfRange {
            point: 0,
            axis: 1,
            value: -10.5,
            min: -10.0,
            max: 10.0
        })
    );
    // A line may start outside the range, to bring an axis back.
    path.plan_line(&[0.0, -10.5], &[0.0, 0.0], &LIMITS, 1.0, 1.0)
        .unwrap();
}

#[test]
fn velocities_over_the_limit() {
    // Axis 1 jumps 8 units in 0.5 s between points 1 and 2 (at rest at both).
    let velocities = [0.0; 6];
    let error = refusal(
        &[0.0, 2.0, 2.5],
        &[0.0, 0.0, 0.0, 1.0, 0.0, 9.0],
        Some(&velocities),
        None,
    );
    assert!(
        matches!(error, PathError::VelocityLimit { point: 2, axis: 1, value, limit: 5.0 }
            if (value - 24.0).abs() < 1e-9),
        "cubic rest to rest: 1.5 · 8 / 0.5 = 24; {error:?}"
    );
    // The last point must be at rest.
    let error = refusal(
        &[0.0, 2.0],
        &[0.0, 0.0, 1.0, 1.0],
        Some(&[0.0, 0.0, 0.3, 0.0]),
        None,
    );
    assert_eq!(
        error,
        PathError::VelocityLimit {
            point: 1,
            axis: 0,
            value: 0.3,
            limit: 0.0
        }
    );
    // The lead-in: to 5 units in 0.2 s.
    let error = refusal(&[0.2, 1.0], &[5.0, 0.0, 5.0, 0.0], None, None);
    assert!(
        matches!(
            error,
            PathError::VelocityLimit {
                point: 0,
                axis: 0,
                ..
            }
        ),
        "{error:?}"
    );
}

#[test]
fn accelerations_over_the_limit() {
    // Axis 0: 0.5 units in 0.2 s, quintic rest to rest: peak velocity 1.875 · 0.5 / 0.2 =
    // 4.69 (within 5), peak acceleration 10/√3 · 0.5 / 0.04 = 72 (over 50).
    let zeros = [0.0; 6];
    let error = refusal(
        &[0.0, 1.0, 1.2],
        &[0.0, 0.0, 0.0, 0.0, 0.5, 0.0],
        Some(&zeros),
        Some(&zeros),
    );
    let PathError::AccelLimit {
        point: 2,
        axis: 0,
        value,
        limit: 50.0,
    } = error
    else {
        panic!("{error:?}");
    };
    assert!(
        (value.abs() - 10.0 / 3f64.sqrt() * 0.5 / 0.04).abs() < 1e-9,
        "{value}"
    );
    let error = refusal(
        &[0.0, 2.0],
        &[0.0, 0.0, 1.0, 1.0],
        Some(&[0.0; 4]),
        Some(&[0.0, 0.0, 0.0, -2.0]),
    );
    assert_eq!(
        error,
        PathError::AccelLimit {
            point: 1,
            axis: 1,
            value: -2.0,
            limit: 0.0
        }
    );
}

#[test]
fn a_start_that_does_not_match_point_0_at_time_0() {
    let mut path = Path::new(2, 8);
    let error = plan_with(
        &mut path,
        &[0.0, 1.0],
        &[0.0, 0.1, 1.0, 1.0],
        None,
        None,
        [0.0, 0.0],
    );
    let Err(PathError::StartMismatch {
        axis: 1,
        distance,
        tolerance: 0.01,
    }) = error
    else {
        panic!("{error:?}");
    };
    assert!((distance - 0.1).abs() < 1e-15);
    // Within the tolerance, the path starts at point 0 exactly.
    plan_with(
        &mut path,
        &[0.0, 1.0],
        &[0.0, 0.005, 1.0, 1.0],
        None,
        None,
        [0.0, 0.0],
    )
    .unwrap();
    let (mut p, mut v, mut a) = ([0.0; 2], [0.0; 2], [0.0; 2]);
    path.sample(0.0, &mut p, &mut v, &mut a);
    assert_eq!(p, [0.0, 0.005]);
}

#[test]
fn bad_scales_and_bad_limits() {
    let mut path = Path::new(2, 8);
    for (v, a) in [(0.0, 1.0), (1.0, 1.5), (f64::NAN, 1.0), (1.0, -0.5)] {
        assert_eq!(
            path.plan_line(&[0.0; 2], &[1.0; 2], &LIMITS, v, a),
            Err(PathError::BadScale)
        );
    }
    for bad in [
        AxisLimits {
            max_velocity: 0.0,
            ..LIMIT
        },
        AxisLimits {
            max_accel: f64::INFINITY,
            ..LIMIT
        },
        AxisLimits {
            min: 1.0,
            max: 0.0,
            ..LIMIT
        },
        AxisLimits {
            min: f64::NAN,
            ..LIMIT
        },
    ] {
        let limits = [LIMIT, bad];
        assert_eq!(
            path.plan_line(&[0.0; 2], &[0.0; 2], &limits, 1.0, 1.0),
            Err(PathError::BadLimits { axis: 1 })
        );
        let points = Points {
            times: &[1.0],
            positions: &[0.0; 2],
            velocities: None,
            accelerations: None,
            stride: 2,
        };
        assert_eq!(
            path.plan_points(
                &[0.0; 2],
                &[0.0; 2],
                &[0.0; 2],
                &points,
                &limits,
                &Tolerances {
                    start: &[0.0; 2],
                    path: &[0.0; 2]
                }
            ),
            Err(PathError::BadLimits { axis: 1 })
        );
    }
    // Infinite ranges are fine (an axis without soft limits).
    let open = [AxisLimits {
        min: f64::NEG_INFINITY,
        max: f64::INFINITY,
        ..LIMIT
    }; 2];
    path.plan_line(&[0.0; 2], &[1e6; 2], &open, 1.0, 1.0)
        .unwrap();
}

#[test]
fn messages_name_the_point_the_axis_and_the_figures() {
    let text = PathError::VelocityLimit {
        point: 7,
        axis: 3,
        value: 12.5,
        limit: 10.0,
    }
    .to_string();
    assert!(
        text.contains("point 7")
            && text.contains("axis 3")
            && text.contains("12.5")
            && text.contains("10"),
        "{text}"
    );
    let text = PathError::OutOfRange {
        point: 2,
        axis: 0,
        value: 11.0,
        min: -10.0,
        max: 10.0,
    }
    .to_string();
    assert!(
        text.contains("point 2, axis 0") && text.contains("-10..10"),
        "{text}"
    );
}

/// Everything observable of a path.
fn snapshot(path: &Path) -> Vec<f64> {
    let mut all = vec![
        path.duration(),
        path.max_feed(),
        f64::from(u8::from(path.is_empty())),
    ];
    all.extend_from_slice(path.end());
    for k in 0..=50 {
        let (mut p, mut v, mut a) = ([0.0; 2], [0.0; 2], [0.0; 2]);
        let point = path.sample(path.duration() * k as f64 / 50.0, &mut p, &mut v, &mut a);
        all.extend(p.into_iter().chain(v).chain(a));
        all.push(point as f64);
    }
    all
}

#[test]
fn a_refused_plan_leaves_the_previous_path_untouched() {
    let mut path = Path::new(2, 8);
    let velocities = [0.0, 0.0, 1.0, -1.0, 0.0, 0.0];
    plan_with(
        &mut path,
        &[1.0, 2.0, 3.5],
        &[1.0, 1.0, 2.0, 0.0, 3.0, -1.0],
        Some(&velocities),
        None,
        [0.0; 2],
    )
    .unwrap();
    let before = snapshot(&path);
    // Refused while checking the points, and refused while checking the segments (after
    // the new segments were built).
    for (times, positions) in [
        ([1.0, 2.0, 2.0], [1.0, 1.0, 2.0, 0.0, 3.0, -1.0]),
        ([1.0, 2.0, 2.1], [1.0, 1.0, 2.0, 0.0, 3.0, -1.0]),
        ([1.0, 2.0, 3.5], [1.0, 1.0, 2.0, 0.0, 3.0, 9.99]),
    ] {
        plan_with(
            &mut path,
            &times,
            &positions,
            Some(&velocities),
            None,
            [0.0; 2],
        )
        .unwrap_err();
        assert_eq!(snapshot(&path), before, "{times:?}");
    }
    path.plan_line(&[0.0; 2], &[0.0, 11.0], &LIMITS, 1.0, 1.0)
        .unwrap_err();
    path.plan_line(&[0.0; 2], &[0.0, 1.0], &LIMITS, 2.0, 1.0)
        .unwrap_err();
    assert_eq!(snapshot(&path), before);
    // And a line refused after a line.
    path.plan_line(&[0.0; 2], &[1.0, 1.0], &LIMITS, 1.0, 1.0)
        .unwrap();
    let line = snapshot(&path);
    plan_with(
        &mut path,
        &[0.0, 1.0],
        &[5.0, 0.0, 1.0, 1.0],
        None,
        None,
        [0.0; 2],
    )
    .unwrap_err();
    assert_eq!(snapshot(&path), line);
}
