//! Raw TOML → validated [`ServerConfig`], collecting every issue with its location.

use core::ops::Range;
use core::time::Duration;
use std::path::PathBuf;

use motion_engine::AxisConfig;
use motion_ipc::{MAX_AXES, MAX_DEVICES, MAX_LINKS, NAME_LEN};
use serde::Deserialize;
use toml::Spanned;

mod groups;
mod home;
mod items;
mod links;
pub mod machine;
mod signals;
mod supervision;

use super::error::{ConfigIssue, Issues};
use super::raw::{IntValue, RawConfig, RawLink, RawServer};
use super::{AxisSpec, DeviceSpec, GivenKeys, ServerConfig, ServerSettings};

pub(crate) fn parse(source: &str) -> Result<ServerConfig, Vec<ConfigIssue>> {
    let mut issues = Issues::new(source);
    let refused = |issues: &mut Issues<'_>, error: toml::de::Error| {
        let span = error.span().unwrap_or(0..0);
        let key = issues.key_at(span.start);
        issues.push(span, key, plain_serde_message(error.message()));
    };
    // The boards' keys come off the tables first: serde reads the general ones.
    let mut doc = match toml::de::DeTable::parse(source) {
        Ok(doc) => doc,
        Err(error) => {
            refused(&mut issues, error);
            return Err(issues.sorted());
        }
    };
    let tables = machine::split::split(&mut doc);
    let raw = match RawConfig::deserialize(toml::de::Deserializer::from(doc)) {
        Ok(raw) => raw,
        Err(error) => {
            refused(&mut issues, error);
            return Err(issues.sorted());
        }
    };
    let mut validator = Validator {
        issues: &mut issues,
        tables: &tables,
    };
    let mut config = validator.run(&raw);
    validator.machine_cross_checks(&config, &raw, &tables);
    config.given = GivenKeys::of(source);
    config.warnings = core::mem::take(&mut issues.warnings);
    config
        .warnings
        .sort_by_key(|issue| (issue.line, issue.column));
    if issues.list.is_empty() {
        Ok(config)
    } else {
        Err(issues.sorted())
    }
}

/// The span of a table's `name` value, else of the whole table.
fn name_span<T>(table: &Spanned<T>, name: impl Fn(&T) -> &Option<Spanned<String>>) -> Range<usize> {
    name(table.get_ref())
        .as_ref()
        .map_or(table.span(), Spanned::span)
}

/// A serde/TOML message in the user's words: no Rust type names (`i64`, `i128 `…); an
/// integer beyond 64 bits says so.
fn plain_serde_message(message: &str) -> String {
    let mut text = message
        .trim()
        .replace('\n', " ")
        .replace("expected i64", "expected an integer")
        .replace("expected f64", "expected a number");
    let mut beyond = false;
    for rust in [" as i128", " as u128"] {
        if text.contains(rust) {
            beyond = true;
            text = text.replace(rust, "");
        }
    }
    for rust in [" as i64", " as u64", " as f64"] {
        text = text.replace(rust, "");
    }
    // serde names the parser's own structs (`expected struct RawSim`): a table to the user.
    while let Some(at) = text.find("struct Raw") {
        let end = text[at + "struct ".len()..]
            .find(|c: char| !c.is_ascii_alphanumeric())
            .map_or(text.len(), |n| at + "struct ".len() + n);
        text.replace_range(at..end, "a table");
    }
    if beyond {
        text.push_str(" (the integer is beyond the 64-bit range every key has)");
    }
    text
}

/// Whether `text` is a name the server takes: 1..=`max` bytes of ASCII letters, digits, `_`
/// and `-` (the server's name becomes part of its service and node names and of paths,
/// where `.` and `..` mean something else).
pub(crate) fn is_identifier(text: &str, max: usize) -> bool {
    !text.is_empty()
        && text.len() <= max
        && text
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}

pub(crate) struct Validator<'i, 's> {
    issues: &'i mut Issues<'s>,
    /// The boards' keys of each `[[device]]` and `[[axis]]` table.
    tables: &'i machine::split::BoardTables<'s>,
}

/// The span of a whole table, for "missing key" issues.
pub(crate) type TableSpan = Range<usize>;

