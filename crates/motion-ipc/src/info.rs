//! What the server drives: [`ServerInfo`], published with history 1 on `motiond/<name>/info`.

use iceoryx2::prelude::ZeroCopySend;

use crate::command::{CommandKind, UnknownValue};
use crate::frame::DeviceState;
use crate::group::GroupInfo;
use crate::read_text;
use crate::signal::SignalInfo;
use crate::{
    MAX_AXES, MAX_DEVICES, MAX_GROUPS, MAX_SIGNALS, MODEL_ID_LEN, NAME_LEN, SCHEMA_VERSION,
    UNIT_LEN,
};

enumeration! {
    /// What an e-stop (and a fault) does to an axis: IEC 60204-1 stop categories. Travels as
    /// `u32` in [`AxisInfo::estop`].
    #[derive(
        serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
    )]
    pub enum EstopCategory(u32) -> name {
        /// Category 2: decelerate and hold, energised.
        #[default]
        Hold = 0 => "hold",
        /// Category 1: decelerate, then de-energise.
        StopOff = 1 => "stop-off",
        /// Category 0: de-energise at once.
        Off = 2 => "off",
    }
}

/// The board model of a device (one type with the drivers and the config:
/// `motion_base::Model`). Travels as its `u32` code in [`DeviceInfo::model`] and as its
/// config id in [`DeviceInfo::model_id`]; `TryFrom<u32>` knows only the built-in boards
/// ([`DeviceModel::BUILT_IN`]), the id names any board ([`DeviceInfo::model_name`]).
pub use motion_base::Model as DeviceModel;

/// Bit set of the [`CommandKind`]s an axis accepts: bit `kind as u32` is set.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub struct Capabilities(pub u32);

impl Capabilities {
    /// No command.
    pub const NONE: Self = Self(0);

    /// `self` with `kind` added.
    #[must_use]
    pub const fn with(self, kind: CommandKind) -> Self {
        Self(self.0 | (1 << kind as u32))
    }

    /// Whether `kind` is accepted.
    pub const fn supports(self, kind: CommandKind) -> bool {
        self.0 & (1 << kind as u32) != 0
    }
}

payload! {
    /// One axis's static description.
    #[derive(Debug, Clone, Copy, PartialEq)]
    #[type_name("motiond::AxisInfo")]
    pub struct AxisInfo {
        /// Axis name, UTF-8, zero padded.
        pub name: [u8; NAME_LEN],
        /// Unit of positions ("mm", "deg"), UTF-8, zero padded.
        pub unit: [u8; UNIT_LEN],
        /// Name of the device that drives the axis.
        pub device: [u8; NAME_LEN],
        /// Device counts per unit.
        pub counts_per_unit: f64,
        /// Lower soft limit, units.
        pub min: f64,
        /// Upper soft limit, units.
        pub max: f64,
        /// Velocity limit, units/s.
        pub max_velocity: f64,
        /// Acceleration limit, units/s².
        pub max_accel: f64,
        /// [`Capabilities`] bits.
        pub capabilities: u32,
        /// Motor number on the device.
        pub channel: u16,
        /// Index into [`ServerInfo::devices`].
        pub device_index: u16,
        /// Following error tolerance, units; 0 = not supervised.
        pub following_error: f64,
        /// Overspeed factor (× `max_velocity`); 0 = not supervised.
        pub overspeed_factor: f64,
        /// Travel limit of a reference search, units; 0 = not supervised.
        pub home_max_travel: f64,
        /// [`EstopCategory`] value.
        pub estop: u32,
        /// Zero.
        pub reserved: u32,
    }
}

impl AxisInfo {
    /// An unused entry.
    pub const EMPTY: Self = Self {
        name: [0; NAME_LEN],
        unit: [0; UNIT_LEN],
        device: [0; NAME_LEN],
        counts_per_unit: 0.0,
        min: 0.0,
        max: 0.0,
        max_velocity: 0.0,
        max_accel: 0.0,
        capabilities: 0,
        channel: 0,
        device_index: 0,
        following_error: 0.0,
        overspeed_factor: 0.0,
        home_max_travel: 0.0,
        estop: 0,
        reserved: 0,
    };

