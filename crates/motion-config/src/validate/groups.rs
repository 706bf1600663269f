//! `[[group]]` tables: axes of any boards and links that move together, with their path
//! and goal tolerances and their streaming rules.

use core::ops::Range;
use core::time::Duration;

use motion_engine::{AxisConfig, GroupConfig, StreamLimit};
use motion_ipc::{MAX_GROUP_AXES, MAX_GROUPS, NAME_LEN};
use toml::Spanned;

use super::{Validator, name_span};
use crate::raw::{RawAxis, RawGroup, RawNumber, RawTolerance};

/// `goal_time_tolerance_ms` default and range.
const GOAL_TIME_MS: (i64, core::ops::RangeInclusive<i64>) = (1000, 1..=60_000);
/// `stream_timeout` default and range, ticks.
const STREAM_TIMEOUT: (i64, core::ops::RangeInclusive<i64>) = (20, 1..=100_000);
/// `stream_buffer` default and range, ticks.
const STREAM_BUFFER: (i64, core::ops::RangeInclusive<i64>) =
    (3, 1..=motion_engine::MAX_STREAM_BUFFER as i64);

/// One listed member of a group: its name, and its index into the config's axes once every
/// axis is valid (`None`: unknown, or an axis with issues of its own).
struct Member<'a> {
    name: &'a str,
    axis: Option<usize>,
}

/// Which tolerance: what it may be and what it defaults to.
#[derive(Clone, Copy)]
enum Tolerance {
    /// `path_tolerance`: >= 0 (0: off), default the axis's `following_error`.
    Path,
    /// `goal_tolerance`: > 0, default the axis's `position_tolerance`.
    Goal,
}

impl Tolerance {
    fn key(self) -> &'static str {
        match self {
            Self::Path => "path_tolerance",
            Self::Goal => "goal_tolerance",
        }
    }

    fn allows(self, value: f64) -> bool {
        match self {
            Self::Path => value.is_finite() && value >= 0.0,
            Self::Goal => value.is_finite() && value > 0.0,
        }
    }

    fn allowed(self) -> &'static str {
        match self {
            Self::Path => "a finite number >= 0, in the axis's unit (0 turns the check off)",
            Self::Goal => "a finite number > 0, in the axis's unit",
        }
    }

    fn default_of(self, axis: &AxisConfig) -> f64 {
        match self {
            Self::Path => axis.following_error,
            Self::Goal => axis.position_tolerance,
        }
    }
}

impl Validator<'_, '_> {
    /// Every `[[group]]` table. `axes`: the `[[axis]]` tables in file order, `None` where
    /// one has issues (the config's axes are the others, in the same order).
    pub(super) fn groups(
        &mut self,
        raw: &[Spanned<RawGroup>],
        raw_axes: &[Spanned<RawAxis>],
        axes: &[Option<AxisConfig>],
    ) -> Vec<GroupConfig> {
        if raw.len() > MAX_GROUPS {
            self.issue(
                raw[MAX_GROUPS].span(),
                "group",
                format!(
                    "{} [[group]] tables; at most {MAX_GROUPS} are supported",
                    raw.len()
                ),
            );
        }
        let groups: Vec<Option<GroupConfig>> = raw
            .iter()
            .enumerate()
            .map(|(index, group)| self.group(index, group, raw_axes, axes))
            .collect();
        let names: Vec<Option<String>> = raw
            .iter()
            .map(|group| {
                let name = group.get_ref().name.as_ref()?.get_ref();
                super::is_identifier(name, NAME_LEN).then(|| name.clone())
            })
            .collect();
        self.duplicates(
            "group",
            names
                .iter()
                .zip(raw)
                .enumerate()
                .filter_map(|(index, (name, raw))| {
                    name.as_deref()
                        .map(|name| (index, name, name_span(raw, |g| &g.name)))
                }),
        );
        groups.into_iter().flatten().collect()
    }

