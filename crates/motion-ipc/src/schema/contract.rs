//! [`contract`]: the one list of every payload, enumeration, flag set, constant and service
//! of the shared-memory contract.

use super::{Constant, Contract, Enum, Scalar, Schema, Service, Struct, Variant};
use crate::{
    AxisFlags, AxisInfo, AxisMode, AxisState, AxisWire, ClientId, CommandKind, CommandReply,
    CommandRequest, CommissionWhat, DeviceInfo, DeviceModel, DeviceState, EstopCategory, FaultCode,
    FrameFlags, GroupAbort, GroupInfo, GroupMotion, GroupPath, GroupState, LatencySummary, LinkIo,
    LinkStats, MAX_AXES, MAX_DEVICES, MAX_GROUP_AXES, MAX_GROUPS, MAX_LINKS, MAX_PARAMS,
    MAX_PATH_POINTS, MAX_SIGNALS, MODEL_ID_LEN, MachineParam, MachineParams, MotionFrame, NAME_LEN,
    PARAM_TEXT_LEN, PATH_VALUES, ParamOwner, PathFlags, PathKind, Reason, SCHEMA_VERSION,
    ServerInfo, ServerStats, ServiceNames, Setpoint, SetpointFlags, SignalFlags, SignalInfo,
    SignalInfoFlags, SignalKind, SignalState, StreamFlags, StreamMode, StreamState, Target,
    UNIT_LEN,
};

/// The contract of this build of `motion-ipc`.
pub fn contract() -> Contract {
    Contract {
        constants: constants(),
        services: services(),
        structs: structs(),
        enums: enums(),
    }
}

/// Every payload, each after the payloads it contains. A new payload is declared with
/// `payload!` and listed here.
fn structs() -> Vec<&'static Struct> {
    vec![
        &ClientId::SCHEMA,
        &AxisState::SCHEMA,
        &SignalState::SCHEMA,
        &AxisWire::SCHEMA,
        &GroupState::SCHEMA,
        &MotionFrame::SCHEMA,
        &CommandRequest::SCHEMA,
        &CommandReply::SCHEMA,
        &AxisInfo::SCHEMA,
        &DeviceInfo::SCHEMA,
        &SignalInfo::SCHEMA,
        &GroupInfo::SCHEMA,
        &ServerInfo::SCHEMA,
        &GroupPath::SCHEMA,
        &Setpoint::SCHEMA,
        &MachineParam::SCHEMA,
        &MachineParams::SCHEMA,
        &LatencySummary::SCHEMA,
        &LinkStats::SCHEMA,
        &LinkIo::SCHEMA,
        &ServerStats::SCHEMA,
    ]
}

fn constant(name: &'static str, value: impl TryInto<u64>, doc: &'static str) -> Constant {
    Constant {
        name,
        value: value.try_into().unwrap_or(u64::MAX),
        doc,
    }
}

fn constants() -> Vec<Constant> {
    vec![
        constant(
            "SCHEMA_VERSION",
            SCHEMA_VERSION,
            "Version of the contract; every payload carries it.",
        ),
        constant(
            "MAX_AXES",
            MAX_AXES,
            "Capacity of the axis arrays of the frame and the server info.",
        ),
        constant(
            "MAX_DEVICES",
            MAX_DEVICES,
            "Capacity of the device arrays of the frame and the server info.",
        ),
        constant(
            "MAX_LINKS",
            MAX_LINKS,
            "Capacity of the link arrays of the server stats.",
        ),
        constant(
            "MAX_SIGNALS",
            MAX_SIGNALS,
            "Capacity of the signal arrays of the frame and the server info.",
        ),
        constant(
            "MAX_PARAMS",
            MAX_PARAMS,
            "Capacity of the machine parameter table.",
        ),
        constant(
            "NAME_LEN",
            NAME_LEN,
            "Bytes of a name field (UTF-8, zero padded).",
        ),
        constant(
            "UNIT_LEN",
            UNIT_LEN,
            "Bytes of a unit or pin field (UTF-8, zero padded).",
        ),
        constant(
            "MODEL_ID_LEN",
            MODEL_ID_LEN,
            "Bytes of a model id field (UTF-8, zero padded).",
        ),
        constant(
            "MAX_GROUPS",
            MAX_GROUPS,
            "Capacity of the group arrays of the frame and the server info.",
        ),
        constant("MAX_GROUP_AXES", MAX_GROUP_AXES, "Axes one group may hold."),
        constant(
            "MAX_PATH_POINTS",
            MAX_PATH_POINTS,
            "Points one group path may hold.",
        ),
        constant(
            "PATH_VALUES",
            PATH_VALUES,
            "Values of one quantity of a group path: point i, axis j at i * MAX_GROUP_AXES + j.",
        ),
        constant(
            "PARAM_TEXT_LEN",
            PARAM_TEXT_LEN,
            "Bytes of a parameter key or value text.",
        ),
        constant(
            "ALL_AXES",
            CommandRequest::ALL_AXES,
            "`CommandRequest.axis` addressing every axis (stop, e-stop, reset, off).",
        ),
    ]
}