    /// The axis name.
    pub fn name(&self) -> &str {
        read_text(&self.name)
    }

    /// The unit.
    pub fn unit(&self) -> &str {
        read_text(&self.unit)
    }

    /// The typed capabilities.
    pub const fn capabilities(&self) -> Capabilities {
        Capabilities(self.capabilities)
    }

    /// The device name.
    pub fn device(&self) -> &str {
        read_text(&self.device)
    }

    /// The typed e-stop category; `Err` for a value this build does not know.
    pub fn estop(&self) -> Result<EstopCategory, UnknownValue> {
        EstopCategory::try_from(self.estop)
    }
}

payload! {
    /// One device's description.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    #[type_name("motiond::DeviceInfo")]
    pub struct DeviceInfo {
        /// Device name.
        pub name: [u8; NAME_LEN],
        /// Link name.
        pub link: [u8; NAME_LEN],
        /// Firmware version as the board reported it ("" until known).
        pub firmware: [u8; NAME_LEN],
        /// [`DeviceModel`] value.
        pub model: u32,
        /// Bus address, 0 when the model has none.
        pub address: u32,
        /// Axes configured on the device.
        pub axis_count: u32,
        /// [`DeviceState`] value when the info was published (the frame has the current one).
        pub state: u32,
        /// The model's config id (`tmcpack`, `example`), UTF-8, zero padded: names the
        /// model of any board, built in or not.
        pub model_id: [u8; MODEL_ID_LEN],
    }
}

impl DeviceInfo {
    /// An unused entry.
    pub const EMPTY: Self = Self {
        name: [0; NAME_LEN],
        link: [0; NAME_LEN],
        firmware: [0; NAME_LEN],
        model: 0,
        address: 0,
        axis_count: 0,
        state: 0,
        model_id: [0; MODEL_ID_LEN],
    };

    /// The device name.
    pub fn name(&self) -> &str {
        read_text(&self.name)
    }

    /// The typed model: one of the built-in boards ([`DeviceModel::BUILT_IN`]), `Err` for
    /// any other code (a board of the server's registry this build does not have; its
    /// [`model_name`](Self::model_name) still names it).
    pub fn model(&self) -> Result<DeviceModel, UnknownValue> {
        DeviceModel::try_from(self.model).map_err(|unknown| UnknownValue(unknown.0))
    }

    /// The model's config id as the server wrote it ("" when it wrote none).
    pub fn model_id(&self) -> &str {
        read_text(&self.model_id)
    }

    /// The model's name for people: its config id, or `model <code>` when the id is empty
    /// or not printable ASCII (the payload is untrusted: never garbage on a terminal).
    pub fn model_name(&self) -> String {
        let id = self.model_id();
        if !id.is_empty() && id.bytes().all(|byte| byte.is_ascii_graphic()) {
            id.to_owned()
        } else {
            format!("model {}", self.model)
        }
    }

    /// The firmware text ("" until known).
    pub fn firmware(&self) -> &str {
        read_text(&self.firmware)
    }

    /// The typed state (`Offline` for a value this build does not know).
    pub fn state(&self) -> DeviceState {
        u8::try_from(self.state)
            .ok()
            .and_then(|state| DeviceState::try_from(state).ok())
            .unwrap_or_default()
    }
}

payload! {
    /// The server's static description, published with history 1 on `motiond/<name>/info`.
    #[derive(Debug, Clone, Copy, PartialEq)]
    #[type_name("motiond::ServerInfo")]
    pub struct ServerInfo {
        /// [`SCHEMA_VERSION`] of the server.
        pub schema_version: u32,
        /// Valid entries in `axes`.
        pub axis_count: u32,
        /// Valid entries in `devices`.
        pub device_count: u32,
        /// Tick rate, Hz.
        pub tick_hz: u32,
        /// Deadman for velocity and power goals, ms; 0 = disabled.
        pub command_timeout_ms: u32,
        /// Configured client limit.
        pub max_clients: u32,
        /// Process id of motiond.
        pub server_pid: u32,
        /// Valid entries in `signals`.
        pub signal_count: u32,
        /// Instance name.
        pub name: [u8; NAME_LEN],
        /// CLOCK_MONOTONIC ns of tick 0.
        pub start_time_ns: u64,
        /// Axes in config order.
        pub axes: [AxisInfo; MAX_AXES],
        /// Devices in config order.
        pub devices: [DeviceInfo; MAX_DEVICES],
        /// Signals in config order.
        pub signals: [SignalInfo; MAX_SIGNALS],
        /// Valid entries in `groups`.
        pub group_count: u32,
        /// Zero.
        pub reserved: u32,
        /// Groups in config order.
        pub groups: [GroupInfo; MAX_GROUPS],
    }
}