    fn group(
        &mut self,
        index: usize,
        raw: &Spanned<RawGroup>,
        raw_axes: &[Spanned<RawAxis>],
        axes: &[Option<AxisConfig>],
    ) -> Option<GroupConfig> {
        let table = raw.span();
        let g = raw.get_ref();
        let key = |k: &str| format!("group[{index}].{k}");
        let name = self
            .required(&g.name, &table, &key("name"), "every group needs a name")
            .and_then(|name| self.name(name, &key("name"), NAME_LEN));
        let members = self
            .required(
                &g.axes,
                &table,
                &key("axes"),
                "the names of its [[axis]] tables, e.g. axes = [\"x\", \"y\"]",
            )
            .map(|list| self.members(&key("axes"), list, raw_axes, axes));
        let label = name.as_deref().unwrap_or("?");
        let path = members.as_ref().and_then(|members| {
            self.tolerance(
                Tolerance::Path,
                &key,
                label,
                g.path_tolerance.as_ref(),
                members,
                axes,
            )
        });
        let goal = members.as_ref().and_then(|members| {
            self.tolerance(
                Tolerance::Goal,
                &key,
                label,
                g.goal_tolerance.as_ref(),
                members,
                axes,
            )
        });
        let int = |me: &mut Self, value: &Option<Spanned<_>>, k: &str, (default, range)| match value
        {
            Some(value) => me.int_in(value, &key(k), range),
            None => Some(default),
        };
        let goal_time = int(
            self,
            &g.goal_time_tolerance_ms,
            "goal_time_tolerance_ms",
            GOAL_TIME_MS,
        );
        let stream_timeout = int(self, &g.stream_timeout, "stream_timeout", STREAM_TIMEOUT);
        let stream_buffer = int(self, &g.stream_buffer, "stream_buffer", STREAM_BUFFER);
        let stream_limit = match &g.stream_limit {
            None => Some(StreamLimit::default()),
            Some(value) => {
                let found = [StreamLimit::Abort, StreamLimit::Clamp]
                    .into_iter()
                    .find(|limit| limit.id() == value.get_ref());
                if found.is_none() {
                    self.issue(
                        value.span(),
                        &key("stream_limit"),
                        format!(
                            "unknown stream limit {:?}; allowed: \"abort\" (stop the group and end the stream; default), \"clamp\" (clamp the setpoint to the limit, count and flag it)",
                            value.get_ref()
                        ),
                    );
                }
                found
            }
        };
        let members = members?;
        Some(GroupConfig {
            name: name?,
            axes: members
                .iter()
                .map(|member| member.axis)
                .collect::<Option<_>>()?,
            path_tolerance: path?,
            goal_tolerance: goal?,
            goal_time_tolerance: Duration::from_millis(goal_time? as u64),
            stream_limit: stream_limit?,
            stream_timeout: stream_timeout? as u32,
            stream_buffer: stream_buffer? as u32,
        })
    }

