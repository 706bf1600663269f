//! Counts (`f64`, as the engine and the config speak) as a board's signed 32-bit register.

/// `counts` rounded to the nearest whole count, if that is a finite value a signed 32-bit
/// register holds (`None` for NaN, ±∞ and anything beyond `i32`).
#[must_use]
pub fn counts_to_i32(counts: f64) -> Option<i32> {
    let rounded = counts.round();
    (rounded.is_finite() && rounded >= f64::from(i32::MIN) && rounded <= f64::from(i32::MAX))
        .then_some(rounded as i32)
}

/// `counts` rounded to the nearest whole count and clamped into `i32` (NaN is 0): for a
/// value that is already known to be sane, such as a validated config key.
#[must_use]
pub fn counts_to_i32_saturating(counts: f64) -> i32 {
    if counts.is_nan() {
        return 0;
    }
    counts
        .round()
        .clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32
}

#[cfg(test)]
mod tests {
    use super::{counts_to_i32, counts_to_i32_saturating};

    #[test]
    fn rounds_and_refuses_what_does_not_fit() {
        assert_eq!(counts_to_i32(-2.5), Some(-3));
        assert_eq!(counts_to_i32(2.4), Some(2));
        assert_eq!(counts_to_i32(f64::from(i32::MAX)), Some(i32::MAX));
        assert_eq!(counts_to_i32(f64::from(i32::MIN)), Some(i32::MIN));
        assert_eq!(counts_to_i32(f64::from(i32::MAX) + 1.0), None);
        assert_eq!(counts_to_i32(f64::from(i32::MIN) - 1.0), None);
        assert_eq!(counts_to_i32(f64::INFINITY), None);
        assert_eq!(counts_to_i32(f64::NAN), None);
    }

    #[test]
    fn saturating_clamps() {
        assert_eq!(counts_to_i32_saturating(1e12), i32::MAX);
        assert_eq!(counts_to_i32_saturating(-1e12), i32::MIN);
        assert_eq!(counts_to_i32_saturating(f64::NAN), 0);
        assert_eq!(counts_to_i32_saturating(7.5), 8);
    }
}
