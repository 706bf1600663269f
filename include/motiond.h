/*
 * motiond.h - the shared-memory contract of motiond for C (C11) and C++ clients.
 *
 * motiond publishes its state and takes commands over iceoryx2 services. Every payload
 * is a fixed-size #[repr(C)] Rust struct (crate motion-ipc); this header mirrors each one
 * field by field, in memory order, with the iceoryx2 type name a port must announce
 * (iceoryx2 only connects ports whose payload type name, size and alignment match the
 * server's). The Rust test crates/motion-ipc/tests/c_header.rs compiles a probe against
 * this header and compares every size, alignment, offset, field type, constant, enum
 * value, text and type name with the Rust definitions; it runs with ./scripts/test.
 *
 * Services of the instance NAME ([server] name in the server's config), with their
 * payloads (user header: none, i.e. iceoryx2's "()" of size 0, alignment 1):
 *
 *   motiond/NAME/frame    publish-subscribe, history 1    motiond_motion_frame_t, every tick
 *   motiond/NAME/tick     event                           notified after every frame
 *   motiond/NAME/command  request-response                motiond_command_request_t ->
 *                                                         motiond_command_reply_t
 *   motiond/NAME/info     publish-subscribe, history 1    motiond_server_info_t
 *   motiond/NAME/stats    publish-subscribe, history 1    motiond_server_stats_t, about 1 Hz
 *   motiond/NAME/params   publish-subscribe, history 1    motiond_machine_params_t
 *   motiond/NAME/estop    event                           any notification latches the e-stop
 *
 * Open the services, never create them. Enumerations travel as the plain integer fields
 * named in each struct; compare them with the MOTIOND_* constants below. Text fields are
 * UTF-8, zero padded (not necessarily zero terminated when full).
 *
 * examples/c/ holds a complete program (frames in, a command out) on iceoryx2's C API.
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

/* --- constants ------------------------------------------------------------------------ */

/** Version of the contract; every payload carries it. */
#define MOTIOND_SCHEMA_VERSION 5u
/** Capacity of the axis arrays of the frame and the server info. */
#define MOTIOND_MAX_AXES 128u
/** Capacity of the device array of the server info. */
#define MOTIOND_MAX_DEVICES 32u
/** Capacity of the link array of the server stats. */
#define MOTIOND_MAX_LINKS 16u
/** Capacity of the signal arrays of the frame and the server info. */
#define MOTIOND_MAX_SIGNALS 64u
/** Capacity of the machine parameter table. */
#define MOTIOND_MAX_PARAMS 2048u
/** Bytes of a name field. */
#define MOTIOND_NAME_LEN 32u
/** Bytes of a unit field. */
#define MOTIOND_UNIT_LEN 16u
/** Bytes of a parameter key or value text. */
#define MOTIOND_PARAM_TEXT_LEN 40u
/** motiond_command_request_t.axis addressing every axis (stop, e-stop, reset, off). */
#define MOTIOND_ALL_AXES 0xFFFFFFFFu

/* Service names: printf formats taking the instance name. */
#define MOTIOND_SERVICE_FRAME "motiond/%s/frame"
#define MOTIOND_SERVICE_TICK "motiond/%s/tick"
#define MOTIOND_SERVICE_COMMAND "motiond/%s/command"
#define MOTIOND_SERVICE_INFO "motiond/%s/info"
#define MOTIOND_SERVICE_STATS "motiond/%s/stats"
#define MOTIOND_SERVICE_PARAMS "motiond/%s/params"
#define MOTIOND_SERVICE_ESTOP "motiond/%s/estop"
/** The iceoryx2 node name of the server of an instance. */
#define MOTIOND_SERVICE_SERVER_NODE "motiond-%s"

