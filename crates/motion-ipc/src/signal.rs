//! Board I/O as named signals: [`SignalState`] in every frame, [`SignalInfo`] in the server
//! description.

use iceoryx2::prelude::ZeroCopySend;

use crate::command::{ClientId, UnknownValue};
use crate::read_text;
use crate::{NAME_LEN, UNIT_LEN};

/// What a signal is (one enum with the drivers and the engine: `motion_base::SignalKind`).
/// Travels as `u8` in [`SignalState::kind`] and [`SignalInfo::kind`].
pub use motion_base::SignalKind;

flag_set! {
    /// Bit set of a signal's state flags ([`SignalState::flags`]).
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
    pub struct SignalFlags(u32) {
        /// The value is older than its board's refresh budget (or was never read).
        STALE = 0, "stale";
        /// A client holds an exclusive claim on the output ([`SignalState::claimed_by`]).
        CLAIMED = 1, "claimed";
        /// The e-stop put the output into its configured safe state.
        SAFE_STATE = 2, "safe-state";
        /// An output value (a level, a trigger's compare position) was commanded and the board
        /// has not acknowledged it yet.
        PENDING = 3, "pending";
    }
}

payload! {
    /// One signal in a frame.
    ///
    /// A `capture` or `trigger` signal also carries events: every capture (every trigger
    /// pulse) the board reports adds one to `sequence`, and `event_tick` is the tick that
    /// took the newest one in. Two events taken in by the same tick show as a step of two
    /// (the value is the newer one's): a client that remembers the sequence it last saw
    /// knows how many it missed.
    #[derive(Debug, Clone, Copy, PartialEq)]
    #[type_name("motiond::SignalState")]
    pub struct SignalState {
        /// Logical value: digital 0.0/1.0 after `invert`; analogue, capture and trigger
        /// raw × scale + offset (a capture: the captured position; a trigger: its compare
        /// position).
        pub value: f64,
        /// Raw value as the board reports it: electrical level 0/1, ADC counts, or counter
        /// counts (capture, trigger).
        pub raw: f64,
        /// Tick at which the board last reported it (outputs: acknowledged it).
        pub last_refresh_tick: u64,
        /// [`SignalFlags`] bits.
        pub flags: u32,
        /// [`SignalKind`] value.
        pub kind: u8,
        /// Zero.
        pub reserved: [u8; 3],
        /// Claim holder of an output; zero when unclaimed.
        pub claimed_by: ClientId,
        /// Tick that took in the newest event (capture, trigger pulse); 0 before the first.
        pub event_tick: u64,
        /// Events (captures, trigger pulses) the board reported since the server started,
        /// wrapping at 2³²; 0 for the other kinds.
        pub sequence: u32,
        /// Zero.
        pub reserved2: u32,
    }
}

impl SignalState {
    /// A signal never heard from: stale, value 0.
    pub const UNKNOWN: Self = Self {
        value: 0.0,
        raw: 0.0,
        last_refresh_tick: 0,
        flags: SignalFlags::STALE.0,
        kind: 0,
        reserved: [0; 3],
        claimed_by: ClientId::NONE,
        event_tick: 0,
        sequence: 0,
        reserved2: 0,
    };

    /// The typed flags.
    pub const fn flags(&self) -> SignalFlags {
        SignalFlags(self.flags)
    }

    /// A digital signal's logical value (`value >= 0.5`).
    pub fn is_on(&self) -> bool {
        self.value >= 0.5
    }

    /// Events (captures, trigger pulses) between a state with sequence `seen` and this
    /// one: 1 for the next event, more when some were missed, 0 for none (through the
    /// wrap at 2³²).
    pub const fn events_since(&self, seen: u32) -> u32 {
        self.sequence.wrapping_sub(seen)
    }
}

impl Default for SignalState {
    fn default() -> Self {
        Self::UNKNOWN
    }
}

flag_set! {
    /// Bit set of a signal's configuration ([`SignalInfo::flags`]).
    #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
    pub struct SignalInfoFlags(u8) {
        /// Digital: the logical value is the inverse of the electrical level.
        INVERT = 0, "invert";
        /// Digital output: the e-stop puts it into [`SignalInfoFlags::SAFE_ON`] (set) or off.
        HAS_SAFE_STATE = 1, "has-safe-state";
        /// Digital output: the safe state is on.
        SAFE_ON = 2, "safe-on";
    }
}

payload! {
    /// One signal's static description.
    #[derive(Debug, Clone, Copy, PartialEq)]
    #[type_name("motiond::SignalInfo")]
    pub struct SignalInfo {
        /// Signal name.
        pub name: [u8; NAME_LEN],
        /// Unit of an analogue value ("" for digital).
        pub unit: [u8; UNIT_LEN],
        /// Device name.
        pub device: [u8; NAME_LEN],
        /// Analogue: value = raw × scale + offset.
        pub scale: f64,
        /// Analogue: value = raw × scale + offset.
        pub offset: f64,
        /// Raw full scale (1023 for a 10-bit converter; 1 for digital).
        pub full_scale: f64,
        /// [`SignalKind`] value.
        pub kind: u8,
        /// [`SignalInfoFlags`] bits.
        pub flags: u8,
        /// Index into [`ServerInfo::devices`](crate::ServerInfo::devices).
        pub device_index: u16,
        /// The board's pin name ("ttlio1"), zero padded.
        pub pin: [u8; UNIT_LEN],
        /// Zero.
        pub reserved: u32,
    }
}

impl SignalInfo {
    /// An unused entry.
    pub const EMPTY: Self = Self {
        name: [0; NAME_LEN],
        unit: [0; UNIT_LEN],
        device: [0; NAME_LEN],
        scale: 1.0,
        offset: 0.0,
        full_scale: 1.0,
        kind: 0,
        flags: 0,
        device_index: 0,
        pin: [0; UNIT_LEN],
        reserved: 0,
    };

    /// The signal name.
    pub fn name(&self) -> &str {
        read_text(&self.name)
    }

    /// The unit.
    pub fn unit(&self) -> &str {
        read_text(&self.unit)
    }

    /// The device name.
    pub fn device(&self) -> &str {
        read_text(&self.device)
    }

    /// The pin name.
    pub fn pin(&self) -> &str {
        read_text(&self.pin)
    }

    /// The typed kind; `Err` for a value this build does not know.
    pub fn kind(&self) -> Result<SignalKind, UnknownValue> {
        SignalKind::try_from(self.kind).map_err(|unknown| UnknownValue(u32::from(unknown.0)))
    }

    /// The typed flags.
    pub const fn flags(&self) -> SignalInfoFlags {
        SignalInfoFlags(self.flags)
    }
}
