//! The shared-memory contract between `motiond` and its clients.
//!
//! This is the only crate a client shares with the server. It defines the payload types of
//! the iceoryx2 services listed in docs/ARCHITECTURE.md ("Shared-memory contract"), their service
//! names, the command kinds and the reason codes, and the schema version. Every payload is
//! `#[repr(C)]`, fixed size, [`ZeroCopySend`](iceoryx2::prelude::ZeroCopySend) and carries
//! an explicit iceoryx2 type name, so that C, C++ and Python iceoryx2 clients can mirror
//! the layout field by field. Each payload is declared once, with its docs, and described
//! by [`schema`]: `include/motiond.h` (every offset and size in its comments) and the
//! Python package's ctypes mirrors are generated from that description
//! (`cargo run -p motion-ipc --example gen`); `tests/layout.rs` pins sizes and offsets.
//!
//! Enumerations travel as plain integers (`u8`/`u16`/`u32` fields) so that a value unknown
//! to an older client is never undefined behaviour; the typed view is obtained with
//! `TryFrom`, and helpers such as [`AxisState::mode`] do that for you.
//!
//! ```
//! use motion_ipc::{CommandKind, CommandRequest, ClientId, ServiceNames};
//!
//! let names = ServiceNames::new("demo");
//! assert_eq!(names.frame(), "motiond/demo/frame");
//!
//! let request = CommandRequest::new(ClientId::from_u128(7), 1, 3, CommandKind::RampPosition)
//!     .with_values([12.5, 40.0, 200.0]);
//! assert_eq!(request.kind(), Ok(CommandKind::RampPosition));
//! ```
#![warn(missing_docs)]
#![forbid(unsafe_code)]

// `payload!`, `flag_set!` and `enumeration!` first: the modules below use them.
#[macro_use]
mod payload;
#[macro_use]
mod flag_set;
#[macro_use]
mod enumeration;

mod command;
mod commission;
mod frame;
mod group;
mod info;
mod params;
mod pid_file;
pub mod playout;
pub mod rules;
pub mod schema;
mod service;
mod signal;
mod stats;

pub use command::{
    ClientId, CommandKind, CommandReply, CommandRequest, Reason, Target, UnknownValue,
};
pub use commission::CommissionWhat;
pub use frame::{
    AxisFlags, AxisMode, AxisState, AxisWire, DeviceState, FaultCode, FrameFlags, MotionFrame,
};
pub use group::{
    GroupAbort, GroupInfo, GroupMotion, GroupPath, GroupState, PATH_VALUES, PathFlags, PathKind,
    Setpoint, SetpointFlags, StreamFlags, StreamMode, StreamState,
};
pub use info::{AxisInfo, Capabilities, DeviceInfo, DeviceModel, EstopCategory, ServerInfo};
/// Fixed-size, zero-padded UTF-8 text fields (from `motion-base`, shared with the drivers).
pub use motion_base::{read_text, write_text};
pub use params::{MAX_PARAMS, MachineParam, MachineParams, PARAM_TEXT_LEN, ParamOwner};
pub use pid_file::{PidFileError, ServerPidFile, ServerProcess, process_start_ticks, process_uid};
pub use service::ServiceNames;
pub use signal::{SignalFlags, SignalInfo, SignalInfoFlags, SignalKind, SignalState};
pub use stats::{LatencySummary, LinkIo, LinkStats, ServerStats};

/// Version of this contract. Bumped on every layout or meaning change; every payload
/// carries it so that a client built against another version can refuse politely.
pub const SCHEMA_VERSION: u32 = 11;

/// Capacity of the axis arrays in [`MotionFrame`] and [`ServerInfo`].
pub const MAX_AXES: usize = 128;
/// Capacity of the device array in [`ServerInfo`].
pub const MAX_DEVICES: usize = 32;
/// Capacity of the link array in [`ServerStats`].
pub const MAX_LINKS: usize = 16;
/// Capacity of the signal arrays in [`MotionFrame`] and [`ServerInfo`].
pub const MAX_SIGNALS: usize = 64;
/// Bytes of a name field (axis, device, link, server): UTF-8, zero padded.
pub const NAME_LEN: usize = 32;
/// Bytes of a unit field ("mm", "deg"): UTF-8, zero padded.
pub const UNIT_LEN: usize = 16;
/// Bytes of a model id field ([`DeviceInfo::model_id`]): UTF-8, zero padded.
pub const MODEL_ID_LEN: usize = 16;
/// Capacity of the group arrays in [`MotionFrame`] and [`ServerInfo`] (`[[group]]`).
pub const MAX_GROUPS: usize = 16;
/// Axes one group may hold.
pub const MAX_GROUP_AXES: usize = 16;
/// Points one trajectory may hold ([`GroupPath`]).
pub const MAX_PATH_POINTS: usize = 1024;
