//! `[[device]]` and `[[axis]]` tables.

use motion_engine::AxisConfig;
use motion_ipc::{NAME_LEN, UNIT_LEN};
use toml::Spanned;

use super::Validator;
use super::machine::{AxisContext, DeviceContext};

use crate::raw::{RawAxis, RawDevice};
use crate::{AxisSpec, DeviceSpec};

impl Validator<'_, '_> {
    pub(super) fn device(
        &mut self,
        index: usize,
        raw: &Spanned<RawDevice>,
        link_names: &[Option<String>],
    ) -> Option<DeviceSpec> {
        let table = raw.span();
        let d = raw.get_ref();
        let key = |k: &str| format!("device[{index}].{k}");
        let name = self
            .required(&d.name, &table, &key("name"), "every device needs a name")
            .and_then(|name| self.name(name, &key("name"), NAME_LEN));
        let link = self
            .required(&d.link, &table, &key("link"), "the name of a [[link]]")
            .and_then(|link| {
                let found = link_names
                    .iter()
                    .position(|name| name.as_deref() == Some(link.get_ref().as_str()));
                if found.is_none() {
                    let known: Vec<&str> =
                        link_names.iter().flatten().map(String::as_str).collect();
                    self.dangling(
                        link.span(),
                        &key("link"),
                        format!(
                            "no link called `{}`; links defined: {}",
                            link.get_ref(),
                            known.join(", ")
                        ),
                    );
                }
                found
            });
        let model = self
            .required(
                &d.model,
                &table,
                &key("model"),
                &format!("one of {}", motion_boards::id_list()),
            )
            .and_then(|model| {
                let parsed = motion_boards::by_id(model.get_ref()).map(|board| board.model());
                if parsed.is_none() {
                    self.issue(
                        model.span(),
                        &key("model"),
                        format!(
                            "unknown model {:?}; allowed: {}",
                            model.get_ref(),
                            motion_boards::id_list()
                        ),
                    );
                }
                parsed
            });
        let keys = self.tables.devices.get(index).cloned();
        let keys = keys.unwrap_or_else(|| motion_board::keys::KeyTable::empty(table.clone()));
        let address_span = d.address.as_ref().map(Spanned::span);
        let fits =
            model.is_none_or(|model| self.device_keys_fit(index, &keys, address_span, model));
        let address = match (
            model.and_then(|m| motion_boards::board(m).address()),
            &d.address,
        ) {
            (Some(rule), None) => Some(rule.default),
            (Some(rule), Some(a)) => match (rule.check)(a.get_ref().0) {
                Ok(address) => Some(address),
                Err(message) => {
                    self.issue(a.span(), &key("address"), message);
                    None
                }
            },
            // An address on a model without one was refused with the keys above.
            (None, Some(_)) => None,
            (None, None) => Some(0),
        };
        let mut sim_seed = index as u64 + 1;
        if let Some(sim) = &d.sim
            && let Some(seed) = &sim.get_ref().seed
            && let Some(seed) = self.int_in(seed, &key("sim.seed"), 0..=i64::MAX)
        {
            sim_seed = seed as u64;
        }
        let ctx = DeviceContext {
            index,
            table: table.clone(),
        };
        let machine = match model {
            Some(model) if fits => self.device_machine(&ctx, model, &keys),
            _ => None,
        };
        Some(DeviceSpec {
            name: name?,
            link: link?,
            model: model?,
            address: address?,
            sim_seed,
            machine: machine.as_ref()?.machine.clone(),
            home_hints: machine?.home,
        })
    }

