/*
 * motiond.h - the shared-memory contract of motiond for C (C11) and C++ clients.
 *
 * GENERATED from the Rust description of the contract (crate motion-ipc, src/schema) by
 * `cargo run -p motion-ipc --example gen` (or scripts/gen): do not edit; change the Rust
 * payload and run the generator. crates/motion-ipc/tests/generated.rs fails while this
 * file differs from what the generator writes, and crates/motion-ipc/tests/c_header.rs
 * compiles a probe against it and compares every size, alignment, offset, field type,
 * constant, enum value, text and type name with the Rust definitions.
 *
 * motiond publishes its state and takes commands over iceoryx2 services. Every payload
 * is a fixed-size #[repr(C)] Rust struct; this header mirrors each one field by field, in
 * memory order, with the iceoryx2 type name a port must announce (iceoryx2 only connects
 * ports whose payload type name, size and alignment match the server's). Open the
 * services, never create them; user header: none (iceoryx2's "()", size 0, alignment 1).
 * Enumerations travel as the plain integer fields named in each struct; compare them with
 * the MOTIOND_* constants below. Text fields are UTF-8, zero padded (not necessarily zero
 * terminated when full).
 *
 * examples/c/ holds a complete program (frames in, a command out) on iceoryx2's C API.
 *
 * Services of the instance NAME ([server] name in the server's config):
 *
 *   MOTIOND_SERVICE_FRAME           publish-subscribe, history 1: motiond_motion_frame_t, every
 *                                   tick
 *   MOTIOND_SERVICE_TICK            event: notified after every frame
 *   MOTIOND_SERVICE_COMMAND         request-response: motiond_command_request_t ->
 *                                   motiond_command_reply_t
 *   MOTIOND_SERVICE_INFO            publish-subscribe, history 1: motiond_server_info_t
 *   MOTIOND_SERVICE_STATS           publish-subscribe, history 1: motiond_server_stats_t, about
 *                                   1 Hz
 *   MOTIOND_SERVICE_PARAMS          publish-subscribe, history 1: motiond_machine_params_t
 *   MOTIOND_SERVICE_PATHS           publish-subscribe: motiond_group_path_t, paths for groups,
 *                                   run by a RUN command
 *   MOTIOND_SERVICE_SETPOINTS       publish-subscribe: motiond_setpoint_t, streamed setpoints
 *                                   of the groups
 *   MOTIOND_SERVICE_ESTOP           event: any notification latches the e-stop
 *   MOTIOND_SERVICE_SERVER_NODE     the iceoryx2 node name of the instance's server
 */