/* iceoryx2 type names of the payloads. */
#define MOTIOND_TYPE_NAME_CLIENT_ID "motiond::ClientId"
#define MOTIOND_TYPE_NAME_AXIS_STATE "motiond::AxisState"
#define MOTIOND_TYPE_NAME_SIGNAL_STATE "motiond::SignalState"
#define MOTIOND_TYPE_NAME_AXIS_WIRE "motiond::AxisWire"
#define MOTIOND_TYPE_NAME_MOTION_FRAME "motiond::MotionFrame"
#define MOTIOND_TYPE_NAME_COMMAND_REQUEST "motiond::CommandRequest"
#define MOTIOND_TYPE_NAME_COMMAND_REPLY "motiond::CommandReply"
#define MOTIOND_TYPE_NAME_AXIS_INFO "motiond::AxisInfo"
#define MOTIOND_TYPE_NAME_DEVICE_INFO "motiond::DeviceInfo"
#define MOTIOND_TYPE_NAME_SIGNAL_INFO "motiond::SignalInfo"
#define MOTIOND_TYPE_NAME_SERVER_INFO "motiond::ServerInfo"
#define MOTIOND_TYPE_NAME_MACHINE_PARAM "motiond::MachineParam"
#define MOTIOND_TYPE_NAME_MACHINE_PARAMS "motiond::MachineParams"
#define MOTIOND_TYPE_NAME_LATENCY_SUMMARY "motiond::LatencySummary"
#define MOTIOND_TYPE_NAME_LINK_STATS "motiond::LinkStats"
#define MOTIOND_TYPE_NAME_LINK_IO "motiond::LinkIo"
#define MOTIOND_TYPE_NAME_SERVER_STATS "motiond::ServerStats"

/* --- enumerations (values of the integer fields) ----------------------------------------- */

/**
 * What a request asks for (motiond_command_request_t.kind). values[] per kind; 0.0 in a
 * velocity or acceleration slot means the axis's configured maximum:
 *   STOP -; POWER [power -1..1]; POSITION [position]; VELOCITY [velocity];
 *   RAMP_POSITION [position, max velocity, acceleration]; RAMP_VELOCITY [velocity,
 *   acceleration]; HOME [search velocity]; SET_POSITION [position];
 *   SET_OUTPUT [0.0 or 1.0] (axis = signal index, target = MOTIOND_TARGET_SIGNAL);
 *   CLAIM, RELEASE, E_STOP, RESET, OFF -.
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
    MOTIOND_COMMAND_KIND_SET_OUTPUT = 14
};

/** Why a request was refused (motiond_command_reply_t.reason); 0 = accepted. */
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
    MOTIOND_REASON_UNKNOWN_TARGET = 23
};

/** What motiond_command_request_t.axis indexes (motiond_command_request_t.target). */
enum motiond_target {
    MOTIOND_TARGET_AXIS = 0,
    MOTIOND_TARGET_SIGNAL = 1
};

/** Where a board is in its life (frame.devices[], axis device_state, device info state). */
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
    MOTIOND_AXIS_MODE_STOPPING = 8
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
    MOTIOND_FAULT_CODE_HOME_FAILED = 11
};

/** What a signal is (signal state and signal info kind). */
enum motiond_signal_kind {
    MOTIOND_SIGNAL_KIND_DIGITAL_IN = 1,
    MOTIOND_SIGNAL_KIND_DIGITAL_OUT = 2,
    MOTIOND_SIGNAL_KIND_ANALOG_IN = 3
};

/** What an e-stop (and a fault) does to an axis (motiond_axis_info_t.estop). */
enum motiond_estop_category {
    MOTIOND_ESTOP_CATEGORY_HOLD = 0,
    MOTIOND_ESTOP_CATEGORY_STOP_OFF = 1,
    MOTIOND_ESTOP_CATEGORY_OFF = 2
};