fn services() -> Vec<Service> {
    let names = ServiceNames::new("%s");
    let service = |leaf, format, doc| Service { leaf, format, doc };
    vec![
        service(
            "frame",
            names.frame(),
            "publish-subscribe, history 1: `MotionFrame`, every tick",
        ),
        service("tick", names.tick(), "event: notified after every frame"),
        service(
            "command",
            names.command(),
            "request-response: `CommandRequest` -> `CommandReply`",
        ),
        service(
            "info",
            names.info(),
            "publish-subscribe, history 1: `ServerInfo`",
        ),
        service(
            "stats",
            names.stats(),
            "publish-subscribe, history 1: `ServerStats`, about 1 Hz",
        ),
        service(
            "params",
            names.params(),
            "publish-subscribe, history 1: `MachineParams`",
        ),
        service(
            "paths",
            names.paths(),
            "publish-subscribe: `GroupPath`, paths for groups, run by a RUN command",
        ),
        service(
            "setpoints",
            names.setpoints(),
            "publish-subscribe: `Setpoint`, streamed setpoints of the groups",
        ),
        service(
            "estop",
            names.estop(),
            "event: any notification latches the e-stop",
        ),
        service(
            "server_node",
            names.server_node(),
            "the iceoryx2 node name of the instance's server",
        ),
    ]
}

/// Raw values tried per enumeration: far beyond any value in use, small enough to be quick.
const SCAN: u64 = 4096;

/// An enumeration whose values are found by trying every raw value in `0..SCAN` with
/// `parse` (its `TryFrom`): a new variant shows up without touching this file.
fn scan<T: core::fmt::Debug>(
    name: &'static str,
    repr: Scalar,
    doc: &'static str,
    parse: impl Fn(u64) -> Option<T>,
    text: impl Fn(&T) -> Option<&'static str>,
) -> Enum {
    scan_named(name, repr, doc, parse, |value| format!("{value:?}"), text)
}

/// [`scan`] with the variant names given by `variant_name` (`CamelCase`, as Rust names an
/// enum variant) rather than by `Debug`.
fn scan_named<T>(
    name: &'static str,
    repr: Scalar,
    doc: &'static str,
    parse: impl Fn(u64) -> Option<T>,
    variant_name: impl Fn(&T) -> String,
    text: impl Fn(&T) -> Option<&'static str>,
) -> Enum {
    let variants = (0..SCAN)
        .filter_map(|raw| {
            parse(raw).map(|value| Variant {
                name: variant_name(&value),
                value: raw,
                text: text(&value),
            })
        })
        .collect();
    Enum {
        name,
        repr,
        flags: false,
        doc,
        variants,
    }
}

/// A flag set: its bits by constant name.
fn flags(name: &'static str, repr: Scalar, doc: &'static str, bits: &[(&str, u64)]) -> Enum {
    Enum {
        name,
        repr,
        flags: true,
        doc,
        variants: bits
            .iter()
            .map(|&(bit, value)| Variant {
                name: bit.to_owned(),
                value,
                text: None,
            })
            .collect(),
    }
}

/// `qq2drv` → `Qq2drv`: a config id as an enum variant name.
fn capitalized(id: &str) -> String {
    let mut chars = id.chars();
    chars.next().map_or_else(String::new, |first| {
        first.to_uppercase().chain(chars).collect()
    })
}

fn raw<T: TryFrom<u64>>(raw: u64) -> Option<T> {
    T::try_from(raw).ok()
}

