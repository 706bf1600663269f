//! Feed override, hold and resume.

mod support;

use motion_trajectory::{AxisLimits, Path, TimeScale};
use support::{DT, follow};

const LIMITS: [AxisLimits; 2] = [
    AxisLimits {
        min: -100.0,
        max: 100.0,
        max_velocity: 10.0,
        max_accel: 20.0,
    },
    AxisLimits {
        min: -100.0,
        max: 100.0,
        max_velocity: 10.0,
        max_accel: 100.0,
    },
];

/// 0 → (20, 5): s' ≤ 0.5, s'' ≤ 1 (axis 0 at its acceleration limit while ramping), ramps of
/// 0.5 s, 2.5 s in all.
fn line(velocity_scale: f64, accel_scale: f64) -> Path {
    let mut path = Path::new(2, 0);
    path.plan_line(
        &[0.0, 0.0],
        &[20.0, 5.0],
        &LIMITS,
        velocity_scale,
        accel_scale,
    )
    .unwrap();
    path
}

#[test]
fn a_hold_while_an_axis_accelerates_at_its_limit_comes_to_rest_and_resumes() {
    let path = line(1.0, 1.0);
    assert!((path.duration() - 2.5).abs() < 1e-12);
    let mut scale = TimeScale::new();
    let (mut p, mut v, mut a) = ([0.0; 2], [0.0; 2], [0.0; 2]);
    for _ in 0..200 {
        scale.step(&path, &LIMITS, DT);
    }
    scale.sample(&path, &mut p, &mut v, &mut a);
    assert!((a[0] - 20.0).abs() < 1e-9, "axis 0 at its limit: {a:?}");
    scale.set_target(0.0);
    let mut ticks = 0;
    while !scale.at_rest() {
        scale.step(&path, &LIMITS, DT);
        ticks += 1;
        assert!(
            ticks < 1000,
            "no rest after {ticks} ticks: feed {}",
            scale.feed()
        );
    }
    assert_eq!(scale.feed(), 0.0);
    // 4 u/s at 20 u/s² takes at least 0.2 s.
    assert!((200..400).contains(&ticks), "{ticks}");
    scale.sample(&path, &mut p, &mut v, &mut a);
    let held = p;
    for _ in 0..100 {
        scale.step(&path, &LIMITS, DT);
    }
    scale.sample(&path, &mut p, &mut v, &mut a);
    assert_eq!((p, v), (held, [0.0; 2]), "held still");
    scale.set_target(1.0);
    while scale.feed() < path.max_feed().min(1.0) {
        scale.step(&path, &LIMITS, DT);
        assert!(!scale.finished(&path));
    }
    while !scale.finished(&path) {
        scale.step(&path, &LIMITS, DT);
    }
    scale.sample(&path, &mut p, &mut v, &mut a);
    assert_eq!(p, [20.0, 5.0]);
    // The same with every limit checked at every tick.
    let run = follow(&path, &LIMITS, 1.0, &[(200, 0.0), (800, 1.0)], 400, 10_000);
    assert_eq!((run.holds, run.end.as_slice()), (1, path.end()));
}

#[test]
fn a_hold_while_decelerating_at_the_limit_rides_the_path_to_its_end() {
    let path = line(1.0, 1.0);
    let mut scale = TimeScale::new();
    for _ in 0..2100 {
        scale.step(&path, &LIMITS, DT);
    }
    scale.set_target(0.0);
    while !scale.at_rest() {
        scale.step(&path, &LIMITS, DT);
        // It cannot stop sooner than the path does: the feed stays (about) 1.
        assert!(scale.at_rest() || scale.feed() > 0.999, "{}", scale.feed());
    }
    let (mut p, mut v, mut a) = ([0.0; 2], [0.0; 2], [0.0; 2]);
    scale.sample(&path, &mut p, &mut v, &mut a);
    // Within a tick of the end: 20 u/s² for 1 ms from rest is 10 µm.
    assert!((p[0] - 20.0).abs() < 1e-5, "{p:?}");
    scale.set_target(1.0);
    while !scale.finished(&path) {
        scale.step(&path, &LIMITS, DT);
    }
    scale.sample(&path, &mut p, &mut v, &mut a);
    assert_eq!(p, [20.0, 5.0]);
}