/** The board model of a device (motiond_device_info_t.model). */
enum motiond_device_model {
    MOTIOND_DEVICE_MODEL_QQ2DRV = 1,
    MOTIOND_DEVICE_MODEL_TMCPACK = 2,
    MOTIOND_DEVICE_MODEL_SPIMOTOR = 3,
    MOTIOND_DEVICE_MODEL_QSB = 4
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
    MOTIOND_AXIS_FLAGS_DEADMAN_EXPIRED = 1 << 8
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
    MOTIOND_FULL_SERVICES_ESTOP = 1 << 6
};

/* --- payloads ------------------------------------------------------------------------- */

/** The iceoryx2 node id of a client (a 128-bit value) in two halves; zero = no client. */
typedef struct motiond_client_id {
    uint64_t lo; /**< low 64 bits */
    uint64_t hi; /**< high 64 bits */
} motiond_client_id_t;

/** One axis in a frame. 80 bytes, alignment 8. */
typedef struct motiond_axis_state {
    double position;                /**< measured position, axis units */
    double velocity;                /**< measured velocity, units/s */
    double target;                  /**< position target, or velocity target in velocity modes */
    int64_t raw_counts;             /**< the board's own position counts */
    uint64_t last_refresh_tick;     /**< tick at which fresh data last arrived */
    uint32_t flags;                 /**< MOTIOND_AXIS_FLAGS_* bits */
    uint16_t fault;                 /**< MOTIOND_FAULT_CODE_* */
    uint8_t mode;                   /**< MOTIOND_AXIS_MODE_* */
    uint8_t device_state;           /**< MOTIOND_DEVICE_STATE_* of the axis's board */
    motiond_client_id_t claimed_by; /**< claim holder, zero when unclaimed */
    double fault_value;             /**< measured figure of the fault, 0 when none */
    double fault_limit;             /**< the tolerance it broke, 0 when none */
} motiond_axis_state_t;

/** One signal in a frame. 48 bytes, alignment 8. */
typedef struct motiond_signal_state {
    double value;                   /**< logical value (digital 0/1 after invert; analogue scaled) */
    double raw;                     /**< as the board reports it (level 0/1, ADC counts) */
    uint64_t last_refresh_tick;     /**< tick at which the board last reported (acknowledged) it */
    uint32_t flags;                 /**< MOTIOND_SIGNAL_FLAGS_* bits */
    uint8_t kind;                   /**< MOTIOND_SIGNAL_KIND_* */
    uint8_t reserved[3];            /**< zero */
    motiond_client_id_t claimed_by; /**< claim holder of an output, zero when unclaimed */
} motiond_signal_state_t;

/** When an axis's current goal was set and its first request reached the wire. 24 bytes.
 *  Command -> wire: wire_ns minus the client's CLOCK_MONOTONIC at sending, or in ticks
 *  wire_tick - goal_tick (0: written in the tick that accepted it). */
typedef struct motiond_axis_wire {
    uint64_t goal_tick; /**< tick in which the current goal was set */
    uint64_t wire_tick; /**< tick during which its first request was written, 0 until then */
    uint64_t wire_ns;   /**< CLOCK_MONOTONIC ns of that write, 0 until then */
} motiond_axis_wire_t;

/** One consistent snapshot of every axis, board and signal, once per tick. 16464 bytes. */
typedef struct motiond_motion_frame {
    uint32_t schema_version;                           /**< MOTIOND_SCHEMA_VERSION */
    uint32_t axis_count;                               /**< valid entries of axes */
    uint64_t tick;                                     /**< tick number, 0 at server start */
    uint64_t time_ns;                                  /**< the tick's deadline, CLOCK_MONOTONIC ns */
    uint64_t publish_ns;                               /**< CLOCK_MONOTONIC ns just before sending */
    uint32_t flags;                                    /**< MOTIOND_FRAME_FLAGS_* bits */
    uint32_t signal_count;                             /**< valid entries of signals */
    uint32_t device_count;                             /**< valid entries of devices */
    uint32_t reserved;                                 /**< zero */
    uint8_t devices[MOTIOND_MAX_DEVICES];              /**< MOTIOND_DEVICE_STATE_* per device */
    motiond_axis_state_t axes[MOTIOND_MAX_AXES];       /**< axes in config order */
    motiond_signal_state_t signals[MOTIOND_MAX_SIGNALS]; /**< signals in config order */
    motiond_axis_wire_t wire[MOTIOND_MAX_AXES];        /**< per axis (index of axes): goal set / on the wire */
} motiond_motion_frame_t;