/// Every enumeration, then every flag set.
fn enums() -> Vec<Enum> {
    let mut all = vec![
        scan(
            "CommandKind",
            Scalar::U32,
            "What a request asks for (`CommandRequest.kind`). `values` per kind; 0.0 in a \
             velocity or acceleration slot means the axis's configured maximum:\n\
             STOP -; POWER [power -1..1]; POSITION [position]; VELOCITY [velocity];\n\
             RAMP_POSITION [position, max velocity, acceleration];\n\
             RAMP_VELOCITY [velocity, acceleration]; HOME [search velocity];\n\
             SET_POSITION [position]; SET_OUTPUT [0.0 or 1.0] (`axis` = signal index, \
             `target` = SIGNAL); CLAIM, RELEASE, E_STOP, RESET, OFF -;\n\
             with `target` = GROUP (`axis` = group index): CLAIM, RELEASE, STOP, RUN [path id], \
             HOLD, RESUME, FEED [0.0..1.5], CANCEL, STREAM [stream mode];\n\
             with `target` = DEVICE (`axis` = device index): COMMISSION [what, new value].",
            |value| raw::<u32>(value).and_then(|v| CommandKind::try_from(v).ok()),
            |kind| Some(kind.name()),
        ),
        scan(
            "Reason",
            Scalar::U32,
            "Why a request was refused (`CommandReply.reason`); 0 = accepted. The text is \
             the server's one-line explanation.",
            |value| raw::<u32>(value).and_then(|v| Reason::try_from(v).ok()),
            |reason| Some(reason.message()),
        ),
        scan(
            "Target",
            Scalar::U32,
            "What `CommandRequest.axis` indexes (`CommandRequest.target`).",
            |value| raw::<u32>(value).and_then(|v| Target::try_from(v).ok()),
            |_| None,
        ),
        scan(
            "DeviceState",
            Scalar::U8,
            "Where a board is in its life (`MotionFrame.devices`, \
             `AxisState.device_state`, `DeviceInfo.state`).",
            |value| raw::<u8>(value).and_then(|v| DeviceState::try_from(v).ok()),
            |state| Some(state.name()),
        ),
        scan(
            "AxisMode",
            Scalar::U8,
            "What an axis is doing (`AxisState.mode`).",
            |value| raw::<u8>(value).and_then(|v| AxisMode::try_from(v).ok()),
            |_| None,
        ),
        scan(
            "FaultCode",
            Scalar::U16,
            "Why an axis is faulted (`AxisState.fault`); 0 = no fault.",
            |value| raw::<u16>(value).and_then(|v| FaultCode::try_from(v).ok()),
            |code| Some(code.name()),
        ),
        scan(
            "SignalKind",
            Scalar::U8,
            "What a signal is (`SignalState.kind`, `SignalInfo.kind`); the text is its \
             config name.",
            |value| raw::<u8>(value).and_then(|v| SignalKind::try_from(v).ok()),
            |kind| Some(kind.name()),
        ),
        scan(
            "EstopCategory",
            Scalar::U32,
            "What an e-stop (and a fault) does to an axis, IEC 60204-1 stop categories \
             (`AxisInfo.estop`); the text is its config name.",
            |value| raw::<u32>(value).and_then(|v| EstopCategory::try_from(v).ok()),
            |category| Some(category.name()),
        ),
        scan_named(
            "DeviceModel",
            Scalar::U32,
            "The built-in board models (`DeviceInfo.model`); the text is its config id. \
             Any board's id travels in `DeviceInfo.model_id`.",
            |value| raw::<u32>(value).and_then(|v| DeviceModel::try_from(v).ok()),
            |model| capitalized(model.id()),
            |model| Some(model.id()),
        ),
        scan(
            "GroupMotion",
            Scalar::U8,
            "Where a group's motion is (`GroupState.motion`).",
            |value| raw::<u8>(value).and_then(|v| GroupMotion::try_from(v).ok()),
            |motion| Some(motion.name()),
        ),
        scan(
            "GroupAbort",
            Scalar::U8,
            "Why a group's motion ended early (`GroupState.abort`); 0 = not aborted.",
            |value| raw::<u8>(value).and_then(|v| GroupAbort::try_from(v).ok()),
            |abort| Some(abort.name()),
        ),
        scan(
            "StreamState",
            Scalar::U8,
            "Where a group's setpoint stream is (`GroupState.stream`).",
            |value| raw::<u8>(value).and_then(|v| StreamState::try_from(v).ok()),
            |state| Some(state.name()),
        ),
        scan(
            "CommissionWhat",
            Scalar::U32,
            "What a COMMISSION request changes (`values[0]`; `values[1]` is the new address \
             or baud rate).",
            |value| raw::<u32>(value).and_then(|v| CommissionWhat::try_from(v).ok()),
            |what| Some(what.name()),
        ),
        scan(
            "StreamMode",
            Scalar::U32,
            "What a group's streamed setpoints are (`Setpoint.mode`, `GroupState.stream_mode`, \
             `values[0]` of a STREAM command).",
            |value| raw::<u32>(value).and_then(|v| StreamMode::try_from(v).ok()),
            |mode| Some(mode.name()),
        ),
        scan(
            "PathKind",
            Scalar::U32,
            "What a group path is (`GroupPath.kind`, `GroupState.kind`).",
            |value| raw::<u32>(value).and_then(|v| PathKind::try_from(v).ok()),
            |kind| Some(kind.name()),
        ),
        scan(
            "ParamOwner",
            Scalar::U8,
            "What a machine parameter belongs to (`MachineParam.owner_kind`).",
            |value| raw::<u8>(value).and_then(|v| ParamOwner::try_from(v).ok()),
            |_| None,
        ),
    ];
    all.extend(flag_sets());
    all
}