#ifndef MOTIOND_H
#define MOTIOND_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
#define MOTIOND_STATIC_ASSERT(cond, msg) static_assert(cond, msg)
#define MOTIOND_ALIGNOF(type) alignof(type)
extern "C" {
#else
#define MOTIOND_STATIC_ASSERT(cond, msg) _Static_assert(cond, msg)
#define MOTIOND_ALIGNOF(type) _Alignof(type)
#endif

/* --- constants ---------------------------------------------------------------------------- */

/** Version of the contract; every payload carries it. */
#define MOTIOND_SCHEMA_VERSION 11u
/** Capacity of the axis arrays of the frame and the server info. */
#define MOTIOND_MAX_AXES 128u
/** Capacity of the device arrays of the frame and the server info. */
#define MOTIOND_MAX_DEVICES 32u
/** Capacity of the link arrays of the server stats. */
#define MOTIOND_MAX_LINKS 16u
/** Capacity of the signal arrays of the frame and the server info. */
#define MOTIOND_MAX_SIGNALS 64u
/** Capacity of the machine parameter table. */
#define MOTIOND_MAX_PARAMS 2048u
/** Bytes of a name field (UTF-8, zero padded). */
#define MOTIOND_NAME_LEN 32u
/** Bytes of a unit or pin field (UTF-8, zero padded). */
#define MOTIOND_UNIT_LEN 16u
/** Bytes of a model id field (UTF-8, zero padded). */
#define MOTIOND_MODEL_ID_LEN 16u
/** Capacity of the group arrays of the frame and the server info. */
#define MOTIOND_MAX_GROUPS 16u
/** Axes one group may hold. */
#define MOTIOND_MAX_GROUP_AXES 16u
/** Points one group path may hold. */
#define MOTIOND_MAX_PATH_POINTS 1024u
/** Values of one quantity of a group path: point i, axis j at i * MAX_GROUP_AXES + j. */
#define MOTIOND_PATH_VALUES 16384u
/** Bytes of a parameter key or value text. */
#define MOTIOND_PARAM_TEXT_LEN 40u
/** motiond_command_request_t.axis addressing every axis (stop, e-stop, reset, off). */
#define MOTIOND_ALL_AXES 4294967295u

/* Service names: printf formats taking the instance name. */
#define MOTIOND_SERVICE_FRAME "motiond/%s/frame"
#define MOTIOND_SERVICE_TICK "motiond/%s/tick"
#define MOTIOND_SERVICE_COMMAND "motiond/%s/command"
#define MOTIOND_SERVICE_INFO "motiond/%s/info"
#define MOTIOND_SERVICE_STATS "motiond/%s/stats"
#define MOTIOND_SERVICE_PARAMS "motiond/%s/params"
#define MOTIOND_SERVICE_PATHS "motiond/%s/paths"
#define MOTIOND_SERVICE_SETPOINTS "motiond/%s/setpoints"
#define MOTIOND_SERVICE_ESTOP "motiond/%s/estop"
#define MOTIOND_SERVICE_SERVER_NODE "motiond-%s"

/* iceoryx2 type names of the payloads. */
#define MOTIOND_TYPE_NAME_CLIENT_ID "motiond::ClientId"
#define MOTIOND_TYPE_NAME_AXIS_STATE "motiond::AxisState"
#define MOTIOND_TYPE_NAME_SIGNAL_STATE "motiond::SignalState"
#define MOTIOND_TYPE_NAME_AXIS_WIRE "motiond::AxisWire"
#define MOTIOND_TYPE_NAME_GROUP_STATE "motiond::GroupState"
#define MOTIOND_TYPE_NAME_MOTION_FRAME "motiond::MotionFrame"
#define MOTIOND_TYPE_NAME_COMMAND_REQUEST "motiond::CommandRequest"
#define MOTIOND_TYPE_NAME_COMMAND_REPLY "motiond::CommandReply"
#define MOTIOND_TYPE_NAME_AXIS_INFO "motiond::AxisInfo"
#define MOTIOND_TYPE_NAME_DEVICE_INFO "motiond::DeviceInfo"
#define MOTIOND_TYPE_NAME_SIGNAL_INFO "motiond::SignalInfo"
#define MOTIOND_TYPE_NAME_GROUP_INFO "motiond::GroupInfo"
#define MOTIOND_TYPE_NAME_SERVER_INFO "motiond::ServerInfo"
#define MOTIOND_TYPE_NAME_GROUP_PATH "motiond::GroupPath"
#define MOTIOND_TYPE_NAME_SETPOINT "motiond::Setpoint"
#define MOTIOND_TYPE_NAME_MACHINE_PARAM "motiond::MachineParam"
#define MOTIOND_TYPE_NAME_MACHINE_PARAMS "motiond::MachineParams"
#define MOTIOND_TYPE_NAME_LATENCY_SUMMARY "motiond::LatencySummary"
#define MOTIOND_TYPE_NAME_LINK_STATS "motiond::LinkStats"
#define MOTIOND_TYPE_NAME_LINK_IO "motiond::LinkIo"
#define MOTIOND_TYPE_NAME_SERVER_STATS "motiond::ServerStats"

/* --- enumerations (values of the integer fields) ------------------------------------------ */

/**
 * What a request asks for (motiond_command_request_t.kind). `values` per kind; 0.0 in a
 * velocity or acceleration slot means the axis's configured maximum: STOP -; POWER [power
 * -1..1]; POSITION [position]; VELOCITY [velocity]; RAMP_POSITION [position, max velocity,
 * acceleration]; RAMP_VELOCITY [velocity, acceleration]; HOME [search velocity]; SET_POSITION
 * [position]; SET_OUTPUT [0.0 or 1.0] (`axis` = signal index, `target` = SIGNAL); CLAIM,
 * RELEASE, E_STOP, RESET, OFF -; with `target` = GROUP (`axis` = group index): CLAIM, RELEASE,
 * STOP, RUN [path id], HOLD, RESUME, FEED [0.0..1.5], CANCEL, STREAM [stream mode]; with
 * `target` = DEVICE (`axis` = device index): COMMISSION [what, new value].
 */
enum motiond_command_kind {
    MOTIOND_COMMAND_KIND_STOP = 1,
    MOTIOND_COMMAND_KIND_POWER = 2,
    MOTIOND_COMMAND_KIND_POSITION = 3,
    MOTIOND_COMMAND_KIND_VELOCITY = 4,
    MOTIOND_COMMAND_KIND_RAMP_POSITION = 5,
    MOTIOND_COMMAND_KIND_RAMP_VELOCITY = 6,
    MOTIOND_COMMAND_KIND_HOME = 7,
    MOTIOND_COMMAND_KIND_SET_POSITION = 8,
    MOTIOND_COMMAND_KIND_CLAIM = 9,
    MOTIOND_COMMAND_KIND_RELEASE = 10,
    MOTIOND_COMMAND_KIND_E_STOP = 11,
    MOTIOND_COMMAND_KIND_RESET = 12,
    MOTIOND_COMMAND_KIND_OFF = 13,
    MOTIOND_COMMAND_KIND_SET_OUTPUT = 14,
    MOTIOND_COMMAND_KIND_RUN = 15,
    MOTIOND_COMMAND_KIND_HOLD = 16,
    MOTIOND_COMMAND_KIND_RESUME = 17,
    MOTIOND_COMMAND_KIND_FEED = 18,
    MOTIOND_COMMAND_KIND_CANCEL = 19,
    MOTIOND_COMMAND_KIND_STREAM = 20,
    MOTIOND_COMMAND_KIND_COMMISSION = 21
};

/**
 * Why a request was refused (motiond_command_reply_t.reason); 0 = accepted. The text is the
 * server's one-line explanation.
 */
enum motiond_reason {
    MOTIOND_REASON_ACCEPTED = 0,
    MOTIOND_REASON_SCHEMA_MISMATCH = 1,
    MOTIOND_REASON_UNKNOWN_KIND = 2,
    MOTIOND_REASON_UNKNOWN_AXIS = 3,
    MOTIOND_REASON_UNSUPPORTED = 4,
    MOTIOND_REASON_NOT_FINITE = 5,
    MOTIOND_REASON_OUT_OF_RANGE = 6,
    MOTIOND_REASON_VELOCITY_LIMIT = 7,
    MOTIOND_REASON_ACCEL_LIMIT = 8,
    MOTIOND_REASON_POWER_LIMIT = 9,
    MOTIOND_REASON_CLAIMED_BY_OTHER = 10,
    MOTIOND_REASON_NOT_CLAIMED = 11,
    MOTIOND_REASON_ESTOP_LATCHED = 12,
    MOTIOND_REASON_AXIS_FAULTED = 13,
    MOTIOND_REASON_LINK_DOWN = 14,
    MOTIOND_REASON_BUSY = 15,
    MOTIOND_REASON_SHUTTING_DOWN = 16,
    MOTIOND_REASON_NO_CLIENT_ID = 17,
    MOTIOND_REASON_IDENTITY_MISMATCH = 18,
    MOTIOND_REASON_DEVICE_STARTING = 19,
    MOTIOND_REASON_DEVICE_OFFLINE = 20,
    MOTIOND_REASON_UNKNOWN_SIGNAL = 21,
    MOTIOND_REASON_NOT_AN_OUTPUT = 22,
    MOTIOND_REASON_UNKNOWN_TARGET = 23,
    MOTIOND_REASON_UNKNOWN_GROUP = 24,
    MOTIOND_REASON_NO_PATH = 25,
    MOTIOND_REASON_PATH_TIMES = 26,
    MOTIOND_REASON_PATH_START = 27,
    MOTIOND_REASON_PATH_LAYOUT = 28,
    MOTIOND_REASON_GROUP_BUSY = 29,
    MOTIOND_REASON_NOT_MOVING = 30,
    MOTIOND_REASON_BLEND_TOLERANCE = 31,
    MOTIOND_REASON_UNKNOWN_DEVICE = 32
};

/** What motiond_command_request_t.axis indexes (motiond_command_request_t.target). */
enum motiond_target {
    MOTIOND_TARGET_AXIS = 0,
    MOTIOND_TARGET_SIGNAL = 1,
    MOTIOND_TARGET_GROUP = 2,
    MOTIOND_TARGET_DEVICE = 3
};

/**
 * Where a board is in its life (motiond_motion_frame_t.devices,
 * motiond_axis_state_t.device_state, motiond_device_info_t.state).
 */
enum motiond_device_state {
    MOTIOND_DEVICE_STATE_OFFLINE = 0,
    MOTIOND_DEVICE_STATE_ONLINE = 1,
    MOTIOND_DEVICE_STATE_STARTING = 2,
    MOTIOND_DEVICE_STATE_FAULTED = 3
};

/** What an axis is doing (motiond_axis_state_t.mode). */
enum motiond_axis_mode {
    MOTIOND_AXIS_MODE_OFF = 0,
    MOTIOND_AXIS_MODE_HOLD = 1,
    MOTIOND_AXIS_MODE_POWER = 2,
    MOTIOND_AXIS_MODE_POSITION = 3,
    MOTIOND_AXIS_MODE_VELOCITY = 4,
    MOTIOND_AXIS_MODE_RAMP_POSITION = 5,
    MOTIOND_AXIS_MODE_RAMP_VELOCITY = 6,
    MOTIOND_AXIS_MODE_HOMING = 7,
    MOTIOND_AXIS_MODE_STOPPING = 8,
    MOTIOND_AXIS_MODE_GROUP = 9
};

/** Why an axis is faulted (motiond_axis_state_t.fault); 0 = no fault. */
enum motiond_fault_code {
    MOTIOND_FAULT_CODE_NONE = 0,
    MOTIOND_FAULT_CODE_LINK_DOWN = 1,
    MOTIOND_FAULT_CODE_BOARD_NOT_RESPONDING = 2,
    MOTIOND_FAULT_CODE_BOARD_RESET = 3,
    MOTIOND_FAULT_CODE_BOARD_ERROR = 4,
    MOTIOND_FAULT_CODE_PROTOCOL = 5,
    MOTIOND_FAULT_CODE_OVERSPEED = 6,
    MOTIOND_FAULT_CODE_LIMIT_SWITCH = 7,
    MOTIOND_FAULT_CODE_OVERRUN = 8,
    MOTIOND_FAULT_CODE_FOLLOWING_ERROR = 9,
    MOTIOND_FAULT_CODE_LIMIT_EXCEEDED = 10,
    MOTIOND_FAULT_CODE_HOME_FAILED = 11,
    MOTIOND_FAULT_CODE_GOAL_TOLERANCE = 12
};

/**
 * What a signal is (motiond_signal_state_t.kind, motiond_signal_info_t.kind); the text is its
 * config name.
 */
enum motiond_signal_kind {
    MOTIOND_SIGNAL_KIND_DIGITAL_IN = 1,
    MOTIOND_SIGNAL_KIND_DIGITAL_OUT = 2,
    MOTIOND_SIGNAL_KIND_ANALOG_IN = 3,
    MOTIOND_SIGNAL_KIND_CAPTURE = 4,
    MOTIOND_SIGNAL_KIND_TRIGGER = 5
};

/**
 * What an e-stop (and a fault) does to an axis, IEC 60204-1 stop categories
 * (motiond_axis_info_t.estop); the text is its config name.
 */
enum motiond_estop_category {
    MOTIOND_ESTOP_CATEGORY_HOLD = 0,
    MOTIOND_ESTOP_CATEGORY_STOP_OFF = 1,
    MOTIOND_ESTOP_CATEGORY_OFF = 2
};

/**
 * The built-in board models (motiond_device_info_t.model); the text is its config id. Any
 * board's id travels in motiond_device_info_t.model_id.
 */
enum motiond_device_model {
    MOTIOND_DEVICE_MODEL_QQ2DRV = 1,
    MOTIOND_DEVICE_MODEL_TMCPACK = 2,
    MOTIOND_DEVICE_MODEL_SPIMOTOR = 3,
    MOTIOND_DEVICE_MODEL_QSB = 4
};

/** Where a group's motion is (motiond_group_state_t.motion). */
enum motiond_group_motion {
    MOTIOND_GROUP_MOTION_IDLE = 0,
    MOTIOND_GROUP_MOTION_MOVING = 1,
    MOTIOND_GROUP_MOTION_HOLDING = 2,
    MOTIOND_GROUP_MOTION_HELD = 3,
    MOTIOND_GROUP_MOTION_DONE = 4,
    MOTIOND_GROUP_MOTION_ABORTED = 5
};

/** Why a group's motion ended early (motiond_group_state_t.abort); 0 = not aborted. */
enum motiond_group_abort {
    MOTIOND_GROUP_ABORT_NONE = 0,
    MOTIOND_GROUP_ABORT_PATH_TOLERANCE = 1,
    MOTIOND_GROUP_ABORT_GOAL_TOLERANCE = 2,
    MOTIOND_GROUP_ABORT_AXIS_FAULT = 3,
    MOTIOND_GROUP_ABORT_E_STOP = 4,
    MOTIOND_GROUP_ABORT_CLAIM_LOST = 5,
    MOTIOND_GROUP_ABORT_CLIENT_DEAD = 6,
    MOTIOND_GROUP_ABORT_STOPPED = 7,
    MOTIOND_GROUP_ABORT_CANCELLED = 8,
    MOTIOND_GROUP_ABORT_STREAM_STALE = 9,
    MOTIOND_GROUP_ABORT_STREAM_LIMIT = 10,
    MOTIOND_GROUP_ABORT_SHUTTING_DOWN = 11,
    MOTIOND_GROUP_ABORT_GOAL_REFUSED = 12
};

/** Where a group's setpoint stream is (motiond_group_state_t.stream). */
enum motiond_stream_state {
    MOTIOND_STREAM_STATE_IDLE = 0,
    MOTIOND_STREAM_STATE_STREAMING = 1,
    MOTIOND_STREAM_STATE_STALE = 2,
    MOTIOND_STREAM_STATE_ABORTED = 3
};

/**
 * What a COMMISSION request changes (`values[0]`; `values[1]` is the new address or baud rate).
 */
enum motiond_commission_what {
    MOTIOND_COMMISSION_WHAT_ADDRESS = 1,
    MOTIOND_COMMISSION_WHAT_BAUD = 2,
    MOTIOND_COMMISSION_WHAT_FACTORY_RESET = 3
};

/**
 * What a group's streamed setpoints are (motiond_setpoint_t.mode,
 * motiond_group_state_t.stream_mode, `values[0]` of a STREAM command).
 */
enum motiond_stream_mode {
    MOTIOND_STREAM_MODE_NONE = 0,
    MOTIOND_STREAM_MODE_POSITION = 1,
    MOTIOND_STREAM_MODE_VELOCITY = 2,
    MOTIOND_STREAM_MODE_POWER = 3
};

/** What a group path is (motiond_group_path_t.kind, motiond_group_state_t.kind). */
enum motiond_path_kind {
    MOTIOND_PATH_KIND_NONE = 0,
    MOTIOND_PATH_KIND_LINE = 1,
    MOTIOND_PATH_KIND_TRAJECTORY = 2,
    MOTIOND_PATH_KIND_STREAM = 3
};

/** What a machine parameter belongs to (motiond_machine_param_t.owner_kind). */
enum motiond_param_owner {
    MOTIOND_PARAM_OWNER_DEVICE = 1,
    MOTIOND_PARAM_OWNER_AXIS = 2
};

/** Bits of motiond_axis_state_t.flags. */
enum motiond_axis_flags {
    MOTIOND_AXIS_FLAGS_MOVING = 1 << 0,
    MOTIOND_AXIS_FLAGS_HOMED = 1 << 1,
    MOTIOND_AXIS_FLAGS_AT_LIMIT = 1 << 2,
    MOTIOND_AXIS_FLAGS_STALE = 1 << 3,
    MOTIOND_AXIS_FLAGS_FAULT = 1 << 4,
    MOTIOND_AXIS_FLAGS_CLAIMED = 1 << 5,
    MOTIOND_AXIS_FLAGS_ARRIVED = 1 << 6,
    MOTIOND_AXIS_FLAGS_ESTOPPED = 1 << 7,
    MOTIOND_AXIS_FLAGS_DEADMAN_EXPIRED = 1 << 8,
    MOTIOND_AXIS_FLAGS_HELD = 1 << 9
};

/** Bits of motiond_motion_frame_t.flags. */
enum motiond_frame_flags {
    MOTIOND_FRAME_FLAGS_ESTOP_LATCHED = 1 << 0,
    MOTIOND_FRAME_FLAGS_OVERRUN = 1 << 1,
    MOTIOND_FRAME_FLAGS_SHUTTING_DOWN = 1 << 2
};

/** Bits of motiond_signal_state_t.flags. */
enum motiond_signal_flags {
    MOTIOND_SIGNAL_FLAGS_STALE = 1 << 0,
    MOTIOND_SIGNAL_FLAGS_CLAIMED = 1 << 1,
    MOTIOND_SIGNAL_FLAGS_SAFE_STATE = 1 << 2,
    MOTIOND_SIGNAL_FLAGS_PENDING = 1 << 3
};

/** Bits of motiond_group_path_t.flags. */
enum motiond_path_flags {
    MOTIOND_PATH_FLAGS_VELOCITIES = 1 << 0,
    MOTIOND_PATH_FLAGS_ACCELERATIONS = 1 << 1
};

/** Bits of motiond_group_state_t.stream_flags. */
enum motiond_stream_flags {
    MOTIOND_STREAM_FLAGS_APPLIED = 1 << 0,
    MOTIOND_STREAM_FLAGS_CLAMPED = 1 << 1
};

/** Bits of motiond_setpoint_t.flags. */
enum motiond_setpoint_flags {
    MOTIOND_SETPOINT_FLAGS_FEED_FORWARD = 1 << 0
};

/** Bits of motiond_signal_info_t.flags. */
enum motiond_signal_info_flags {
    MOTIOND_SIGNAL_INFO_FLAGS_INVERT = 1 << 0,
    MOTIOND_SIGNAL_INFO_FLAGS_HAS_SAFE_STATE = 1 << 1,
    MOTIOND_SIGNAL_INFO_FLAGS_SAFE_ON = 1 << 2
};

/** Bits of motiond_server_stats_t.rt_flags. */
enum motiond_rt_flags {
    MOTIOND_RT_FLAGS_FIFO = 1 << 0,
    MOTIOND_RT_FLAGS_LOCKED = 1 << 1,
    MOTIOND_RT_FLAGS_PINNED = 1 << 2,
    MOTIOND_RT_FLAGS_DMA_LATENCY = 1 << 3
};

/** Bits of motiond_server_stats_t.full_services: services whose port slots are all taken. */
enum motiond_full_services {
    MOTIOND_FULL_SERVICES_FRAME = 1 << 0,
    MOTIOND_FULL_SERVICES_TICK = 1 << 1,
    MOTIOND_FULL_SERVICES_COMMAND = 1 << 2,
    MOTIOND_FULL_SERVICES_INFO = 1 << 3,
    MOTIOND_FULL_SERVICES_STATS = 1 << 4,
    MOTIOND_FULL_SERVICES_PARAMS = 1 << 5,
    MOTIOND_FULL_SERVICES_ESTOP = 1 << 6,
    MOTIOND_FULL_SERVICES_PATHS = 1 << 7,
    MOTIOND_FULL_SERVICES_SETPOINTS = 1 << 8
};

/* --- payloads ----------------------------------------------------------------------------- */

/**
 * The iceoryx2 node id of a client (`Node::id().value()`, a u128), split into two little halves
 * so that the layout is the same for every C ABI. Zero means "no client".
 *
 * 16 bytes, alignment 8; iceoryx2 type name "motiond::ClientId".
 */
typedef struct motiond_client_id {
    uint64_t lo; /**< Low 64 bits of the node id. (offset 0) */
    uint64_t hi; /**< High 64 bits of the node id. (offset 8) */
} motiond_client_id_t;
MOTIOND_STATIC_ASSERT(sizeof(motiond_client_id_t) == 16, "motiond_client_id_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_client_id_t) == 8, "motiond_client_id_t alignment");

/**
 * One axis in a frame.
 *
 * 96 bytes, alignment 8; iceoryx2 type name "motiond::AxisState".
 */
typedef struct motiond_axis_state {
    double position; /**< Measured position in axis units. (offset 0) */
    double velocity; /**< Measured velocity in units/s. (offset 8) */
    /** Position target (position modes) or velocity target (velocity modes), in units. */
    double target; /* offset 16 */
    int64_t raw_counts; /**< Position in the board's own counts. (offset 24) */
    /** Tick at which fresh data last arrived from the board. */
    uint64_t last_refresh_tick; /* offset 32 */
    uint32_t flags; /**< MOTIOND_AXIS_FLAGS_* bits. (offset 40) */
    uint16_t fault; /**< MOTIOND_FAULT_CODE_* value; 0 = no fault. (offset 44) */
    uint8_t mode; /**< MOTIOND_AXIS_MODE_* value. (offset 46) */
    uint8_t device_state; /**< MOTIOND_DEVICE_STATE_* value of the axis's board. (offset 47) */
    /** The client holding a claim on the axis; zero when unclaimed. */
    motiond_client_id_t claimed_by; /* offset 48 */
    /**
     * The measured figure of the latched fault (units, units/s; see MOTIOND_FAULT_CODE_*), 0
     * when none.
     */
    double fault_value; /* offset 64 */
    double fault_limit; /**< The tolerance or limit the fault broke, 0 when none. (offset 72) */
    /**
     * Where the server wants the axis now, in units: the group's path while the axis follows a
     * group (mode `group`), the target while it holds or moves to a position, the measured
     * position otherwise.
     */
    double desired_position; /* offset 80 */
    /**
     * The velocity the server wants now, units/s: the group path's while it follows a group,
     * the velocity target of a velocity mode, 0 otherwise.
     */
    double desired_velocity; /* offset 88 */
} motiond_axis_state_t;
MOTIOND_STATIC_ASSERT(sizeof(motiond_axis_state_t) == 96, "motiond_axis_state_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_axis_state_t) == 8, "motiond_axis_state_t alignment");

/**
 * One signal in a frame.
 *
 * A `capture` or `trigger` signal also carries events: every capture (every trigger pulse) the
 * board reports adds one to `sequence`, and `event_tick` is the tick that took the newest one
 * in. Two events taken in by the same tick show as a step of two (the value is the newer
 * one's): a client that remembers the sequence it last saw knows how many it missed.
 *
 * 64 bytes, alignment 8; iceoryx2 type name "motiond::SignalState".
 */
typedef struct motiond_signal_state {
    /**
     * Logical value: digital 0.0/1.0 after `invert`; analogue, capture and trigger raw × scale
     * + offset (a capture: the captured position; a trigger: its compare position).
     */
    double value; /* offset 0 */
    /**
     * Raw value as the board reports it: electrical level 0/1, ADC counts, or counter counts
     * (capture, trigger).
     */
    double raw; /* offset 8 */
    /** Tick at which the board last reported it (outputs: acknowledged it). */
    uint64_t last_refresh_tick; /* offset 16 */
    uint32_t flags; /**< MOTIOND_SIGNAL_FLAGS_* bits. (offset 24) */
    uint8_t kind; /**< MOTIOND_SIGNAL_KIND_* value. (offset 28) */
    uint8_t reserved[3]; /**< Zero. (offset 29) */
    /** Claim holder of an output; zero when unclaimed. */
    motiond_client_id_t claimed_by; /* offset 32 */
    /** Tick that took in the newest event (capture, trigger pulse); 0 before the first. */
    uint64_t event_tick; /* offset 48 */
    /**
     * Events (captures, trigger pulses) the board reported since the server started, wrapping
     * at 2³²; 0 for the other kinds.
     */
    uint32_t sequence; /* offset 56 */
    uint32_t reserved2; /**< Zero. (offset 60) */
} motiond_signal_state_t;
MOTIOND_STATIC_ASSERT(sizeof(motiond_signal_state_t) == 64, "motiond_signal_state_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_signal_state_t) == 8, "motiond_signal_state_t alignment");

/**
 * When the current goal of one axis was set and when its first request reached the wire
 * (motiond_motion_frame_t.wire, same index as `axes`).
 *
 * Command → wire: `wire_ns` minus the client's CLOCK_MONOTONIC when it sent the command, or in
 * ticks `wire_tick − goal_tick` (0: written in the tick that accepted it).
 *
 * 24 bytes, alignment 8; iceoryx2 type name "motiond::AxisWire".
 */
typedef struct motiond_axis_wire {
    /**
     * Tick in which the current goal was set (a client's command: the reply's `tick_applied`;
     * or the server's own stop).
     */
    uint64_t goal_tick; /* offset 0 */
    /**
     * Tick during which the goal's first request was written to the link (its last byte
     * accepted by the transport); 0 until then.
     */
    uint64_t wire_tick; /* offset 8 */
    /**
     * CLOCK_MONOTONIC ns of that write; 0 until then (and for a goal that needs no request).
     */
    uint64_t wire_ns; /* offset 16 */
} motiond_axis_wire_t;
MOTIOND_STATIC_ASSERT(sizeof(motiond_axis_wire_t) == 24, "motiond_axis_wire_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_axis_wire_t) == 8, "motiond_axis_wire_t alignment");

/**
 * One group in a frame (motiond_motion_frame_t.groups, config order).
 *
 * 152 bytes, alignment 8; iceoryx2 type name "motiond::GroupState".
 */
typedef struct motiond_group_state {
    /** The client whose motion or stream the group runs; zero when none. */
    motiond_client_id_t owner; /* offset 0 */
    /** The id of the path running (or last run), as the client gave it. */
    uint64_t path_id; /* offset 16 */
    /** Seconds along the path (path time: it advances by the feed each second). */
    double time; /* offset 24 */
    double duration; /**< The path's length in seconds at feed 1. (offset 32) */
    /** The feed in effect (0 while held; below the set feed while the path's limits cap it). */
    double feed; /* offset 40 */
    double feed_set; /**< The feed set by the client (1.0 = 100 %). (offset 48) */
    /** The figure that aborted the motion (|desired − measured| in the axis's unit). */
    double abort_value; /* offset 56 */
    double abort_limit; /**< The tolerance it broke. (offset 64) */
    uint32_t point; /**< Index of the point the path is heading to (0 for a line). (offset 72) */
    /** Config index of the axis that aborted it; `u32::MAX` when none. */
    uint32_t abort_axis; /* offset 76 */
    uint8_t motion; /**< MOTIOND_GROUP_MOTION_* value. (offset 80) */
    uint8_t abort; /**< MOTIOND_GROUP_ABORT_* value. (offset 81) */
    uint8_t kind; /**< MOTIOND_PATH_KIND_* value of the path running or last run. (offset 82) */
    uint8_t stream; /**< MOTIOND_STREAM_STATE_* value. (offset 83) */
    /** MOTIOND_STREAM_MODE_* value of the stream running or last run. */
    uint8_t stream_mode; /* offset 84 */
    uint8_t stream_flags; /**< MOTIOND_STREAM_FLAGS_* bits of this tick. (offset 85) */
    /**
     * Ticks the stream runs behind its setpoints' own ticks: a setpoint for tick `k` is applied
     * in tick `k + stream_delay`. 0 at the start; grows to the lateness of a setpoint that
     * arrived after its tick (at most `stream_buffer`), never shrinks while the stream runs
     * (schema 10; saturates at 65535).
     */
    uint16_t stream_delay; /* offset 86 */
    uint64_t last_sequence; /**< Sequence of the last streamed setpoint applied. (offset 88) */
    uint64_t last_applied_tick; /**< Tick in which it was applied. (offset 96) */
    uint64_t applied; /**< Streamed setpoints applied. (offset 104) */
    uint64_t late; /**< Streamed setpoints dropped because their tick had passed. (offset 112) */
    /**
     * Streamed setpoints dropped because they were addressed more than `stream_buffer` ticks
     * ahead.
     */
    uint64_t early; /* offset 120 */
    /** Streamed setpoints clamped to a limit (`stream_limit = "clamp"`). */
    uint64_t clamped; /* offset 128 */
    /** Streamed setpoints dropped because their sender does not hold the group. */
    uint64_t refused; /* offset 136 */
    /**
     * When the server took the last applied setpoint from the `setpoints` service
     * (CLOCK_MONOTONIC ns, the clock of motiond_motion_frame_t.publish_ns): a client subtracts
     * its own send stamp, or a frame's `publish_ns`; 0 until one is applied.
     */
    uint64_t last_received_ns; /* offset 144 */
} motiond_group_state_t;
MOTIOND_STATIC_ASSERT(sizeof(motiond_group_state_t) == 152, "motiond_group_state_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_group_state_t) == 8, "motiond_group_state_t alignment");

/**
 * One consistent snapshot of every axis, board and signal, published once per tick on
 * `motiond/<name>/frame`.
 *
 * 21968 bytes, alignment 8; iceoryx2 type name "motiond::MotionFrame".
 */
typedef struct motiond_motion_frame {
    uint32_t schema_version; /**< MOTIOND_SCHEMA_VERSION of the writer. (offset 0) */
    uint32_t axis_count; /**< Number of valid entries at the start of `axes`. (offset 4) */
    uint64_t tick; /**< Tick number, 0 at server start. (offset 8) */
    uint64_t time_ns; /**< The tick's deadline on CLOCK_MONOTONIC, ns. (offset 16) */
    /** CLOCK_MONOTONIC, ns, taken just before the frame was sent. */
    uint64_t publish_ns; /* offset 24 */
    uint32_t flags; /**< MOTIOND_FRAME_FLAGS_* bits. (offset 32) */
    uint32_t signal_count; /**< Number of valid entries at the start of `signals`. (offset 36) */
    uint32_t device_count; /**< Number of valid entries at the start of `devices`. (offset 40) */
    uint32_t group_count; /**< Number of valid entries at the start of `groups`. (offset 44) */
    /**
     * MOTIOND_DEVICE_STATE_* per device, config order; entries past `device_count` are zero.
     */
    uint8_t devices[MOTIOND_MAX_DEVICES]; /* offset 48 */
    /** Axes in config order; entries past `axis_count` are motiond_axis_state_t.UNKNOWN. */
    motiond_axis_state_t axes[MOTIOND_MAX_AXES]; /* offset 80 */
    /**
     * Signals in config order; entries past `signal_count` are motiond_signal_state_t.UNKNOWN.
     */
    motiond_signal_state_t signals[MOTIOND_MAX_SIGNALS]; /* offset 12368 */
    /**
     * Per axis (same index as `axes`): when its current goal was set and when its first request
     * reached the wire.
     */
    motiond_axis_wire_t wire[MOTIOND_MAX_AXES]; /* offset 16464 */
    /** Groups in config order; entries past `group_count` are motiond_group_state_t.IDLE. */
    motiond_group_state_t groups[MOTIOND_MAX_GROUPS]; /* offset 19536 */
} motiond_motion_frame_t;
MOTIOND_STATIC_ASSERT(sizeof(motiond_motion_frame_t) == 21968, "motiond_motion_frame_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_motion_frame_t) == 8, "motiond_motion_frame_t alignment");

/**
 * A command to the server, on `motiond/<name>/command`; `values` per kind: see
 * MOTIOND_COMMAND_KIND_*.
 *
 * Identity comes from the transport: the server knows which iceoryx2 node sent a request and
 * owns every claim by that node. `client` may be zero ("the sender"); a non-zero `client` that
 * is not the sender's node is refused with `Reason::IdentityMismatch`.
 *
 * 64 bytes, alignment 8; iceoryx2 type name "motiond::CommandRequest".
 */
typedef struct motiond_command_request {
    uint32_t schema_version; /**< MOTIOND_SCHEMA_VERSION of the sender. (offset 0) */
    uint32_t kind; /**< MOTIOND_COMMAND_KIND_* value. (offset 4) */
    motiond_client_id_t client; /**< The sender's iceoryx2 node id, or zero. (offset 8) */
    uint64_t sequence; /**< The client's sequence number, echoed in the reply. (offset 24) */
    /** Axis (or signal) index, config order, or motiond_command_request_t.ALL_AXES. */
    uint32_t axis; /* offset 32 */
    /** MOTIOND_TARGET_* value: 0 = axis, 1 = signal, 2 = group, 3 = device. */
    uint32_t target; /* offset 36 */
    double values[3]; /**< Arguments; see MOTIOND_COMMAND_KIND_*. (offset 40) */
} motiond_command_request_t;
MOTIOND_STATIC_ASSERT(sizeof(motiond_command_request_t) == 64, "motiond_command_request_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_command_request_t) == 8, "motiond_command_request_t alignment");

/**
 * The server's answer to one motiond_command_request_t; every request gets exactly one.
 *
 * 72 bytes, alignment 8; iceoryx2 type name "motiond::CommandReply".
 */
typedef struct motiond_command_reply {
    uint32_t schema_version; /**< MOTIOND_SCHEMA_VERSION of the server. (offset 0) */
    uint32_t reason; /**< MOTIOND_REASON_* value; 0 = accepted. (offset 4) */
    uint64_t sequence; /**< The request's sequence. (offset 8) */
    /** Tick in which the command took effect (or was refused). */
    uint64_t tick_applied; /* offset 16 */
    uint32_t axis; /**< The request's axis. (offset 24) */
    uint32_t kind; /**< The request's kind. (offset 28) */
    /** A refused path: the index of the point at fault; `u32::MAX` when none. */
    uint32_t at_point; /* offset 32 */
    /**
     * The config index of the axis at fault (a path's axis, the axis a claim found held, the
     * axis a group motion owns); `u32::MAX` when none.
     */
    uint32_t at_axis; /* offset 36 */
    /** `ClaimedByOther`: the client holding that axis; zero otherwise. */
    motiond_client_id_t holder; /* offset 40 */
    /** A refused path: the figure at fault (position, velocity, acceleration, distance). */
    double value; /* offset 56 */
    double limit; /**< The limit it broke. (offset 64) */
} motiond_command_reply_t;
MOTIOND_STATIC_ASSERT(sizeof(motiond_command_reply_t) == 72, "motiond_command_reply_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_command_reply_t) == 8, "motiond_command_reply_t alignment");

/**
 * One axis's static description.
 *
 * 160 bytes, alignment 8; iceoryx2 type name "motiond::AxisInfo".
 */
typedef struct motiond_axis_info {
    uint8_t name[MOTIOND_NAME_LEN]; /**< Axis name, UTF-8, zero padded. (offset 0) */
    /** Unit of positions ("mm", "deg"), UTF-8, zero padded. */
    uint8_t unit[MOTIOND_UNIT_LEN]; /* offset 32 */
    uint8_t device[MOTIOND_NAME_LEN]; /**< Name of the device that drives the axis. (offset 48) */
    double counts_per_unit; /**< Device counts per unit. (offset 80) */
    double min; /**< Lower soft limit, units. (offset 88) */
    double max; /**< Upper soft limit, units. (offset 96) */
    double max_velocity; /**< Velocity limit, units/s. (offset 104) */
    double max_accel; /**< Acceleration limit, units/s². (offset 112) */
    uint32_t capabilities; /**< `Capabilities` bits. (offset 120) */
    uint16_t channel; /**< Motor number on the device. (offset 124) */
    uint16_t device_index; /**< Index into motiond_server_info_t.devices. (offset 126) */
    /** Following error tolerance, units; 0 = not supervised. */
    double following_error; /* offset 128 */
    /** Overspeed factor (× `max_velocity`); 0 = not supervised. */
    double overspeed_factor; /* offset 136 */
    /** Travel limit of a reference search, units; 0 = not supervised. */
    double home_max_travel; /* offset 144 */
    uint32_t estop; /**< MOTIOND_ESTOP_CATEGORY_* value. (offset 152) */
    uint32_t reserved; /**< Zero. (offset 156) */
} motiond_axis_info_t;
MOTIOND_STATIC_ASSERT(sizeof(motiond_axis_info_t) == 160, "motiond_axis_info_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_axis_info_t) == 8, "motiond_axis_info_t alignment");

/**
 * One device's description.
 *
 * 128 bytes, alignment 4; iceoryx2 type name "motiond::DeviceInfo".
 */
typedef struct motiond_device_info {
    uint8_t name[MOTIOND_NAME_LEN]; /**< Device name. (offset 0) */
    uint8_t link[MOTIOND_NAME_LEN]; /**< Link name. (offset 32) */
    /** Firmware version as the board reported it ("" until known). */
    uint8_t firmware[MOTIOND_NAME_LEN]; /* offset 64 */
    uint32_t model; /**< MOTIOND_DEVICE_MODEL_* value. (offset 96) */
    uint32_t address; /**< Bus address, 0 when the model has none. (offset 100) */
    uint32_t axis_count; /**< Axes configured on the device. (offset 104) */
    /**
     * MOTIOND_DEVICE_STATE_* value when the info was published (the frame has the current one).
     */
    uint32_t state; /* offset 108 */
    /**
     * The model's config id (`tmcpack`, `example`), UTF-8, zero padded: names the model of any
     * board, built in or not.
     */
    uint8_t model_id[MOTIOND_MODEL_ID_LEN]; /* offset 112 */
} motiond_device_info_t;
MOTIOND_STATIC_ASSERT(sizeof(motiond_device_info_t) == 128, "motiond_device_info_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_device_info_t) == 4, "motiond_device_info_t alignment");

/**
 * One signal's static description.
 *
 * 128 bytes, alignment 8; iceoryx2 type name "motiond::SignalInfo".
 */
typedef struct motiond_signal_info {
    uint8_t name[MOTIOND_NAME_LEN]; /**< Signal name. (offset 0) */
    uint8_t unit[MOTIOND_UNIT_LEN]; /**< Unit of an analogue value ("" for digital). (offset 32) */
    uint8_t device[MOTIOND_NAME_LEN]; /**< Device name. (offset 48) */
    double scale; /**< Analogue: value = raw × scale + offset. (offset 80) */
    double offset; /**< Analogue: value = raw × scale + offset. (offset 88) */
    /** Raw full scale (1023 for a 10-bit converter; 1 for digital). */
    double full_scale; /* offset 96 */
    uint8_t kind; /**< MOTIOND_SIGNAL_KIND_* value. (offset 104) */
    uint8_t flags; /**< MOTIOND_SIGNAL_INFO_FLAGS_* bits. (offset 105) */
    uint16_t device_index; /**< Index into motiond_server_info_t.devices. (offset 106) */
    /** The board's pin name ("ttlio1"), zero padded. */
    uint8_t pin[MOTIOND_UNIT_LEN]; /* offset 108 */
    uint32_t reserved; /**< Zero. (offset 124) */
} motiond_signal_info_t;
MOTIOND_STATIC_ASSERT(sizeof(motiond_signal_info_t) == 128, "motiond_signal_info_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_signal_info_t) == 8, "motiond_signal_info_t alignment");

/**
 * One group as configured (motiond_server_info_t.groups).
 *
 * 376 bytes, alignment 8; iceoryx2 type name "motiond::GroupInfo".
 */
typedef struct motiond_group_info {
    uint8_t name[MOTIOND_NAME_LEN]; /**< Group name, UTF-8, zero padded. (offset 0) */
    uint32_t axis_count; /**< Valid entries in `axes` and the tolerance arrays. (offset 32) */
    uint32_t stream_limit; /**< `stream_limit`: 0 = clamp, 1 = abort. (offset 36) */
    /** Ticks without a streamed setpoint before the group stops. */
    uint32_t stream_timeout; /* offset 40 */
    uint32_t stream_buffer; /**< Ticks ahead a streamed setpoint may wait. (offset 44) */
    /** Seconds after the path's end every axis has to come within its goal tolerance. */
    double goal_time_tolerance; /* offset 48 */
    /** Config indices of the member axes, in the group's order. */
    uint32_t axes[MOTIOND_MAX_GROUP_AXES]; /* offset 56 */
    /** Per member axis: the path tolerance, its unit (0 = not checked). */
    double path_tolerance[MOTIOND_MAX_GROUP_AXES]; /* offset 120 */
    /** Per member axis: the goal tolerance, its unit. */
    double goal_tolerance[MOTIOND_MAX_GROUP_AXES]; /* offset 248 */
} motiond_group_info_t;
MOTIOND_STATIC_ASSERT(sizeof(motiond_group_info_t) == 376, "motiond_group_info_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_group_info_t) == 8, "motiond_group_info_t alignment");

/**
 * The server's static description, published with history 1 on `motiond/<name>/info`.
 *
 * 38864 bytes, alignment 8; iceoryx2 type name "motiond::ServerInfo".
 */
typedef struct motiond_server_info {
    uint32_t schema_version; /**< MOTIOND_SCHEMA_VERSION of the server. (offset 0) */
    uint32_t axis_count; /**< Valid entries in `axes`. (offset 4) */
    uint32_t device_count; /**< Valid entries in `devices`. (offset 8) */
    uint32_t tick_hz; /**< Tick rate, Hz. (offset 12) */
    /** Deadman for velocity and power goals, ms; 0 = disabled. */
    uint32_t command_timeout_ms; /* offset 16 */
    uint32_t max_clients; /**< Configured client limit. (offset 20) */
    uint32_t server_pid; /**< Process id of motiond. (offset 24) */
    uint32_t signal_count; /**< Valid entries in `signals`. (offset 28) */
    uint8_t name[MOTIOND_NAME_LEN]; /**< Instance name. (offset 32) */
    uint64_t start_time_ns; /**< CLOCK_MONOTONIC ns of tick 0. (offset 64) */
    motiond_axis_info_t axes[MOTIOND_MAX_AXES]; /**< Axes in config order. (offset 72) */
    /** Devices in config order. */
    motiond_device_info_t devices[MOTIOND_MAX_DEVICES]; /* offset 20552 */
    /** Signals in config order. */
    motiond_signal_info_t signals[MOTIOND_MAX_SIGNALS]; /* offset 24648 */
    uint32_t group_count; /**< Valid entries in `groups`. (offset 32840) */
    uint32_t reserved; /**< Zero. (offset 32844) */
    motiond_group_info_t groups[MOTIOND_MAX_GROUPS]; /**< Groups in config order. (offset 32848) */
} motiond_server_info_t;
MOTIOND_STATIC_ASSERT(sizeof(motiond_server_info_t) == 38864, "motiond_server_info_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_server_info_t) == 8, "motiond_server_info_t alignment");

/**
 * A path for a group, published on `motiond/<name>/paths` and run by a `Run` command
 * (`values[0]` = `id`). Point `i`, axis `j` (the group's order) is at `i * MAX_GROUP_AXES + j`
 * of `positions`, `velocities` and `accelerations`.
 *
 * 401456 bytes, alignment 8; iceoryx2 type name "motiond::GroupPath".
 */
typedef struct motiond_group_path {
    uint32_t schema_version; /**< MOTIOND_SCHEMA_VERSION of the sender. (offset 0) */
    uint32_t kind; /**< MOTIOND_PATH_KIND_* value: line or trajectory. (offset 4) */
    /**
     * The client's id for this path (echoed in motiond_group_state_t.path_id); the newest path
     * with this id from the sender is the one run.
     */
    uint64_t id; /* offset 8 */
    /** Group index (config order), as the `Run` command must name it too. */
    uint32_t group; /* offset 16 */
    uint32_t point_count; /**< Valid points (1 for a line). (offset 20) */
    uint32_t axis_count; /**< Axes per point: the group's axis count. (offset 24) */
    uint32_t flags; /**< MOTIOND_PATH_FLAGS_* bits. (offset 28) */
    /** A line: fraction (0, 1] of every axis's `max_velocity`; 0 means 1. */
    double velocity_scale; /* offset 32 */
    /** A line: fraction (0, 1] of every axis's `max_accel`; 0 means 1. */
    double accel_scale; /* offset 40 */
    /** Per point: seconds from the start of the trajectory (ignored for a line). */
    double times[MOTIOND_MAX_PATH_POINTS]; /* offset 48 */
    /** Per point and axis: position, the axis's unit. */
    double positions[MOTIOND_PATH_VALUES]; /* offset 8240 */
    /** Per point and axis: velocity, unit/s (with `VELOCITIES`). */
    double velocities[MOTIOND_PATH_VALUES]; /* offset 139312 */
    /** Per point and axis: acceleration, unit/s² (with `ACCELERATIONS`). */
    double accelerations[MOTIOND_PATH_VALUES]; /* offset 270384 */
} motiond_group_path_t;
MOTIOND_STATIC_ASSERT(sizeof(motiond_group_path_t) == 401456, "motiond_group_path_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_group_path_t) == 8, "motiond_group_path_t alignment");

/**
 * One setpoint of a group's stream, published on `motiond/<name>/setpoints` by the client that
 * holds the group's claim and started the stream (`Stream` command); from any other node it is
 * dropped and counted (motiond_group_state_t.refused). The server applies each setpoint on its
 * own time, once and in order: the one for tick `k` in tick `k + stream_delay`
 * (`crate::playout`); one for a tick more than `stream_buffer` ahead is dropped (`early`), one
 * more than `stream_buffer` behind, superseded or out of sequence is dropped (`late`).
 * Velocities and accelerations are judged over the setpoints' own ticks.
 *
 * 288 bytes, alignment 8; iceoryx2 type name "motiond::Setpoint".
 */
typedef struct motiond_setpoint {
    uint32_t schema_version; /**< MOTIOND_SCHEMA_VERSION of the sender. (offset 0) */
    uint32_t group; /**< Group index (config order). (offset 4) */
    /**
     * The client's sequence number: increasing; a setpoint not above the last applied one is
     * late.
     */
    uint64_t sequence; /* offset 8 */
    /**
     * The tick this setpoint is for (a frame's `tick` + the client's lead: 1 is the next tick).
     */
    uint64_t for_tick; /* offset 16 */
    uint32_t mode; /**< MOTIOND_STREAM_MODE_* value: must be the stream's. (offset 24) */
    uint32_t flags; /**< MOTIOND_SETPOINT_FLAGS_* bits. (offset 28) */
    /** Per axis, in the group's order: position (unit), velocity (unit/s) or power. */
    double values[MOTIOND_MAX_GROUP_AXES]; /* offset 32 */
    /** Per axis: velocity feed-forward, unit/s (with `FEED_FORWARD`). */
    double velocities[MOTIOND_MAX_GROUP_AXES]; /* offset 160 */
} motiond_setpoint_t;
MOTIOND_STATIC_ASSERT(sizeof(motiond_setpoint_t) == 288, "motiond_setpoint_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_setpoint_t) == 8, "motiond_setpoint_t alignment");

/**
 * One effective machine parameter.
 *
 * 88 bytes, alignment 4; iceoryx2 type name "motiond::MachineParam".
 */
typedef struct motiond_machine_param {
    /** The config key, dotted for tables (`current.standstill`). */
    uint8_t key[MOTIOND_PARAM_TEXT_LEN]; /* offset 0 */
    /** The value in effect, with its unit (`50 %`). */
    uint8_t value[MOTIOND_PARAM_TEXT_LEN]; /* offset 40 */
    uint16_t owner_index; /**< Device or axis index. (offset 80) */
    uint8_t owner_kind; /**< MOTIOND_PARAM_OWNER_* value. (offset 82) */
    uint8_t from_config; /**< 1: the config file set it; 0: the default. (offset 83) */
    uint32_t reserved; /**< Zero. (offset 84) */
} motiond_machine_param_t;
MOTIOND_STATIC_ASSERT(sizeof(motiond_machine_param_t) == 88, "motiond_machine_param_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_machine_param_t) == 4, "motiond_machine_param_t alignment");

/**
 * Every machine parameter in effect, published with history 1 on `motiond/<name>/params`.
 *
 * 180240 bytes, alignment 4; iceoryx2 type name "motiond::MachineParams".
 */
typedef struct motiond_machine_params {
    uint32_t schema_version; /**< MOTIOND_SCHEMA_VERSION of the server. (offset 0) */
    uint32_t count; /**< Valid entries. (offset 4) */
    /** 1 when more parameters existed than MOTIOND_MAX_PARAMS (entries were left out). */
    uint32_t truncated; /* offset 8 */
    uint32_t reserved; /**< Zero. (offset 12) */
    /** Devices' then axes' parameters, config order. */
    motiond_machine_param_t entries[MOTIOND_MAX_PARAMS]; /* offset 16 */
} motiond_machine_params_t;
MOTIOND_STATIC_ASSERT(sizeof(motiond_machine_params_t) == 180240, "motiond_machine_params_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_machine_params_t) == 4, "motiond_machine_params_t alignment");

/**
 * Percentiles of one latency distribution, in nanoseconds.
 *
 * 40 bytes, alignment 8; iceoryx2 type name "motiond::LatencySummary".
 */
typedef struct motiond_latency_summary {
    uint64_t samples; /**< Number of samples. (offset 0) */
    uint64_t p50_ns; /**< Median. (offset 8) */
    uint64_t p99_ns; /**< 99th percentile. (offset 16) */
    uint64_t p999_ns; /**< 99.9th percentile. (offset 24) */
    uint64_t max_ns; /**< Maximum. (offset 32) */
} motiond_latency_summary_t;
MOTIOND_STATIC_ASSERT(sizeof(motiond_latency_summary_t) == 40, "motiond_latency_summary_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_latency_summary_t) == 8, "motiond_latency_summary_t alignment");

/**
 * Counters of one link since start.
 *
 * 80 bytes, alignment 8; iceoryx2 type name "motiond::LinkStats".
 */
typedef struct motiond_link_stats {
    uint8_t name[MOTIOND_NAME_LEN]; /**< Link name. (offset 0) */
    uint64_t bytes_in; /**< Bytes received. (offset 32) */
    uint64_t bytes_out; /**< Bytes sent. (offset 40) */
    uint64_t frames; /**< Replies decoded. (offset 48) */
    uint64_t errors; /**< Bad frames, I/O errors, timeouts. (offset 56) */
    uint64_t reconnects; /**< Successful reopens. (offset 64) */
    uint32_t up; /**< 1 when the link is open. (offset 72) */
    /**
     * Messages a link the tick runs itself (`io = "tick"`) put off to a later tick because the
     * tick's wire-time budget was spent (saturating; 0 on other links).
     */
    uint32_t deferred; /* offset 76 */
} motiond_link_stats_t;
MOTIOND_STATIC_ASSERT(sizeof(motiond_link_stats_t) == 80, "motiond_link_stats_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_link_stats_t) == 8, "motiond_link_stats_t alignment");

/**
 * The I/O side of one link: when bytes last went out and came in, and how often. Stamps are
 * CLOCK_MONOTONIC ns taken by the link's I/O thread right after the transport accepted or
 * returned the bytes; 0 when it never did.
 *
 * 32 bytes, alignment 8; iceoryx2 type name "motiond::LinkIo".
 */
typedef struct motiond_link_io {
    /** CLOCK_MONOTONIC ns of the last write that moved bytes; 0: never. */
    uint64_t last_write_ns; /* offset 0 */
    /** CLOCK_MONOTONIC ns of the last read that returned bytes; 0: never. */
    uint64_t last_read_ns; /* offset 8 */
    uint64_t transactions; /**< Messages written whole (SPI: transactions). (offset 16) */
    uint64_t reads; /**< Reads that returned bytes. (offset 24) */
} motiond_link_io_t;
MOTIOND_STATIC_ASSERT(sizeof(motiond_link_io_t) == 32, "motiond_link_io_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_link_io_t) == 8, "motiond_link_io_t alignment");

/**
 * Server figures, published about once a second on `motiond/<name>/stats`.
 *
 * 2016 bytes, alignment 8; iceoryx2 type name "motiond::ServerStats".
 */
typedef struct motiond_server_stats {
    uint32_t schema_version; /**< MOTIOND_SCHEMA_VERSION of the server. (offset 0) */
    uint32_t link_count; /**< Valid entries in `links`. (offset 4) */
    uint64_t tick; /**< Tick at which these figures were taken. (offset 8) */
    uint64_t time_ns; /**< CLOCK_MONOTONIC ns of that tick. (offset 16) */
    /** Wake-up latency (actual wake − deadline) since start. */
    motiond_latency_summary_t wakeup; /* offset 24 */
    motiond_latency_summary_t work; /**< Tick work time since start. (offset 64) */
    uint64_t overruns; /**< Ticks that missed their deadline since start. (offset 104) */
    uint64_t max_consecutive_overruns; /**< Longest run of consecutive overruns. (offset 112) */
    uint64_t commands; /**< Requests answered. (offset 120) */
    uint64_t rejected; /**< Requests refused. (offset 128) */
    uint32_t clients; /**< Live client nodes at the last liveness check. (offset 136) */
    /**
     * Real-time set-up bits (MOTIOND_RT_FLAGS_*): bit 0 SCHED_FIFO, bit 1 memory locked, bit 2
     * pinned, bit 3 cpu_dma_latency held.
     */
    uint32_t rt_flags; /* offset 140 */
    motiond_link_stats_t links[MOTIOND_MAX_LINKS]; /**< Per-link counters. (offset 144) */
    /** Axis faults latched by the server's supervision since start. */
    uint64_t faults; /* offset 1424 */
    /** Ticks whose frame could not be loaned or sent, since start. */
    uint64_t frames_lost; /* offset 1432 */
    /**
     * Services whose port slots are all taken now (MOTIOND_FULL_SERVICES_* bits, the `FULL_*`
     * constants): new clients are refused there until a slot frees.
     */
    uint32_t full_services; /* offset 1440 */
    /** Times a service was found with all its slots taken, since start. */
    uint32_t full_events; /* offset 1444 */
    /**
     * Info, stats and params samples that could not be loaned or sent, and tick notifications
     * that failed, since start (a lost frame counts in `frames_lost`).
     */
    uint64_t publish_failures; /* offset 1448 */
    /**
     * Command replies that could not be sent (the client vanished before its answer), since
     * start.
     */
    uint64_t replies_lost; /* offset 1456 */
    /**
     * Log reports the main thread's queue had no room for, and failed iceoryx2 housekeeping
     * (connection updates, e-stop event reads), since start.
     */
    uint64_t events_dropped; /* offset 1464 */
    /** Per link (same index as `links`): the I/O thread's stamps. */
    motiond_link_io_t link_io[MOTIOND_MAX_LINKS]; /* offset 1472 */
    /**
     * Records of dead iceoryx2 nodes removed from the service root (crashed clients, clients
     * killed while they started), since start.
     */
    uint64_t nodes_cleaned; /* offset 1984 */
    /**
     * Black-box records the tick dropped because the recorder's queue was full, since start: a
     * saved black box has a hole there, and a replay stops at it.
     */
    uint64_t blackbox_lost; /* offset 1992 */
    /**
     * Paths taken from the `paths` service and dropped, since start: no room left for their
     * node or among the claimants' paths, or their publisher gone before the tick looked
     * (docs/SECURITY.md "Paths and setpoints no other process can starve").
     */
    uint64_t paths_dropped; /* offset 2000 */
    /**
     * Setpoints taken from the `setpoints` service and dropped unread, since start: beyond
     * their node's budget of the tick, or their publisher gone before the tick looked (the
     * engine's own refusals count in motiond_group_state_t.refused).
     */
    uint64_t setpoints_dropped; /* offset 2008 */
} motiond_server_stats_t;
MOTIOND_STATIC_ASSERT(sizeof(motiond_server_stats_t) == 2016, "motiond_server_stats_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_server_stats_t) == 8, "motiond_server_stats_t alignment");

/* --- texts -------------------------------------------------------------------------------- */

/** The text of a MOTIOND_COMMAND_KIND_* value; NULL for a value unknown here. */
static inline const char *motiond_command_kind_text(uint32_t value) {
    switch (value) {
    case MOTIOND_COMMAND_KIND_STOP: return "stop";
    case MOTIOND_COMMAND_KIND_POWER: return "power";
    case MOTIOND_COMMAND_KIND_POSITION: return "position";
    case MOTIOND_COMMAND_KIND_VELOCITY: return "velocity";
    case MOTIOND_COMMAND_KIND_RAMP_POSITION: return "ramp-position";
    case MOTIOND_COMMAND_KIND_RAMP_VELOCITY: return "ramp-velocity";
    case MOTIOND_COMMAND_KIND_HOME: return "home";
    case MOTIOND_COMMAND_KIND_SET_POSITION: return "set-position";
    case MOTIOND_COMMAND_KIND_CLAIM: return "claim";
    case MOTIOND_COMMAND_KIND_RELEASE: return "release";
    case MOTIOND_COMMAND_KIND_E_STOP: return "e-stop";
    case MOTIOND_COMMAND_KIND_RESET: return "reset";
    case MOTIOND_COMMAND_KIND_OFF: return "off";
    case MOTIOND_COMMAND_KIND_SET_OUTPUT: return "set-output";
    case MOTIOND_COMMAND_KIND_RUN: return "run";
    case MOTIOND_COMMAND_KIND_HOLD: return "hold";
    case MOTIOND_COMMAND_KIND_RESUME: return "resume";
    case MOTIOND_COMMAND_KIND_FEED: return "feed";
    case MOTIOND_COMMAND_KIND_CANCEL: return "cancel";
    case MOTIOND_COMMAND_KIND_STREAM: return "stream";
    case MOTIOND_COMMAND_KIND_COMMISSION: return "commission";
    default: return NULL;
    }
}

/** The text of a MOTIOND_REASON_* value; NULL for a value unknown here. */
static inline const char *motiond_reason_text(uint32_t value) {
    switch (value) {
    case MOTIOND_REASON_ACCEPTED: return "accepted";
    case MOTIOND_REASON_SCHEMA_MISMATCH: return "client and server use different motion-ipc schema versions";
    case MOTIOND_REASON_UNKNOWN_KIND: return "unknown command kind";
    case MOTIOND_REASON_UNKNOWN_AXIS: return "no such axis on this server";
    case MOTIOND_REASON_UNSUPPORTED: return "the axis's board cannot do this command";
    case MOTIOND_REASON_NOT_FINITE: return "a value is NaN or infinite";
    case MOTIOND_REASON_OUT_OF_RANGE: return "position outside the axis's min..max soft limits, or an output level other than 0 or 1";
    case MOTIOND_REASON_VELOCITY_LIMIT: return "velocity above the axis's max_velocity, or below the smallest step its board represents";
    case MOTIOND_REASON_ACCEL_LIMIT: return "acceleration above the axis's max_accel or not positive, or below the smallest step its board represents";
    case MOTIOND_REASON_POWER_LIMIT: return "power outside -1.0..1.0";
    case MOTIOND_REASON_CLAIMED_BY_OTHER: return "the axis is claimed by another client";
    case MOTIOND_REASON_NOT_CLAIMED: return "this client holds no claim on the axis";
    case MOTIOND_REASON_ESTOP_LATCHED: return "e-stop is latched: send reset first";
    case MOTIOND_REASON_AXIS_FAULTED: return "the axis is faulted: clear the cause, then reset";
    case MOTIOND_REASON_LINK_DOWN: return "the axis's link is down";
    case MOTIOND_REASON_BUSY: return "the server's command queue is full: retry";
    case MOTIOND_REASON_SHUTTING_DOWN: return "the server is shutting down";
    case MOTIOND_REASON_NO_CLIENT_ID: return "claim and release need a client id";
    case MOTIOND_REASON_IDENTITY_MISMATCH: return "the request's client id is not the sender's iceoryx2 node: ids cannot be borrowed";
    case MOTIOND_REASON_DEVICE_STARTING: return "the axis's board is starting: its link is not open yet, or it awaits its first answer and its start-up stop";
    case MOTIOND_REASON_DEVICE_OFFLINE: return "the axis's board is not answering";
    case MOTIOND_REASON_UNKNOWN_SIGNAL: return "no such signal on this server";
    case MOTIOND_REASON_NOT_AN_OUTPUT: return "the signal is not an output (a digital output, or a trigger's compare position)";
    case MOTIOND_REASON_UNKNOWN_TARGET: return "unknown target: 0 = axis, 1 = signal, 2 = group, 3 = device";
    case MOTIOND_REASON_UNKNOWN_GROUP: return "no such group on this server";
    case MOTIOND_REASON_NO_PATH: return "no path with this id for this group was published by this client on `paths` (publish it first; a path runs once)";
    case MOTIOND_REASON_PATH_TIMES: return "the path's point times must start at 0 or later and increase";
    case MOTIOND_REASON_PATH_START: return "the path's first point has time 0 but is not where the group is";
    case MOTIOND_REASON_PATH_LAYOUT: return "malformed path: no points, too many, an axis count other than the group's, an unknown kind, or a scale outside (0, 1]";
    case MOTIOND_REASON_GROUP_BUSY: return "an axis of this request is moving (with a group, or on its own, still stopping): cancel that motion or wait for the axis to rest";
    case MOTIOND_REASON_NOT_MOVING: return "the group has no motion running, or the axis no position move to hold or held move to resume";
    case MOTIOND_REASON_BLEND_TOLERANCE: return "positions alone cannot be blended at this point within the axis's path_tolerance at its max_accel: space the points further apart, or send velocities";
    case MOTIOND_REASON_UNKNOWN_DEVICE: return "no such device on this server";
    default: return NULL;
    }
}

/** The text of a MOTIOND_DEVICE_STATE_* value; NULL for a value unknown here. */
static inline const char *motiond_device_state_text(uint32_t value) {
    switch (value) {
    case MOTIOND_DEVICE_STATE_OFFLINE: return "offline";
    case MOTIOND_DEVICE_STATE_ONLINE: return "online";
    case MOTIOND_DEVICE_STATE_STARTING: return "starting";
    case MOTIOND_DEVICE_STATE_FAULTED: return "faulted";
    default: return NULL;
    }
}

/** The text of a MOTIOND_FAULT_CODE_* value; NULL for a value unknown here. */
static inline const char *motiond_fault_code_text(uint32_t value) {
    switch (value) {
    case MOTIOND_FAULT_CODE_NONE: return "none";
    case MOTIOND_FAULT_CODE_LINK_DOWN: return "link-down";
    case MOTIOND_FAULT_CODE_BOARD_NOT_RESPONDING: return "board-not-responding";
    case MOTIOND_FAULT_CODE_BOARD_RESET: return "board-reset";
    case MOTIOND_FAULT_CODE_BOARD_ERROR: return "board-error";
    case MOTIOND_FAULT_CODE_PROTOCOL: return "protocol";
    case MOTIOND_FAULT_CODE_OVERSPEED: return "overspeed";
    case MOTIOND_FAULT_CODE_LIMIT_SWITCH: return "limit-switch";
    case MOTIOND_FAULT_CODE_OVERRUN: return "overrun";
    case MOTIOND_FAULT_CODE_FOLLOWING_ERROR: return "following-error";
    case MOTIOND_FAULT_CODE_LIMIT_EXCEEDED: return "limit-exceeded";
    case MOTIOND_FAULT_CODE_HOME_FAILED: return "home-failed";
    case MOTIOND_FAULT_CODE_GOAL_TOLERANCE: return "goal-tolerance";
    default: return NULL;
    }
}

/** The text of a MOTIOND_SIGNAL_KIND_* value; NULL for a value unknown here. */
static inline const char *motiond_signal_kind_text(uint32_t value) {
    switch (value) {
    case MOTIOND_SIGNAL_KIND_DIGITAL_IN: return "digital-in";
    case MOTIOND_SIGNAL_KIND_DIGITAL_OUT: return "digital-out";
    case MOTIOND_SIGNAL_KIND_ANALOG_IN: return "analog-in";
    case MOTIOND_SIGNAL_KIND_CAPTURE: return "capture";
    case MOTIOND_SIGNAL_KIND_TRIGGER: return "trigger";
    default: return NULL;
    }
}

/** The text of a MOTIOND_ESTOP_CATEGORY_* value; NULL for a value unknown here. */
static inline const char *motiond_estop_category_text(uint32_t value) {
    switch (value) {
    case MOTIOND_ESTOP_CATEGORY_HOLD: return "hold";
    case MOTIOND_ESTOP_CATEGORY_STOP_OFF: return "stop-off";
    case MOTIOND_ESTOP_CATEGORY_OFF: return "off";
    default: return NULL;
    }
}

/** The text of a MOTIOND_DEVICE_MODEL_* value; NULL for a value unknown here. */
static inline const char *motiond_device_model_text(uint32_t value) {
    switch (value) {
    case MOTIOND_DEVICE_MODEL_QQ2DRV: return "qq2drv";
    case MOTIOND_DEVICE_MODEL_TMCPACK: return "tmcpack";
    case MOTIOND_DEVICE_MODEL_SPIMOTOR: return "spimotor";
    case MOTIOND_DEVICE_MODEL_QSB: return "qsb";
    default: return NULL;
    }
}

/** The text of a MOTIOND_GROUP_MOTION_* value; NULL for a value unknown here. */
static inline const char *motiond_group_motion_text(uint32_t value) {
    switch (value) {
    case MOTIOND_GROUP_MOTION_IDLE: return "idle";
    case MOTIOND_GROUP_MOTION_MOVING: return "moving";
    case MOTIOND_GROUP_MOTION_HOLDING: return "holding";
    case MOTIOND_GROUP_MOTION_HELD: return "held";
    case MOTIOND_GROUP_MOTION_DONE: return "done";
    case MOTIOND_GROUP_MOTION_ABORTED: return "aborted";
    default: return NULL;
    }
}

/** The text of a MOTIOND_GROUP_ABORT_* value; NULL for a value unknown here. */
static inline const char *motiond_group_abort_text(uint32_t value) {
    switch (value) {
    case MOTIOND_GROUP_ABORT_NONE: return "none";
    case MOTIOND_GROUP_ABORT_PATH_TOLERANCE: return "path-tolerance";
    case MOTIOND_GROUP_ABORT_GOAL_TOLERANCE: return "goal-tolerance";
    case MOTIOND_GROUP_ABORT_AXIS_FAULT: return "axis-fault";
    case MOTIOND_GROUP_ABORT_E_STOP: return "e-stop";
    case MOTIOND_GROUP_ABORT_CLAIM_LOST: return "claim-lost";
    case MOTIOND_GROUP_ABORT_CLIENT_DEAD: return "client-dead";
    case MOTIOND_GROUP_ABORT_STOPPED: return "stopped";
    case MOTIOND_GROUP_ABORT_CANCELLED: return "cancelled";
    case MOTIOND_GROUP_ABORT_STREAM_STALE: return "stream-stale";
    case MOTIOND_GROUP_ABORT_STREAM_LIMIT: return "stream-limit";
    case MOTIOND_GROUP_ABORT_SHUTTING_DOWN: return "shutting-down";
    case MOTIOND_GROUP_ABORT_GOAL_REFUSED: return "goal-refused";
    default: return NULL;
    }
}

/** The text of a MOTIOND_STREAM_STATE_* value; NULL for a value unknown here. */
static inline const char *motiond_stream_state_text(uint32_t value) {
    switch (value) {
    case MOTIOND_STREAM_STATE_IDLE: return "idle";
    case MOTIOND_STREAM_STATE_STREAMING: return "streaming";
    case MOTIOND_STREAM_STATE_STALE: return "stale";
    case MOTIOND_STREAM_STATE_ABORTED: return "aborted";
    default: return NULL;
    }
}

/** The text of a MOTIOND_COMMISSION_WHAT_* value; NULL for a value unknown here. */
static inline const char *motiond_commission_what_text(uint32_t value) {
    switch (value) {
    case MOTIOND_COMMISSION_WHAT_ADDRESS: return "address";
    case MOTIOND_COMMISSION_WHAT_BAUD: return "baud";
    case MOTIOND_COMMISSION_WHAT_FACTORY_RESET: return "factory-reset";
    default: return NULL;
    }
}

/** The text of a MOTIOND_STREAM_MODE_* value; NULL for a value unknown here. */
static inline const char *motiond_stream_mode_text(uint32_t value) {
    switch (value) {
    case MOTIOND_STREAM_MODE_NONE: return "none";
    case MOTIOND_STREAM_MODE_POSITION: return "position";
    case MOTIOND_STREAM_MODE_VELOCITY: return "velocity";
    case MOTIOND_STREAM_MODE_POWER: return "power";
    default: return NULL;
    }
}

/** The text of a MOTIOND_PATH_KIND_* value; NULL for a value unknown here. */
static inline const char *motiond_path_kind_text(uint32_t value) {
    switch (value) {
    case MOTIOND_PATH_KIND_NONE: return "none";
    case MOTIOND_PATH_KIND_LINE: return "line";
    case MOTIOND_PATH_KIND_TRAJECTORY: return "trajectory";
    case MOTIOND_PATH_KIND_STREAM: return "stream";
    default: return NULL;
    }
}

/* --- helpers ------------------------------------------------------------------------------ */

/** A client id from an iceoryx2 node id given as its two 64-bit halves. */
static inline motiond_client_id_t motiond_client_id(uint64_t lo, uint64_t hi) {
    motiond_client_id_t id;
    id.lo = lo;
    id.hi = hi;
    return id;
}

/** A request of this schema: kind on axis (or signal) index, values zero. */
static inline motiond_command_request_t motiond_command_request(
    uint32_t kind, uint32_t axis, uint64_t sequence) {
    motiond_command_request_t request;
    request.schema_version = MOTIOND_SCHEMA_VERSION;
    request.kind = kind;
    request.client = motiond_client_id(0, 0);
    request.sequence = sequence;
    request.axis = axis;
    request.target = MOTIOND_TARGET_AXIS;
    request.values[0] = 0.0;
    request.values[1] = 0.0;
    request.values[2] = 0.0;
    return request;
}

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* MOTIOND_H */
