//! `[[signal]]` tables: named board I/O pins.

use motion_drivers::{SignalKind, find_pin};
use motion_ipc::{MAX_SIGNALS, NAME_LEN, UNIT_LEN};
use toml::Spanned;

use motion_engine::AxisConfig;

use super::Validator;
use crate::raw::{RawDevice, RawSignal};
use crate::{DeviceSpec, SignalSpec};

fn kind_list(kinds: impl Iterator<Item = SignalKind>) -> String {
    kinds.map(SignalKind::name).collect::<Vec<_>>().join(", ")
}

impl Validator<'_, '_> {
    /// Every `[[signal]]` table, checked against its device's pins.
    pub(super) fn signals(
        &mut self,
        raw: &[Spanned<RawSignal>],
        devices: &[Option<DeviceSpec>],
        raw_devices: &[Spanned<RawDevice>],
        axes: &[Option<AxisConfig>],
    ) -> Vec<SignalSpec> {
        if raw.len() > MAX_SIGNALS {
            self.issue(
                raw[MAX_SIGNALS].span(),
                "signal",
                format!(
                    "{} [[signal]] tables; at most {MAX_SIGNALS} are supported",
                    raw.len()
                ),
            );
        }
        let mut specs: Vec<Option<SignalSpec>> = Vec::with_capacity(raw.len());
        for (index, signal) in raw.iter().enumerate() {
            let spec = self.signal(index, signal, devices, raw_devices, axes);
            if let Some(spec) = &spec {
                if let Some(first) = specs.iter().flatten().find(|s| s.name == spec.name) {
                    let span = signal
                        .get_ref()
                        .name
                        .as_ref()
                        .map_or(signal.span(), Spanned::span);
                    self.issue(
                        span,
                        &format!("signal[{index}].name"),
                        format!(
                            "a signal called `{}` is already defined; names must be unique",
                            first.name
                        ),
                    );
                }
                if let Some(first) = specs
                    .iter()
                    .flatten()
                    .find(|s| s.device == spec.device && s.pin == spec.pin)
                {
                    let span = signal
                        .get_ref()
                        .pin
                        .as_ref()
                        .map_or(signal.span(), Spanned::span);
                    self.issue(
                        span,
                        &format!("signal[{index}].pin"),
                        format!(
                            "pin `{}` of device `{}` is already used by signal `{}`; one signal per pin",
                            spec.pin_name, devices[spec.device].as_ref().map_or("?", |d| d.name.as_str()), first.name
                        ),
                    );
                }
            }
            specs.push(spec);
        }
        specs.into_iter().flatten().collect()
    }

