//! The velocity profile of manual 8.3/8.4, one 500 Hz tick at a time.
//!
//! Velocities are kept in 1/64 units (`vq = v · 64`) because $14 accumulates `amax/64` per
//! 2 ms tick; the step generator uses the integer part `v = vq / 64`. Positions are kept as
//! microsteps plus a fraction in units of `1 / ((clkdiv+1) · 2^(14+div))` microsteps
//! ("fine" units), so that a velocity `v` moves exactly `TICK_CYCLES · v` fine units per
//! tick, which is the manual's 8.2 formula with no rounding drift.
//!
//! A ramp starts at *vstart* at once ("starting and ending velocity for acceleration
//! ramp"), accelerates by amax/64 per tick up to *vmax*, decelerates by the same amount when
//! the remaining distance requires it, finishes at *vstart* and stops exactly on the
//! target. A target behind a motor faster than vstart makes it decelerate with amax and come
//! back ("the peak will decelerate with amax instantly and continue driving a reverse ramp on
//! its own", $26).

use tmcpack::convert::{AMAX_DIVISOR, TICK_CYCLES};

/// Scale of `vq`.
pub(crate) const Q: i64 = AMAX_DIVISOR as i64;

/// Ramp limits in `vq` units.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Limits {
    /// vstart · 64: velocities up to this start and stop at once.
    pub vs: i64,
    /// vmax · 64.
    pub vmax: i64,
    /// amax: change per tick.
    pub d: i64,
}

/// Fine units moved in one tick at `vq`.
pub(crate) fn step(vq: i64) -> i128 {
    i128::from(TICK_CYCLES) * i128::from(vq / Q)
}

/// An upper bound of the fine units needed to brake from `a` (≥ 0) down to vstart.
pub(crate) fn brake_distance(a: i64, lim: Limits) -> i128 {
    if a <= lim.vs || lim.d <= 0 {
        return 0;
    }
    let n = i128::from((a - lim.vs + lim.d - 1) / lim.d);
    let (a, d) = (i128::from(a), i128::from(lim.d));
    let sum = n * a - d * n * (n + 1) / 2 + i128::from(lim.vs);
    i128::from(TICK_CYCLES) * sum.max(0) / i128::from(Q) + step(lim.vs)
}

/// The velocity for the next tick of a ramp with `remaining` fine units to go (signed).
pub(crate) fn ramp_velocity(vq: i64, remaining: i128, lim: Limits) -> i64 {
    let dir = remaining.signum() as i64;
    if dir == 0 || (vq != 0 && vq.signum() != dir) {
        // Moving away from the target (or on it at speed): decelerate with amax first.
        let m = vq.abs() - lim.d;
        return if m <= lim.vs { 0 } else { vq.signum() * m };
    }
    let r = remaining.abs();
    let mut a = vq.abs();
    if a < lim.vs {
        a = lim.vs;
    } else if r - step(a) <= brake_distance(a, lim) {
        a = (a - lim.d).max(lim.vs);
    } else if a < lim.vmax {
        let up = (a + lim.d).min(lim.vmax);
        if r - step(up) > brake_distance(up, lim) {
            a = up;
        }
    } else if a > lim.vmax {
        a = (a - lim.d).max(lim.vmax).max(lim.vs);
    }
    dir * a
}

/// The velocity for the next tick when heading for velocity `want` (rotation, PI
/// controller, reference search): changes by at most amax/64 per tick, except inside
/// ±vstart, where starting and stopping are immediate.
pub(crate) fn slew(cur: i64, want: i64, lim: Limits) -> i64 {
    if cur == want {
        return cur;
    }
    if cur != 0 && want.signum() != cur.signum() {
        let m = cur.abs() - lim.d;
        return if m <= lim.vs { 0 } else { cur.signum() * m };
    }
    let s = if want != 0 {
        want.signum()
    } else {
        cur.signum()
    };
    let (c, w) = (cur.abs(), want.abs());
    let n = if w > c {
        if c < lim.vs {
            lim.vs.min(w)
        } else {
            (c + lim.d).min(w)
        }
    } else {
        let m = c - lim.d;
        if m > lim.vs { m.max(w) } else { w }
    };
    s * n
}

#[cfg(test)]
mod tests {
    use super::*;

    const LIM: Limits = Limits {
        vs: 5 * Q,
        vmax: 511 * Q,
        d: 128,
    };
    const DENOM: i128 = 6 << 16; // clkdiv 5, div 2

    /// Runs a ramp over `dist` microsteps; returns (ticks, peak |v|, max |Δvq| outside the
    /// vstart band).
    fn run(dist: i64, lim: Limits) -> (u32, i64, i64) {
        let target = i128::from(dist) * DENOM;
        let (mut x, mut vq, mut ticks, mut peak, mut jerk) = (0i128, 0i64, 0u32, 0i64, 0i64);
        loop {
            let rem = target - x;
            let nv = ramp_velocity(vq, rem, lim);
            if vq.abs() > lim.vs || nv.abs() > lim.vs {
                jerk = jerk.max((nv - vq).abs());
            }
            vq = nv;
            let s = step(vq);
            ticks += 1;
            peak = peak.max(vq.abs());
            if s.abs() >= rem.abs() && s.signum() == rem.signum() {
                assert!(vq.abs() <= lim.vs, "arrived at speed {vq}");
                return (ticks, peak, jerk);
            }
            x += s;
            assert!(ticks < 1_000_000, "never arrives");
        }
    }

    #[test]
    fn ramps_reach_target_within_limits() {
        for dist in [1, 7, 100, 6400, 100_000, -3, -50_000] {
            let (_, peak, jerk) = run(dist, LIM);
            assert!(peak <= LIM.vmax);
            assert!(jerk <= LIM.d, "dist {dist}: Δv {jerk}");
        }
        let (_, peak, _) = run(1_000_000, LIM);
        assert_eq!(peak, LIM.vmax);
    }

    #[test]
    fn slew_obeys_amax_outside_the_vstart_band() {
        let mut v = 0;
        let mut prev = 0;
        for _ in 0..1000 {
            v = slew(v, 300 * Q, LIM);
            assert!((v - prev).abs() <= LIM.d || v.abs() <= LIM.vs);
            prev = v;
        }
        assert_eq!(v, 300 * Q);
        for _ in 0..1000 {
            v = slew(v, -20 * Q, LIM);
            assert!(
                (v - prev).abs() <= LIM.d || (v.abs() <= LIM.vs && prev.abs() <= LIM.vs + LIM.d)
            );
            prev = v;
        }
        assert_eq!(v, -20 * Q);
    }
}