#[test]
fn the_override_reaches_150_percent_only_where_the_path_has_headroom() {
    // At half velocity and a quarter acceleration: max_feed 2.
    let path = line(0.5, 0.25);
    assert!((path.max_feed() - 2.0).abs() < 1e-12, "{}", path.max_feed());
    let run = follow(&path, &LIMITS, 1.0, &[(100, 1.5)], 0, 100_000);
    let nominal = (path.duration() / DT).ceil() as usize;
    assert!(run.ticks < nominal * 3 / 4, "{} of {nominal}", run.ticks);
    assert_eq!(run.end.as_slice(), path.end());
    let mut scale = TimeScale::new();
    scale.set_target(2.0);
    assert_eq!(scale.target(), 1.5, "clamped");
    for _ in 0..2000 {
        scale.step(&path, &LIMITS, DT);
    }
    assert_eq!(scale.feed(), 1.5);
    // At full limits there is no headroom: the feed stays at max_feed (1).
    let path = line(1.0, 1.0);
    let run = follow(&path, &LIMITS, 1.0, &[(0, 1.5)], 0, 100_000);
    assert!(run.velocity_ratio <= 1.0 + 1e-9 && run.velocity_ratio > 0.999);
    let mut scale = TimeScale::new();
    scale.set_target(1.5);
    for _ in 0..1000 {
        scale.step(&path, &LIMITS, DT);
        assert!(scale.feed() <= path.max_feed());
    }
}

#[test]
fn restart_sets_the_feed_capped_by_the_path_at_the_next_step() {
    let path = line(1.0, 1.0);
    let mut scale = TimeScale::new();
    scale.restart(1.5);
    assert_eq!(
        (scale.feed(), scale.target(), scale.time()),
        (1.5, 1.5, 0.0)
    );
    scale.step(&path, &LIMITS, DT);
    assert!(scale.feed() <= path.max_feed(), "{}", scale.feed());
    // Restarted held: nothing moves until resumed.
    scale.restart(0.0);
    for _ in 0..10 {
        scale.step(&path, &LIMITS, DT);
    }
    assert!(scale.at_rest() && scale.time() == 0.0);
    let run = follow(&path, &LIMITS, 0.0, &[(50, 0.7)], 0, 100_000);
    assert_eq!(run.end.as_slice(), path.end());
}

#[test]
fn targets_are_clamped_and_a_bad_dt_does_nothing() {
    let mut scale = TimeScale::default();
    assert_eq!(
        (scale.feed(), scale.target(), scale.time()),
        (1.0, 1.0, 0.0)
    );
    for (set, kept) in [
        (-1.0, 0.0),
        (f64::NAN, 0.0),
        (0.5, 0.5),
        (f64::INFINITY, 1.5),
    ] {
        scale.set_target(set);
        assert_eq!(scale.target(), kept);
    }
    let path = line(1.0, 1.0);
    let before = scale;
    for dt in [0.0, -1e-3, f64::NAN, f64::INFINITY] {
        scale.step(&path, &LIMITS, dt);
        assert_eq!(scale, before);
    }
}

#[test]
fn empty_and_zero_length_paths_are_finished_at_once() {
    let mut path = Path::new(2, 4);
    let mut scale = TimeScale::new();
    assert!(scale.finished(&path));
    scale.step(&path, &LIMITS, DT);
    assert!(scale.finished(&path));
    path.plan_line(&[1.0, 1.0], &[1.0, 1.0], &LIMITS, 1.0, 1.0)
        .unwrap();
    scale.restart(1.0);
    scale.step(&path, &LIMITS, DT);
    assert!(scale.finished(&path));
    let (mut p, mut v, mut a) = ([0.0; 2], [0.0; 2], [0.0; 2]);
    scale.sample(&path, &mut p, &mut v, &mut a);
    assert_eq!((p, v, a), ([1.0; 2], [0.0; 2], [0.0; 2]));
}