impl Validator<'_, '_> {
    pub(crate) fn issue(&mut self, span: Range<usize>, key: &str, message: impl Into<String>) {
        self.issues.push(span, key, message);
    }

    /// An issue about a name that refers to nothing (reported before the others).
    pub(crate) fn dangling(&mut self, span: Range<usize>, key: &str, message: impl Into<String>) {
        self.issues.push_reference(span, key, message);
    }

    /// A warning: the config is used, and motiond (and `--check-config`) print it.
    pub(crate) fn warn(&mut self, span: Range<usize>, key: &str, message: impl Into<String>) {
        self.issues.warn(span, key, message);
    }

    pub(crate) fn required<'v, T>(
        &mut self,
        value: &'v Option<Spanned<T>>,
        table: &TableSpan,
        key: &str,
        allowed: &str,
    ) -> Option<&'v Spanned<T>> {
        if value.is_none() {
            self.issue(table.clone(), key, format!("missing; {allowed}"));
        }
        value.as_ref()
    }

    /// `value` when it lies in `range`; otherwise an issue naming the range (the same
    /// check the boards' keys use).
    pub(crate) fn int_in<T: IntValue>(
        &mut self,
        value: &Spanned<T>,
        key: &str,
        range: core::ops::RangeInclusive<i64>,
    ) -> Option<i64> {
        let issues: &mut dyn motion_board::keys::KeyIssues = self;
        issues.int_in(value, key, range)
    }

    pub(super) fn name(
        &mut self,
        value: &Spanned<String>,
        key: &str,
        max: usize,
    ) -> Option<String> {
        let text = value.get_ref();
        if is_identifier(text, max) {
            Some(text.clone())
        } else {
            self.issue(
                value.span(),
                key,
                format!(
                    "{text:?} is not a valid name; a name is an identifier: 1..={max} characters of A-Z a-z 0-9 _ - (no `.`, so never `.` or `..`)"
                ),
            );
            None
        }
    }

    fn run(&mut self, raw: &RawConfig) -> ServerConfig {
        let server = self.server(raw.server.as_ref());
        if raw.link.is_empty() {
            self.issue(0..0, "link", "no [[link]] table: a server needs at least one link to a board (a sim link runs a simulated one)");
        }
        if raw.device.is_empty() {
            self.issue(
                0..0,
                "device",
                "no [[device]] table: a server needs at least one board",
            );
        }
        if raw.axis.is_empty() && raw.signal.is_empty() {
            self.issue(
                0..0,
                "axis",
                "no [[axis]] or [[signal]] table: the server would have nothing to serve",
            );
        }
        for (what, count, max, items) in [
            (
                "link",
                raw.link.len(),
                MAX_LINKS,
                raw.link.first().map(Spanned::span),
            ),
            (
                "device",
                raw.device.len(),
                MAX_DEVICES,
                raw.device.first().map(Spanned::span),
            ),
            (
                "axis",
                raw.axis.len(),
                MAX_AXES,
                raw.axis.first().map(Spanned::span),
            ),
        ] {
            if count > max {
                self.issue(
                    items.unwrap_or(0..0),
                    what,
                    format!("{count} [[{what}]] tables; at most {max} are supported"),
                );
            }
        }
        let links: Vec<Option<(String, &Spanned<RawLink>)>> = raw
            .link
            .iter()
            .enumerate()
            .map(|(index, link)| {
                let key = format!("link[{index}].name");
                let table = link.span();
                let name = self
                    .required(
                        &link.get_ref().name,
                        &table,
                        &key,
                        "every link needs a name",
                    )
                    .and_then(|name| self.name(name, &key, NAME_LEN));
                name.map(|name| (name, link))
            })
            .collect();
        self.duplicates(
            "link",
            links.iter().enumerate().filter_map(|(index, link)| {
                link.as_ref()
                    .map(|(name, link)| (index, name.as_str(), name_span(link, |l| &l.name)))
            }),
        );
        let link_names: Vec<Option<String>> = links
            .iter()
            .map(|link| link.as_ref().map(|(name, _)| name.clone()))
            .collect();

        let devices: Vec<Option<DeviceSpec>> = raw
            .device
            .iter()
            .enumerate()
            .map(|(index, device)| self.device(index, device, &link_names))
            .collect();
        self.duplicates(
            "device",
            devices
                .iter()
                .zip(&raw.device)
                .enumerate()
                .filter_map(|(index, (spec, raw))| {
                    spec.as_ref()
                        .map(|spec| (index, spec.name.as_str(), name_span(raw, |d| &d.name)))
                }),
        );
        let links = self.links(&links, &devices, &raw.device, server.tick_hz);
        let axes: Vec<Option<(AxisConfig, AxisSpec)>> = raw
            .axis
            .iter()
            .enumerate()
            .map(|(index, axis)| self.axis(index, axis, &devices, &raw.device))
            .collect();
        let axis_specs: Vec<AxisSpec> = axes
            .iter()
            .flatten()
            .map(|(_, spec)| spec.clone())
            .collect();
        let axes: Vec<Option<AxisConfig>> = axes
            .into_iter()
            .map(|axis| axis.map(|(axis, _)| axis))
            .collect();
        let signals = self.signals(&raw.signal, &devices, &raw.device, &axes);
        self.duplicates(
            "axis",
            axes.iter()
                .zip(&raw.axis)
                .enumerate()
                .filter_map(|(index, (axis, raw))| {
                    axis.as_ref()
                        .map(|axis| (index, axis.name.as_str(), name_span(raw, |a| &a.name)))
                }),
        );
        for (index, axis) in axes.iter().enumerate() {
            let Some(axis) = axis else { continue };
            if let Some(first) = axes[..index]
                .iter()
                .flatten()
                .find(|other| other.device == axis.device && other.channel == axis.channel)
            {
                let span = raw.axis[index]
                    .get_ref()
                    .channel
                    .as_ref()
                    .map_or(raw.axis[index].span(), Spanned::span);
                let message = format!(
                    "channel {} of this device is already driven by axis `{}`; one axis per channel",
                    axis.channel, first.name
                );
                self.issue(span, &format!("axis[{index}].channel"), message);
            }
        }
        let groups = self.groups(&raw.group, &raw.axis, &axes);
        ServerConfig {
            path: PathBuf::new(),
            server,
            links,
            devices: devices.into_iter().flatten().collect(),
            axes: axes.into_iter().flatten().collect(),
            axis_specs,
            signals,
            groups,
            given: GivenKeys::default(),
            warnings: Vec::new(),
        }
    }

    /// Every table whose name an earlier table of its kind has: an issue on its `name`
    /// (`items`: the table's index, its name, the span of its `name` value).
    fn duplicates<'a>(
        &mut self,
        what: &str,
        items: impl Iterator<Item = (usize, &'a str, Range<usize>)>,
    ) {
        let items: Vec<_> = items.collect();
        for (position, (index, name, span)) in items.iter().enumerate() {
            if items[..position]
                .iter()
                .any(|(_, earlier, _)| earlier == name)
            {
                self.issue(
                    span.clone(),
                    &format!("{what}[{index}].name"),
                    format!("a {what} called `{name}` is already defined; names must be unique"),
                );
            }
        }
    }

    fn server(&mut self, raw: Option<&Spanned<RawServer>>) -> ServerSettings {
        let mut settings = ServerSettings {
            name: "motiond".into(),
            tick_hz: 1000,
            command_timeout: Duration::from_millis(250),
            rt_priority: None,
            io_rt_priority: None,
            cpu: None,
            io_cpu: None,
            lock_memory: false,
            max_clients: 32,
            max_consecutive_overruns: 50,
            liveness_check: Duration::from_millis(100),
            claim_lease: Duration::ZERO,
            blackbox_seconds: 10,
            blackbox_on_exit: false,
            // Unless given, under the state directory (below).
            blackbox_dir: PathBuf::new(),
            blackbox_keep: 20,
            state_dir: crate::default_state_dir(),
        };
        const NAME: &str =
            "the instance name: services are motiond/<name>/frame, …; e.g. name = \"demo\"";
        let Some(raw) = raw else {
            self.issue(
                0..0,
                "server.name",
                format!("missing [server] table with its name; {NAME}"),
            );
            return settings;
        };
        let table = raw.span();
        let raw = raw.get_ref();
        if let Some(name) = self.required(&raw.name, &table, "server.name", NAME)
            && let Some(name) = self.name(name, "server.name", NAME_LEN)
        {
            settings.name = name;
        }
        if let Some(v) = &raw.tick_hz
            && let Some(v) = self.int_in(v, "server.tick_hz", 1..=20_000)
        {
            settings.tick_hz = v as u32;
        }
        if let Some(v) = &raw.command_timeout_ms
            && let Some(v) = self.int_in(v, "server.command_timeout_ms", 0..=60_000)
        {
            settings.command_timeout = Duration::from_millis(v as u64);
        }
        if let Some(v) = &raw.rt_priority {
            settings.rt_priority = self
                .int_in(v, "server.rt_priority", 1..=99)
                .map(|v| v as u8);
        }
        settings.io_rt_priority = settings.rt_priority.map(|p| p.saturating_sub(1).max(1));
        if let Some(v) = &raw.io_rt_priority
            && let Some(v) = self.int_in(v, "server.io_rt_priority", 0..=99)
        {
            // 0: the normal policy, explicitly (I/O threads beside a real-time tick).
            settings.io_rt_priority = (v > 0).then_some(v as u8);
        }
        if let Some(v) = &raw.cpu {
            settings.cpu = self.int_in(v, "server.cpu", 0..=1023).map(|v| v as usize);
        }
        if let Some(v) = &raw.io_cpu {
            settings.io_cpu = self
                .int_in(v, "server.io_cpu", 0..=1023)
                .map(|v| v as usize);
        }
        if let Some(v) = &raw.lock_memory {
            settings.lock_memory = *v.get_ref();
        }
        if let Some(v) = &raw.max_clients
            && let Some(v) = self.int_in(v, "server.max_clients", 1..=1024)
        {
            settings.max_clients = v as u32;
        }
        if let Some(v) = &raw.max_consecutive_overruns
            && let Some(v) = self.int_in(v, "server.max_consecutive_overruns", 0..=1_000_000)
        {
            settings.max_consecutive_overruns = v as u32;
        }
        if let Some(v) = &raw.liveness_check_ms
            && let Some(v) = self.int_in(v, "server.liveness_check_ms", 10..=10_000)
        {
            settings.liveness_check = Duration::from_millis(v as u64);
        }
        if let Some(v) = &raw.claim_lease_ms
            && let Some(v) = self.int_in(v, "server.claim_lease_ms", 0..=3_600_000)
        {
            settings.claim_lease = Duration::from_millis(v as u64);
        }
        if let Some(v) = &raw.blackbox_seconds
            && let Some(v) = self.int_in(v, "server.blackbox_seconds", 0..=600)
        {
            settings.blackbox_seconds = v as u32;
        }
        if let Some(v) = &raw.blackbox_keep
            && let Some(v) = self.int_in(v, "server.blackbox_keep", 1..=10_000)
        {
            settings.blackbox_keep = v as u32;
        }
        if let Some(v) = &raw.blackbox_on_exit {
            settings.blackbox_on_exit = *v.get_ref();
        }
        if let Some(v) = &raw.blackbox_dir {
            if v.get_ref().is_empty() {
                self.issue(
                    v.span(),
                    "server.blackbox_dir",
                    "an empty path; give the directory black box files go to, e.g. \
                     blackbox_dir = \"/var/lib/motiond/blackbox\""
                        .to_owned(),
                );
            } else {
                settings.blackbox_dir = v.get_ref().into();
            }
        }
        if let Some(v) = &raw.state_dir {
            if v.get_ref().is_empty() {
                self.issue(
                    v.span(),
                    "server.state_dir",
                    "an empty path; give the directory the server keeps its state in \
                     (the references of power_down = \"restore\" devices), e.g. \
                     state_dir = \"/var/lib/motiond\""
                        .to_owned(),
                );
            } else {
                settings.state_dir = v.get_ref().into();
            }
        }
        if settings.blackbox_dir.as_os_str().is_empty() {
            settings.blackbox_dir = settings.state_dir.join(crate::BLACKBOX_SUBDIR);
        }
        settings
    }
}
