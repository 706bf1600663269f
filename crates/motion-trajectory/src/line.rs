//! The scalar profile s(t) ∈ [0, 1] of a straight line in joint space: trapezoidal, or
//! triangular when the line is too short to reach its rate.

/// The profile of s from rest at 0 to rest at 1 under |s'| ≤ `rate` and |s''| ≤ `accel`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Profile {
    /// The peak rate s' reached (`rate`, or less when triangular).
    pub peak: f64,
    /// |s''| while accelerating and decelerating.
    pub accel: f64,
    /// Seconds of acceleration (and of deceleration).
    pub ramp_time: f64,
    /// Seconds at `peak` (0 when triangular).
    pub cruise_time: f64,
    /// s covered while accelerating (and while decelerating).
    pub ramp_distance: f64,
}

impl Profile {
    /// The fastest profile under `rate` and `accel` (both finite and positive).
    pub(crate) fn new(rate: f64, accel: f64) -> Self {
        // Reaching `rate` and coming back to rest covers rate²/accel.
        let (peak, cruise_time) = if rate * rate >= accel {
            (accel.sqrt(), 0.0)
        } else {
            (rate, 1.0 / rate - rate / accel)
        };
        let ramp_time = peak / accel;
        Self {
            peak,
            accel,
            ramp_time,
            cruise_time,
            ramp_distance: 0.5 * peak * ramp_time,
        }
    }

    /// The whole profile's duration.
    pub(crate) fn duration(&self) -> f64 {
        2.0 * self.ramp_time + self.cruise_time
    }

    /// Whether it never cruises.
    #[cfg(test)]
    pub(crate) fn is_triangular(&self) -> bool {
        self.cruise_time == 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_lines_cruise_short_lines_do_not() {
        // rate 1, accel 4: ramps 0.25 s covering 0.125 each; cruise 0.75 s.
        let p = Profile::new(1.0, 4.0);
        assert!(!p.is_triangular());
        assert!((p.ramp_time - 0.25).abs() < 1e-15);
        assert!((p.cruise_time - 0.75).abs() < 1e-15);
        assert!((p.duration() - 1.25).abs() < 1e-15);
        // rate 1, accel 0.5: rate² ≥ accel, triangular: peak √0.5, ramps √2 s.
        let p = Profile::new(1.0, 0.5);
        assert!(p.is_triangular());
        assert!((p.peak - 0.5f64.sqrt()).abs() < 1e-15);
        assert!((p.duration() - 2.0 * 2.0f64.sqrt()).abs() < 1e-12);
        assert!((p.ramp_distance - 0.5).abs() < 1e-15);
    }
}