    pub(super) fn axis(
        &mut self,
        index: usize,
        raw: &Spanned<RawAxis>,
        devices: &[Option<DeviceSpec>],
        raw_devices: &[Spanned<RawDevice>],
    ) -> Option<(AxisConfig, AxisSpec)> {
        let table = raw.span();
        let a = raw.get_ref();
        let key = |k: &str| format!("axis[{index}].{k}");
        let name = self
            .required(&a.name, &table, &key("name"), "every axis needs a name")
            .and_then(|name| self.name(name, &key("name"), NAME_LEN));
        let device = self
            .required(
                &a.device,
                &table,
                &key("device"),
                "the name of a [[device]]",
            )
            .and_then(|device| {
                let named = raw_devices.iter().position(|raw| {
                    raw.get_ref()
                        .name
                        .as_ref()
                        .is_some_and(|n| n.get_ref() == device.get_ref())
                });
                let found = named.filter(|&index| devices[index].is_some());
                if named.is_none() {
                    let known: Vec<&str> =
                        devices.iter().flatten().map(|d| d.name.as_str()).collect();
                    self.dangling(
                        device.span(),
                        &key("device"),
                        format!(
                            "no device called `{}`; devices defined: {}",
                            device.get_ref(),
                            known.join(", ")
                        ),
                    );
                }
                found
            });
        let channel = self
            .required(
                &a.channel,
                &table,
                &key("channel"),
                "the motor number on the device, from 0",
            )
            .and_then(|channel| {
                let spec = device.and_then(|d| devices[d].as_ref())?;
                let count = spec.channel_count();
                let value = channel.get_ref().0;
                if (0..count as i128).contains(&value) {
                    Some(value as usize)
                } else {
                    self.issue(
                        channel.span(),
                        &key("channel"),
                        format!(
                            "{value} is not a channel of {} device `{}`; allowed: 0..={}",
                            spec.model,
                            spec.name,
                            count - 1
                        ),
                    );
                    None
                }
            });
        let unit = match &a.unit {
            Some(unit) if !unit.get_ref().is_empty() && unit.get_ref().len() <= UNIT_LEN => {
                Some(unit.get_ref().clone())
            }
            Some(unit) => {
                self.issue(
                    unit.span(),
                    &key("unit"),
                    format!(
                        "{:?}: allowed: 1..={UNIT_LEN} bytes, e.g. \"mm\" or \"deg\"",
                        unit.get_ref()
                    ),
                );
                None
            }
            None => {
                self.issue(
                    table.clone(),
                    &key("unit"),
                    "missing; the unit of positions, e.g. \"mm\" or \"deg\"",
                );
                None
            }
        };
        let number = |me: &mut Self,
                      value: &Option<Spanned<f64>>,
                      k: &str,
                      allowed: &str,
                      ok: &dyn Fn(f64) -> bool|
         -> Option<f64> {
            let value = me.required(value, &table, &key(k), allowed)?;
            let v = *value.get_ref();
            if ok(v) {
                Some(v)
            } else {
                me.issue(
                    value.span(),
                    &key(k),
                    format!("{v} is not allowed; {allowed}"),
                );
                None
            }
        };
        let cpu = number(
            self,
            &a.counts_per_unit,
            "counts_per_unit",
            "a finite number, not 0 (negative reverses the direction)",
            &|v| v.is_finite() && v != 0.0,
        );
        let min = number(
            self,
            &a.min,
            "min",
            "a finite number (soft limit, units)",
            &|v| v.is_finite(),
        );
        let max = number(
            self,
            &a.max,
            "max",
            "a finite number (soft limit, units)",
            &|v| v.is_finite(),
        );
        let max_velocity = number(
            self,
            &a.max_velocity,
            "max_velocity",
            "a finite number > 0 (units/s)",
            &|v| v.is_finite() && v > 0.0,
        );
        let max_accel = number(
            self,
            &a.max_accel,
            "max_accel",
            "a finite number > 0 (units/s²)",
            &|v| v.is_finite() && v > 0.0,
        );
        if let (Some(lo), Some(hi), Some(value)) = (min, max, &a.max)
            && lo >= hi
        {
            self.issue(
                value.span(),
                &key("max"),
                format!("max ({hi}) must be greater than min ({lo})"),
            );
        }
        let tolerance = match &a.position_tolerance {
            Some(t) if t.get_ref().is_finite() && *t.get_ref() > 0.0 => Some(*t.get_ref()),
            Some(t) => {
                self.issue(
                    t.span(),
                    &key("position_tolerance"),
                    format!(
                        "{} is not allowed; a finite number > 0 (units)",
                        t.get_ref()
                    ),
                );
                None
            }
            None => cpu.map(|cpu| 2.0 / cpu.abs()),
        };
        let spec = device.and_then(|d| devices[d].as_ref());
        let keys = self.tables.axes.get(index).cloned();
        let keys = keys.unwrap_or_else(|| motion_board::keys::KeyTable::empty(table.clone()));
        let home_span = a.home.as_ref().map(Spanned::span);
        let fits = spec.is_none_or(|spec| self.axis_keys_fit(index, &keys, home_span, spec.model));
        let supervision = self.supervision(index, a, cpu, min, max, tolerance);
        let ctx = AxisContext {
            index,
            table: table.clone(),
            counts_per_unit: cpu,
            min,
            max,
            max_span: a.max.as_ref().map(Spanned::span),
            unit: unit.as_deref(),
            channel,
            home_position: a
                .home
                .as_ref()
                .and_then(|home| home.get_ref().position.as_ref())
                .map(|position| (*position.get_ref(), position.span())),
            max_velocity,
            max_accel,
        };
        let machine = match spec {
            Some(spec) if fits => self.axis_machine(&ctx, spec.model, &keys, &spec.machine),
            _ => None,
        };
        let home = spec.and_then(|spec| {
            let hints = machine.as_ref().map(|keys| &keys.home);
            self.home(index, a, spec, hints, cpu, min, max)
        });
        let (min, max) = (min?, max?);
        if min >= max {
            return None;
        }
        let (following_error, overspeed_factor, estop) = supervision?;
        let home = home?;
        let axis = AxisConfig {
            name: name?,
            unit: unit?,
            device: device?,
            channel: channel?,
            counts_per_unit: cpu?,
            min,
            max,
            max_velocity: max_velocity?,
            max_accel: max_accel?,
            position_tolerance: tolerance?,
            following_error,
            overspeed_factor,
            estop,
            home_max_travel: home.max_travel,
        };
        Some((
            axis,
            AxisSpec {
                home,
                machine: machine?.machine,
            },
        ))
    }
}