/** A command to the server. 64 bytes, alignment 8. */
typedef struct motiond_command_request {
    uint32_t schema_version;    /**< MOTIOND_SCHEMA_VERSION */
    uint32_t kind;              /**< MOTIOND_COMMAND_KIND_* */
    motiond_client_id_t client; /**< the sender's iceoryx2 node id, or zero ("the sender") */
    uint64_t sequence;          /**< the client's sequence number, echoed in the reply */
    uint32_t axis;              /**< axis or signal index (config order), or MOTIOND_ALL_AXES */
    uint32_t target;            /**< MOTIOND_TARGET_* */
    double values[3];           /**< arguments, see enum motiond_command_kind */
} motiond_command_request_t;

/** The server's answer to one request. 32 bytes, alignment 8. */
typedef struct motiond_command_reply {
    uint32_t schema_version; /**< MOTIOND_SCHEMA_VERSION */
    uint32_t reason;         /**< MOTIOND_REASON_*; 0 = accepted */
    uint64_t sequence;       /**< the request's sequence */
    uint64_t tick_applied;   /**< tick in which it took effect (or was refused) */
    uint32_t axis;           /**< the request's axis */
    uint32_t kind;           /**< the request's kind */
} motiond_command_reply_t;

/** One axis's static description. 160 bytes, alignment 8. */
typedef struct motiond_axis_info {
    uint8_t name[MOTIOND_NAME_LEN];   /**< axis name */
    uint8_t unit[MOTIOND_UNIT_LEN];   /**< unit ("mm", "deg") */
    uint8_t device[MOTIOND_NAME_LEN]; /**< device name */
    double counts_per_unit;           /**< device counts per unit */
    double min;                       /**< soft limit, units */
    double max;                       /**< soft limit, units */
    double max_velocity;              /**< units/s */
    double max_accel;                 /**< units/s^2 */
    uint32_t capabilities;            /**< bit (1 << kind) set for every command kind accepted */
    uint16_t channel;                 /**< motor number on the device */
    uint16_t device_index;            /**< index into the server info's devices */
    double following_error;           /**< units; 0 = not supervised */
    double overspeed_factor;          /**< x max_velocity; 0 = not supervised */
    double home_max_travel;           /**< units; 0 = not supervised */
    uint32_t estop;                   /**< MOTIOND_ESTOP_CATEGORY_* */
    uint32_t reserved;                /**< zero */
} motiond_axis_info_t;

/** One device's description. 112 bytes, alignment 4. */
typedef struct motiond_device_info {
    uint8_t name[MOTIOND_NAME_LEN];     /**< device name */
    uint8_t link[MOTIOND_NAME_LEN];     /**< link name */
    uint8_t firmware[MOTIOND_NAME_LEN]; /**< firmware as the board reported it ("" until known) */
    uint32_t model;                     /**< MOTIOND_DEVICE_MODEL_* */
    uint32_t address;                   /**< bus address (0 when the model has none) */
    uint32_t axis_count;                /**< axes configured on the device */
    uint32_t state;                     /**< MOTIOND_DEVICE_STATE_* when published */
} motiond_device_info_t;

