//! The `home` table of every model that homes, and its aliases: qsb `home_direction`,
//! `home_max_travel`, `home_offset` on the `[[device]]`, tmcpack `reference.side`.

use motion_drivers::Model;
use toml::Spanned;

use super::{TableSpan, Validator};
use crate::config::raw::{RawAxis, RawDevice};
use crate::config::{DeviceSpec, Direction, HomeInput, HomeInputKind, HomeSpec};

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

    /// The resolved [`HomeSpec`] of axis `index` on `device`; `None` after an issue.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn home(
        &mut self,
        index: usize,
        a: &RawAxis,
        device: &DeviceSpec,
        device_index: usize,
        raw_device: Option<&RawDevice>,
        counts_per_unit: Option<f64>,
        min: Option<f64>,
        max: Option<f64>,
    ) -> Option<HomeSpec> {
        let key = |k: &str| format!("axis[{index}].home.{k}");
        let dkey = |k: &str| format!("device[{device_index}].{k}");
        let home = a.home.as_ref().map(Spanned::get_ref);
        let mut ok = true;
        let mut direction = Alias::new();
        if let Some(h) = home {
            if let Some(d) = &h.direction {
                match self.direction(d, &key("direction")) {
                    Some(dir) => direction.set(self, dir, d.span(), key("direction")),
                    None => ok = false,
                }
            }
            if let Some(p) = &h.positive_end {
                let dir = if *p.get_ref() {
                    Direction::Positive
                } else {
                    Direction::Negative
                };
                direction.set(self, dir, p.span(), key("positive_end"));
            }
        }
        if device.model == Model::TMCPACK
            && let Some(side) = a.reference.as_ref().and_then(|r| r.get_ref().side.as_ref())
        {
            let k = format!("axis[{index}].reference.side");
            match side.get_ref().as_str() {
                "left" => direction.set(self, Direction::Negative, side.span(), k),
                "right" => direction.set(self, Direction::Positive, side.span(), k),
                other => {
                    ok = false;
                    self.issue(
                        side.span(),
                        &k,
                        format!("unknown side {other:?}; allowed: \"left\" (zero point left of the driving range: the search runs to decreasing positions; NullLeft, default), \"right\""),
                    );
                }
            }
        }
        let mut max_travel = Alias::new();
        let mut position = Alias::new();
        if let Some(h) = home {
            if let Some(t) = &h.max_travel {
                max_travel.set(self, *t.get_ref(), t.span(), key("max_travel"));
            }
            if let Some(p) = &h.position {
                position.set(self, *p.get_ref(), p.span(), key("position"));
            }
        }
        if device.model == Model::QSB
            && let Some(d) = raw_device
        {
            if let Some(v) = &d.home_direction {
                match self.direction(v, &dkey("home_direction")) {
                    Some(dir) => direction.set(self, dir, v.span(), dkey("home_direction")),
                    None => ok = false,
                }
            }
            if let Some(t) = &d.home_max_travel {
                max_travel.set(self, *t.get_ref(), t.span(), dkey("home_max_travel"));
            }
            if let Some(p) = &d.home_offset {
                position.set(self, *p.get_ref(), p.span(), dkey("home_offset"));
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
        let input = if device.model == Model::QQ2DRV {
            match home {
                Some(h) => self.home_input(
                    index,
                    h,
                    a.home.as_ref().map_or(0..0, Spanned::span),
                    counts_per_unit,
                ),
                None => Some(None),
            }
        } else {
            Some(None)
        };
        if !ok {
            return None;
        }
        Some(HomeSpec {
            direction: direction.value.map_or(Direction::Negative, |(d, _, _)| d),
            max_travel: max_travel?,
            position: position?,
            input: input?,
        })
    }

    /// qq2drv: `home.input`, `active_high`, `spacing`.
    fn home_input(
        &mut self,
        index: usize,
        h: &crate::config::raw::RawHome,
        table: TableSpan,
        counts_per_unit: Option<f64>,
    ) -> Option<Option<HomeInput>> {
        let key = |k: &str| format!("axis[{index}].home.{k}");
        let kind = self
            .required(&h.input, &table, &key("input"), "a qq2drv axis homes on its channel's IN pin: one of \"home\", \"index\", \"edge\"")
            .and_then(|input| match input.get_ref().as_str() {
                "home" => Some(HomeInputKind::Home),
                "index" => Some(HomeInputKind::Index),
                "edge" => Some(HomeInputKind::Edge),
                other => {
                    self.issue(
                        input.span(),
                        &key("input"),
                        format!("unknown input {other:?}; allowed: \"home\" (switch, acts while active), \"index\" (encoder index), \"edge\" (inactive-to-active edge)"),
                    );
                    None
                }
            });
        let spacing = match &h.spacing {
            None => Some(None),
            Some(s) => {
                let v = *s.get_ref();
                let counts = counts_per_unit.map(|cpu| (v * cpu).abs().round());
                if !(v.is_finite() && v > 0.0) {
                    self.issue(s.span(), &key("spacing"), format!("{v} is not allowed; a finite distance > 0 (units) between the positive-end and negative-end triggers"));
                    None
                } else if counts.is_some_and(|c| !(1.0..=f64::from(u16::MAX)).contains(&c)) {
                    self.issue(s.span(), &key("spacing"), format!("{v} is {} transitions; packet 14 Spacing is U16: allowed 1..=65535 transitions", counts.unwrap_or(0.0)));
                    None
                } else {
                    Some(Some(v))
                }
            }
        };
        Some(Some(HomeInput {
            kind: kind?,
            active_high: h.active_high.as_ref().is_none_or(|v| *v.get_ref()),
            spacing: spacing?,
        }))
    }
}
