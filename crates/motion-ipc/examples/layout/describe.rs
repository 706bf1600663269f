//! The shared-memory contract as data: every payload's size, alignment, iceoryx2 type name
//! and fields (name, offset, size, type), every enumeration's values, names and texts, the
//! flag bits, the constants and the service name formats.
//!
//! Shared by the `layout` example (which prints it as JSON for the Python package's tests)
//! and by `tests/c_header.rs` (which checks `include/motiond.h` against it).
//!
//! How a change on the Rust side reaches the mirrors: every payload is destructured below
//! WITHOUT `..`, so a field added to (or removed from) a Rust payload stops this module from
//! compiling until the field list here is updated; from then on the emitted description
//! has the new field, and the C header check and the Python mirror check fail, naming the
//! field, until `include/motiond.h` and `python/src/motiond/ipc.py` have it too. Enum
//! values are found by trying every raw value with `TryFrom`, so a new variant shows up
//! without touching this file. Flag bits are associated constants and are listed by hand.
#![allow(dead_code, unsafe_code)]

use core::mem::{align_of, offset_of, size_of, size_of_val};
use std::fmt::Write as _;

use iceoryx2::prelude::ZeroCopySend;
use motion_ipc::*;

/// One field of a payload.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Field {
    /// The Rust field name.
    pub name: &'static str,
    /// Byte offset in the payload.
    pub offset: usize,
    /// Bytes.
    pub size: usize,
    /// `u8`, `u16`, `u32`, `u64`, `i64`, `f64`, a payload's Rust name, or `T[N]`.
    pub ty: String,
}

/// One payload type.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Layout {
    /// The Rust type name (`MotionFrame`).
    pub rust: &'static str,
    /// The iceoryx2 type name (`motiond::MotionFrame`).
    pub type_name: &'static str,
    /// `size_of`.
    pub size: usize,
    /// `align_of`.
    pub align: usize,
    /// Fields in memory order.
    pub fields: Vec<Field>,
}

/// One value of an enumeration or one flag bit.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Variant {
    /// The Rust variant or constant name (`RampPosition`, `MOVING`).
    pub name: String,
    /// Its value.
    pub value: u64,
    /// Its text where the contract has one (`Reason::message`, `CommandKind::name`, …).
    pub text: Option<&'static str>,
}

/// An enumeration (travels as an integer) or a flag set.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Enum {
    /// The Rust type name (`Reason`, `AxisFlags`).
    pub rust: &'static str,
    /// The integer it travels as (`u32`).
    pub repr: &'static str,
    /// `true` for a bit set.
    pub flags: bool,
    /// Values in increasing order.
    pub variants: Vec<Variant>,
}

/// The whole contract.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Contract {
    /// Named constants (`SCHEMA_VERSION`, `MAX_AXES`, `ALL_AXES`, …).
    pub constants: Vec<(&'static str, u64)>,
    /// Service name formats with `%s` for the instance name, by leaf (`frame`).
    pub services: Vec<(&'static str, String)>,
    /// Payloads, each after the payloads it contains.
    pub layouts: Vec<Layout>,
    /// Enumerations and flag sets.
    pub enums: Vec<Enum>,
}

/// The type of a field, as the description spells it.
pub trait Ty {
    /// `u32`, `MotionFrame`, `f64[3]`, …
    fn ty() -> String;
}

macro_rules! ty {
    ($($t:ty => $name:expr),* $(,)?) => {
        $(impl Ty for $t {
            fn ty() -> String {
                $name.to_owned()
            }
        })*
    };
}

ty!(
    u8 => "u8", u16 => "u16", u32 => "u32", u64 => "u64", i64 => "i64", f64 => "f64",
    ClientId => "ClientId", AxisState => "AxisState", SignalState => "SignalState",
    AxisInfo => "AxisInfo", DeviceInfo => "DeviceInfo", SignalInfo => "SignalInfo",
    MachineParam => "MachineParam", LatencySummary => "LatencySummary",
    LinkStats => "LinkStats", AxisWire => "AxisWire", LinkIo => "LinkIo",
);

impl<T: Ty, const N: usize> Ty for [T; N] {
    fn ty() -> String {
        format!("{}[{N}]", T::ty())
    }
}

fn ty_of<T: Ty>(_: &T) -> String {
    T::ty()
}

fn type_name<T: ZeroCopySend>() -> &'static str {
    // SAFETY: `type_name` has no preconditions; it is `unsafe` in iceoryx2 only so that
    // implementing it is a promise about the payload layout.
    unsafe { <T as ZeroCopySend>::type_name() }
}

