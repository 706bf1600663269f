//! Raw TOML → validated [`ServerConfig`], collecting every issue with its location.

use core::ops::Range;
use core::time::Duration;
use std::path::PathBuf;

use motion_drivers::{BusKind, Model};
use motion_engine::AxisConfig;
use motion_ipc::{MAX_AXES, MAX_DEVICES, MAX_LINKS, NAME_LEN, UNIT_LEN};
use toml::Spanned;

use super::error::{ConfigIssue, Issues};
use super::raw::{RawAxis, RawConfig, RawDevice, RawLink, RawServer};
use super::{DeviceSpec, LinkSpec, PackVariant, ServerConfig, ServerSettings, SpiDrive, Transport};

pub(crate) fn parse(source: &str) -> Result<ServerConfig, Vec<ConfigIssue>> {
    let mut issues = Issues::new(source);
    let raw: RawConfig = match toml::from_str(source) {
        Ok(raw) => raw,
        Err(error) => {
            let span = error.span().unwrap_or(0..0);
            let key = issues.key_at(span.start);
            let message = error
                .message()
                .trim()
                .replace('\n', " ")
                .replace("expected i64", "expected an integer")
                .replace("expected f64", "expected a number");
            issues.push(span, key, message);
            return Err(issues.list);
        }
    };
    let config = Validator {
        issues: &mut issues,
    }
    .run(raw);
    if issues.list.is_empty() {
        Ok(config)
    } else {
        issues.list.sort_by_key(|issue| (issue.line, issue.column));
        Err(issues.list)
    }
}

struct Validator<'i, 's> {
    issues: &'i mut Issues<'s>,
}

/// The span of a whole table, for "missing key" issues.
type TableSpan = Range<usize>;

impl Validator<'_, '_> {
    fn issue(&mut self, span: Range<usize>, key: &str, message: impl Into<String>) {
        self.issues.push(span, key, message);
    }

    fn required<'v, T>(
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

    fn int_in(
        &mut self,
        value: &Spanned<i64>,
        key: &str,
        range: core::ops::RangeInclusive<i64>,
    ) -> Option<i64> {
        let v = *value.get_ref();
        if range.contains(&v) {
            Some(v)
        } else {
            self.issue(
                value.span(),
                key,
                format!(
                    "{v} is out of range; allowed: {}..={}",
                    range.start(),
                    range.end()
                ),
            );
            None
        }
    }

    fn name(&mut self, value: &Spanned<String>, key: &str, max: usize) -> Option<String> {
        let text = value.get_ref();
        let ok = !text.is_empty()
            && text.len() <= max
            && text
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.');
        if ok {
            Some(text.clone())
        } else {
            self.issue(
                value.span(),
                key,
                format!(
                    "{text:?} is not a valid name; allowed: 1..={max} characters of A-Z a-z 0-9 _ - ."
                ),
            );
            None
        }
    }

