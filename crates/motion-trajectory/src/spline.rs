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

/// Preallocated scratch for the tridiagonal solve. The matrix depends only on the times, so
/// it is eliminated once for all axes; only the right-hand sides are per axis.
#[derive(Debug, Clone)]
pub(crate) struct Spline {
    axes: usize,
    upper: Vec<f64>,
    /// Point i, axis j at `i * axes + j`.
    velocity: Vec<f64>,
}

impl Spline {
    /// Scratch for up to `max_points` points of `axes` axes.
    pub(crate) fn new(max_points: usize, axes: usize) -> Self {
        Self {
            axes,
            upper: vec![0.0; max_points],
            velocity: vec![0.0; max_points * axes],
        }
    }

    /// The velocity at `point` (≤ n−2) of `axis` from the last [`Spline::solve`].
    #[inline]
    pub(crate) fn velocity(&self, point: usize, axis: usize) -> f64 {
        self.velocity[point * self.axes + axis]
    }

    /// Solves for the velocities at points 0 ..= n−2 (the one at n−1 is 0) of every axis
    /// through the positions `position(point, axis)` at `times` (n = times.len() ≥ 3, times
    /// strictly increasing). `clamp`: the velocity of each axis at point 0 (no lead-in), or
    /// `None` for the natural condition.
    pub(crate) fn solve(
        &mut self,
        times: &[f64],
        position: impl Fn(usize, usize) -> f64,
        clamp: Option<&[f64]>,
    ) {
        let n = times.len();
        let axes = self.axes;
        debug_assert!(n >= 3 && n <= self.upper.len());
        let last = n - 2;
        let h = |i: usize| times[i + 1] - times[i];
        let delta = |i: usize, axis: usize| position(i + 1, axis) - position(i, axis);
        let upper = &mut self.upper[..=last];
        let velocity = &mut self.velocity[..(last + 1) * axes];
        // Row 0.
        match clamp {
            Some(v) => {
                upper[0] = 0.0;
                velocity[..axes].copy_from_slice(&v[..axes]);
            }
            None => {
                // (2/h0)·m0 + (1/h0)·m1 = 3·δ0/h0², that is m0 + m1/2 = 1.5·δ0/h0.
                let h0 = h(0);
                upper[0] = 0.5;
                for (axis, m) in velocity[..axes].iter_mut().enumerate() {
                    *m = 1.5 * delta(0, axis) / h0;
                }
            }
        }
        // Rows 1 ..= n−2, eliminated as they come (Thomas's algorithm).
        for i in 1..=last {
            let (sub, diagonal, sup, rhs_before, rhs_after) = if i < last {
                // C2 at point i.
                let (a, b) = (1.0 / h(i - 1), 1.0 / h(i));
                (a, 2.0 * (a + b), b, 3.0 * a * a, 3.0 * b * b)
            } else {
                // C3 at point n−2 between the cubic of length h and the quintic of length t.
                let (ih, it) = (1.0 / h(i - 1), 1.0 / h(i));
                (
                    6.0 * ih * ih + 18.0 * ih * it,
                    6.0 * ih * ih + 36.0 * it * it + 36.0 * ih * it,
                    0.0,
                    54.0 * it * ih * ih + 12.0 * ih * ih * ih,
                    60.0 * it * it * it,
                )
            };
            let w = 1.0 / (diagonal - sub * upper[i - 1]);
            upper[i] = sup * w;
            let (done, row) = velocity.split_at_mut(i * axes);
            let before = &done[(i - 1) * axes..];
            for (axis, m) in row[..axes].iter_mut().enumerate() {
                let rhs = rhs_before * delta(i - 1, axis) + rhs_after * delta(i, axis);
                *m = (rhs - sub * before[axis]) * w;
            }
        }
        for i in (0..last).rev() {
            let (row, after) = velocity.split_at_mut((i + 1) * axes);
            for (m, next) in row[i * axes..].iter_mut().zip(&after[..axes]) {
                *m -= upper[i] * next;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::polynomial::{Span, cubic_hermite, eval, quintic_hermite};

    /// The segments of one axis through `p` at `times`, as the path builds them.
    fn segments(times: &[f64], p: &[f64], clamp: Option<f64>) -> Vec<([f64; 6], f64)> {
        let mut spline = Spline::new(times.len(), 1);
        let clamp = clamp.map(|v| [v]);
        spline.solve(times, |i, _| p[i], clamp.as_ref().map(|v| &v[..]));
        let n = times.len();
        let m = |i: usize| {
            if i < n - 1 {
                spline.velocity(i, 0)
            } else {
                0.0
            }
        };
        let mut out = Vec::new();
        for i in 0..n - 2 {
            let h = times[i + 1] - times[i];
            out.push((
                cubic_hermite(p[i], m(i), p[i + 1], m(i + 1), &Span::new(h)),
                h,
            ));
        }
        let (c, h) = out[n - 3];
        let a = eval(&c, h)[2];
        let t = times[n - 1] - times[n - 2];
        out.push((
            quintic_hermite([p[n - 2], m(n - 2), a], [p[n - 1], 0.0, 0.0], &Span::new(t)),
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
