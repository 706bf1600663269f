//! Pins the shared-memory layout: a C, C++ or Python mirror of these types relies on every
//! size and offset below (they are also tabled in each type's docs). Checked at compile
//! time; the test functions exist so the suite reports them.

use core::mem::{align_of, offset_of, size_of};

use motion_ipc::*;

macro_rules! pin {
    ($ty:ty, size $size:expr, align $align:expr, { $($field:ident @ $offset:expr),* $(,)? }) => {
        const _: () = assert!(size_of::<$ty>() == $size);
        const _: () = assert!(align_of::<$ty>() == $align);
        $(const _: () = assert!(offset_of!($ty, $field) == $offset);)*
    };
}

pin!(ClientId, size 16, align 8, { lo @ 0, hi @ 8 });
pin!(AxisState, size 96, align 8, {
    position @ 0, velocity @ 8, target @ 16, raw_counts @ 24, last_refresh_tick @ 32,
    flags @ 40, fault @ 44, mode @ 46, device_state @ 47, claimed_by @ 48,
    fault_value @ 64, fault_limit @ 72, desired_position @ 80, desired_velocity @ 88,
});
pin!(SignalState, size 64, align 8, {
    value @ 0, raw @ 8, last_refresh_tick @ 16, flags @ 24, kind @ 28, reserved @ 29,
    claimed_by @ 32, event_tick @ 48, sequence @ 56, reserved2 @ 60,
});
pin!(AxisWire, size 24, align 8, { goal_tick @ 0, wire_tick @ 8, wire_ns @ 16 });
pin!(GroupState, size 152, align 8, {
    owner @ 0, path_id @ 16, time @ 24, duration @ 32, feed @ 40, feed_set @ 48,
    abort_value @ 56, abort_limit @ 64, point @ 72, abort_axis @ 76, motion @ 80, abort @ 81,
    kind @ 82, stream @ 83, stream_mode @ 84, stream_flags @ 85, stream_delay @ 86, last_sequence @ 88, last_applied_tick @ 96,
    applied @ 104, late @ 112, early @ 120, clamped @ 128, refused @ 136,
    last_received_ns @ 144,
});
pin!(MotionFrame, size 21968, align 8, {
    schema_version @ 0, axis_count @ 4, tick @ 8, time_ns @ 16, publish_ns @ 24,
    flags @ 32, signal_count @ 36, device_count @ 40, group_count @ 44, devices @ 48,
    axes @ 80, signals @ 12368, wire @ 16464, groups @ 19536,
});
pin!(CommandRequest, size 64, align 8, {
    schema_version @ 0, kind @ 4, client @ 8, sequence @ 24, axis @ 32, target @ 36,
    values @ 40,
});
pin!(CommandReply, size 72, align 8, {
    schema_version @ 0, reason @ 4, sequence @ 8, tick_applied @ 16, axis @ 24, kind @ 28,
    at_point @ 32, at_axis @ 36, holder @ 40, value @ 56, limit @ 64,
});
pin!(AxisInfo, size 160, align 8, {
    name @ 0, unit @ 32, device @ 48, counts_per_unit @ 80, min @ 88, max @ 96,
    max_velocity @ 104, max_accel @ 112, capabilities @ 120, channel @ 124, device_index @ 126,
    following_error @ 128, overspeed_factor @ 136, home_max_travel @ 144, estop @ 152,
    reserved @ 156,
});
pin!(DeviceInfo, size 128, align 4, {
    name @ 0, link @ 32, firmware @ 64, model @ 96, address @ 100, axis_count @ 104, state @ 108,
    model_id @ 112,
});
pin!(SignalInfo, size 128, align 8, {
    name @ 0, unit @ 32, device @ 48, scale @ 80, offset @ 88, full_scale @ 96, kind @ 104,
    flags @ 105, device_index @ 106, pin @ 108, reserved @ 124,
});
pin!(GroupInfo, size 376, align 8, {
    name @ 0, axis_count @ 32, stream_limit @ 36, stream_timeout @ 40, stream_buffer @ 44,
    goal_time_tolerance @ 48, axes @ 56, path_tolerance @ 120, goal_tolerance @ 248,
});
pin!(ServerInfo, size 38864, align 8, {
    schema_version @ 0, axis_count @ 4, device_count @ 8, tick_hz @ 12,
    command_timeout_ms @ 16, max_clients @ 20, server_pid @ 24, signal_count @ 28, name @ 32,
    start_time_ns @ 64, axes @ 72, devices @ 20552, signals @ 24648, group_count @ 32840,
    reserved @ 32844, groups @ 32848,
});
pin!(Setpoint, size 288, align 8, {
    schema_version @ 0, group @ 4, sequence @ 8, for_tick @ 16, mode @ 24, flags @ 28,
    values @ 32, velocities @ 160,
});
pin!(GroupPath, size 401456, align 8, {
    schema_version @ 0, kind @ 4, id @ 8, group @ 16, point_count @ 20, axis_count @ 24,
    flags @ 28, velocity_scale @ 32, accel_scale @ 40, times @ 48, positions @ 8240,
    velocities @ 139312, accelerations @ 270384,
});
pin!(MachineParam, size 88, align 4, {
    key @ 0, value @ 40, owner_index @ 80, owner_kind @ 82, from_config @ 83, reserved @ 84,
});
pin!(MachineParams, size 180240, align 4, {
    schema_version @ 0, count @ 4, truncated @ 8, reserved @ 12, entries @ 16,
});
pin!(LatencySummary, size 40, align 8, {
    samples @ 0, p50_ns @ 8, p99_ns @ 16, p999_ns @ 24, max_ns @ 32,
});
pin!(LinkStats, size 80, align 8, {
    name @ 0, bytes_in @ 32, bytes_out @ 40, frames @ 48, errors @ 56, reconnects @ 64,
    up @ 72, deferred @ 76,
});
pin!(LinkIo, size 32, align 8, {
    last_write_ns @ 0, last_read_ns @ 8, transactions @ 16, reads @ 24,
});
pin!(ServerStats, size 2016, align 8, {
    schema_version @ 0, link_count @ 4, tick @ 8, time_ns @ 16, wakeup @ 24, work @ 64,
    overruns @ 104, max_consecutive_overruns @ 112, commands @ 120, rejected @ 128,
    clients @ 136, rt_flags @ 140, links @ 144, faults @ 1424, frames_lost @ 1432,
    full_services @ 1440, full_events @ 1444, publish_failures @ 1448, replies_lost @ 1456,
    events_dropped @ 1464, link_io @ 1472, nodes_cleaned @ 1984, blackbox_lost @ 1992,
    paths_dropped @ 2000, setpoints_dropped @ 2008,
});