/// Describes `$ty` from a value of it. The destructuring has no `..`: a field added to the
/// Rust type and not listed here is a compile error.
macro_rules! layout {
    ($ty:ident, $value:expr, [$($field:ident),* $(,)?]) => {{
        let value: $ty = $value;
        let $ty { $($field),* } = value;
        Layout {
            rust: stringify!($ty),
            type_name: type_name::<$ty>(),
            size: size_of::<$ty>(),
            align: align_of::<$ty>(),
            fields: vec![$(Field {
                name: stringify!($field),
                offset: offset_of!($ty, $field),
                size: size_of_val(&$field),
                ty: ty_of(&$field),
            }),*],
        }
    }};
}

fn layouts() -> Vec<Layout> {
    let request = CommandRequest::new(ClientId::NONE, 0, 0, CommandKind::Stop);
    vec![
        layout!(ClientId, ClientId::NONE, [lo, hi]),
        layout!(
            AxisState,
            AxisState::UNKNOWN,
            [
                position,
                velocity,
                target,
                raw_counts,
                last_refresh_tick,
                flags,
                fault,
                mode,
                device_state,
                claimed_by,
                fault_value,
                fault_limit,
            ]
        ),
        layout!(
            SignalState,
            SignalState::UNKNOWN,
            [
                value,
                raw,
                last_refresh_tick,
                flags,
                kind,
                reserved,
                claimed_by
            ]
        ),
        layout!(AxisWire, AxisWire::NONE, [goal_tick, wire_tick, wire_ns]),
        layout!(
            MotionFrame,
            MotionFrame::EMPTY,
            [
                schema_version,
                axis_count,
                tick,
                time_ns,
                publish_ns,
                flags,
                signal_count,
                device_count,
                reserved,
                devices,
                axes,
                signals,
                wire,
            ]
        ),
        layout!(
            CommandRequest,
            request,
            [schema_version, kind, client, sequence, axis, target, values]
        ),
        layout!(
            CommandReply,
            CommandReply::to(&request, Reason::Accepted, 0),
            [schema_version, reason, sequence, tick_applied, axis, kind]
        ),
        layout!(
            AxisInfo,
            AxisInfo::EMPTY,
            [
                name,
                unit,
                device,
                counts_per_unit,
                min,
                max,
                max_velocity,
                max_accel,
                capabilities,
                channel,
                device_index,
                following_error,
                overspeed_factor,
                home_max_travel,
                estop,
                reserved,
            ]
        ),
        layout!(
            DeviceInfo,
            DeviceInfo::EMPTY,
            [name, link, firmware, model, address, axis_count, state]
        ),
        layout!(
            SignalInfo,
            SignalInfo::EMPTY,
            [
                name,
                unit,
                device,
                scale,
                offset,
                full_scale,
                kind,
                flags,
                device_index,
                pin,
                reserved,
            ]
        ),
        layout!(
            ServerInfo,
            ServerInfo::EMPTY,
            [
                schema_version,
                axis_count,
                device_count,
                tick_hz,
                command_timeout_ms,
                max_clients,
                server_pid,
                signal_count,
                name,
                start_time_ns,
                axes,
                devices,
                signals,
            ]
        ),
        layout!(
            MachineParam,
            MachineParam::EMPTY,
            [key, value, owner_index, owner_kind, from_config, reserved]
        ),
        layout!(
            MachineParams,
            MachineParams::EMPTY,
            [schema_version, count, truncated, reserved, entries]
        ),
        layout!(
            LatencySummary,
            LatencySummary::default(),
            [samples, p50_ns, p99_ns, p999_ns, max_ns]
        ),
        layout!(
            LinkStats,
            LinkStats::EMPTY,
            [
                name, bytes_in, bytes_out, frames, errors, reconnects, up, reserved
            ]
        ),
        layout!(
            LinkIo,
            LinkIo::EMPTY,
            [last_write_ns, last_read_ns, transactions, reads]
        ),
        layout!(
            ServerStats,
            ServerStats::EMPTY,
            [
                schema_version,
                link_count,
                tick,
                time_ns,
                wakeup,
                work,
                overruns,
                max_consecutive_overruns,
                commands,
                rejected,
                clients,
                rt_flags,
                links,
                faults,
                frames_lost,
                full_services,
                full_events,
                publish_failures,
                replies_lost,
                events_dropped,
                link_io,
                nodes_cleaned,
            ]
        ),
    ]
}

/// Every value of an enumeration found by trying each raw value in `0..=max`.
fn scan<T: core::fmt::Debug>(
    rust: &'static str,
    repr: &'static str,
    max: u64,
    parse: impl Fn(u64) -> Option<T>,
    text: impl Fn(&T) -> Option<&'static str>,
) -> Enum {
    let variants = (0..=max)
        .filter_map(|raw| {
            parse(raw).map(|value| Variant {
                name: format!("{value:?}"),
                value: raw,
                text: text(&value),
            })
        })
        .collect();
    Enum {
        rust,
        repr,
        flags: false,
        variants,
    }
}