/// The flag sets (`flag_set!`: each lists its own bits).
fn flag_sets() -> Vec<Enum> {
    vec![
        flags(
            "AxisFlags",
            Scalar::U32,
            "Bits of `AxisState.flags`.",
            &AxisFlags::BITS,
        ),
        flags(
            "FrameFlags",
            Scalar::U32,
            "Bits of `MotionFrame.flags`.",
            &FrameFlags::BITS,
        ),
        flags(
            "SignalFlags",
            Scalar::U32,
            "Bits of `SignalState.flags`.",
            &SignalFlags::BITS,
        ),
        flags(
            "PathFlags",
            Scalar::U32,
            "Bits of `GroupPath.flags`.",
            &PathFlags::BITS,
        ),
        flags(
            "StreamFlags",
            Scalar::U8,
            "Bits of `GroupState.stream_flags`.",
            &StreamFlags::BITS,
        ),
        flags(
            "SetpointFlags",
            Scalar::U32,
            "Bits of `Setpoint.flags`.",
            &SetpointFlags::BITS,
        ),
        flags(
            "SignalInfoFlags",
            Scalar::U8,
            "Bits of `SignalInfo.flags`.",
            &SignalInfoFlags::BITS,
        ),
        flags(
            "RtFlags",
            Scalar::U32,
            "Bits of `ServerStats.rt_flags`.",
            &[
                ("FIFO", ServerStats::RT_FIFO.into()),
                ("LOCKED", ServerStats::RT_LOCKED.into()),
                ("PINNED", ServerStats::RT_PINNED.into()),
                ("DMA_LATENCY", ServerStats::RT_DMA_LATENCY.into()),
            ],
        ),
        flags(
            "FullServices",
            Scalar::U32,
            "Bits of `ServerStats.full_services`: services whose port slots are all taken.",
            &[
                ("FRAME", ServerStats::FULL_FRAME.into()),
                ("TICK", ServerStats::FULL_TICK.into()),
                ("COMMAND", ServerStats::FULL_COMMAND.into()),
                ("INFO", ServerStats::FULL_INFO.into()),
                ("STATS", ServerStats::FULL_STATS.into()),
                ("PARAMS", ServerStats::FULL_PARAMS.into()),
                ("ESTOP", ServerStats::FULL_ESTOP.into()),
                ("PATHS", ServerStats::FULL_PATHS.into()),
                ("SETPOINTS", ServerStats::FULL_SETPOINTS.into()),
            ],
        ),
    ]
}

#[cfg(test)]
mod tests {
    use super::super::Type;
    use super::*;

    /// Alignment of a field type, from the description.
    fn align_of(ty: &Type) -> usize {
        match ty {
            Type::Scalar(scalar) => scalar.size(),
            Type::Struct { schema } => schema.align,
            Type::Array { element, .. } => align_of(element),
        }
    }

    /// Size of a field type, from the description.
    fn size_of(ty: &Type) -> usize {
        match ty {
            Type::Scalar(scalar) => scalar.size(),
            Type::Struct { schema } => schema.size,
            Type::Array { element, len, .. } => size_of(element) * len,
        }
    }

