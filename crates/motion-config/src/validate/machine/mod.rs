//! Machine keys: what depends on the motor, the mechanics and the wiring of one board
//! model. Each board's crate validates its own keys (`motion_board::Board::device_keys`,
//! `axis_keys`, `cross_check`) into its typed struct, held opaquely in `MachineKeys`; this
//! module splits them off the file's tables (`split.rs`), refuses a key the device's model
//! does not have (naming the models where it is valid, from the registry), hands the rest
//! to the board, and lets each board present check across tables.

pub(crate) mod split;

pub use motion_board::keys::{AxisContext, DeviceContext};
use motion_board::keys::{KeyIssues, KeyTable, Span};
use motion_board::machine::{AxisView, DeviceView, LinkView, MachineView, SignalView};
use motion_board::{AxisKeys, Board, DeviceKeys};
use motion_drivers::Model;
pub use motion_drivers::spec::DeviceMachine;
use toml::Spanned;

use super::{Validator, plain_serde_message};
use crate::ServerConfig;
use crate::raw::RawConfig;

impl KeyIssues for Validator<'_, '_> {
    fn report_issue(&mut self, span: Span, key: &str, message: String) {
        self.issue(span, key, message);
    }

    fn report_warning(&mut self, span: Span, key: &str, message: String) {
        self.warn(span, key, message);
    }

    fn report_refused(&mut self, span: Span, message: &str) {
        let key = self.issues.key_at(span.start);
        self.issue(span, &key, plain_serde_message(message));
    }
}

/// The models whose boards have `has`, for messages (`qq2drv, tmcpack`).
fn models_with(has: impl Fn(&dyn Board) -> bool) -> Vec<&'static str> {
    motion_boards::BOARDS
        .iter()
        .filter(|board| has(**board))
        .map(|board| board.model().id())
        .collect()
}

/// `unknown field `key`, expected one of …`: serde's words, with the general keys and the
/// model's.
fn unknown(key: &str, general: &[&str], model: &[&str]) -> String {
    let expected: Vec<String> = general
        .iter()
        .chain(model)
        .map(|k| format!("`{k}`"))
        .collect();
    format!(
        "unknown field `{key}`, expected one of {}",
        expected.join(", ")
    )
}

impl Validator<'_, '_> {
    /// Refuses every board key of device `index` that `model` does not have; `false` when
    /// one was found.
    pub(super) fn device_keys_fit(
        &mut self,
        index: usize,
        keys: &KeyTable<'_>,
        address: Option<Span>,
        model: Model,
    ) -> bool {
        let board = motion_boards::board(model);
        let mut fit = true;
        if let (Some(span), None) = (address, board.address()) {
            fit = false;
            let valid = models_with(|b| b.address().is_some()).join(", ");
            self.issue(
                span,
                &format!("device[{index}].address"),
                format!("`address` is not a key of {model} devices; it is valid on: {valid}"),
            );
        }
        for (key, span) in keys.keys() {
            if board.device_key_names().contains(&key) {
                continue;
            }
            fit = false;
            let valid = models_with(|b| b.device_key_names().contains(&key));
            let message = if valid.is_empty() {
                unknown(key, split::DEVICE_KEYS, board.device_key_names())
            } else {
                format!(
                    "`{key}` is not a key of {model} devices; it is valid on: {}",
                    valid.join(", ")
                )
            };
            self.issue(span, &format!("device[{index}].{key}"), message);
        }
        fit
    }

    /// Refuses every board key of axis `index` that its device's `model` does not have
    /// (and a `home` table on a model that cannot home).
    pub(super) fn axis_keys_fit(
        &mut self,
        index: usize,
        keys: &KeyTable<'_>,
        home: Option<Span>,
        model: Model,
    ) -> bool {
        let board = motion_boards::board(model);
        let mut fit = true;
        if let (Some(span), Some(why)) = (home.clone(), board.cannot_home()) {
            fit = false;
            let valid = models_with(|b| b.cannot_home().is_none()).join(", ");
            self.issue(
                span,
                &format!("axis[{index}].home"),
                format!("`home` is not a key of {model} axes; it is valid on: {valid}; {why}"),
            );
        }
        let names = board.axis_key_names();
        for (key, span) in keys.keys() {
            if key == "home" {
                continue;
            }
            if names.contains(&key) {
                continue;
            }
            fit = false;
            let valid = models_with(|b| b.axis_key_names().contains(&key));
            let message = if valid.is_empty() {
                unknown(key, split::AXIS_KEYS, names)
            } else {
                format!(
                    "`{key}` is not a key of {model} axes; it is valid on: {}",
                    valid.join(", ")
                )
            };
            self.issue(span, &format!("axis[{index}].{key}"), message);
        }
        if home.is_some() && board.cannot_home().is_none() {
            for (sub, span) in keys.keys_under("home") {
                let dotted = format!("home.{sub}");
                if names.contains(&dotted.as_str()) {
                    continue;
                }
                fit = false;
                let valid = models_with(|b| b.axis_key_names().contains(&dotted.as_str()));
                let message = if valid.is_empty() {
                    let home: Vec<String> = names
                        .iter()
                        .filter_map(|k| k.strip_prefix("home."))
                        .map(str::to_owned)
                        .collect();
                    let home: Vec<&str> = home.iter().map(String::as_str).collect();
                    unknown(sub, split::HOME_KEYS, &home)
                } else {
                    format!(
                        "`{dotted}` is not a key of {model} axes; it is valid on: {}",
                        valid.join(", ")
                    )
                };
                self.issue(span, &format!("axis[{index}].home.{sub}"), message);
            }
        }
        fit
    }

