//! The effective machine parameters: [`MachineParams`], published with history 1 on
//! `motiond/<name>/params`.

use iceoryx2::prelude::ZeroCopySend;

use crate::SCHEMA_VERSION;
use crate::command::UnknownValue;
use crate::read_text;

/// Capacity of [`MachineParams::entries`].
pub const MAX_PARAMS: usize = 2048;
/// Bytes of a parameter key or value text.
pub const PARAM_TEXT_LEN: usize = 40;

enumeration! {
    /// What a parameter belongs to. Travels as `u8` in [`MachineParam::owner_kind`].
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub enum ParamOwner(u8) -> name {
        /// A device (`owner_index` into `ServerInfo::devices`).
        Device = 1 => "device",
        /// An axis (`owner_index` into `ServerInfo::axes`).
        Axis = 2 => "axis",
    }
}

payload! {
    /// One effective machine parameter.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    #[type_name("motiond::MachineParam")]
    pub struct MachineParam {
        /// The config key, dotted for tables (`current.standstill`).
        pub key: [u8; PARAM_TEXT_LEN],
        /// The value in effect, with its unit (`50 %`).
        pub value: [u8; PARAM_TEXT_LEN],
        /// Device or axis index.
        pub owner_index: u16,
        /// [`ParamOwner`] value.
        pub owner_kind: u8,
        /// 1: the config file set it; 0: the default.
        pub from_config: u8,
        /// Zero.
        pub reserved: u32,
    }
}

impl MachineParam {
    /// An unused entry.
    pub const EMPTY: Self = Self {
        key: [0; PARAM_TEXT_LEN],
        value: [0; PARAM_TEXT_LEN],
        owner_index: 0,
        owner_kind: 0,
        from_config: 0,
        reserved: 0,
    };

    /// The key.
    pub fn key(&self) -> &str {
        read_text(&self.key)
    }

    /// The value.
    pub fn value(&self) -> &str {
        read_text(&self.value)
    }

    /// The typed owner kind.
    pub fn owner(&self) -> Result<ParamOwner, UnknownValue> {
        ParamOwner::try_from(self.owner_kind)
    }
}

payload! {
    /// Every machine parameter in effect, published with history 1 on `motiond/<name>/params`.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    #[type_name("motiond::MachineParams")]
    pub struct MachineParams {
        /// [`SCHEMA_VERSION`] of the server.
        pub schema_version: u32,
        /// Valid entries.
        pub count: u32,
        /// 1 when more parameters existed than [`MAX_PARAMS`] (entries were left out).
        pub truncated: u32,
        /// Zero.
        pub reserved: u32,
        /// Devices' then axes' parameters, config order.
        pub entries: [MachineParam; MAX_PARAMS],
    }
}

impl MachineParams {
    /// No parameters, of the current schema.
    pub const EMPTY: Self = Self {
        schema_version: SCHEMA_VERSION,
        count: 0,
        truncated: 0,
        reserved: 0,
        entries: [MachineParam::EMPTY; MAX_PARAMS],
    };

    /// The valid entries.
    pub fn entries(&self) -> &[MachineParam] {
        &self.entries[..(self.count as usize).min(MAX_PARAMS)]
    }
}

impl Default for MachineParams {
    fn default() -> Self {
        Self::EMPTY
    }
}
