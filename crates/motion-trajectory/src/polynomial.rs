//! Polynomials of degree five or less on one segment: evaluation, Hermite interpolation, and
//! their exact extremes on the segment.
//!
//! The extremes are analytic, not sampled: on the segment normalised to x ∈ [0, 1], the roots
//! of p‴ (a quadratic, closed form) split [0, 1] into intervals where p″ is monotonic, so each
//! holds at most one root of p″, found by a safeguarded Newton iteration inside its bracket;
//! the roots of p″ split it again for the roots of p′. |velocity| is largest at a root of p″ or
//! at an end, |acceleration| at a root of p‴ or at an end, the position at a root of p′ or at
//! an end. The position's roots are only looked for when the convex hull of the position's
//! Bernstein coefficients (which contains the whole segment) leaves the range.

/// c0..c5 of p(u) = c0 + c1·u + … + c5·u⁵, u in seconds from the segment's start.
pub(crate) type Coeffs = [f64; 6];

/// Position, velocity and acceleration of `c` at local time `u`.
#[inline]
pub(crate) fn eval(c: &Coeffs, u: f64) -> [f64; 3] {
    let p = ((((c[5] * u + c[4]) * u + c[3]) * u + c[2]) * u + c[1]) * u + c[0];
    let v = (((5.0 * c[5] * u + 4.0 * c[4]) * u + 3.0 * c[3]) * u + 2.0 * c[2]) * u + c[1];
    let a = ((20.0 * c[5] * u + 12.0 * c[4]) * u + 6.0 * c[3]) * u + 2.0 * c[2];
    [p, v, a]
}

/// A segment's duration, its powers and those of its inverse, computed once for all axes.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Span {
    /// The duration, seconds (> 0).
    pub t: f64,
    /// 1, t, t², t³, t⁴, t⁵.
    powers: [f64; 6],
    /// 1/t, 1/t², 1/t³, 1/t⁴, 1/t⁵.
    inverse: [f64; 5],
}

impl Span {
    pub(crate) fn new(t: f64) -> Self {
        let i = 1.0 / t;
        let (i2, t2) = (i * i, t * t);
        Self {
            t,
            powers: [1.0, t, t2, t2 * t, t2 * t2, t2 * t2 * t],
            inverse: [i, i2, i2 * i, i2 * i2, i2 * i2 * i],
        }
    }
}

/// The quintic over `span` from `start` to `end`, each (position, velocity, acceleration).
pub(crate) fn quintic_hermite(start: [f64; 3], end: [f64; 3], span: &Span) -> Coeffs {
    let [p0, v0, a0] = start;
    let [p1, v1, a1] = end;
    let d = p1 - p0;
    let (t, t2) = (span.t, span.t * span.t);
    let [_, _, i3, i4, i5] = span.inverse;
    [
        p0,
        v0,
        0.5 * a0,
        0.5 * (20.0 * d - (8.0 * v1 + 12.0 * v0) * t - (3.0 * a0 - a1) * t2) * i3,
        0.5 * (-30.0 * d + (14.0 * v1 + 16.0 * v0) * t + (3.0 * a0 - 2.0 * a1) * t2) * i4,
        0.5 * (12.0 * d - 6.0 * (v1 + v0) * t + (a1 - a0) * t2) * i5,
    ]
}

/// The cubic over `span` from (p0, v0) to (p1, v1).
pub(crate) fn cubic_hermite(p0: f64, v0: f64, p1: f64, v1: f64, span: &Span) -> Coeffs {
    let [i1, i2, ..] = span.inverse;
    let slope = (p1 - p0) * i1;
    [
        p0,
        v0,
        (3.0 * slope - 2.0 * v0 - v1) * i1,
        (v0 + v1 - 2.0 * slope) * i2,
        0.0,
        0.0,
    ]
}

/// At most four points of (0, 1), in increasing order.
#[derive(Debug, Clone, Copy)]
struct Roots {
    x: [f64; 4],
    n: usize,
}

impl Roots {
    const NONE: Self = Self { x: [0.0; 4], n: 0 };

    fn push(&mut self, x: f64) {
        if self.n < self.x.len() {
            self.x[self.n] = x;
            self.n += 1;
        }
    }

    fn as_slice(&self) -> &[f64] {
        &self.x[..self.n]
    }
}