    fn signal(
        &mut self,
        index: usize,
        raw: &Spanned<RawSignal>,
        devices: &[Option<DeviceSpec>],
        raw_devices: &[Spanned<RawDevice>],
        axes: &[Option<AxisConfig>],
    ) -> Option<SignalSpec> {
        let table = raw.span();
        let s = raw.get_ref();
        let key = |k: &str| format!("signal[{index}].{k}");
        let name = self
            .required(&s.name, &table, &key("name"), "every signal needs a name")
            .and_then(|name| self.name(name, &key("name"), NAME_LEN));
        let device = self
            .required(
                &s.device,
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
                named.filter(|&index| devices[index].is_some())
            });
        let kind = self
            .required(
                &s.kind,
                &table,
                &key("kind"),
                "one of \"digital-in\", \"digital-out\", \"analog-in\", \"capture\", \"trigger\"",
            )
            .and_then(|kind| {
                let found = SignalKind::ALL
                    .into_iter()
                    .find(|k| k.name() == kind.get_ref());
                if found.is_none() {
                    self.issue(
                        kind.span(),
                        &key("kind"),
                        format!(
                            "unknown kind {:?}; allowed: {}",
                            kind.get_ref(),
                            kind_list(SignalKind::ALL.into_iter())
                        ),
                    );
                }
                found
            });
        let spec = device.and_then(|d| devices[d].as_ref());
        let pin = self
            .required(
                &s.pin,
                &table,
                &key("pin"),
                "the board's pin name (docs/IO.md lists each board's pins)",
            )
            .and_then(|pin| {
                let spec = spec?;
                let pins = spec.pins();
                let name = pin.get_ref().as_str();
                let Some(found) = find_pin(pins, name) else {
                    let known: Vec<&str> = pins.iter().map(|p| p.name).collect();
                    let model = motion_boards::board(spec.model).product_name(&spec.machine);
                    let allowed = if known.is_empty() {
                        format!("a {model} board has no I/O pins")
                    } else {
                        format!("pins of a {model} board: {}", known.join(", "))
                    };
                    self.issue(
                        pin.span(),
                        &key("pin"),
                        format!("device `{}` has no pin `{name}`; {allowed}", spec.name),
                    );
                    return None;
                };
                let info = &pins[usize::from(found.0)];
                if let Some(kind) = kind
                    && !info.kinds.contains(kind)
                {
                    self.issue(
                        pin.span(),
                        &key("pin"),
                        format!(
                            "pin `{name}` cannot be {}; it can be: {}",
                            kind.name(),
                            kind_list(
                                SignalKind::ALL
                                    .into_iter()
                                    .filter(|k| info.kinds.contains(*k))
                            )
                        ),
                    );
                    return None;
                }
                Some((found, name.to_owned()))
            });
        let digital =
            kind.is_some_and(|k| matches!(k, SignalKind::DigitalIn | SignalKind::DigitalOut));
        if kind.is_some() {
            let numeric = "analog-in, capture and trigger";
            for (set, k, only) in [
                (s.scale.as_ref().map(Spanned::span), "scale", numeric),
                (s.offset.as_ref().map(Spanned::span), "offset", numeric),
                (s.unit.as_ref().map(Spanned::span), "unit", numeric),
                (
                    s.invert.as_ref().map(Spanned::span),
                    "invert",
                    "digital-in and digital-out",
                ),
                (s.safe.as_ref().map(Spanned::span), "safe", "digital-out"),
            ] {
                let applies = match k {
                    "invert" => digital,
                    "safe" => kind == Some(SignalKind::DigitalOut),
                    _ => !digital,
                };
                if let (Some(span), false) = (set, applies) {
                    self.issue(
                        span,
                        &key(k),
                        format!("`{k}` applies only to {only} signals"),
                    );
                }
            }
        }
        let finite =
            |me: &mut Self, value: &Option<Spanned<f64>>, k: &str, default: f64| match value {
                Some(v) if v.get_ref().is_finite() => Some(*v.get_ref()),
                Some(v) => {
                    me.issue(v.span(), &key(k), "a finite number");
                    None
                }
                None => Some(default),
            };
        // A capture or a trigger's compare position is a count of the device's counter:
        // in the units of its axis (the one axis on the device), unless said otherwise.
        let position_axis = kind
            .filter(|k| matches!(k, SignalKind::Capture | SignalKind::Trigger))
            .and(device)
            .and_then(|d| {
                let mut on = axes.iter().flatten().filter(|a| a.device == d);
                on.next().filter(|_| on.next().is_none())
            });
        let default_scale = position_axis.map_or(1.0, |a| 1.0 / a.counts_per_unit);
        let scale = finite(self, &s.scale, "scale", default_scale);
        let offset = finite(self, &s.offset, "offset", 0.0);
        let unit = match &s.unit {
            None if position_axis.is_some() => position_axis.map(|a| a.unit.clone()),
            Some(u) if u.get_ref().len() <= UNIT_LEN => Some(u.get_ref().clone()),
            Some(u) => {
                self.issue(
                    u.span(),
                    &key("unit"),
                    format!("{:?}: allowed: at most {UNIT_LEN} bytes", u.get_ref()),
                );
                None
            }
            None => Some(String::new()),
        };
        let (pin, pin_name) = pin?;
        Some(SignalSpec {
            name: name?,
            device: device?,
            kind: kind?,
            pin,
            pin_name,
            invert: s.invert.as_ref().is_some_and(|v| *v.get_ref()),
            scale: scale?,
            offset: offset?,
            unit: unit?,
            safe: s.safe.as_ref().map(|v| *v.get_ref()),
        })
    }
}