/** One signal's static description. 128 bytes, alignment 8. */
typedef struct motiond_signal_info {
    uint8_t name[MOTIOND_NAME_LEN];   /**< signal name */
    uint8_t unit[MOTIOND_UNIT_LEN];   /**< unit of an analogue value ("" for digital) */
    uint8_t device[MOTIOND_NAME_LEN]; /**< device name */
    double scale;                     /**< analogue: value = raw * scale + offset */
    double offset;                    /**< analogue: value = raw * scale + offset */
    double full_scale;                /**< raw full scale (1023 for 10 bits; 1 for digital) */
    uint8_t kind;                     /**< MOTIOND_SIGNAL_KIND_* */
    uint8_t flags;                    /**< MOTIOND_SIGNAL_INFO_FLAGS_* bits */
    uint16_t device_index;            /**< index into the server info's devices */
    uint8_t pin[MOTIOND_UNIT_LEN];    /**< the board's pin name ("ttlio1") */
    uint32_t reserved;                /**< zero */
} motiond_signal_info_t;

/** The server's static description. 32328 bytes, alignment 8. */
typedef struct motiond_server_info {
    uint32_t schema_version;                           /**< MOTIOND_SCHEMA_VERSION */
    uint32_t axis_count;                               /**< valid entries of axes */
    uint32_t device_count;                             /**< valid entries of devices */
    uint32_t tick_hz;                                  /**< tick rate */
    uint32_t command_timeout_ms;                       /**< deadman; 0 = disabled */
    uint32_t max_clients;                              /**< configured client limit */
    uint32_t server_pid;                               /**< process id of motiond */
    uint32_t signal_count;                             /**< valid entries of signals */
    uint8_t name[MOTIOND_NAME_LEN];                    /**< instance name */
    uint64_t start_time_ns;                            /**< CLOCK_MONOTONIC ns of tick 0 */
    motiond_axis_info_t axes[MOTIOND_MAX_AXES];        /**< axes in config order */
    motiond_device_info_t devices[MOTIOND_MAX_DEVICES]; /**< devices in config order */
    motiond_signal_info_t signals[MOTIOND_MAX_SIGNALS]; /**< signals in config order */
} motiond_server_info_t;

/** One effective machine parameter. 88 bytes, alignment 4. */
typedef struct motiond_machine_param {
    uint8_t key[MOTIOND_PARAM_TEXT_LEN];   /**< config key, dotted for tables */
    uint8_t value[MOTIOND_PARAM_TEXT_LEN]; /**< value in effect, with its unit */
    uint16_t owner_index;                  /**< device or axis index */
    uint8_t owner_kind;                    /**< MOTIOND_PARAM_OWNER_* */
    uint8_t from_config;                   /**< 1: set by the config file; 0: the default */
    uint32_t reserved;                     /**< zero */
} motiond_machine_param_t;

/** Every machine parameter in effect. 180240 bytes, alignment 4. */
typedef struct motiond_machine_params {
    uint32_t schema_version;                            /**< MOTIOND_SCHEMA_VERSION */
    uint32_t count;                                     /**< valid entries */
    uint32_t truncated;                                 /**< 1 when parameters were left out */
    uint32_t reserved;                                  /**< zero */
    motiond_machine_param_t entries[MOTIOND_MAX_PARAMS]; /**< devices' then axes' */
} motiond_machine_params_t;

/** Percentiles of one latency distribution, ns. 40 bytes. */
typedef struct motiond_latency_summary {
    uint64_t samples;
    uint64_t p50_ns;
    uint64_t p99_ns;
    uint64_t p999_ns;
    uint64_t max_ns;
} motiond_latency_summary_t;

/** Counters of one link since start. 80 bytes, alignment 8. */
typedef struct motiond_link_stats {
    uint8_t name[MOTIOND_NAME_LEN]; /**< link name */
    uint64_t bytes_in;              /**< bytes received */
    uint64_t bytes_out;             /**< bytes sent */
    uint64_t frames;                /**< replies decoded */
    uint64_t errors;                /**< bad frames, I/O errors, timeouts */
    uint64_t reconnects;            /**< successful reopens */
    uint32_t up;                    /**< 1 when the link is open */
    uint32_t reserved;              /**< zero */
} motiond_link_stats_t;

