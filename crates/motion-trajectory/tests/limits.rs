//! Property tests: random groups (1–16 axes, random limits), random lines and random
//! trajectories. Whenever a plan is accepted, sampling it every millisecond never exceeds an
//! axis's limits; following it with random feed changes, holds and resumes never does either
//! (analytic and finite-differenced), every hold comes to rest, and it ends at `end()`.

mod support;

use motion_trajectory::{AxisLimits, Path, PathError, Points, Tolerances};
use proptest::prelude::*;
use support::{ANALYTIC_SLACK, DT, follow};

/// Hands out the random numbers of a case in order (each in [0, 1)).
struct Draw<'a>(std::slice::Iter<'a, f64>);

impl Draw<'_> {
    fn unit(&mut self) -> f64 {
        *self.0.next().expect("enough random numbers")
    }

    /// Uniform in [low, high).
    fn range(&mut self, low: f64, high: f64) -> f64 {
        low + (high - low) * self.unit()
    }

    /// Uniform in (-1, 1).
    fn signed(&mut self) -> f64 {
        2.0 * self.unit() - 1.0
    }
}

/// Checks the path at feed 1 every millisecond (and at its end) against `limits`.
fn check_sampled(path: &Path, limits: &[AxisLimits]) {
    let axes = path.axes();
    let (mut p, mut v, mut a) = (vec![0.0; axes], vec![0.0; axes], vec![0.0; axes]);
    let ticks = (path.duration() / DT).ceil() as usize;
    for k in 0..=ticks {
        let t = (k as f64 * DT).min(path.duration());
        path.sample(t, &mut p, &mut v, &mut a);
        for (j, l) in limits.iter().enumerate() {
            assert!(
                p[j] >= l.min && p[j] <= l.max,
                "t {t} axis {j}: {} out of {l:?}",
                p[j]
            );
            assert!(
                v[j].abs() <= l.max_velocity * (1.0 + ANALYTIC_SLACK),
                "t {t} axis {j}: velocity {} over {l:?}",
                v[j]
            );
            assert!(
                a[j].abs() <= l.max_accel * (1.0 + ANALYTIC_SLACK),
                "t {t} axis {j}: acceleration {} over {l:?}",
                a[j]
            );
        }
    }
}

/// A random feed schedule over about `duration` seconds: (tick, target), sorted, holds (0)
/// among them; and the feed to start at.
fn schedule(draw: &mut Draw<'_>, duration: f64) -> (f64, Vec<(usize, f64)>) {
    let initial = if draw.unit() < 0.2 {
        0.0
    } else {
        draw.range(0.3, 1.5)
    };
    let ticks = duration / DT;
    let count = (draw.unit() * 5.0) as usize;
    let mut events: Vec<(usize, f64)> = (0..count)
        .map(|_| {
            let tick = (draw.unit() * 1.2 * ticks) as usize;
            let target = if draw.unit() < 0.4 {
                0.0
            } else {
                draw.range(0.05, 1.5)
            };
            (tick, target)
        })
        .collect();
    events.sort_by_key(|e| e.0);
    (initial, events)
}