    /// The axes a group lists, each once, with an issue for an empty list, too many, an
    /// unknown name and a name listed twice (the second time).
    fn members<'a>(
        &mut self,
        key: &str,
        list: &'a Spanned<Vec<Spanned<String>>>,
        raw_axes: &[Spanned<RawAxis>],
        axes: &[Option<AxisConfig>],
    ) -> Vec<Member<'a>> {
        let names = list.get_ref();
        if names.is_empty() {
            self.issue(
                list.span(),
                key,
                "a group needs at least one axis: the names of its [[axis]] tables, e.g. axes = [\"x\", \"y\"]",
            );
        }
        if names.len() > MAX_GROUP_AXES {
            self.issue(
                list.span(),
                key,
                format!(
                    "{} axes; a group holds at most {MAX_GROUP_AXES}",
                    names.len()
                ),
            );
        }
        let mut members: Vec<Member<'a>> = Vec::with_capacity(names.len());
        for name in names {
            let text = name.get_ref().as_str();
            if members.iter().any(|member| member.name == text) {
                self.issue(
                    name.span(),
                    key,
                    format!("axis `{text}` is listed twice; each axis once"),
                );
                continue;
            }
            let named = raw_axes.iter().position(|raw| {
                raw.get_ref()
                    .name
                    .as_ref()
                    .is_some_and(|n| n.get_ref() == text)
            });
            if named.is_none() {
                let known: Vec<&str> = axes.iter().flatten().map(|a| a.name.as_str()).collect();
                self.dangling(
                    name.span(),
                    key,
                    format!(
                        "no axis called `{text}`; axes defined: {}",
                        known.join(", ")
                    ),
                );
            }
            // Its index among the valid axes (all of them, when the file has no issues).
            let axis = named
                .filter(|&at| axes[at].is_some())
                .map(|at| axes[..at].iter().flatten().count());
            members.push(Member { name: text, axis });
        }
        members
    }

    /// One tolerance per member axis, in the group's order: the number given for all, the
    /// axis's own entry of the table, or the axis's default.
    fn tolerance(
        &mut self,
        which: Tolerance,
        key: &dyn Fn(&str) -> String,
        group: &str,
        raw: Option<&Spanned<RawTolerance>>,
        members: &[Member<'_>],
        axes: &[Option<AxisConfig>],
    ) -> Option<Vec<f64>> {
        let mut given: Vec<Option<f64>> = vec![None; members.len()];
        let mut ok = true;
        match raw.map(|raw| (raw.span(), raw.get_ref())) {
            None => {}
            Some((span, RawTolerance::One(value))) => {
                match self.tolerance_value(which, &key(which.key()), span, *value, false) {
                    Some(v) => given.fill(Some(v)),
                    None => ok = false,
                }
            }
            Some((_, RawTolerance::PerAxis(entries))) => {
                for (axis, value) in entries {
                    let k = key(&format!("{}.{}", which.key(), axis.get_ref()));
                    let v = self.tolerance_value(which, &k, value.span(), *value.get_ref(), true);
                    ok &= v.is_some();
                    match members.iter().position(|m| m.name == axis.get_ref()) {
                        Some(at) => given[at] = v,
                        None => {
                            ok = false;
                            let listed: Vec<&str> = members.iter().map(|m| m.name).collect();
                            let listed = if listed.is_empty() {
                                "it has none".to_owned()
                            } else {
                                format!("its axes: {}", listed.join(", "))
                            };
                            self.issue(
                                axis.span(),
                                &k,
                                format!(
                                    "`{}` is not an axis of group `{group}`; {listed}",
                                    axis.get_ref()
                                ),
                            );
                        }
                    }
                }
            }
        }
        let values: Option<Vec<f64>> = members
            .iter()
            .zip(given)
            .map(|(member, given)| {
                // The index into the valid axes is the index into `axes.flatten()`.
                let axis = axes.iter().flatten().nth(member.axis?)?;
                Some(given.unwrap_or_else(|| which.default_of(axis)))
            })
            .collect();
        values.filter(|_| ok)
    }

    /// A tolerance's number when it is one the tolerance allows; else an issue at `span`
    /// (`per_axis`: an entry of a table by axis).
    fn tolerance_value(
        &mut self,
        which: Tolerance,
        key: &str,
        span: Range<usize>,
        value: RawNumber,
        per_axis: bool,
    ) -> Option<f64> {
        let message = match value {
            RawNumber::Number(v) if which.allows(v) => {
                if matches!(which, Tolerance::Path) && v == 0.0 {
                    self.warn(
                        span,
                        key,
                        "0 turns off the group's path check of this axis: a path it does not follow goes unnoticed until the axis's own following_error",
                    );
                }
                return Some(v);
            }
            RawNumber::Number(v) => format!("{v} is not allowed; {}", which.allowed()),
            RawNumber::Not(what) if per_axis => {
                format!("{what} is not allowed; {}", which.allowed())
            }
            RawNumber::Not(what) => format!(
                "{what} is not allowed; {}, or a table of them by axis: {} = {{ x = 0.5 }}",
                which.allowed(),
                which.key()
            ),
        };
        self.issue(span, key, message);
        None
    }
}