/** The I/O side of one link (CLOCK_MONOTONIC ns stamps, 0: never). 32 bytes, alignment 8. */
typedef struct motiond_link_io {
    uint64_t last_write_ns; /**< the last write that moved bytes */
    uint64_t last_read_ns;  /**< the last read that returned bytes */
    uint64_t transactions;  /**< messages written whole (SPI: transactions) */
    uint64_t reads;         /**< reads that returned bytes */
} motiond_link_io_t;

/** Server figures, published about once a second. 1992 bytes, alignment 8. */
typedef struct motiond_server_stats {
    uint32_t schema_version;                    /**< MOTIOND_SCHEMA_VERSION */
    uint32_t link_count;                        /**< valid entries of links */
    uint64_t tick;                              /**< tick at which these were taken */
    uint64_t time_ns;                           /**< CLOCK_MONOTONIC ns of that tick */
    motiond_latency_summary_t wakeup;           /**< actual wake - deadline, since start */
    motiond_latency_summary_t work;             /**< tick work time, since start */
    uint64_t overruns;                          /**< ticks that missed their deadline */
    uint64_t max_consecutive_overruns;          /**< longest run of overruns */
    uint64_t commands;                          /**< requests answered */
    uint64_t rejected;                          /**< requests refused */
    uint32_t clients;                           /**< live client nodes at the last check */
    uint32_t rt_flags;                          /**< MOTIOND_RT_FLAGS_* bits */
    motiond_link_stats_t links[MOTIOND_MAX_LINKS]; /**< per link */
    uint64_t faults;                            /**< axis faults latched since start */
    uint64_t frames_lost;                       /**< ticks whose frame could not be sent */
    uint32_t full_services;                     /**< MOTIOND_FULL_SERVICES_* bits, now */
    uint32_t full_events;                       /**< times a service was found full */
    uint64_t publish_failures;                  /**< info/stats/params samples and tick notifications not sent */
    uint64_t replies_lost;                      /**< command replies that could not be sent */
    uint64_t events_dropped;                    /**< log reports and iceoryx2 housekeeping that failed */
    motiond_link_io_t link_io[MOTIOND_MAX_LINKS]; /**< per link (index of links): I/O stamps */
    uint64_t nodes_cleaned;                     /**< dead iceoryx2 nodes' records removed */
} motiond_server_stats_t;

/* Sizes and alignments the Rust side pins (crates/motion-ipc/tests/layout.rs). */
MOTIOND_STATIC_ASSERT(sizeof(motiond_client_id_t) == 16, "motiond_client_id_t size");
MOTIOND_STATIC_ASSERT(sizeof(motiond_axis_state_t) == 80, "motiond_axis_state_t size");
MOTIOND_STATIC_ASSERT(sizeof(motiond_signal_state_t) == 48, "motiond_signal_state_t size");
MOTIOND_STATIC_ASSERT(sizeof(motiond_axis_wire_t) == 24, "motiond_axis_wire_t size");
MOTIOND_STATIC_ASSERT(sizeof(motiond_motion_frame_t) == 16464, "motiond_motion_frame_t size");
MOTIOND_STATIC_ASSERT(sizeof(motiond_command_request_t) == 64, "motiond_command_request_t size");
MOTIOND_STATIC_ASSERT(sizeof(motiond_command_reply_t) == 32, "motiond_command_reply_t size");
MOTIOND_STATIC_ASSERT(sizeof(motiond_axis_info_t) == 160, "motiond_axis_info_t size");
MOTIOND_STATIC_ASSERT(sizeof(motiond_device_info_t) == 112, "motiond_device_info_t size");
MOTIOND_STATIC_ASSERT(sizeof(motiond_signal_info_t) == 128, "motiond_signal_info_t size");
MOTIOND_STATIC_ASSERT(sizeof(motiond_server_info_t) == 32328, "motiond_server_info_t size");
MOTIOND_STATIC_ASSERT(sizeof(motiond_machine_param_t) == 88, "motiond_machine_param_t size");
MOTIOND_STATIC_ASSERT(sizeof(motiond_machine_params_t) == 180240, "motiond_machine_params_t size");
MOTIOND_STATIC_ASSERT(sizeof(motiond_latency_summary_t) == 40, "motiond_latency_summary_t size");
MOTIOND_STATIC_ASSERT(sizeof(motiond_link_stats_t) == 80, "motiond_link_stats_t size");
MOTIOND_STATIC_ASSERT(sizeof(motiond_link_io_t) == 32, "motiond_link_io_t size");
MOTIOND_STATIC_ASSERT(sizeof(motiond_server_stats_t) == 1992, "motiond_server_stats_t size");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_motion_frame_t) == 8, "motiond_motion_frame_t align");
MOTIOND_STATIC_ASSERT(MOTIOND_ALIGNOF(motiond_machine_params_t) == 4, "motiond_machine_params_t align");