#[test]
fn layout_is_pinned() {
    // The assertions above run at compile time; this checks the constants they rely on.
    assert_eq!(
        (MAX_AXES, MAX_DEVICES, MAX_LINKS, MAX_SIGNALS, MAX_PARAMS),
        (128, 32, 16, 64, 2048)
    );
    assert_eq!(
        (NAME_LEN, UNIT_LEN, MODEL_ID_LEN, PARAM_TEXT_LEN),
        (32, 16, 16, 40)
    );
    assert_eq!(SCHEMA_VERSION, 11);
    assert_eq!(
        (MAX_GROUPS, MAX_GROUP_AXES, MAX_PATH_POINTS, PATH_VALUES),
        (16, 16, 1024, 16384)
    );
}

#[test]
#[allow(unsafe_code)] // calling iceoryx2's `type_name`, see the SAFETY note
fn iceoryx2_type_names_are_explicit() {
    use iceoryx2::prelude::ZeroCopySend;
    let names = [
        <MotionFrame as ZeroCopySend>::type_name as unsafe fn() -> &'static str,
        <CommandRequest as ZeroCopySend>::type_name,
        <CommandReply as ZeroCopySend>::type_name,
        <ServerInfo as ZeroCopySend>::type_name,
        <ServerStats as ZeroCopySend>::type_name,
        <MachineParams as ZeroCopySend>::type_name,
        <SignalState as ZeroCopySend>::type_name,
        <SignalInfo as ZeroCopySend>::type_name,
        <GroupPath as ZeroCopySend>::type_name,
        <Setpoint as ZeroCopySend>::type_name,
    ];
    let expected = [
        "motiond::MotionFrame",
        "motiond::CommandRequest",
        "motiond::CommandReply",
        "motiond::ServerInfo",
        "motiond::ServerStats",
        "motiond::MachineParams",
        "motiond::SignalState",
        "motiond::SignalInfo",
        "motiond::GroupPath",
        "motiond::Setpoint",
    ];
    for (name, want) in names.iter().zip(expected) {
        // SAFETY: `type_name` has no preconditions; it is `unsafe` in iceoryx2 only so that
        // implementing it is a promise about the payload layout.
        let got = unsafe { name() };
        assert_eq!(got, want);
    }
}

#[test]
fn empty_payloads_are_consistent() {
    let frame = MotionFrame::default();
    assert_eq!(frame.schema_version, SCHEMA_VERSION);
    assert!(frame.axes().is_empty());
    assert!(frame.axes[0].flags().contains(AxisFlags::STALE));
    let info = ServerInfo::default();
    assert_eq!(info.axis_index("x"), None);
    assert!(frame.wire().is_empty() && !frame.wire[0].written());
    assert!(ServerStats::default().links().is_empty());
    assert!(ServerStats::default().link_io().is_empty());
}
