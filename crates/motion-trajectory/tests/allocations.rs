//! Planning and sampling allocate nothing after `Path::new`: a blended trajectory through
//! positions alone included. Counted per thread, so that the harness and other tests running
//! in parallel do not disturb the count.
#[path = "../../../tests/support/counting_alloc.rs"]
mod counting_alloc;

use counting_alloc::{CountingAllocator, allocations};
use motion_trajectory::{AxisLimits, Path, Points, TimeScale, Tolerances};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn a_blended_path_is_planned_and_followed_without_allocating() {
    const AXES: usize = 16;
    const POINTS: usize = 1024;
    let limits = [AxisLimits {
        min: -1000.0,
        max: 1000.0,
        max_velocity: 10.0,
        max_accel: 200.0,
    }; AXES];
    // A zigzag at 9.5 units/s: its spline overshoots 10 units/s, its blends pass each turn
    // at 19·0.095/8 ≈ 0.23.
    let times: Vec<f64> = (0..POINTS).map(|i| i as f64).collect();
    let positions: Vec<f64> = (0..POINTS * AXES)
        .map(|k| if (k / AXES) % 2 == 1 { 9.5 } else { 0.0 })
        .collect();
    let points = Points {
        times: &times,
        positions: &positions,
        velocities: None,
        accelerations: None,
        stride: AXES,
    };
    let zero = [0.0; AXES];
    let mut path = Path::new(AXES, POINTS);
    let mut scale = TimeScale::new();
    let (mut p, mut v, mut a) = ([0.0; AXES], [0.0; AXES], [0.0; AXES]);

    let before = allocations();
    let planned = path.plan_points(
        &zero,
        &zero,
        &zero,
        &points,
        &limits,
        &Tolerances {
            start: &zero,
            path: &[0.5; AXES],
        },
    );
    let mut ticks = 0u32;
    while !scale.finished(&path) && ticks < 3_000 {
        scale.step(&path, &limits, 1e-3);
        scale.sample(&path, &mut p, &mut v, &mut a);
        ticks += 1;
    }
    for k in 0..20_000 {
        path.sample(k as f64 * 0.05, &mut p, &mut v, &mut a);
    }
    let counted = allocations() - before;

    planned.expect("blended");
    path.sample(2.0, &mut p, &mut v, &mut a);
    assert!(
        (p[0] - 19.0 * 0.095 / 8.0).abs() < 1e-9,
        "blended: {}",
        p[0]
    );
    assert_eq!(counted, 0, "allocations while planning and sampling");
}