impl ServerInfo {
    /// An empty description of the current schema.
    pub const EMPTY: Self = Self {
        schema_version: SCHEMA_VERSION,
        axis_count: 0,
        device_count: 0,
        tick_hz: 0,
        command_timeout_ms: 0,
        max_clients: 0,
        server_pid: 0,
        signal_count: 0,
        name: [0; NAME_LEN],
        start_time_ns: 0,
        axes: [AxisInfo::EMPTY; MAX_AXES],
        devices: [DeviceInfo::EMPTY; MAX_DEVICES],
        signals: [SignalInfo::EMPTY; MAX_SIGNALS],
        group_count: 0,
        reserved: 0,
        groups: [GroupInfo::EMPTY; MAX_GROUPS],
    };

    /// The valid axes.
    pub fn axes(&self) -> &[AxisInfo] {
        &self.axes[..(self.axis_count as usize).min(MAX_AXES)]
    }

    /// The valid devices.
    pub fn devices(&self) -> &[DeviceInfo] {
        &self.devices[..(self.device_count as usize).min(MAX_DEVICES)]
    }

    /// The valid signals.
    pub fn signals(&self) -> &[SignalInfo] {
        &self.signals[..(self.signal_count as usize).min(MAX_SIGNALS)]
    }

    /// The valid groups.
    pub fn groups(&self) -> &[GroupInfo] {
        &self.groups[..(self.group_count as usize).min(MAX_GROUPS)]
    }

    /// Index of the group called `name`.
    pub fn group_index(&self, name: &str) -> Option<usize> {
        self.groups().iter().position(|group| group.name() == name)
    }

    /// Index of the axis called `name`.
    pub fn axis_index(&self, name: &str) -> Option<usize> {
        self.axes().iter().position(|axis| axis.name() == name)
    }

    /// Index of the signal called `name`.
    pub fn signal_index(&self, name: &str) -> Option<usize> {
        self.signals()
            .iter()
            .position(|signal| signal.name() == name)
    }

    /// The instance name.
    pub fn name(&self) -> &str {
        read_text(&self.name)
    }
}

impl Default for ServerInfo {
    fn default() -> Self {
        Self::EMPTY
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::write_text;

    #[test]
    fn a_device_model_is_named_by_its_id_or_else_its_code() {
        let mut device = DeviceInfo::EMPTY;
        device.model = 99;
        write_text(&mut device.model_id, "widget");
        assert_eq!(
            (device.model_id(), device.model_name().as_str()),
            ("widget", "widget")
        );
        assert!(device.model().is_err(), "99 is no built-in board");
        device.model_id = [0; MODEL_ID_LEN];
        assert_eq!(device.model_name(), "model 99");
        // Untrusted bytes: a control character, a space, text that is not UTF-8, a full
        // field with no terminating zero.
        for garbage in [
            &b"wid\x1bget"[..],
            b"two words",
            b"\xff\xfe",
            b"0123456789abcdef",
        ] {
            device.model_id = [0; MODEL_ID_LEN];
            device.model_id[..garbage.len()].copy_from_slice(garbage);
            let name = device.model_name();
            let full = garbage.len() == MODEL_ID_LEN;
            assert_eq!(name == "model 99", !full, "{garbage:?} gave {name}");
        }
        device.model = DeviceModel::TMCPACK.code();
        write_text(&mut device.model_id, DeviceModel::TMCPACK.id());
        assert_eq!(device.model(), Ok(DeviceModel::TMCPACK));
        assert_eq!(device.model_name(), "tmcpack");
    }
}
