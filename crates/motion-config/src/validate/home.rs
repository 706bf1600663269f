//! The `home` table of every model that homes, and what the boards' keys say about it
//! (`motion_board::HomeHints`: qsb `home_direction`, `home_max_travel`, `home_offset` on
//! the `[[device]]`, tmcpack `reference.side`, qq2drv `home.positive_end` and its home
//! input): one fact given under two names must agree.

use motion_board::HomeHints;
use toml::Spanned;

use super::{TableSpan, Validator};
use crate::raw::RawAxis;
use crate::{DeviceSpec, Direction, HomeSpec};

/// Default `max_travel` as a multiple of the axis's travel (the Trinamic manual's 5/4 rule).
pub(crate) const DEFAULT_MAX_TRAVEL_OF_RANGE: f64 = 1.25;

/// One fact given under two names: both must agree.
struct Alias<T> {
    value: Option<(T, TableSpan, String)>,
}

impl<T: PartialEq + Copy + core::fmt::Debug> Alias<T> {
    fn new() -> Self {
        Self { value: None }
    }

    fn set(&mut self, v: &mut Validator<'_, '_>, value: T, span: TableSpan, key: String) {
        match &self.value {
            Some((earlier, _, earlier_key)) if *earlier != value => {
                v.issue(
                    span,
                    &key,
                    format!("disagrees with `{earlier_key}` ({earlier:?} vs {value:?}); both set the same thing, keep one"),
                );
            }
            Some(_) => {}
            None => self.value = Some((value, span, key)),
        }
    }
}

impl Validator<'_, '_> {
    fn direction(&mut self, value: &Spanned<String>, key: &str) -> Option<Direction> {
        match value.get_ref().as_str() {
            "negative" => Some(Direction::Negative),
            "positive" => Some(Direction::Positive),
            other => {
                self.issue(
                    value.span(),
                    key,
                    format!("unknown direction {other:?}; allowed: \"negative\" (towards min; default), \"positive\" (towards max)"),
                );
                None
            }
        }
    }

    /// The resolved [`HomeSpec`] of axis `index` on `device`: the general `home` table
    /// merged with what the board's keys of the axis (`axis`) and of its device say
    /// (`reference.side`, `home_direction`, …); `None` after an issue.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn home(
        &mut self,
        index: usize,
        a: &RawAxis,
        device: &DeviceSpec,
        axis: Option<&HomeHints>,
        counts_per_unit: Option<f64>,
        min: Option<f64>,
        max: Option<f64>,
    ) -> Option<HomeSpec> {
        let key = |k: &str| format!("axis[{index}].home.{k}");
        let home = a.home.as_ref().map(Spanned::get_ref);
        let mut ok = true;
        let mut direction = Alias::new();
        let mut max_travel = Alias::new();
        let mut position = Alias::new();
        if let Some(h) = home {
            if let Some(d) = &h.direction {
                match self.direction(d, &key("direction")) {
                    Some(dir) => direction.set(self, dir, d.span(), key("direction")),
                    None => ok = false,
                }
            }
            if let Some(t) = &h.max_travel {
                max_travel.set(self, *t.get_ref(), t.span(), key("max_travel"));
            }
            if let Some(p) = &h.position {
                position.set(self, *p.get_ref(), p.span(), key("position"));
            }
        }
        for hints in axis.into_iter().chain([&device.home_hints]) {
            for given in &hints.direction {
                direction.set(self, given.value, given.span.clone(), given.key.clone());
            }
            for given in &hints.max_travel {
                max_travel.set(self, given.value, given.span.clone(), given.key.clone());
            }
            for given in &hints.position {
                position.set(self, given.value, given.span.clone(), given.key.clone());
            }
        }
        let max_travel = match max_travel.value {
            Some((t, _, _)) if t.is_finite() && t > 0.0 => Some(t),
            Some((t, span, k)) => {
                self.issue(
                    span,
                    &k,
                    format!("{t} is not allowed; a finite distance > 0 (units)"),
                );
                None
            }
            None => match (min, max) {
                (Some(lo), Some(hi)) => Some(DEFAULT_MAX_TRAVEL_OF_RANGE * (hi - lo).abs()),
                _ => None,
            },
        };
        let position = match position.value {
            Some((p, span, k)) => {
                let fits = counts_per_unit.is_none_or(|cpu| (p * cpu).abs() <= f64::from(i32::MAX));
                if !p.is_finite() {
                    self.issue(span, &k, "a finite number (units)");
                    None
                } else if !fits {
                    self.issue(span, &k, "beyond the board's 32-bit position counter");
                    None
                } else {
                    Some(p)
                }
            }
            None => Some(0.0),
        };
        if !ok {
            return None;
        }
        Some(HomeSpec {
            direction: direction.value.map_or(Direction::Negative, |(d, _, _)| d),
            max_travel: max_travel?,
            position: position?,
            input: axis.and_then(|hints| hints.input),
        })
    }
}