/// Value and derivative of the quartic (or lower) `q` at `x`.
#[inline]
fn horner(q: &[f64; 5], x: f64) -> (f64, f64) {
    let mut f = q[4];
    let mut df = 0.0;
    for &c in q[..4].iter().rev() {
        df = df * x + f;
        f = f * x + c;
    }
    (f, df)
}

/// The roots in (0, 1) of c0 + c1·x + c2·x², in increasing order.
fn quadratic_roots(c0: f64, c1: f64, c2: f64) -> Roots {
    let mut roots = Roots::NONE;
    let mut keep = |x: f64| {
        if x > 0.0 && x < 1.0 {
            roots.push(x);
        }
    };
    if c2 == 0.0 {
        if c1 != 0.0 {
            keep(-c0 / c1);
        }
    } else {
        let disc = c1 * c1 - 4.0 * c2 * c0;
        if disc >= 0.0 {
            // The cancellation-free pair: q / c2 and c0 / q.
            let q = -0.5 * (c1 + disc.sqrt().copysign(c1));
            let (a, b) = if q == 0.0 {
                (0.0, 0.0)
            } else {
                (q / c2, c0 / q)
            };
            keep(a.min(b));
            if b != a {
                keep(a.max(b));
            }
        }
    }
    roots
}

/// The root of `q` in the bracket [lo, hi] where `q` is monotonic and changes sign
/// (`f_lo`, `f_hi` of opposite signs): Newton's iteration, falling back to bisection whenever
/// a step would leave the bracket or not halve it.
fn bracketed_root(q: &[f64; 5], mut lo: f64, mut hi: f64, f_lo: f64, f_hi: f64) -> f64 {
    const TOLERANCE: f64 = 1e-14;
    let rising = f_lo < 0.0;
    let mut x = lo - f_lo * (hi - lo) / (f_hi - f_lo);
    if !(x > lo && x < hi) {
        x = 0.5 * (lo + hi);
    }
    let mut step_before = hi - lo;
    for _ in 0..100 {
        let (f, df) = horner(q, x);
        if f == 0.0 {
            return x;
        }
        if (f < 0.0) == rising {
            lo = x;
        } else {
            hi = x;
        }
        let newton = x - f / df;
        let step = if df != 0.0
            && newton > lo
            && newton < hi
            && (2.0 * f).abs() <= (step_before * df).abs()
        {
            newton - x
        } else {
            0.5 * (lo + hi) - x
        };
        step_before = step;
        x += step;
        if step.abs() <= TOLERANCE || hi - lo <= TOLERANCE {
            return x;
        }
    }
    x
}

/// The roots in (0, 1) of `q`, given the roots of its derivative in (0, 1) (`critical`): `q`
/// is monotonic between consecutive critical points, so each such interval holds at most one.
/// A root exactly at a critical point is kept too (a candidate more does no harm).
fn roots_between(q: &[f64; 5], critical: &Roots) -> Roots {
    let mut roots = Roots::NONE;
    let mut a = 0.0;
    let mut f_a = q[0];
    for k in 0..=critical.n {
        let b = if k < critical.n { critical.x[k] } else { 1.0 };
        let f_b = horner(q, b).0;
        if f_b == 0.0 && k < critical.n {
            roots.push(b);
        } else if (f_a < 0.0 && f_b > 0.0) || (f_a > 0.0 && f_b < 0.0) {
            roots.push(bracketed_root(q, a, b, f_a, f_b));
        }
        a = b;
        f_a = f_b;
    }
    roots
}

/// Of `best` and `x`, the one of larger magnitude; NaN if either is NaN (a NaN must refuse).
#[inline]
fn wider(best: f64, x: f64) -> f64 {
    if x.is_nan() || best.is_nan() {
        f64::NAN
    } else if x.abs() > best.abs() {
        x
    } else {
        best
    }
}

/// What one axis does on one segment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Extremes {
    /// The velocity of largest magnitude on the segment, signed (infinite when the polynomial
    /// is not finite).
    pub velocity: f64,
    /// The acceleration of largest magnitude, signed (infinite when not finite).
    pub acceleration: f64,
    /// The position furthest outside `min..max` on the segment, if any.
    pub outside: Option<f64>,
}

