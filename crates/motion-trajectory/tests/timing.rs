//! The engine plans inside its 1 ms tick: a trajectory of 1024 points × 16 axes must plan
//! (and pass its exact checks). How long it takes is printed, not asserted
//! (`cargo test --release -p motion-trajectory --test timing -- --nocapture`).

use std::f64::consts::TAU;
use std::time::{Duration, Instant};

use motion_trajectory::{AxisLimits, Path, Points, TimeScale, Tolerances};

const POINTS: usize = 1024;
const AXES: usize = 16;
const STRIDE: usize = 16;
const STEP: f64 = 0.01;

/// Points (stride 16) and the limits of the group.
struct Trajectory {
    times: Vec<f64>,
    positions: Vec<f64>,
    velocities: Vec<f64>,
    accelerations: Vec<f64>,
    limits: Vec<AxisLimits>,
}

/// p(t) = A·(x − sin(2πkx)/(2πk)), x = t/T: at rest at both ends, k oscillations between.
fn trajectory() -> Trajectory {
    let duration = (POINTS - 1) as f64 * STEP;
    let times: Vec<f64> = (0..POINTS).map(|i| i as f64 * STEP).collect();
    let (mut p, mut v, mut a) = (
        vec![0.0; POINTS * STRIDE],
        vec![0.0; POINTS * STRIDE],
        vec![0.0; POINTS * STRIDE],
    );
    let mut limits = Vec::new();
    for j in 0..AXES {
        let amplitude = 1.0 + j as f64;
        let w = TAU * (1 + j % 5) as f64;
        for (i, &t) in times.iter().enumerate() {
            let x = t / duration;
            p[i * STRIDE + j] = amplitude * (x - (w * x).sin() / w);
            if i + 1 < POINTS {
                v[i * STRIDE + j] = amplitude / duration * (1.0 - (w * x).cos());
                a[i * STRIDE + j] = amplitude / (duration * duration) * w * (w * x).sin();
            }
        }
        limits.push(AxisLimits {
            min: -1.0,
            max: amplitude + 1.0,
            max_velocity: 3.0 * 2.0 * amplitude / duration,
            max_accel: 3.0 * amplitude / (duration * duration) * w,
        });
    }
    Trajectory {
        times,
        positions: p,
        velocities: v,
        accelerations: a,
        limits,
    }
}

#[test]
fn a_trajectory_of_1024_points_by_16_axes_plans() {
    let Trajectory {
        times,
        positions,
        velocities,
        accelerations,
        limits,
    } = trajectory();
    let mut path = Path::new(AXES, POINTS);
    let start = [0.0; AXES];
    for (name, velocities, accelerations) in [
        ("quintic", Some(&velocities[..]), Some(&accelerations[..])),
        ("cubic", Some(&velocities[..]), None),
        ("positions only", None, None),
    ] {
        let points = Points {
            times: &times,
            positions: &positions,
            velocities,
            accelerations,
            stride: STRIDE,
        };
        let mut best = Duration::MAX;
        for _ in 0..5 {
            path.clear();
            let began = Instant::now();
            let planned = path.plan_points(
                &start,
                &start,
                &start,
                &points,
                &limits,
                &Tolerances {
                    start: &[1e-9; AXES],
                    path: &[0.0; AXES],
                },
            );
            best = best.min(began.elapsed());
            planned.unwrap_or_else(|e| panic!("{name}: {e}"));
        }
        assert_eq!(path.duration(), times[POINTS - 1]);
        assert!(path.max_feed() > 1.0, "{name}: {}", path.max_feed());
        eprintln!(
            "plan_points, {POINTS} points × {AXES} axes, {name}: {:.3} ms (best of 5; {:.0} ns a \
             segment and axis)",
            best.as_secs_f64() * 1e3,
            best.as_secs_f64() * 1e9 / (POINTS * AXES) as f64
        );
    }
}

/// Positions alone whose spline exceeds the velocity limit: blended at every point (a zigzag
/// at 95 % of the limit). The spline's checks stop at the first segment over a limit, so a
/// blended plan costs at most a spline's planning and a blend's.
#[test]
fn a_blended_trajectory_of_1024_points_by_16_axes_plans() {
    let limits = [AxisLimits {
        min: -1000.0,
        max: 1000.0,
        max_velocity: 10.0,
        max_accel: 2000.0,
    }; AXES];
    let times: Vec<f64> = (0..POINTS).map(|i| i as f64 * 0.1).collect();
    let positions: Vec<f64> = (0..POINTS * STRIDE)
        .map(|k| {
            if (k / STRIDE) % 2 == 1 {
                0.95 * (1 + k % STRIDE) as f64 / AXES as f64
            } else {
                0.0
            }
        })
        .collect();
    let points = Points {
        times: &times,
        positions: &positions,
        velocities: None,
        accelerations: None,
        stride: STRIDE,
    };
    let mut path = Path::new(AXES, POINTS);
    let zero = [0.0; AXES];
    let mut best = Duration::MAX;
    for _ in 0..5 {
        path.clear();
        let began = Instant::now();
        let planned = path.plan_points(
            &zero,
            &zero,
            &zero,
            &points,
            &limits,
            &Tolerances {
                start: &zero,
                path: &[0.1; AXES],
            },
        );
        best = best.min(began.elapsed());
        planned.unwrap_or_else(|e| panic!("blended: {e}"));
    }
    assert_eq!(path.duration(), times[POINTS - 1]);
    eprintln!(
        "plan_points, {POINTS} points × {AXES} axes, positions only, blended: {:.3} ms (best of \
         5; {:.0} ns a point and axis)",
        best.as_secs_f64() * 1e3,
        best.as_secs_f64() * 1e9 / (POINTS * AXES) as f64
    );
}

#[test]
fn following_it_with_a_hold_and_a_resume() {
    let Trajectory {
        times,
        positions,
        velocities,
        accelerations,
        limits,
    } = trajectory();
    let mut path = Path::new(AXES, POINTS);
    let points = Points {
        times: &times,
        positions: &positions,
        velocities: Some(&velocities),
        accelerations: Some(&accelerations),
        stride: STRIDE,
    };
    let start = [0.0; AXES];
    path.plan_points(
        &start,
        &start,
        &start,
        &points,
        &limits,
        &Tolerances {
            start: &[1e-9; AXES],
            path: &[0.0; AXES],
        },
    )
    .unwrap();
    let mut scale = TimeScale::new();
    let (mut p, mut v, mut a) = ([0.0; AXES], [0.0; AXES], [0.0; AXES]);
    let (mut ticks, mut total, mut longest) = (0u32, Duration::ZERO, Duration::ZERO);
    let mut each = Vec::with_capacity(20_000);
    while !scale.finished(&path) {
        match ticks {
            3000 => scale.set_target(0.0),
            5000 => scale.set_target(1.5),
            _ => {}
        }
        let began = Instant::now();
        scale.step(&path, &limits, 1e-3);
        scale.sample(&path, &mut p, &mut v, &mut a);
        let took = began.elapsed();
        total += took;
        longest = longest.max(took);
        each.push(took);
        ticks += 1;
        assert!(ticks < 100_000);
    }
    assert_eq!(p.as_slice(), path.end());
    each.sort();
    eprintln!(
        "TimeScale::step + sample, {AXES} axes: {:.2} µs a tick on average, 99.9 % within \
         {:.2} µs, {:.2} µs at most ({ticks} ticks, a hold and a resume to 150 %)",
        total.as_secs_f64() * 1e6 / f64::from(ticks),
        each[each.len() * 999 / 1000].as_secs_f64() * 1e6,
        longest.as_secs_f64() * 1e6
    );
}