/// Follows `path` with a random schedule: within the limits throughout, every hold at rest
/// in bounded time, ending at `end()`.
fn check_followed(path: &Path, limits: &[AxisLimits], draw: &mut Draw<'_>) {
    let (initial, events) = schedule(draw, path.duration());
    // A hold takes at most the rest of the path (about duration / feed ≥ 0.05) plus slack.
    let hold_bound = (path.duration() / 0.05 / DT) as usize + 2000;
    let tick_bound = 200 * (path.duration() / DT) as usize + 200_000;
    let run = follow(path, limits, initial, &events, hold_bound, tick_bound);
    assert_eq!(run.end.as_slice(), path.end(), "{events:?}");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn lines_stay_within_the_limits_start_and_arrive_together(
        axes in 1usize..=16,
        numbers in prop::collection::vec(0.0f64..1.0, 200),
    ) {
        let mut draw = Draw(numbers.iter());
        let limits: Vec<AxisLimits> = (0..axes)
            .map(|_| {
                let min = draw.range(-100.0, 0.0);
                let span = draw.range(1.0, 200.0);
                AxisLimits {
                    min,
                    max: min + span,
                    max_velocity: span * draw.range(0.2, 3.0),
                    max_accel: span * draw.range(0.5, 30.0),
                }
            })
            .collect();
        let start: Vec<f64> = limits.iter().map(|l| l.min + (l.max - l.min) * draw.unit()).collect();
        let target: Vec<f64> = limits
            .iter()
            .zip(&start)
            .map(|(l, &s)| if draw.unit() < 0.2 { s } else { l.min + (l.max - l.min) * draw.unit() })
            .collect();
        let (velocity_scale, accel_scale) = (draw.range(0.25, 1.0), draw.range(0.25, 1.0));
        let mut path = Path::new(axes, 0);
        path.plan_line(&start, &target, &limits, velocity_scale, accel_scale).unwrap();
        check_sampled(&path, &limits);
        let (mut p, mut v, mut a) = (vec![0.0; axes], vec![0.0; axes], vec![0.0; axes]);
        path.sample(0.0, &mut p, &mut v, &mut a);
        prop_assert_eq!(&p, &start);
        path.sample(path.duration(), &mut p, &mut v, &mut a);
        prop_assert_eq!(&p, &target);
        // Together: every moving axis at the same fraction of its move, all the way.
        for k in 0..=20 {
            path.sample(path.duration() * k as f64 / 20.0, &mut p, &mut v, &mut a);
            let fractions = (0..axes)
                .filter(|&j| target[j] != start[j])
                .map(|j| (p[j] - start[j]) / (target[j] - start[j]));
            let (low, high) = fractions.fold((f64::MAX, f64::MIN), |(l, h), s| (l.min(s), h.max(s)));
            prop_assert!(low > high || high - low < 1e-9, "{} {}", low, high);
        }
        // The slowest axis sets the time: some axis's acceleration reaches its scaled limit
        // (so the feed can rise by 1/√accel_scale at most), none exceeds it.
        if path.duration() > 0.0 {
            prop_assert!(path.max_feed() >= 1.0 - 1e-12, "{}", path.max_feed());
            prop_assert!(path.max_feed() <= 1.0 / accel_scale.sqrt() + 1e-9, "{}", path.max_feed());
        }
        check_followed(&path, &limits, &mut draw);
    }

    #[test]
    fn trajectories_accepted_stay_within_the_limits(
        axes in 1usize..=16,
        count in 1usize..=10,
        kind in 0u8..3,
        lead_in in any::<bool>(),
        numbers in prop::collection::vec(0.0f64..1.0, 1200),
    ) {
        let mut draw = Draw(numbers.iter());
        // The trajectory, drawn within a range per axis at a pace per axis.
        let ranges: Vec<(f64, f64, f64)> = (0..axes)
            .map(|_| {
                let min = draw.range(-50.0, 0.0);
                let span = draw.range(1.0, 100.0);
                (min, min + span, span * draw.range(0.05, 0.5))
            })
            .collect();
        let mut times = Vec::with_capacity(count);
        let mut t = if lead_in { draw.range(0.1, 1.0) } else { 0.0 };
        for _ in 0..count {
            times.push(t);
            t += draw.range(0.1, 1.0);
        }
        let stride = 16;
        let (mut positions, mut velocities, mut accelerations) =
            (vec![0.0; stride * count], vec![0.0; stride * count], vec![0.0; stride * count]);
        for (j, &(min, max, pace)) in ranges.iter().enumerate() {
            let mut p = min + (max - min) * draw.unit();
            for i in 0..count {
                if i > 0 {
                    p = (p + draw.signed() * pace * (times[i] - times[i - 1])).clamp(min, max);
                }
                positions[i * stride + j] = p;
                if i + 1 < count {
                    velocities[i * stride + j] = draw.signed() * pace;
                    accelerations[i * stride + j] = draw.signed() * pace * 3.0;
                }
            }
        }
        let start_position: Vec<f64> = ranges
            .iter()
            .enumerate()
            .map(|(j, &(min, max, pace))| {
                if lead_in {
                    (positions[j] + draw.signed() * pace * times[0]).clamp(min, max)
                } else {
                    positions[j]
                }
            })
            .collect();
        let start_velocity: Vec<f64> = ranges.iter().map(|r| draw.signed() * r.2 * 0.5).collect();
        let start_acceleration: Vec<f64> = ranges.iter().map(|r| draw.signed() * r.2).collect();
        let points = Points {
            times: &times,
            positions: &positions,
            velocities: (kind >= 1).then_some(velocities.as_slice()),
            accelerations: (kind == 2).then_some(accelerations.as_slice()),
            stride,
        };
        let plan = |path: &mut Path, limits: &[AxisLimits]| {
            path.plan_points(
                &start_position, &start_velocity, &start_acceleration, &points, limits, &Tolerances { start: &vec![0.0; axes], path: &vec![0.0; axes] },
            )
        };

        // Planned with limits that bind nothing, then sampled: what each axis does.
        let loose = vec![AxisLimits { min: -1e9, max: 1e9, max_velocity: 1e9, max_accel: 1e12 }; axes];
        let mut path = Path::new(axes, 10);
        plan(&mut path, &loose).unwrap();
        let mut seen = vec![(f64::MAX, f64::MIN, 0.0f64, 0.0f64); axes];
        let (mut p, mut v, mut a) = (vec![0.0; axes], vec![0.0; axes], vec![0.0; axes]);
        let ticks = (path.duration() / DT).ceil() as usize;
        for k in 0..=ticks {
            path.sample((k as f64 * DT).min(path.duration()), &mut p, &mut v, &mut a);
            for (j, s) in seen.iter_mut().enumerate() {
                *s = (s.0.min(p[j]), s.1.max(p[j]), s.2.max(v[j].abs()), s.3.max(a[j].abs()));
            }
        }
        // max_feed is exact: at least what sampling shows, and not much more.
        let sampled = seen.iter().zip(&loose).fold(f64::INFINITY, |feed, (s, l)| {
            let by_velocity = if s.2 > 0.0 { l.max_velocity / s.2 } else { f64::INFINITY };
            let by_accel = if s.3 > 0.0 { (l.max_accel / s.3).sqrt() } else { f64::INFINITY };
            feed.min(by_velocity).min(by_accel)
        });
        prop_assert!(
            path.max_feed() <= sampled * (1.0 + 1e-9) && path.max_feed() >= sampled * 0.9,
            "max_feed {} from samples {}", path.max_feed(), sampled
        );

        // Limits around what was seen: over it (by 0–30 %), except, in half the cases, one
        // limit of one axis a little under it (by 0.1–5 %), which must be refused.
        let tightened = (draw.unit() < 0.5)
            .then(|| ((draw.unit() * axes as f64) as usize, (draw.unit() * 4.0) as usize));
        let mut must_refuse = false;
        let mut must_accept = true;
        let mut limits = Vec::with_capacity(axes);
        for (j, &(low, high, velocity, accel)) in seen.iter().enumerate() {
            let size = high - low + 1e-3;
            let mut margin = [0.0; 4];
            for (kind, m) in margin.iter_mut().enumerate() {
                *m = if tightened == Some((j, kind)) {
                    if kind < 2 { -size * draw.range(0.001, 0.05) } else { draw.range(0.95, 0.999) }
                } else {
                    let over = draw.range(0.0, 0.3);
                    if kind < 2 { size * over } else { 1.0 + over }
                };
            }
            let [below, above, fv, fa] = margin;
            let mut scaled = |seen: f64, f: f64| {
                if seen > 1e-9 {
                    must_refuse |= f < 1.0;
                    must_accept &= f >= 1.05;
                }
                if seen > 0.0 { seen * f } else { 1.0 }
            };
            let (max_velocity, max_accel) = (scaled(velocity, fv), scaled(accel, fa));
            must_refuse |= below < 0.0 || above < 0.0;
            must_accept &= below > 1e-6 && above > 1e-6;
            limits.push(AxisLimits { min: low - below, max: high + above, max_velocity, max_accel });
        }
        let mut tight = Path::new(axes, 10);
        match plan(&mut tight, &limits) {
            Ok(()) => {
                // Positions alone may be blended at the points when the spline exceeds a limit.
                prop_assert!(!must_refuse || kind == 0, "accepted over the limits: {:?}", limits);
                check_sampled(&tight, &limits);
                check_followed(&tight, &limits, &mut draw);
            }
            Err(error) => {
                prop_assert!(!must_accept, "refused within the limits: {}", error);
                prop_assert!(
                    matches!(
                        error,
                        PathError::VelocityLimit { .. }
                            | PathError::AccelLimit { .. }
                            | PathError::OutOfRange { .. }
                    ) || (kind == 0 && matches!(error, PathError::BlendTolerance { .. })) || (matches!(error, PathError::BadLimits { axis } if limits[axis].min > limits[axis].max)),
                    "{}", error
                );
                prop_assert!(tight.is_empty());
            }
        }
    }
}