/// `c` on [0, t] normalised to x ∈ [0, 1]: P(x) = p(t·x), so p' = P'/t and p'' = P''/t².
#[inline]
fn normalise(c: &Coeffs, t: f64) -> [f64; 6] {
    let mut b = [0.0; 6];
    let mut tk = 1.0;
    for (bk, &ck) in b.iter_mut().zip(c) {
        *bk = ck * tk;
        tk *= t;
    }
    b
}

/// Bounds on the polynomial `c` on [0, t] from the convex hulls of the Bernstein coefficients
/// of its position, velocity and acceleration (each lies within its hull): the bounds on
/// |velocity| and |acceleration| when the position's hull is within `min..max`; `None` when
/// it is not (or the polynomial is not finite), and only [`extremes`] can tell.
#[inline]
pub(crate) fn hull_bounds(c: &Coeffs, span: &Span, min: f64, max: f64) -> Option<(f64, f64)> {
    let mut b = [0.0; 6];
    for ((b, c), tk) in b.iter_mut().zip(c).zip(span.powers) {
        *b = c * tk;
    }
    let position = bernstein_position(&b);
    if !position.iter().all(|&x| x >= min && x <= max) {
        return None;
    }
    // P' = q0 + q1·x + … + q4·x⁴ and P'' = r0 + … + r3·x³, in Bernstein form.
    let q = [b[1], 2.0 * b[2], 3.0 * b[3], 4.0 * b[4], 5.0 * b[5]];
    let velocity = [
        q[0],
        q[0] + 0.25 * q[1],
        q[0] + 0.5 * q[1] + q[2] * (1.0 / 6.0),
        q[0] + 0.75 * q[1] + 0.5 * q[2] + 0.25 * q[3],
        q[0] + q[1] + q[2] + q[3] + q[4],
    ];
    let r = [2.0 * b[2], 6.0 * b[3], 12.0 * b[4], 20.0 * b[5]];
    let acceleration = [
        r[0],
        r[0] + r[1] * (1.0 / 3.0),
        r[0] + (2.0 * r[1] + r[2]) * (1.0 / 3.0),
        r[0] + r[1] + r[2] + r[3],
    ];
    let largest = |x: &[f64]| x.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let [i1, i2, ..] = span.inverse;
    let bounds = (largest(&velocity) * i1, largest(&acceleration) * i2);
    (bounds.0.is_finite() && bounds.1.is_finite()).then_some(bounds)
}

/// The Bernstein coefficients of the quintic `b` on [0, 1].
#[inline]
fn bernstein_position(b: &[f64; 6]) -> [f64; 6] {
    [
        b[0],
        b[0] + 0.2 * b[1],
        b[0] + 0.4 * b[1] + 0.1 * b[2],
        b[0] + 0.6 * b[1] + 0.3 * b[2] + 0.1 * b[3],
        b[0] + 0.8 * b[1] + 0.6 * b[2] + 0.4 * b[3] + 0.2 * b[4],
        b[0] + b[1] + b[2] + b[3] + b[4] + b[5],
    ]
}

/// The exact extremes of the polynomial `c` on [0, t] (t > 0), and whether its position
/// leaves `min..max`.
pub(crate) fn extremes(c: &Coeffs, t: f64, min: f64, max: f64) -> Extremes {
    let b = normalise(c, t);
    if !b.iter().all(|x| x.is_finite()) {
        return Extremes {
            velocity: f64::INFINITY,
            acceleration: f64::INFINITY,
            outside: Some(f64::NAN),
        };
    }
    let d1 = [b[1], 2.0 * b[2], 3.0 * b[3], 4.0 * b[4], 5.0 * b[5]];
    let d2 = [2.0 * b[2], 6.0 * b[3], 12.0 * b[4], 20.0 * b[5], 0.0];
    let r3 = quadratic_roots(6.0 * b[3], 24.0 * b[4], 60.0 * b[5]);
    let r2 = roots_between(&d2, &r3);

    let mut acceleration = wider(d2[0], horner(&d2, 1.0).0);
    for &x in r3.as_slice() {
        acceleration = wider(acceleration, horner(&d2, x).0);
    }
    let mut velocity = wider(d1[0], horner(&d1, 1.0).0);
    for &x in r2.as_slice() {
        velocity = wider(velocity, horner(&d1, x).0);
    }

    let outside = position_outside(&b, &d1, &r2, min, max);
    let to_infinite = |x: f64| if x.is_nan() { f64::INFINITY } else { x };
    Extremes {
        velocity: to_infinite(velocity / t),
        acceleration: to_infinite(acceleration / (t * t)),
        outside,
    }
}