/* --- texts ---------------------------------------------------------------------------- */

/** The server's one-line explanation of a refusal reason; NULL for a value unknown here. */
static inline const char *motiond_reason_text(uint32_t reason) {
    switch (reason) {
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
    case MOTIOND_REASON_NOT_AN_OUTPUT: return "the signal is not a digital output";
    case MOTIOND_REASON_UNKNOWN_TARGET: return "unknown target: 0 = axis, 1 = signal";
    default: return NULL;
    }
}

/** The command's name as the CLI and logs spell it; NULL for a value unknown here. */
static inline const char *motiond_command_kind_text(uint32_t kind) {
    switch (kind) {
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
    default: return NULL;
    }
}

/** A device state's name; NULL for a value unknown here. */
static inline const char *motiond_device_state_text(uint32_t state) {
    switch (state) {
    case MOTIOND_DEVICE_STATE_OFFLINE: return "offline";
    case MOTIOND_DEVICE_STATE_ONLINE: return "online";
    case MOTIOND_DEVICE_STATE_STARTING: return "starting";
    case MOTIOND_DEVICE_STATE_FAULTED: return "faulted";
    default: return NULL;
    }
}

/** A fault code's name; NULL for a value unknown here. */
static inline const char *motiond_fault_code_text(uint32_t fault) {
    switch (fault) {
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
    default: return NULL;
    }
}

/** A signal kind's config name; NULL for a value unknown here. */
static inline const char *motiond_signal_kind_text(uint32_t kind) {
    switch (kind) {
    case MOTIOND_SIGNAL_KIND_DIGITAL_IN: return "digital-in";
    case MOTIOND_SIGNAL_KIND_DIGITAL_OUT: return "digital-out";
    case MOTIOND_SIGNAL_KIND_ANALOG_IN: return "analog-in";
    default: return NULL;
    }
}

/** An e-stop category's config name; NULL for a value unknown here. */
static inline const char *motiond_estop_category_text(uint32_t category) {
    switch (category) {
    case MOTIOND_ESTOP_CATEGORY_HOLD: return "hold";
    case MOTIOND_ESTOP_CATEGORY_STOP_OFF: return "stop-off";
    case MOTIOND_ESTOP_CATEGORY_OFF: return "off";
    default: return NULL;
    }
}

/** A device model's config id ("qq2drv"); NULL for a value unknown here. */
static inline const char *motiond_device_model_text(uint32_t model) {
    switch (model) {
    case MOTIOND_DEVICE_MODEL_QQ2DRV: return "qq2drv";
    case MOTIOND_DEVICE_MODEL_TMCPACK: return "tmcpack";
    case MOTIOND_DEVICE_MODEL_SPIMOTOR: return "spimotor";
    case MOTIOND_DEVICE_MODEL_QSB: return "qsb";
    default: return NULL;
    }
}

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