    fn run(mut self, raw: RawConfig) -> ServerConfig {
        let server = self.server(raw.server.as_ref());
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
        let links: Vec<Option<(String, Spanned<RawLink>)>> = raw
            .link
            .into_iter()
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
            links
                .iter()
                .flatten()
                .map(|(name, link)| (name.as_str(), link.span())),
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
            devices.iter().zip(&raw.device).filter_map(|(spec, raw)| {
                spec.as_ref().map(|spec| (spec.name.as_str(), raw.span()))
            }),
        );
        let links = self.links(&links, &devices, &raw.device);
        let axes: Vec<Option<AxisConfig>> = raw
            .axis
            .iter()
            .enumerate()
            .map(|(index, axis)| self.axis(index, axis, &devices, &raw.device))
            .collect();
        self.duplicates(
            "axis",
            axes.iter().zip(&raw.axis).filter_map(|(axis, raw)| {
                axis.as_ref().map(|axis| (axis.name.as_str(), raw.span()))
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
        ServerConfig {
            path: PathBuf::new(),
            server,
            links,
            devices: devices.into_iter().flatten().collect(),
            axes: axes.into_iter().flatten().collect(),
        }
    }

    fn duplicates<'a>(&mut self, what: &str, items: impl Iterator<Item = (&'a str, Range<usize>)>) {
        let items: Vec<_> = items.collect();
        for (index, (name, span)) in items.iter().enumerate() {
            if items[..index].iter().any(|(earlier, _)| earlier == name) {
                self.issue(
                    span.clone(),
                    &format!("{what}.name"),
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
            cpu: None,
            lock_memory: false,
            max_clients: 32,
            max_consecutive_overruns: 10,
            liveness_check: Duration::from_millis(100),
        };
        let Some(raw) = raw else {
            return settings;
        };
        let raw = raw.get_ref();
        if let Some(name) = &raw.name
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
        if let Some(v) = &raw.cpu {
            settings.cpu = self.int_in(v, "server.cpu", 0..=1023).map(|v| v as usize);
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
        settings
    }

    fn device(
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
                    self.issue(
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
                "one of qq2drv, tmcpack, spimotor, qsb",
            )
            .and_then(|model| {
                let parsed = match model.get_ref().as_str() {
                    "qq2drv" => Some(Model::Qq2drv),
                    "tmcpack" => Some(Model::Tmcpack),
                    "spimotor" => Some(Model::Spimotor),
                    "qsb" => Some(Model::Qsb),
                    _ => None,
                };
                if parsed.is_none() {
                    self.issue(
                        model.span(),
                        &key("model"),
                        format!(
                            "unknown model {:?}; allowed: qq2drv, tmcpack, spimotor, qsb",
                            model.get_ref()
                        ),
                    );
                }
                parsed
            });
        let mut variant = PackVariant::Sixpack;
        if let Some(v) = &d.variant {
            match (model, v.get_ref().as_str()) {
                (Some(Model::Tmcpack), "sixpack") => variant = PackVariant::Sixpack,
                (Some(Model::Tmcpack), "quadpack") => variant = PackVariant::Quadpack,
                (Some(Model::Tmcpack), other) => self.issue(
                    v.span(),
                    &key("variant"),
                    format!("unknown variant {other:?}; allowed: \"sixpack\" (6 motors), \"quadpack\" (4)"),
                ),
                _ => self.issue(v.span(), &key("variant"), "only tmcpack devices have a variant"),
            }
        }
        let mut drive = SpiDrive::Stepper;
        if let Some(v) = &d.drive {
            match (model, v.get_ref().as_str()) {
                (Some(Model::Spimotor), "stepper") => drive = SpiDrive::Stepper,
                (Some(Model::Spimotor), "brushed") => drive = SpiDrive::Brushed,
                (Some(Model::Spimotor), other) => self.issue(
                    v.span(),
                    &key("drive"),
                    format!("unknown drive {other:?}; allowed: \"stepper\" (one axis, channel 0), \"brushed\" (channels 0 = A, 1 = B)"),
                ),
                _ => self.issue(v.span(), &key("drive"), "only spimotor devices have a drive"),
            }
        }
        let address = match (model, &d.address) {
            (Some(Model::Tmcpack), None) => Some(1),
            (Some(Model::Tmcpack), Some(a)) => {
                self.int_in(a, &key("address"), 0..=255).map(|a| a as u32)
            }
            (Some(Model::Spimotor), None) => Some(0x90),
            (Some(Model::Spimotor), Some(a)) => {
                let value = *a.get_ref();
                if (2..=254).contains(&value) && value % 2 == 0 {
                    Some(value as u32)
                } else {
                    self.issue(
                        a.span(),
                        &key("address"),
                        format!("{value} is not an SPI_motor address; allowed: an even number 2..=254 (bit 0 is the read flag), default 0x90 = 144"),
                    );
                    None
                }
            }
            (Some(_), Some(a)) => {
                self.issue(
                    a.span(),
                    &key("address"),
                    "only tmcpack and spimotor devices have an address",
                );
                None
            }
            (_, None) => Some(0),
            (None, Some(_)) => None,
        };
        let mut sim_seed = index as u64 + 1;
        if let Some(sim) = &d.sim
            && let Some(seed) = &sim.get_ref().seed
            && let Some(seed) = self.int_in(seed, &key("sim.seed"), 0..=i64::MAX)
        {
            sim_seed = seed as u64;
        }
        Some(DeviceSpec {
            name: name?,
            link: link?,
            model: model?,
            address: address?,
            variant,
            drive,
            sim_seed,
        })
    }

    /// Links, checked against the devices on them (transport fits the model, sharing rules,
    /// addresses distinct, sim tables only on sim links).
    fn links(
        &mut self,
        links: &[Option<(String, Spanned<RawLink>)>],
        devices: &[Option<DeviceSpec>],
        raw_devices: &[Spanned<RawDevice>],
    ) -> Vec<LinkSpec> {
        let mut specs = Vec::new();
        for (index, entry) in links.iter().enumerate() {
            let Some((name, raw)) = entry else { continue };
            let table = raw.span();
            let l = raw.get_ref();
            let key = |k: &str| format!("link[{index}].{k}");
            let on_link: Vec<(usize, &DeviceSpec)> = devices
                .iter()
                .enumerate()
                .filter_map(|(i, d)| d.as_ref().filter(|d| d.link == index).map(|d| (i, d)))
                .collect();
            let models: Vec<Model> = on_link.iter().map(|(_, d)| d.model).collect();
            let spi = models
                .first()
                .is_some_and(|m| matches!(m, Model::Qq2drv | Model::Spimotor));
            if let Some((_, first)) = on_link.first() {
                for (i, device) in &on_link[1..] {
                    if device.model != first.model {
                        self.issue(
                            raw_devices[*i].span(),
                            &format!("device[{i}].link"),
                            format!(
                                "link `{name}` already carries a {} device; one model per link",
                                first.model
                            ),
                        );
                    } else if matches!(device.model, Model::Qq2drv | Model::Qsb) {
                        self.issue(
                            raw_devices[*i].span(),
                            &format!("device[{i}].link"),
                            format!(
                                "a {} board cannot share its link; give it its own [[link]]",
                                device.model
                            ),
                        );
                    }
                }
                for (n, (i, device)) in on_link.iter().enumerate() {
                    if on_link[..n].iter().any(|(_, other)| {
                        other.address == device.address && other.model == device.model
                    }) {
                        let span = raw_devices[*i]
                            .get_ref()
                            .address
                            .as_ref()
                            .map_or(raw_devices[*i].span(), Spanned::span);
                        self.issue(span, &format!("device[{i}].address"),
                            format!("address {} is already used on link `{name}`; addresses on one bus must differ", device.address));
                    }
                }
            }
            let Some(kind) = self.required(
                &l.kind,
                &table,
                &key("type"),
                "one of serial, spidev, spi-socket, sim",
            ) else {
                continue;
            };
            let kind_name = kind.get_ref().as_str();
            let path = |me: &mut Self, required: bool| -> Option<PathBuf> {
                match (&l.path, required) {
                    (Some(p), true) if !p.get_ref().is_empty() => Some(PathBuf::from(p.get_ref())),
                    (Some(p), true) => {
                        me.issue(p.span(), &key("path"), "empty path");
                        None
                    }
                    (None, true) => {
                        me.issue(
                            table.clone(),
                            &key("path"),
                            format!("missing; a {kind_name} link needs a path"),
                        );
                        None
                    }
                    (Some(p), false) => {
                        me.issue(p.span(), &key("path"), "a sim link has no path");
                        None
                    }
                    (None, false) => None,
                }
            };
            let forbid = |me: &mut Self, value: &Option<Spanned<i64>>, k: &str, why: &str| {
                if let Some(v) = value {
                    me.issue(v.span(), &key(k), why.to_owned());
                }
            };
            let serial_models_ok = models
                .iter()
                .all(|m| matches!(m, Model::Tmcpack | Model::Qsb));
            let spi_models_ok = models
                .iter()
                .all(|m| matches!(m, Model::Qq2drv | Model::Spimotor));
            let transport = match kind_name {
                "serial" => {
                    if !serial_models_ok {
                        self.issue(kind.span(), &key("type"), "serial links carry tmcpack or qsb boards; qq2drv and spimotor need spidev, spi-socket or sim");
                    }
                    forbid(
                        self,
                        &l.speed_hz,
                        "speed_hz",
                        "speed_hz is for spidev and SPI sim links; a serial link has baud",
                    );
                    forbid(self, &l.mode, "mode", "mode is for spidev links");
                    let baud = self
                        .required(
                            &l.baud,
                            &table,
                            &key("baud"),
                            "the line rate, e.g. 19200 (tmcpack) or 230400 (qsb)",
                        )
                        .and_then(|b| self.int_in(b, &key("baud"), 300..=4_000_000));
                    let path = path(self, true);
                    match (path, baud) {
                        (Some(path), Some(baud)) => Some(Transport::Serial {
                            path,
                            baud: baud as u32,
                        }),
                        _ => None,
                    }
                }
                "spidev" | "spi-socket" => {
                    if !spi_models_ok {
                        self.issue(kind.span(), &key("type"), "SPI links carry qq2drv or spimotor boards; tmcpack and qsb need serial or sim");
                    }
                    forbid(
                        self,
                        &l.baud,
                        "baud",
                        "baud is for serial and serial sim links; SPI links have speed_hz",
                    );
                    let path = path(self, true);
                    if kind_name == "spi-socket" {
                        forbid(
                            self,
                            &l.speed_hz,
                            "speed_hz",
                            "the SPI socket peer sets its own clock",
                        );
                        forbid(
                            self,
                            &l.mode,
                            "mode",
                            "the SPI socket peer sets its own mode",
                        );
                        path.map(|path| Transport::SpiSocket { path })
                    } else {
                        let speed = match &l.speed_hz {
                            Some(s) => self.int_in(s, &key("speed_hz"), 1_000..=50_000_000),
                            None => Some(500_000),
                        };
                        let default_mode = if models.contains(&Model::Qq2drv) {
                            1
                        } else {
                            0
                        };
                        let mode = match &l.mode {
                            Some(m) => self.int_in(m, &key("mode"), 0..=3),
                            None => Some(default_mode),
                        };
                        match (path, speed, mode) {
                            (Some(path), Some(speed), Some(mode)) => Some(Transport::Spidev {
                                path,
                                speed_hz: speed as u32,
                                mode: mode as u8,
                            }),
                            _ => None,
                        }
                    }
                }
                "sim" => {
                    let _ = path(self, false);
                    forbid(self, &l.mode, "mode", "mode is for spidev links");
                    if spi {
                        forbid(
                            self,
                            &l.baud,
                            "baud",
                            "this sim link carries SPI boards: give speed_hz, not baud",
                        );
                        let speed = match &l.speed_hz {
                            Some(s) => self.int_in(s, &key("speed_hz"), 1_000..=50_000_000),
                            None => Some(500_000),
                        };
                        speed.map(|rate| Transport::Sim { rate: rate as u32 })
                    } else {
                        forbid(
                            self,
                            &l.speed_hz,
                            "speed_hz",
                            "this sim link carries serial boards: give baud, not speed_hz",
                        );
                        let default = if models.contains(&Model::Qsb) {
                            230_400
                        } else {
                            19_200
                        };
                        let baud = match &l.baud {
                            Some(b) => self.int_in(b, &key("baud"), 300..=4_000_000),
                            None => Some(default),
                        };
                        baud.map(|rate| Transport::Sim { rate: rate as u32 })
                    }
                }
                other => {
                    self.issue(
                        kind.span(),
                        &key("type"),
                        format!(
                            "unknown link type {other:?}; allowed: serial, spidev, spi-socket, sim"
                        ),
                    );
                    None
                }
            };
            if kind_name != "sim" {
                for (i, _) in &on_link {
                    if let Some(sim) = &raw_devices[*i].get_ref().sim {
                        self.issue(
                            sim.span(),
                            &format!("device[{i}].sim"),
                            format!("sim parameters need a sim link; link `{name}` is {kind_name}"),
                        );
                    }
                }
            }
            if let Some(transport) = transport {
                specs.push(LinkSpec {
                    name: name.clone(),
                    transport,
                    kind: if spi || matches!(kind_name, "spidev" | "spi-socket") {
                        BusKind::Spi
                    } else {
                        BusKind::Stream
                    },
                });
            }
        }
        specs
    }

    fn axis(
        &mut self,
        index: usize,
        raw: &Spanned<RawAxis>,
        devices: &[Option<DeviceSpec>],
        raw_devices: &[Spanned<RawDevice>],
    ) -> Option<AxisConfig> {
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
                    self.issue(
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
                let value = *channel.get_ref();
                if (0..count as i64).contains(&value) {
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
        let (min, max) = (min?, max?);
        if min >= max {
            return None;
        }
        Some(AxisConfig {
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
        })
    }
}