    #[test]
    fn every_description_matches_the_compilers_layout() {
        for payload in contract().structs {
            let name = payload.name;
            assert!(!payload.fields.is_empty(), "{name} has no fields");
            assert_eq!(
                payload.size % payload.align,
                0,
                "{name}: size not a multiple of align"
            );
            let mut end = 0;
            let mut align = 1;
            for field in payload.fields {
                let what = format!("{name}.{}", field.name);
                assert_eq!(field.size, size_of(&field.ty), "{what}: size vs type");
                assert!(field.offset >= end, "{what} overlaps the field before");
                assert_eq!(field.offset % align_of(&field.ty), 0, "{what} misaligned");
                assert!(!field.docs.is_empty(), "{what} has no docs");
                end = field.offset + field.size;
                align = align.max(align_of(&field.ty));
            }
            assert!(end <= payload.size, "{name}: fields run past its size");
            assert_eq!(payload.align, align, "{name}: align vs its fields'");
            assert!(payload.type_name.ends_with(name), "{name}: type name");
        }
    }

    #[test]
    fn known_layouts_come_out_of_the_description() {
        let frame = &MotionFrame::SCHEMA;
        assert_eq!(
            (frame.size, frame.align),
            (size_of_val(&MotionFrame::EMPTY), 8)
        );
        let axes = frame.field("axes").expect("MotionFrame.axes");
        assert_eq!(axes.offset, core::mem::offset_of!(MotionFrame, axes));
        assert_eq!(
            axes.ty,
            Type::Array {
                element: &Type::Struct {
                    schema: &AxisState::SCHEMA
                },
                len: MAX_AXES,
                len_name: Some("MAX_AXES"),
            }
        );
        let values = CommandRequest::SCHEMA.field("values").expect("values");
        assert_eq!(values.ty.spelling(), "f64[3]");
        assert!(matches!(values.ty, Type::Array { len_name: None, .. }));
    }

    #[test]
    fn array_lengths_named_by_constants_have_their_values() {
        let contract = contract();
        for payload in &contract.structs {
            for field in payload.fields {
                if let Type::Array {
                    len,
                    len_name: Some(constant),
                    ..
                } = field.ty
                {
                    let value = contract.constant(constant).map(|c| c.value);
                    assert_eq!(value, Some(len as u64), "{}.{}", payload.name, field.name);
                }
            }
        }
    }

    #[test]
    fn nested_payloads_come_first_and_every_payload_is_listed_once() {
        let structs = structs();
        for (index, payload) in structs.iter().enumerate() {
            let earlier = &structs[..index];
            assert!(
                !earlier.iter().any(|s| s.name == payload.name),
                "{} twice",
                payload.name
            );
            for field in payload.fields {
                let mut ty = &field.ty;
                while let Type::Array { element, .. } = ty {
                    ty = element;
                }
                if let Type::Struct { schema } = ty {
                    assert!(
                        earlier.iter().any(|s| s.name == schema.name),
                        "{} must come after {}",
                        payload.name,
                        schema.name
                    );
                }
            }
        }
    }

    #[test]
    fn enumerations_have_their_values() {
        let enums = enums();
        let reason = enums.iter().find(|e| e.name == "Reason").expect("Reason");
        assert_eq!(reason.variants.len(), Reason::ALL.len());
        assert_eq!(reason.variants[6].name, "OutOfRange");
        assert_eq!(reason.variants[6].text, Some(Reason::OutOfRange.message()));
        let kinds = enums
            .iter()
            .find(|e| e.name == "CommandKind")
            .expect("kinds");
        assert_eq!(kinds.variants.len(), CommandKind::ALL.len());
        let models = enums
            .iter()
            .find(|e| e.name == "DeviceModel")
            .expect("models");
        let first = &models.variants[0];
        assert_eq!((first.name.as_str(), first.value), ("Qq2drv", 1));
        assert_eq!(first.text, Some(DeviceModel::QQ2DRV.id()));
        let flags = enums
            .iter()
            .find(|e| e.name == "AxisFlags")
            .expect("AxisFlags");
        assert_eq!(flags.variants.len(), AxisFlags::NAMED.len());
        for item in &enums {
            assert!(!item.variants.is_empty(), "{} has no values", item.name);
            assert!(item.variants.windows(2).all(|w| w[0].value < w[1].value));
        }
    }
}