fn flags(rust: &'static str, repr: &'static str, bits: &[(&str, u64)]) -> Enum {
    Enum {
        rust,
        repr,
        flags: true,
        variants: bits
            .iter()
            .map(|&(name, value)| Variant {
                name: name.to_owned(),
                value,
                text: None,
            })
            .collect(),
    }
}

/// Raw values tried per enumeration: far beyond any value in use, small enough to be quick.
const SCAN: u64 = 4096;

fn enums() -> Vec<Enum> {
    let u8_of = |raw: u64| u8::try_from(raw).ok();
    let u16_of = |raw: u64| u16::try_from(raw).ok();
    let u32_of = |raw: u64| u32::try_from(raw).ok();
    vec![
        scan(
            "CommandKind",
            "u32",
            SCAN,
            |raw| u32_of(raw).and_then(|v| CommandKind::try_from(v).ok()),
            |kind| Some(kind.name()),
        ),
        scan(
            "Reason",
            "u32",
            SCAN,
            |raw| u32_of(raw).and_then(|v| Reason::try_from(v).ok()),
            |reason| Some(reason.message()),
        ),
        scan(
            "Target",
            "u32",
            SCAN,
            |raw| u32_of(raw).and_then(|v| Target::try_from(v).ok()),
            |_| None,
        ),
        scan(
            "DeviceState",
            "u8",
            u64::from(u8::MAX),
            |raw| u8_of(raw).and_then(|v| DeviceState::try_from(v).ok()),
            |state| Some(state.name()),
        ),
        scan(
            "AxisMode",
            "u8",
            u64::from(u8::MAX),
            |raw| u8_of(raw).and_then(|v| AxisMode::try_from(v).ok()),
            |_| None,
        ),
        scan(
            "FaultCode",
            "u16",
            SCAN,
            |raw| u16_of(raw).and_then(|v| FaultCode::try_from(v).ok()),
            |code| Some(code.name()),
        ),
        scan(
            "SignalKind",
            "u8",
            u64::from(u8::MAX),
            |raw| u8_of(raw).and_then(|v| SignalKind::try_from(v).ok()),
            |kind| Some(kind.name()),
        ),
        scan(
            "EstopCategory",
            "u32",
            SCAN,
            |raw| u32_of(raw).and_then(|v| EstopCategory::try_from(v).ok()),
            |category| Some(category.name()),
        ),
        scan(
            "DeviceModel",
            "u32",
            SCAN,
            |raw| u32_of(raw).and_then(|v| DeviceModel::try_from(v).ok()),
            |model| Some(model.id()),
        ),
        scan(
            "ParamOwner",
            "u8",
            u64::from(u8::MAX),
            |raw| u8_of(raw).and_then(|v| ParamOwner::try_from(v).ok()),
            |_| None,
        ),
        flags(
            "AxisFlags",
            "u32",
            &[
                ("MOVING", AxisFlags::MOVING.0.into()),
                ("HOMED", AxisFlags::HOMED.0.into()),
                ("AT_LIMIT", AxisFlags::AT_LIMIT.0.into()),
                ("STALE", AxisFlags::STALE.0.into()),
                ("FAULT", AxisFlags::FAULT.0.into()),
                ("CLAIMED", AxisFlags::CLAIMED.0.into()),
                ("ARRIVED", AxisFlags::ARRIVED.0.into()),
                ("ESTOPPED", AxisFlags::ESTOPPED.0.into()),
                ("DEADMAN_EXPIRED", AxisFlags::DEADMAN_EXPIRED.0.into()),
            ],
        ),
        flags(
            "FrameFlags",
            "u32",
            &[
                ("ESTOP_LATCHED", FrameFlags::ESTOP_LATCHED.0.into()),
                ("OVERRUN", FrameFlags::OVERRUN.0.into()),
                ("SHUTTING_DOWN", FrameFlags::SHUTTING_DOWN.0.into()),
            ],
        ),
        flags(
            "SignalFlags",
            "u32",
            &[
                ("STALE", SignalFlags::STALE.0.into()),
                ("CLAIMED", SignalFlags::CLAIMED.0.into()),
                ("SAFE_STATE", SignalFlags::SAFE_STATE.0.into()),
                ("PENDING", SignalFlags::PENDING.0.into()),
            ],
        ),
        flags(
            "SignalInfoFlags",
            "u8",
            &[
                ("INVERT", SignalInfoFlags::INVERT.0.into()),
                ("HAS_SAFE_STATE", SignalInfoFlags::HAS_SAFE_STATE.0.into()),
                ("SAFE_ON", SignalInfoFlags::SAFE_ON.0.into()),
            ],
        ),
        flags(
            "RtFlags",
            "u32",
            &[
                ("FIFO", ServerStats::RT_FIFO.into()),
                ("LOCKED", ServerStats::RT_LOCKED.into()),
                ("PINNED", ServerStats::RT_PINNED.into()),
                ("DMA_LATENCY", ServerStats::RT_DMA_LATENCY.into()),
            ],
        ),
        flags(
            "FullServices",
            "u32",
            &[
                ("FRAME", ServerStats::FULL_FRAME.into()),
                ("TICK", ServerStats::FULL_TICK.into()),
                ("COMMAND", ServerStats::FULL_COMMAND.into()),
                ("INFO", ServerStats::FULL_INFO.into()),
                ("STATS", ServerStats::FULL_STATS.into()),
                ("PARAMS", ServerStats::FULL_PARAMS.into()),
                ("ESTOP", ServerStats::FULL_ESTOP.into()),
            ],
        ),
    ]
}

