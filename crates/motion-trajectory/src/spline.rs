//! The velocities at the points of a path through positions only: a C2 cubic spline that ends
//! at rest.
//!
//! The choice: for n ≥ 3 points, segments 0 → 1 … n−3 → n−2 are cubics (velocity mᵢ at point
//! i) and the last segment n−2 → n−1 is a quintic that arrives with velocity 0 AND acceleration
//! 0, so the group can stop at the last point. The unknowns m₀ … m_{n−2} solve one tridiagonal
//! system:
//! - point 0: with a lead-in (times[0] > 0) the natural condition, acceleration 0 at point 0
//!   (the lead-in quintic meets whatever velocity the spline has there); without one
//!   (times[0] = 0) m₀ is clamped to the start velocity, so the velocity is continuous;
//! - points 1 … n−3: the cubics' accelerations meet (C2);
//! - point n−2: the last cubic's acceleration is the quintic's start acceleration by
//!   construction (C2), and the row makes their jerks meet too (C3), which fixes the one degree
//!   of freedom left. The row is strictly diagonally dominant, as are the others (point 0's
//!   natural row weakly), so Thomas's algorithm needs no pivoting.
//!
//! Two points: the single segment is that quintic, leaving point 0 with the start velocity
//! (times[0] = 0) or at rest (after a lead-in) and zero acceleration.

/// Preallocated scratch for the tridiagonal solve.
#[derive(Debug, Clone)]
pub(crate) struct Spline {
    upper: Vec<f64>,
    velocity: Vec<f64>,
}

impl Spline {
    /// Scratch for up to `max_points` points.
    pub(crate) fn new(max_points: usize) -> Self {
        Self {
            upper: vec![0.0; max_points],
            velocity: vec![0.0; max_points],
        }
    }

    /// The velocities at points 0 ..= n−2 (the one at n−1 is 0) of one axis through the
    /// positions `position(i)` at `times` (n = times.len() ≥ 3, times strictly increasing).
    /// `clamp`: the velocity at point 0 (no lead-in), or `None` for the natural condition.
    pub(crate) fn solve(
        &mut self,
        times: &[f64],
        position: impl Fn(usize) -> f64,
        clamp: Option<f64>,
    ) -> &[f64] {
        let n = times.len();
        debug_assert!(n >= 3 && n <= self.velocity.len());
        let unknowns = n - 1;
        let h = |i: usize| times[i + 1] - times[i];
        let delta = |i: usize| position(i + 1) - position(i);
        // (sub, diagonal, super, right-hand side) of row i.
        let row = |i: usize| -> [f64; 4] {
            if i == 0 {
                match clamp {
                    Some(v) => [0.0, 1.0, 0.0, v],
                    None => {
                        let h0 = h(0);
                        [0.0, 2.0 / h0, 1.0 / h0, 3.0 * delta(0) / (h0 * h0)]
                    }
                }
            } else if i < unknowns - 1 {
                let (a, b) = (h(i - 1), h(i));
                [
                    1.0 / a,
                    2.0 * (1.0 / a + 1.0 / b),
                    1.0 / b,
                    3.0 * (delta(i - 1) / (a * a) + delta(i) / (b * b)),
                ]
            } else {
                // C3 at point n−2 between the cubic of length h and the quintic of length t.
                let (h, t) = (h(i - 1), h(i));
                let (dc, dq) = (delta(i - 1), delta(i));
                let (h2, t2) = (h * h, t * t);
                [
                    6.0 / h2 + 18.0 / (h * t),
                    6.0 / h2 + 36.0 / t2 + 36.0 / (h * t),
                    0.0,
                    60.0 * dq / (t2 * t) + 54.0 * dc / (t * h2) + 12.0 * dc / (h2 * h),
                ]
            }
        };
        let upper = &mut self.upper[..unknowns];
        let velocity = &mut self.velocity[..unknowns];
        let [_, diagonal, sup, rhs] = row(0);
        upper[0] = sup / diagonal;
        velocity[0] = rhs / diagonal;
        for i in 1..unknowns {
            let [sub, diagonal, sup, rhs] = row(i);
            let w = diagonal - sub * upper[i - 1];
            upper[i] = sup / w;
            velocity[i] = (rhs - sub * velocity[i - 1]) / w;
        }
        for i in (0..unknowns - 1).rev() {
            velocity[i] -= upper[i] * velocity[i + 1];
        }
        velocity
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::polynomial::{cubic_hermite, eval, quintic_hermite};

    /// The segments of one axis through `p` at `times`, as the path builds them.
    fn segments(times: &[f64], p: &[f64], clamp: Option<f64>) -> Vec<([f64; 6], f64)> {
        let mut spline = Spline::new(times.len());
        let m = spline.solve(times, |i| p[i], clamp).to_vec();
        let n = times.len();
        let mut out = Vec::new();
        for i in 0..n - 2 {
            let h = times[i + 1] - times[i];
            out.push((cubic_hermite(p[i], m[i], p[i + 1], m[i + 1], h), h));
        }
        let (c, h) = out[n - 3];
        let a = eval(&c, h)[2];
        let t = times[n - 1] - times[n - 2];
        out.push((
            quintic_hermite([p[n - 2], m[n - 2], a], [p[n - 1], 0.0, 0.0], t),
            t,
        ));
        out
    }

    #[test]
    fn the_spline_is_c2_passes_the_points_and_ends_at_rest() {
        let times = [0.5, 1.0, 1.7, 2.0, 3.1, 3.5];
        let p = [0.0, 1.0, -0.5, 0.2, 2.0, 1.5];
        for clamp in [None, Some(0.3)] {
            let segs = segments(&times, &p, clamp);
            for (i, (c, h)) in segs.iter().enumerate() {
                let start = eval(c, 0.0);
                let end = eval(c, *h);
                assert!((start[0] - p[i]).abs() < 1e-12);
                assert!((end[0] - p[i + 1]).abs() < 1e-9, "{i}: {end:?}");
                if let Some((next, _)) = segs.get(i + 1) {
                    let next = eval(next, 0.0);
                    assert!((end[1] - next[1]).abs() < 1e-9, "velocity at {}", i + 1);
                    assert!((end[2] - next[2]).abs() < 1e-8, "acceleration at {}", i + 1);
                } else {
                    assert!(end[1].abs() < 1e-9 && end[2].abs() < 1e-8, "{end:?}");
                }
            }
            let first = eval(&segs[0].0, 0.0);
            match clamp {
                Some(v) => assert_eq!(first[1], v),
                None => assert!(first[2].abs() < 1e-9, "natural start: {first:?}"),
            }
            // C3 at the last cubic / the quintic.
            let (c, h) = segs[segs.len() - 2];
            let (q, _) = segs[segs.len() - 1];
            let jerk_cubic = 6.0 * c[3] + 24.0 * c[4] * h + 60.0 * c[5] * h * h;
            assert!((jerk_cubic - 6.0 * q[3]).abs() < 1e-7 * (1.0 + jerk_cubic.abs()));
        }
    }
}