/// The position of `b` (normalised) furthest outside `min..max`, if any. `d1` is its
/// derivative, `r2` the roots of its second derivative.
fn position_outside(b: &[f64; 6], d1: &[f64; 5], r2: &Roots, min: f64, max: f64) -> Option<f64> {
    // The segment lies within the hull of its Bernstein coefficients.
    if bernstein_position(b).iter().all(|&x| x >= min && x <= max) {
        return None;
    }
    let position = |x: f64| ((((b[5] * x + b[4]) * x + b[3]) * x + b[2]) * x + b[1]) * x + b[0];
    let r1 = roots_between(d1, r2);
    let (mut low, mut high) = (b[0], b[0]);
    for x in r1.as_slice().iter().copied().chain([1.0]) {
        let p = position(x);
        if p.is_nan() {
            return Some(p);
        }
        low = low.min(p);
        high = high.max(p);
    }
    if !crate::at_most(high, max) {
        Some(high)
    } else if !crate::at_most(min, low) {
        Some(low)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-9 * (1.0 + a.abs().max(b.abs()))
    }

    #[test]
    fn quintic_hermite_meets_both_ends() {
        let c = quintic_hermite([1.0, -2.0, 3.0], [4.0, 0.5, -1.0], &Span::new(0.7));
        assert_eq!(eval(&c, 0.0), [1.0, -2.0, 3.0]);
        let [p, v, a] = eval(&c, 0.7);
        assert!(
            close(p, 4.0) && close(v, 0.5) && close(a, -1.0),
            "{p} {v} {a}"
        );
    }

    #[test]
    fn cubic_hermite_meets_both_ends() {
        let c = cubic_hermite(1.0, -2.0, 4.0, 0.5, &Span::new(0.7));
        let [p, v, _] = eval(&c, 0.7);
        assert!(close(p, 4.0) && close(v, 0.5), "{p} {v}");
        assert_eq!(eval(&c, 0.0)[..2], [1.0, -2.0]);
    }

    #[test]
    fn quadratic_roots_in_the_unit_interval_sorted() {
        // (x - 0.25)(x - 0.75) = x² - x + 0.1875
        let r = quadratic_roots(0.1875, -1.0, 1.0);
        assert_eq!(r.n, 2);
        assert!(close(r.x[0], 0.25) && close(r.x[1], 0.75));
        // linear, root outside
        assert_eq!(quadratic_roots(2.0, 1.0, 0.0).n, 0);
        assert_eq!(quadratic_roots(0.0, 0.0, 0.0).n, 0);
        // no real root
        assert_eq!(quadratic_roots(1.0, 0.0, 1.0).n, 0);
    }

    #[test]
    fn extremes_of_a_sine_like_quintic_match_dense_sampling() {
        let t = 2.0;
        let c = quintic_hermite([0.0, 3.0, -1.0], [1.0, -2.0, 4.0], &Span::new(t));
        let e = extremes(&c, t, -10.0, 10.0);
        let (mut v_max, mut a_max) = (0.0f64, 0.0f64);
        for k in 0..=200_000 {
            let [_, v, a] = eval(&c, t * k as f64 / 200_000.0);
            v_max = v_max.max(v.abs());
            a_max = a_max.max(a.abs());
        }
        assert!(
            e.velocity.abs() >= v_max && e.velocity.abs() - v_max < 1e-6,
            "{e:?} {v_max}"
        );
        assert!(
            e.acceleration.abs() >= a_max && e.acceleration.abs() - a_max < 1e-6,
            "{e:?} {a_max}"
        );
        assert_eq!(e.outside, None);
        let span = Span::new(t);
        let (v_bound, a_bound) = hull_bounds(&c, &span, -10.0, 10.0).expect("within the range");
        assert!(v_bound >= v_max && a_bound >= a_max, "{v_bound} {a_bound}");
        assert_eq!(hull_bounds(&c, &span, 0.1, 10.0), None, "starts below 0.1");
    }

    /// A xorshift in (-1, 1), for reproducible random polynomials.
    fn random(state: &mut u64) -> f64 {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        (*state >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }

    #[test]
    fn exact_extremes_and_hull_bounds_agree_with_dense_sampling_on_random_segments() {
        let mut state = 0x9e37_79b9_7f4a_7c15;
        for case in 0..400 {
            let t = 0.05 + 2.0 * random(&mut state).abs();
            let mut end = |scale: f64| [random(&mut state), scale * random(&mut state), 0.0];
            let (mut start, mut stop) = (end(3.0), end(3.0));
            // Quintic, cubic, and (every fifth) a line's parabola or a straight segment.
            let c = match case % 5 {
                0 | 1 => {
                    start[2] = 10.0 * random(&mut state);
                    stop[2] = 10.0 * random(&mut state);
                    quintic_hermite(start, stop, &Span::new(t))
                }
                2 | 3 => cubic_hermite(start[0], start[1], stop[0], stop[1], &Span::new(t)),
                _ => [start[0], start[1], 2.0 * random(&mut state), 0.0, 0.0, 0.0],
            };
            let (mut v_max, mut a_max, mut low, mut high) = (0.0f64, 0.0f64, f64::MAX, f64::MIN);
            for k in 0..=20_000 {
                let [p, v, a] = eval(&c, t * k as f64 / 20_000.0);
                (v_max, a_max) = (v_max.max(v.abs()), a_max.max(a.abs()));
                (low, high) = (low.min(p), high.max(p));
            }
            // Sampling misses a position's extreme by up to |a|·(step/2)²/2 ≈ 10⁻⁸.
            let e = extremes(&c, t, low - 1e-6, high + 1e-6);
            let (v, a) = (e.velocity.abs(), e.acceleration.abs());
            // Exact: never below what sampling finds (but for rounding), and barely above.
            let near = |exact: f64, sampled: f64| {
                exact >= sampled * (1.0 - 1e-12) && exact - sampled <= 1e-6 * (1.0 + exact)
            };
            assert!(near(v, v_max), "{case}: {v} {v_max}");
            assert!(near(a, a_max), "{case}: {a} {a_max}");
            assert_eq!(e.outside, None, "{case}");
            // The range a hair inside what the segment reaches: found outside.
            let middle = 0.5 * (low + high);
            let inside = extremes(&c, t, low + 1e-6 * (middle - low), f64::INFINITY);
            assert!(
                inside.outside.is_some_and(|x| x <= low + 1e-12),
                "{case}: {inside:?}"
            );
            let span = Span::new(t);
            if let Some((v_bound, a_bound)) = hull_bounds(&c, &span, f64::MIN, f64::MAX) {
                assert!(v_bound >= v * (1.0 - 1e-12), "{case}: {v_bound} < {v}");
                assert!(a_bound >= a * (1.0 - 1e-12), "{case}: {a_bound} < {a}");
            }
            // Wherever the hull says "within", it is.
            let narrow = (low + 1e-3 * (high - low), high);
            if hull_bounds(&c, &span, narrow.0, narrow.1).is_some() {
                panic!("{case}: the hull is within a range the segment leaves");
            }
        }
    }

    #[test]
    fn an_overshoot_between_the_ends_is_found() {
        // 0 → 0 with velocity 4 at the start: rises to about 0.59 in between.
        let t = 1.0;
        let c = cubic_hermite(0.0, 4.0, 0.0, 0.0, &Span::new(t));
        let peak = (0..=100_000)
            .map(|k| eval(&c, k as f64 / 100_000.0)[0])
            .fold(f64::MIN, f64::max);
        let e = extremes(&c, t, -1.0, 0.5);
        let outside = e.outside.expect("overshoot found");
        assert!(outside >= peak && outside - peak < 1e-9, "{outside} {peak}");
        assert_eq!(extremes(&c, t, -1.0, 0.6).outside, None);
    }

    #[test]
    fn a_polynomial_that_is_not_finite_is_infinite() {
        let e = extremes(&[0.0, 1.0, f64::NAN, 0.0, 0.0, 0.0], 1.0, -1.0, 1.0);
        assert_eq!(e.velocity, f64::INFINITY);
    }
}