fn services() -> Vec<(&'static str, String)> {
    let names = ServiceNames::new("%s");
    vec![
        ("frame", names.frame()),
        ("tick", names.tick()),
        ("command", names.command()),
        ("info", names.info()),
        ("stats", names.stats()),
        ("params", names.params()),
        ("estop", names.estop()),
        ("server_node", names.server_node()),
    ]
}

fn to_u64(value: usize) -> u64 {
    u64::try_from(value).unwrap_or(u64::MAX)
}

/// The contract of this build of `motion-ipc`.
pub fn contract() -> Contract {
    Contract {
        constants: vec![
            ("SCHEMA_VERSION", SCHEMA_VERSION.into()),
            ("MAX_AXES", to_u64(MAX_AXES)),
            ("MAX_DEVICES", to_u64(MAX_DEVICES)),
            ("MAX_LINKS", to_u64(MAX_LINKS)),
            ("MAX_SIGNALS", to_u64(MAX_SIGNALS)),
            ("MAX_PARAMS", to_u64(MAX_PARAMS)),
            ("NAME_LEN", to_u64(NAME_LEN)),
            ("UNIT_LEN", to_u64(UNIT_LEN)),
            ("PARAM_TEXT_LEN", to_u64(PARAM_TEXT_LEN)),
            ("ALL_AXES", CommandRequest::ALL_AXES.into()),
        ],
        services: services(),
        layouts: layouts(),
        enums: enums(),
    }
}

/// `text` as a JSON string.
pub fn json_string(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

impl Contract {
    /// The contract as a JSON document (one object; stable key order).
    pub fn to_json(&self) -> String {
        let mut out = String::from("{\n  \"constants\": {");
        let constants: Vec<String> = self
            .constants
            .iter()
            .map(|(name, value)| format!("\n    {}: {value}", json_string(name)))
            .collect();
        out.push_str(&constants.join(","));
        out.push_str("\n  },\n  \"services\": {");
        let services: Vec<String> = self
            .services
            .iter()
            .map(|(leaf, format)| format!("\n    {}: {}", json_string(leaf), json_string(format)))
            .collect();
        out.push_str(&services.join(","));
        out.push_str("\n  },\n  \"layouts\": [");
        let layouts: Vec<String> = self.layouts.iter().map(layout_json).collect();
        out.push_str(&layouts.join(","));
        out.push_str("\n  ],\n  \"enums\": [");
        let enums: Vec<String> = self.enums.iter().map(enum_json).collect();
        out.push_str(&enums.join(","));
        out.push_str("\n  ]\n}\n");
        out
    }
}

fn layout_json(layout: &Layout) -> String {
    let fields: Vec<String> = layout
        .fields
        .iter()
        .map(|field| {
            format!(
                "\n        {{\"name\": {}, \"offset\": {}, \"size\": {}, \"type\": {}}}",
                json_string(field.name),
                field.offset,
                field.size,
                json_string(&field.ty)
            )
        })
        .collect();
    format!(
        "\n    {{\n      \"rust\": {},\n      \"type_name\": {},\n      \"size\": {},\n      \
         \"align\": {},\n      \"fields\": [{}\n      ]\n    }}",
        json_string(layout.rust),
        json_string(layout.type_name),
        layout.size,
        layout.align,
        fields.join(",")
    )
}

fn enum_json(item: &Enum) -> String {
    let variants: Vec<String> = item
        .variants
        .iter()
        .map(|variant| {
            let text = variant.text.map_or_else(|| "null".to_owned(), json_string);
            format!(
                "\n        {{\"name\": {}, \"value\": {}, \"text\": {text}}}",
                json_string(&variant.name),
                variant.value
            )
        })
        .collect();
    format!(
        "\n    {{\n      \"rust\": {},\n      \"repr\": {},\n      \"flags\": {},\n      \
         \"variants\": [{}\n      ]\n    }}",
        json_string(item.rust),
        json_string(item.repr),
        item.flags,
        variants.join(",")
    )
}