    /// The model's device keys.
    pub(super) fn device_machine(
        &mut self,
        ctx: &DeviceContext,
        model: Model,
        keys: &KeyTable<'_>,
    ) -> Option<DeviceKeys> {
        motion_boards::board(model).device_keys(keys, ctx, self)
    }

    /// The model's axis keys, on a device with `device` keys. A board without keys of its
    /// own in an axis's `home` table gets the table without it.
    pub(super) fn axis_machine(
        &mut self,
        ctx: &AxisContext<'_>,
        model: Model,
        keys: &KeyTable<'_>,
        device: &DeviceMachine,
    ) -> Option<AxisKeys> {
        let board = motion_boards::board(model);
        let homes = board
            .axis_key_names()
            .iter()
            .any(|key| key.starts_with("home."));
        let keys = if homes {
            keys.clone()
        } else {
            keys.without(|key| key == "home")
        };
        board.axis_keys(&keys, device, ctx, self)
    }

    /// Checks across tables (keys that must agree between axes of one device, addresses
    /// against other devices), after everything else was validated: each model present
    /// checks its own.
    pub(super) fn machine_cross_checks(
        &mut self,
        config: &ServerConfig,
        raw: &RawConfig,
        tables: &split::BoardTables<'_>,
    ) {
        let view = view(config, raw, tables);
        let mut models: Vec<Model> = Vec::new();
        for device in &config.devices {
            if !models.contains(&device.model) {
                models.push(device.model);
            }
        }
        for model in models {
            motion_boards::board(model).cross_check(&view, self);
        }
    }
}

/// Where the raw table of `items` named `name` is.
fn named<'r, T>(
    items: &'r [Spanned<T>],
    name: &str,
    name_of: impl Fn(&T) -> Option<&Spanned<String>>,
) -> Option<(usize, &'r Spanned<T>)> {
    items
        .iter()
        .enumerate()
        .find(|(_, item)| name_of(item.get_ref()).is_some_and(|n| n.get_ref() == name))
}

/// The validated machine with where each part was written, for the boards' cross-checks.
fn view<'a>(
    config: &'a ServerConfig,
    raw: &'a RawConfig,
    tables: &'a split::BoardTables<'a>,
) -> MachineView<'a> {
    let mut view = MachineView::default();
    for link in &config.links {
        let Some((index, raw_link)) = named(&raw.link, &link.name, |l| l.name.as_ref()) else {
            continue;
        };
        let raw_link = raw_link.get_ref();
        view.links.push(LinkView {
            index,
            name: &link.name,
            kind: link.kind,
            framing: link.framing(),
            line_rate: link.transport.rate(),
            rate_span: raw_link
                .speed_hz
                .as_ref()
                .or(raw_link.baud.as_ref())
                .or(raw_link.bitrate.as_ref())
                .map(Spanned::span),
        });
    }
    for device in &config.devices {
        let Some((index, raw_device)) = named(&raw.device, &device.name, |d| d.name.as_ref())
        else {
            continue;
        };
        let Some(keys) = tables.devices.get(index) else {
            continue;
        };
        view.devices.push(DeviceView {
            index,
            name: &device.name,
            // `device.link` is the link's table index; the view holds the valid links only
            // (one refused before this one would shift every later index).
            link: view
                .links
                .iter()
                .position(|link| link.index == device.link)
                .unwrap_or(usize::MAX),
            model: device.model,
            address: device.address,
            address_span: raw_device.get_ref().address.as_ref().map(Spanned::span),
            table: raw_device.span(),
            machine: &device.machine,
            keys,
        });
    }
    for (axis, spec) in config.axes.iter().zip(&config.axis_specs) {
        let Some((index, raw_axis)) = named(&raw.axis, &axis.name, |a| a.name.as_ref()) else {
            continue;
        };
        let Some(keys) = tables.axes.get(index) else {
            continue;
        };
        view.axes.push(AxisView {
            index,
            name: &axis.name,
            device: axis.device,
            channel: axis.channel,
            counts_per_unit: axis.counts_per_unit,
            unit: &axis.unit,
            table: raw_axis.span(),
            device_span: raw_axis
                .get_ref()
                .device
                .as_ref()
                .map_or(raw_axis.span(), Spanned::span),
            machine: &spec.machine,
            keys,
        });
    }
    for signal in &config.signals {
        let Some((index, raw_signal)) = named(&raw.signal, &signal.name, |s| s.name.as_ref())
        else {
            continue;
        };
        let r = raw_signal.get_ref();
        view.signals.push(SignalView {
            index,
            name: &signal.name,
            device: signal.device,
            kind: signal.kind,
            pin: signal.pin,
            pin_name: &signal.pin_name,
            pin_span: r.pin.as_ref().map_or(raw_signal.span(), Spanned::span),
            kind_span: r.kind.as_ref().map_or(raw_signal.span(), Spanned::span),
            table: raw_signal.span(),
        });
    }
    view
}
