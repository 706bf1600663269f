//! `[[link]]` tables, checked against the devices on them.

use core::time::Duration;
use std::path::PathBuf;

/// The bit rate of a CAN link without boards and without `bitrate`: a common factory
/// setting (the Trinamic pack's with no jumper set, manual 6.2).
const DEFAULT_CAN_BITRATE: u32 = 250_000;

use motion_drivers::{LinkKind, Model};
use toml::Spanned;

use super::Validator;
use crate::raw::{Int, RawDevice, RawLink};
use crate::{DeviceSpec, IoMode, LinkSpec, Transport};

impl Validator<'_, '_> {
    /// Links, checked against the devices on them (transport fits the model, sharing rules,
    /// addresses distinct, sim tables only on sim links).
    pub(super) fn links(
        &mut self,
        links: &[Option<(String, &Spanned<RawLink>)>],
        devices: &[Option<DeviceSpec>],
        raw_devices: &[Spanned<RawDevice>],
        tick_hz: u32,
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
                .is_some_and(|m| m.link_kind() == LinkKind::Spi);
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
                    } else if !motion_boards::board(device.model).link().shared {
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
                "one of serial, spidev, spi-socket, sim, socketcan, sim-can",
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
            let forbid = |me: &mut Self, value: &Option<Spanned<Int>>, k: &str, why: &str| {
                if let Some(v) = value {
                    me.issue(v.span(), &key(k), why.to_owned());
                }
            };
            let serial_models_ok = models.iter().all(|m| m.link_kind() == LinkKind::Stream);
            let spi_models_ok = models.iter().all(|m| m.link_kind() == LinkKind::Spi);
            let serial = |b: &dyn motion_boards::Board| b.model().link_kind() == LinkKind::Stream;
            let spi_board = |b: &dyn motion_boards::Board| b.model().link_kind() == LinkKind::Spi;
            // The line rate a link of these boards starts at unless given (every board on
            // one link shares it; the first board's, as the models on a link agree).
            let default_rate = models
                .first()
                .map(|m| motion_boards::board(*m).link().default_rate);
            let transport = match kind_name {
                "serial" => {
                    if !serial_models_ok {
                        self.issue(
                            kind.span(),
                            &key("type"),
                            format!(
                                "serial links carry {} boards; {} need spidev, spi-socket or sim",
                                motion_boards::ids(serial, "or"),
                                motion_boards::ids(spi_board, "and"),
                            ),
                        );
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
                        self.issue(
                            kind.span(),
                            &key("type"),
                            format!(
                                "SPI links carry {} boards; {} need serial or sim",
                                motion_boards::ids(spi_board, "or"),
                                motion_boards::ids(serial, "and"),
                            ),
                        );
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
                            None => Some(i64::from(default_rate.unwrap_or(500_000))),
                        };
                        let default_mode = models
                            .first()
                            .map_or(0, |m| motion_boards::board(*m).link().spi_mode);
                        let mode = match &l.mode {
                            Some(m) => self.int_in(m, &key("mode"), 0..=3),
                            None => Some(i64::from(default_mode)),
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
                            None => Some(i64::from(default_rate.unwrap_or(500_000))),
                        };
                        speed.map(|rate| Transport::Sim { rate: rate as u32 })
                    } else {
                        forbid(
                            self,
                            &l.speed_hz,
                            "speed_hz",
                            "this sim link carries serial boards: give baud, not speed_hz",
                        );
                        let baud = match &l.baud {
                            Some(b) => self.int_in(b, &key("baud"), 300..=4_000_000),
                            None => Some(i64::from(default_rate.unwrap_or(19_200))),
                        };
                        baud.map(|rate| Transport::Sim { rate: rate as u32 })
                    }
                }
                "socketcan" | "sim-can" => {
                    let sim = kind_name == "sim-can";
                    let bitrate = self.can_link(index, name, l, sim, &on_link, raw_devices);
                    let interface = if sim {
                        let _ = path(self, false);
                        if let Some(interface) = &l.interface {
                            self.issue(
                                interface.span(),
                                &key("interface"),
                                "a sim-can link is simulated in the server: it has no interface",
                            );
                        }
                        None
                    } else {
                        Some(self.can_interface(index, l, &table))
                    };
                    match (interface, bitrate) {
                        (None, Some(bitrate)) => Some(Transport::SimCan { bitrate }),
                        (Some(Some(interface)), Some(bitrate)) => {
                            Some(Transport::SocketCan { interface, bitrate })
                        }
                        _ => None,
                    }
                }
                other => {
                    self.issue(
                        kind.span(),
                        &key("type"),
                        format!(
                            "unknown link type {other:?}; allowed: serial, spidev, spi-socket, \
                             sim, socketcan, sim-can"
                        ),
                    );
                    None
                }
            };
            if !matches!(kind_name, "socketcan" | "sim-can") {
                if let Some(interface) = &l.interface {
                    self.issue(
                        interface.span(),
                        &key("interface"),
                        "interface is for socketcan links (a CAN network interface such as can0)",
                    );
                }
                if let Some(bitrate) = &l.bitrate {
                    self.issue(
                        bitrate.span(),
                        &key("bitrate"),
                        "bitrate is for socketcan and sim-can links; a serial link has baud, \
                         an SPI link speed_hz",
                    );
                }
            }
            if !matches!(kind_name, "sim" | "sim-can") {
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
            let link_kind = if spi || matches!(kind_name, "spidev" | "spi-socket") {
                LinkKind::Spi
            } else {
                LinkKind::Stream
            };
            let io = self.io_mode(index, l, kind_name, link_kind, tick_hz);
            if let (Some(transport), Some(io)) = (transport, io) {
                specs.push(LinkSpec {
                    name: name.clone(),
                    transport,
                    kind: link_kind,
                    io,
                });
            }
        }
        specs
    }

    /// The checks of a CAN link (`socketcan`, `sim-can` when `sim`): every board on it
    /// speaks CAN, no serial or SPI key, and its `bitrate` (default: the boards' factory
    /// rate) is one the boards can be set to. Returns the bit rate.
    fn can_link(
        &mut self,
        index: usize,
        name: &str,
        l: &RawLink,
        sim: bool,
        on_link: &[(usize, &DeviceSpec)],
        raw_devices: &[Spanned<RawDevice>],
    ) -> Option<u32> {
        let key = |k: &str| format!("link[{index}].{k}");
        let kind_name = if sim { "sim-can" } else { "socketcan" };
        let can_board = |b: &dyn motion_boards::Board| b.can().is_some();
        let mut facts = None;
        for (i, device) in on_link {
            match motion_boards::board(device.model).can() {
                Some(can) => facts = facts.or(Some(can)),
                None => {
                    let span = raw_devices[*i]
                        .get_ref()
                        .link
                        .as_ref()
                        .map_or(raw_devices[*i].span(), Spanned::span);
                    self.issue(
                        span,
                        &format!("device[{i}].link"),
                        format!(
                            "link `{name}` is a {kind_name} link, and a {} board has no CAN \
                             interface; CAN links carry {} boards (give this one a serial, \
                             spidev, spi-socket or sim link)",
                            device.model,
                            motion_boards::ids(can_board, "or"),
                        ),
                    );
                }
            }
        }
        for (k, value, why) in [
            (
                "baud",
                &l.baud,
                "a CAN link has bitrate, not baud (the serial line rate)",
            ),
            (
                "speed_hz",
                &l.speed_hz,
                "a CAN link has bitrate, not speed_hz (the SPI clock)",
            ),
            ("mode", &l.mode, "mode is for spidev links"),
        ] {
            if let Some(v) = value {
                self.issue(v.span(), &key(k), why.to_owned());
            }
        }
        if !sim && let Some(p) = &l.path {
            self.issue(
                p.span(),
                &key("path"),
                "a socketcan link names its network interface with `interface`, not a path",
            );
        }
        let Some(value) = &l.bitrate else {
            return Some(facts.map_or(DEFAULT_CAN_BITRATE, |f| f.default_bitrate));
        };
        let rate = self.int_in(value, &key("bitrate"), 10_000..=1_000_000)? as u32;
        if let Some(facts) = facts
            && !facts.bitrates.contains(&rate)
        {
            let allowed = facts
                .bitrates
                .iter()
                .map(u32::to_string)
                .collect::<Vec<_>>()
                .join(", ");
            self.issue(
                value.span(),
                &key("bitrate"),
                format!(
                    "{rate} bit/s is not a rate the boards on link `{name}` can be set to; \
                     allowed: {allowed} (default {})",
                    facts.default_bitrate
                ),
            );
            return None;
        }
        Some(rate)
    }

    /// `interface` of socketcan link `index`: a network interface name (1 to 15 characters,
    /// no `/` or white space).
    fn can_interface(
        &mut self,
        index: usize,
        l: &RawLink,
        table: &core::ops::Range<usize>,
    ) -> Option<String> {
        let key = format!("link[{index}].interface");
        let value = self.required(
            &l.interface,
            table,
            &key,
            "a socketcan link needs its network interface, e.g. interface = \"can0\"",
        )?;
        let text = value.get_ref();
        let valid = !text.is_empty()
            && text.len() <= 15
            && !text
                .chars()
                .any(|c| c == '/' || c == ':' || c.is_whitespace());
        if !valid {
            self.issue(
                value.span(),
                &key,
                format!(
                    "{text:?} is no network interface name; give 1 to 15 characters without \
                     '/', ':' or spaces, as `ip link` lists them (can0, vcan0)"
                ),
            );
            return None;
        }
        Some(text.clone())
    }

    /// `io` and `io_budget_us` of link `index`: "tick" by default on SPI socket links (a
    /// write there only queues: nothing waits), "thread" on spidev (a transfer holds its
    /// caller until clocked out, and a stuck controller until the kernel's timeout), on
    /// sim links (the simulated board runs where its wire is served: in the tick it would
    /// be counted as the server's work) and on every stream link (which must keep its
    /// thread).
    fn io_mode(
        &mut self,
        index: usize,
        l: &RawLink,
        kind_name: &str,
        link_kind: LinkKind,
        tick_hz: u32,
    ) -> Option<IoMode> {
        let key = |k: &str| format!("link[{index}].{k}");
        let default_tick = link_kind == LinkKind::Spi && kind_name == "spi-socket";
        let tick = match &l.io {
            None => default_tick,
            Some(value) => match value.get_ref().as_str() {
                "thread" => false,
                "tick" if link_kind == LinkKind::Spi => true,
                "tick" => {
                    self.issue(
                        value.span(),
                        &key("io"),
                        "io = \"tick\" is for SPI links, whose transfers end when their bytes \
                         are clocked; a serial link keeps its I/O thread (a board answers when \
                         it answers)",
                    );
                    return None;
                }
                other => {
                    self.issue(
                        value.span(),
                        &key("io"),
                        format!("unknown io {other:?}; allowed: tick, thread"),
                    );
                    return None;
                }
            },
        };
        let period_us = 1_000_000 / i64::from(tick_hz.max(1));
        if !tick {
            if let Some(budget) = &l.io_budget_us {
                self.issue(
                    budget.span(),
                    &key("io_budget_us"),
                    "io_budget_us is the wire time an io = \"tick\" link may take of a tick; \
                     this link has its own I/O thread",
                );
                return None;
            }
            return Some(IoMode::Thread);
        }
        let budget_us = match &l.io_budget_us {
            None => (period_us / 4).max(1),
            Some(value) => self.int_in(value, &key("io_budget_us"), 1..=period_us.max(1))?,
        };
        Some(IoMode::Tick {
            budget: Duration::from_micros(budget_us as u64),
        })
    }
}
