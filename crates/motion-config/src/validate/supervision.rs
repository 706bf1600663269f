//! Per-axis supervision keys of every model: `following_error`, `overspeed_factor`,
//! `estop`.

use motion_engine::EstopCategory;
use toml::Spanned;

use super::Validator;
use crate::raw::RawAxis;

/// `following_error` default: 1 % of the travel, but at least 50 and at most 1000 board
/// counts (and never below 5 × `position_tolerance`).
pub(crate) fn default_following_error(counts_per_unit: f64, travel: f64, tolerance: f64) -> f64 {
    let count = 1.0 / counts_per_unit.abs();
    (0.01 * travel)
        .clamp(50.0 * count, 1000.0 * count)
        .max(5.0 * tolerance)
}

/// `overspeed_factor` default.
pub(crate) const DEFAULT_OVERSPEED_FACTOR: f64 = 1.5;

impl Validator<'_, '_> {
    /// `(following_error, overspeed_factor, estop)` of axis `index`, defaults resolved.
    pub(super) fn supervision(
        &mut self,
        index: usize,
        a: &RawAxis,
        counts_per_unit: Option<f64>,
        min: Option<f64>,
        max: Option<f64>,
        tolerance: Option<f64>,
    ) -> Option<(f64, f64, EstopCategory)> {
        let key = |k: &str| format!("axis[{index}].{k}");
        let non_negative = |me: &mut Self, value: &Spanned<f64>, k: &str, what: &str| {
            let v = *value.get_ref();
            if v.is_finite() && v >= 0.0 {
                Some(v)
            } else {
                me.issue(
                    value.span(),
                    &key(k),
                    format!(
                        "{v} is not allowed; a finite number >= 0 ({what}; 0 disables the check)"
                    ),
                );
                None
            }
        };
        let following_error = match &a.following_error {
            Some(value) => non_negative(self, value, "following_error", "units"),
            None => match (counts_per_unit, min, max, tolerance) {
                (Some(cpu), Some(lo), Some(hi), Some(tol)) => {
                    Some(default_following_error(cpu, hi - lo, tol))
                }
                _ => None,
            },
        };
        if let (Some(value), Some(fe), Some(tol)) = (&a.following_error, following_error, tolerance)
            && fe > 0.0
            && fe < tol
        {
            self.issue(
                value.span(),
                &key("following_error"),
                format!(
                    "{fe} is smaller than position_tolerance ({tol}): an axis that arrived could fault at once; allowed: 0 (off) or >= position_tolerance"
                ),
            );
        }
        let overspeed_factor = match &a.overspeed_factor {
            Some(value) => {
                let v = non_negative(self, value, "overspeed_factor", "times max_velocity");
                match v {
                    Some(f) if f > 0.0 && f < 1.0 => {
                        self.issue(
                            value.span(),
                            &key("overspeed_factor"),
                            format!("{f} is below 1: the axis would fault at its own max_velocity; allowed: 0 (off) or >= 1"),
                        );
                        None
                    }
                    other => other,
                }
            }
            None => Some(DEFAULT_OVERSPEED_FACTOR),
        };
        for (value, k, what) in [
            (
                &a.following_error,
                "following_error",
                "the following-error and soft-limit supervision",
            ),
            (
                &a.overspeed_factor,
                "overspeed_factor",
                "the overspeed supervision",
            ),
        ] {
            if let Some(value) = value
                && *value.get_ref() == 0.0
            {
                self.warn(
                    value.span(),
                    &key(k),
                    format!("0 turns off {what} of this axis: a board that drives it away goes unnoticed"),
                );
            }
        }
        let estop = match &a.estop {
            None => Some(EstopCategory::Hold),
            Some(value) => match value.get_ref().as_str() {
                "hold" => Some(EstopCategory::Hold),
                "stop-off" => Some(EstopCategory::StopOff),
                "off" => Some(EstopCategory::Off),
                other => {
                    self.issue(
                        value.span(),
                        &key("estop"),
                        format!("unknown stop category {other:?}; allowed: \"hold\" (decelerate and hold energised, IEC 60204-1 category 2; default), \"stop-off\" (decelerate, then de-energise: category 1), \"off\" (de-energise at once: category 0)"),
                    );
                    None
                }
            },
        };
        Some((following_error?, overspeed_factor?, estop?))
    }
}

#[cfg(test)]
mod tests {
    use super::default_following_error;

    #[test]
    fn following_error_default_is_one_percent_within_count_bounds() {
        // 400 counts/mm, 300 mm: 1 % = 3 mm = 1200 counts → capped at 1000 counts.
        assert!((default_following_error(400.0, 300.0, 0.005) - 2.5).abs() < 1e-12);
        // 100 counts/mm, 20 mm: 0.2 mm = 20 counts → raised to 50 counts.
        assert!((default_following_error(-100.0, 20.0, 0.02) - 0.5).abs() < 1e-12);
        // 1 count/unit, 10 000 units: 100 units, within 50..1000 counts.
        assert!((default_following_error(1.0, 10_000.0, 2.0) - 100.0).abs() < 1e-12);
        // never below 5 × the position tolerance
        assert!((default_following_error(1.0, 100.0, 20.0) - 100.0).abs() < 1e-12);
    }
}
