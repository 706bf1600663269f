//! The field table of the wire codec: every payload that crosses the network, its fields in
//! C order, the structs and arrays inside it, and the sizes it was written against. The only
//! file to follow a payload change (and the one a schema generator will write): a field
//! added to a type and not listed here does not compile, and a size change trips the pins.

use core::mem::{offset_of, size_of};

use motion_ipc::{
    AxisInfo, AxisState, AxisWire, ClientId, CommandReply, CommandRequest, DeviceInfo,
    LatencySummary, LinkIo, LinkStats, MachineParam, MachineParams, MotionFrame, ServerInfo,
    ServerStats, SignalInfo, SignalState,
};

use super::{Field, Payload, Reader, Writer, sealed};

// The layout these encoders were written against (`motion-ipc`'s `tests/layout.rs` pins
// every offset). A change of a payload must be followed here: add the new field below.
const _: () = assert!(size_of::<MotionFrame>() == 16464);
const _: () = assert!(size_of::<ServerInfo>() == 32328);
const _: () = assert!(size_of::<ServerStats>() == 1992);
const _: () = assert!(size_of::<MachineParams>() == 180_240);
const _: () = assert!(size_of::<CommandRequest>() == 64);
const _: () = assert!(size_of::<CommandReply>() == 32);

// The payloads that travel over the network.
payload!(
    MotionFrame,
    ServerInfo,
    ServerStats,
    MachineParams,
    CommandRequest,
    CommandReply
);

// Arrays inside the payloads.
array_of!(
    f64,
    AxisState,
    SignalState,
    AxisInfo,
    DeviceInfo,
    SignalInfo,
    LinkStats,
    MachineParam,
    AxisWire,
    LinkIo
);

// Every struct, each field at its `offset_of!`.
record!(ClientId { lo, hi });
record!(AxisState {
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
});
record!(SignalState {
    value,
    raw,
    last_refresh_tick,
    flags,
    kind,
    reserved,
    claimed_by,
});
record!(MotionFrame {
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
});
record!(AxisWire {
    goal_tick,
    wire_tick,
    wire_ns,
});
record!(LinkIo {
    last_write_ns,
    last_read_ns,
    transactions,
    reads,
});
record!(CommandRequest {
    schema_version,
    kind,
    client,
    sequence,
    axis,
    target,
    values,
});
record!(CommandReply {
    schema_version,
    reason,
    sequence,
    tick_applied,
    axis,
    kind,
});
record!(AxisInfo {
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
});
record!(DeviceInfo {
    name,
    link,
    firmware,
    model,
    address,
    axis_count,
    state,
});
record!(SignalInfo {
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
});
record!(ServerInfo {
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
});
record!(MachineParam {
    key,
    value,
    owner_index,
    owner_kind,
    from_config,
    reserved,
});
record!(MachineParams {
    schema_version,
    count,
    truncated,
    reserved,
    entries,
});
record!(LatencySummary {
    samples,
    p50_ns,
    p99_ns,
    p999_ns,
    max_ns,
});
record!(LinkStats {
    name,
    bytes_in,
    bytes_out,
    frames,
    errors,
    reconnects,
    up,
    reserved,
});
record!(ServerStats {
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
});
