//! Following a path tick by tick with a [`TimeScale`], checking every limit on the way.

#![allow(dead_code)]

use motion_trajectory::{AxisLimits, Path, TimeScale};

/// The tick.
pub const DT: f64 = 1e-3;

/// The relative slack of the checks of analytic values (the planner's own is 10⁻⁹).
pub const ANALYTIC_SLACK: f64 = 1e-6;

/// The relative slack of the finite-difference acceleration: the feed changes once per tick
/// while the path's p' and p'' change within it, and the time scaling checks the tick's ends
/// and the segment boundaries it crosses, not every instant in between. (Over 8000 random
/// cases the largest ratio seen was 1 + 1.1·10⁻⁸.)
pub const DISCRETE_SLACK: f64 = 1e-5;

/// What a run saw.
#[derive(Debug, Clone, Default)]
pub struct Run {
    /// Ticks until finished.
    pub ticks: usize,
    /// The final position.
    pub end: Vec<f64>,
    /// The largest |a| / max_accel seen, analytic and finite-differenced.
    pub accel_ratio: f64,
    /// The largest finite-difference |a| / max_accel.
    pub discrete_accel_ratio: f64,
    /// The largest |v| / max_velocity, analytic.
    pub velocity_ratio: f64,
    /// The largest number of ticks a hold took to come to rest.
    pub longest_hold: usize,
    /// The holds that came to rest.
    pub holds: usize,
}

/// Whether `x` is within `limit` up to a relative slack and an absolute one (rounding).
fn within(x: f64, limit: f64, relative: f64, absolute: f64) -> bool {
    x.abs() <= limit * (1.0 + relative) + absolute
}

/// Follows `path` from τ = 0 at feed `initial`, setting each event's target at its tick
/// (events sorted by tick), then resuming a hold at feed 1 once the events are over, until it
/// finishes. Panics on any limit exceeded, on a hold that does not come to rest within
/// `hold_bound` ticks, or on a run longer than `tick_bound`.
pub fn follow(
    path: &Path,
    limits: &[AxisLimits],
    initial: f64,
    events: &[(usize, f64)],
    hold_bound: usize,
    tick_bound: usize,
) -> Run {
    let axes = path.axes();
    let mut scale = TimeScale::new();
    scale.restart(initial);
    let (mut p, mut v, mut a) = (vec![0.0; axes], vec![0.0; axes], vec![0.0; axes]);
    scale.sample(path, &mut p, &mut v, &mut a);
    // The positions of the last two ticks.
    let (mut before, mut last) = (p.clone(), p.clone());
    let mut ticks = 0usize;
    let mut hold_since: Option<usize> = None;
    let mut next_event = 0;
    let mut run = Run::default();
    let scale_of = |x: &[f64]| x.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    loop {
        while next_event < events.len() && events[next_event].0 <= ticks {
            scale.set_target(events[next_event].1);
            next_event += 1;
        }
        if next_event == events.len() && scale.target() == 0.0 && scale.at_rest() {
            scale.set_target(1.0);
        }
        match (scale.target() == 0.0, hold_since) {
            (true, None) if !scale.at_rest() => hold_since = Some(ticks),
            (false, _) => hold_since = None,
            _ => {}
        }
        let held = scale.at_rest() && scale.target() == 0.0;
        scale.step(path, limits, DT);
        ticks += 1;
        scale.sample(path, &mut p, &mut v, &mut a);
        let rounding = 8.0 * f64::EPSILON * scale_of(&p) / (DT * DT);
        for (j, l) in limits.iter().enumerate() {
            let context = || {
                format!(
                    "tick {ticks}, axis {j}: p {} v {} a {}, feed {} → target {}, τ {} of {}, \
                     limits {l:?}",
                    p[j],
                    v[j],
                    a[j],
                    scale.feed(),
                    scale.target(),
                    scale.time(),
                    path.duration()
                )
            };
            assert!(
                p[j] >= l.min && p[j] <= l.max,
                "out of range: {}",
                context()
            );
            assert!(
                within(v[j], l.max_velocity, ANALYTIC_SLACK, 1e-12),
                "velocity: {}",
                context()
            );
            assert!(
                within(a[j], l.max_accel, ANALYTIC_SLACK, 1e-9),
                "acceleration: {}",
                context()
            );
            let fd_v = (p[j] - last[j]) / DT;
            assert!(
                within(fd_v, l.max_velocity, ANALYTIC_SLACK, rounding * DT),
                "finite-difference velocity {fd_v}: {}",
                context()
            );
            // From the second tick on: three positions the run went through.
            let fd_a = if ticks >= 2 {
                (p[j] - 2.0 * last[j] + before[j]) / (DT * DT)
            } else {
                0.0
            };
            assert!(
                within(fd_a, l.max_accel, DISCRETE_SLACK, rounding),
                "finite-difference acceleration {fd_a}: {}",
                context()
            );
            run.velocity_ratio = run.velocity_ratio.max(v[j].abs() / l.max_velocity);
            run.accel_ratio = run.accel_ratio.max(a[j].abs() / l.max_accel);
            run.discrete_accel_ratio = run.discrete_accel_ratio.max(fd_a.abs() / l.max_accel);
        }
        if let Some(since) = hold_since {
            if scale.at_rest() {
                run.holds += 1;
                run.longest_hold = run.longest_hold.max(ticks - since);
                hold_since = None;
            } else {
                assert!(
                    ticks - since <= hold_bound,
                    "a hold since tick {since} has not come to rest (feed {}, τ {} of {})",
                    scale.feed(),
                    scale.time(),
                    path.duration()
                );
            }
        }
        if held {
            assert_eq!(p, last, "moving while held at tick {ticks}");
        }
        before.clone_from(&last);
        last.clone_from(&p);
        if scale.finished(path) && next_event == events.len() {
            break;
        }
        assert!(ticks <= tick_bound, "not finished after {ticks} ticks");
    }
    run.ticks = ticks;
    run.end = p;
    run
}
