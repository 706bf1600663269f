//! Typed parameter values shared by requests and replies: actions, current levels, and the
//! bitfields of $15, $16, $30, $45 and the motor masks.

use crate::Error;

/// Highest motor number of any pack ("motnr (0..5)", manual section 8). A QUADpack only has
/// motors 0..=3, but the protocol field is the same.
pub const MAX_MOTOR: u8 = 5;

/// Checks a motor number against the protocol range 0..=5.
pub const fn check_motor(motor: u8) -> Result<u8, Error> {
    if motor <= MAX_MOTOR {
        Ok(motor)
    } else {
        Err(Error::InvalidMotor(motor))
    }
}

/// What a motor is doing, as reported by $20, $21 and $28 (manual 8.4 "Current action").
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Action {
    /// 0: inactive.
    Inactive,
    /// 5: trapezoidal ramp.
    Ramp,
    /// 10: PI controller.
    PiController,
    /// 15: rotation.
    Rotation,
    /// 20–29: reference switch search; the value is the phase 0..=9 (the manual does not
    /// name the phases; see the simulator for the ones it uses).
    ReferenceSearch(u8),
    /// 30: mechanical reference.
    MechanicalReference,
    /// Any other value: not documented, kept so that a reply from a newer firmware still
    /// decodes.
    Unknown(u8),
}

/// An action travels as its code ([`Action::to_u8`] / [`Action::from_u8`]).
impl crate::params::Param for Action {
    fn put(self, p: &mut [u8; crate::params::PARAMS], at: usize) {
        self.to_u8().put(p, at);
    }
    fn take(p: &[u8; crate::params::PARAMS], at: usize) -> Result<Self, Error> {
        u8::take(p, at).map(Self::from_u8)
    }
}

/// Consecutive action bytes ($28: P0..P5 for motors 0..5).
impl<const N: usize> crate::params::Param for [Action; N] {
    fn put(self, p: &mut [u8; crate::params::PARAMS], at: usize) {
        for (k, action) in self.into_iter().enumerate() {
            action.put(p, at + k);
        }
    }
    fn take(p: &[u8; crate::params::PARAMS], at: usize) -> Result<Self, Error> {
        let bytes = <[u8; N]>::take(p, at)?;
        Ok(bytes.map(Action::from_u8))
    }
}

impl Action {
    /// The wire value.
    pub const fn to_u8(self) -> u8 {
        match self {
            Self::Inactive => 0,
            Self::Ramp => 5,
            Self::PiController => 10,
            Self::Rotation => 15,
            Self::ReferenceSearch(phase) => 20 + if phase > 9 { 9 } else { phase },
            Self::MechanicalReference => 30,
            Self::Unknown(v) => v,
        }
    }

    /// The action for a wire value.
    pub const fn from_u8(v: u8) -> Self {
        match v {
            0 => Self::Inactive,
            5 => Self::Ramp,
            10 => Self::PiController,
            15 => Self::Rotation,
            20..=29 => Self::ReferenceSearch(v - 20),
            30 => Self::MechanicalReference,
            other => Self::Unknown(other),
        }
    }

    /// `true` for everything but [`Action::Inactive`].
    pub const fn is_active(self) -> bool {
        !matches!(self, Self::Inactive)
    }

    /// `true` while a reference search (switch or mechanical) runs.
    pub const fn is_referencing(self) -> bool {
        matches!(self, Self::ReferenceSearch(_) | Self::MechanicalReference)
    }
}

/// A current level of $11 (I0..I3): "(0=100%, 75, 50, 38, 25, 19, [13, 9,] 0%)".
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CurrentLevel {
    /// Index 0: 100 %.
    P100,
    /// Index 1: 75 %.
    P75,
    /// Index 2: 50 %.
    P50,
    /// Index 3: 38 %.
    P38,
    /// Index 4: 25 %.
    P25,
    /// Index 5: 19 % (the lowest that still microsteps properly, manual 7.1).
    P19,
    /// Index 6: 13 %.
    P13,
    /// Index 7: 9 %.
    P9,
    /// Index 8: 0 %.
    Off,
}

/// A current level travels as its wire index; an index out of the table is an error.
impl crate::params::Param for CurrentLevel {
    fn put(self, p: &mut [u8; crate::params::PARAMS], at: usize) {
        self.index().put(p, at);
    }
    fn take(p: &[u8; crate::params::PARAMS], at: usize) -> Result<Self, Error> {
        Self::from_index(u8::take(p, at)?)
    }
}

impl CurrentLevel {
    /// The wire index 0..=8.
    pub const fn index(self) -> u8 {
        self as u8
    }

    /// The level for a wire index.
    pub const fn from_index(i: u8) -> Result<Self, Error> {
        Ok(match i {
            0 => Self::P100,
            1 => Self::P75,
            2 => Self::P50,
            3 => Self::P38,
            4 => Self::P25,
            5 => Self::P19,
            6 => Self::P13,
            7 => Self::P9,
            8 => Self::Off,
            _ => {
                return Err(Error::OutOfRange {
                    field: "current index",
                });
            }
        })
    }

    /// Every level, in wire order (index 0 = 100 % … index 8 = 0 %).
    pub const ALL: [Self; 9] = [
        Self::P100,
        Self::P75,
        Self::P50,
        Self::P38,
        Self::P25,
        Self::P19,
        Self::P13,
        Self::P9,
        Self::Off,
    ];

    /// The level of exactly `percent` % of the peak current ("0=100%, 75, 50, 38, 25, 19,
    /// [13, 9,] 0%"); `None` for any other value.
    pub const fn from_percent(percent: u8) -> Option<Self> {
        let mut i = 0;
        while i < Self::ALL.len() {
            if Self::ALL[i].percent() == percent {
                return Some(Self::ALL[i]);
            }
            i += 1;
        }
        None
    }

    /// Percent of the peak current.
    pub const fn percent(self) -> u8 {
        match self {
            Self::P100 => 100,
            Self::P75 => 75,
            Self::P50 => 50,
            Self::P38 => 38,
            Self::P25 => 25,
            Self::P19 => 19,
            Self::P13 => 13,
            Self::P9 => 9,
            Self::Off => 0,
        }
    }
}

macro_rules! flags {
    ($(#[$doc:meta])* $name:ident : $repr:ty { $($(#[$fdoc:meta])* $flag:ident = $bit:expr;)* }) => {
        $(#[$doc])*
        #[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
        pub struct $name($repr);

        impl $name {
            $($(#[$fdoc])* pub const $flag: Self = Self(1 << $bit);)*
            /// No flag set.
            pub const EMPTY: Self = Self(0);

            /// The raw bits, undocumented ones included.
            pub const fn bits(self) -> $repr {
                self.0
            }

            /// Flags from raw bits; undocumented bits are kept as they are.
            pub const fn from_bits_retain(bits: $repr) -> Self {
                Self(bits)
            }

            /// `true` when every flag of `other` is set in `self`.
            pub const fn contains(self, other: Self) -> bool {
                self.0 & other.0 == other.0
            }

            /// `self` with the flags of `other` set or cleared.
            #[must_use]
            pub const fn with(self, other: Self, on: bool) -> Self {
                if on { Self(self.0 | other.0) } else { Self(self.0 & !other.0) }
            }
        }

        impl core::ops::BitOr for $name {
            type Output = Self;
            fn bitor(self, rhs: Self) -> Self {
                Self(self.0 | rhs.0)
            }
        }

        impl crate::params::Param for $name {
            fn put(self, p: &mut [u8; crate::params::PARAMS], at: usize) {
                self.0.put(p, at);
            }
            fn take(p: &[u8; crate::params::PARAMS], at: usize) -> Result<Self, Error> {
                <$repr>::take(p, at).map(Self)
            }
        }
    };
}

flags! {
    /// $15 P5 "motor type" (manual 8.3).
    MotorType: u8 {
        /// Bit 0: 1 = PI controller, 0 = trapezoidal ramp.
        PI_MODE = 0;
        /// Bit 1: rotary axis (0 = linear).
        ROTARY = 1;
        /// Bit 2: AutoNullCmd, starts an automatic reference search (as $22).
        AUTO_NULL_CMD = 2;
        /// Bit 3: TestNull, set the stop bit if the motor stops at the zero point but the
        /// switch stays inactive after the settle time.
        TEST_NULL = 3;
        /// Bit 4: NullLeft, zero point left of the driving range (otherwise right).
        NULL_LEFT = 4;
        /// Bit 5: NullCenter, zero point at the centre of the switch's active area.
        NULL_CENTER = 5;
        /// Bit 6: StopNull, stop and set the stop bit when the zero switch is active outside
        /// the tolerance area (or an analogue limit is exceeded).
        STOP_NULL = 6;
        /// Bit 7: FilterSwitch, de-bounce the zero switch (mask of $16).
        FILTER_SWITCH = 7;
    }
}

flags! {
    /// $15 P6 options (manual 8.3).
    MotorOptions: u8 {
        /// Bit 0: way optimisation for rotary axes.
        WAY_OPTIMIZATION = 0;
        /// Bit 1: FastRef, search the switch with vrefmax.
        FAST_REF = 1;
        /// Bit 2: MechRef, mechanical reference (5/4 poslimit towards the zero point).
        MECH_REF = 2;
        /// Bit 3: DelayTestNull, delay the zero point check by the T0 time.
        DELAY_TEST_NULL = 3;
        /// Bit 4: StopSoft, decelerate with amax on a stop condition instead of stopping
        /// abruptly.
        STOP_SOFT = 4;
        /// Bit 5: StopNoRef, do not start a reference search on a stop condition.
        STOP_NO_REF = 5;
        /// Bit 6: NullPositive, zero switch high active (0 = low active).
        NULL_POSITIVE = 6;
        /// Bit 7: StopAtFullsteps, stop ramps only at the nearest full step.
        STOP_AT_FULLSTEPS = 7;
    }
}

/// Where the pack's firmware keeps StopNoRef and NullPositive in `$15` P6. The manual
/// ("SIXpack / QUADpack manual" V2.43, 8.3 `$15`) gives two readings: its table has
/// "Bit 5: StopNoRef" and "Bit 6: NullPositive"; its prose says "StopNoRef(P6, Bit 6)"
/// twice (under P5 bit 3 TestNull and bit 6 StopNull). If the prose is right the table
/// swapped the two rows, so NullPositive is then bit 5. Nothing on the wire tells them
/// apart (`$15` cannot be read back), so it is a per-device setting (`stop_no_ref_bit`,
/// docs/keys/tmcpack.md). [`MotorOptions`] always names the flags as the table does; this
/// maps them to and from the byte on the wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum OptionsLayout {
    /// The table: StopNoRef bit 5, NullPositive bit 6. The default.
    #[default]
    Table,
    /// The prose: StopNoRef bit 6, NullPositive bit 5.
    Prose,
}

impl OptionsLayout {
    /// The bit of StopNoRef: 5 (table) or 6 (prose).
    pub const fn stop_no_ref_bit(self) -> u8 {
        match self {
            Self::Table => 5,
            Self::Prose => 6,
        }
    }

    /// The reading whose StopNoRef is `bit`; `None` for anything but 5 and 6.
    pub const fn from_stop_no_ref_bit(bit: u8) -> Option<Self> {
        match bit {
            5 => Some(Self::Table),
            6 => Some(Self::Prose),
            _ => None,
        }
    }

    /// The P6 byte carrying `options` under this reading; applied to a byte off the wire it
    /// gives the options back (swapping bits 5 and 6 is its own inverse).
    pub const fn wire(self, options: MotorOptions) -> MotorOptions {
        match self {
            Self::Table => options,
            Self::Prose => {
                let bits = options.bits();
                let five = (bits >> 5) & 1;
                let six = (bits >> 6) & 1;
                MotorOptions::from_bits_retain((bits & !0x60) | (five << 6) | (six << 5))
            }
        }
    }
}

flags! {
    /// $16 P5 (manual 8.3 "Reference Search Parameters").
    ReferenceFlags: u8 {
        /// Bit 0: 1 = stop after the reference search, 0 = continue the previous action.
        STOP_AFTER_SEARCH = 0;
    }
}

flags! {
    /// A motor mask: bit 0 = motor 0 … bit 5 = motor 5 ($28, $29, $2A, $33, $50).
    MotorMask: u8 {
        /// Motor 0.
        M0 = 0;
        /// Motor 1.
        M1 = 1;
        /// Motor 2.
        M2 = 2;
        /// Motor 3.
        M3 = 3;
        /// Motor 4.
        M4 = 4;
        /// Motor 5.
        M5 = 5;
    }
}

impl MotorMask {
    /// The mask with only `motor` set (motors above 5 give an empty mask).
    pub const fn single(motor: u8) -> Self {
        if motor <= MAX_MOTOR {
            Self(1 << motor)
        } else {
            Self(0)
        }
    }

    /// `true` when `motor` is selected.
    pub const fn has(self, motor: u8) -> bool {
        motor <= MAX_MOTOR && self.0 & (1 << motor) != 0
    }

    /// Checks that no bit above motor 5 is set.
    pub const fn check(self, field: &'static str) -> Result<Self, Error> {
        if self.0 & 0xC0 == 0 {
            Ok(self)
        } else {
            Err(Error::OutOfRange { field })
        }
    }
}

flags! {
    /// $30 response P4: "all reference inputs / jumpers" (bit n = motor n's reference input,
    /// inverted as all reference inputs are; bit 6 = jumper 1, bit 7 = jumper 2).
    RefInputs: u8 {
        /// Motor 0's reference input.
        REF0 = 0;
        /// Motor 1's reference input.
        REF1 = 1;
        /// Motor 2's reference input.
        REF2 = 2;
        /// Motor 3's reference input.
        REF3 = 3;
        /// Motor 4's reference input.
        REF4 = 4;
        /// Motor 5's reference input.
        REF5 = 5;
        /// Jumper JP1 set.
        JUMPER1 = 6;
        /// Jumper JP2 set.
        JUMPER2 = 7;
    }
}

impl RefInputs {
    /// The CAN bit rate the jumpers select (manual 6.2 table).
    pub const fn can_bitrate(self) -> CanBitrate {
        CanBitrate::from_jumpers(self.contains(Self::JUMPER1), self.contains(Self::JUMPER2))
    }
}

/// CAN bit rate set by jumpers JP1/JP2 (manual 6.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum CanBitrate {
    /// JP1 and JP2 set.
    Mbit1,
    /// JP2 only.
    Kbit500,
    /// No jumper (default).
    #[default]
    Kbit250,
    /// JP1 only.
    Kbit125,
}

impl CanBitrate {
    /// Every rate of the table, slowest first.
    pub const ALL: [Self; 4] = [Self::Kbit125, Self::Kbit250, Self::Kbit500, Self::Mbit1];

    /// The jumper setting for a rate in bits per second; `None` for a rate the table lacks.
    pub const fn from_bits_per_second(rate: u32) -> Option<Self> {
        match rate {
            1_000_000 => Some(Self::Mbit1),
            500_000 => Some(Self::Kbit500),
            250_000 => Some(Self::Kbit250),
            125_000 => Some(Self::Kbit125),
            _ => None,
        }
    }

    /// The rate for the two jumpers.
    pub const fn from_jumpers(jp1: bool, jp2: bool) -> Self {
        match (jp1, jp2) {
            (true, true) => Self::Mbit1,
            (false, true) => Self::Kbit500,
            (true, false) => Self::Kbit125,
            (false, false) => Self::Kbit250,
        }
    }

    /// The jumpers (JP1, JP2) that select this rate.
    pub const fn jumpers(self) -> (bool, bool) {
        match self {
            Self::Mbit1 => (true, true),
            Self::Kbit500 => (false, true),
            Self::Kbit125 => (true, false),
            Self::Kbit250 => (false, false),
        }
    }

    /// Bits per second.
    pub const fn bits_per_second(self) -> u32 {
        match self {
            Self::Mbit1 => 1_000_000,
            Self::Kbit500 => 500_000,
            Self::Kbit250 => 250_000,
            Self::Kbit125 => 125_000,
        }
    }
}

flags! {
    /// $45 request P1 (manual 8.6 "Power-Down modus").
    PowerDownRequest: u8 {
        /// Bit 0: read positions from EEPROM into the position registers if valid.
        LOAD_POSITIONS = 0;
        /// Bit 1: mark the positions in EEPROM invalid.
        INVALIDATE_POSITIONS = 1;
        /// Bit 2: activate power-down (stop motors and save positions on undervoltage).
        ACTIVATE = 2;
        /// Bit 3: reset the power-down state and re-enable the motors.
        RESET_STATE = 3;
    }
}

flags! {
    /// $45 response P0 (manual 8.6 "Power-Down modus").
    PowerDownStatus: u8 {
        /// Bit 0: loaded valid positions from EEPROM.
        LOADED = 0;
        /// Bit 1: valid positions are in EEPROM.
        VALID_IN_EEPROM = 1;
        /// Bit 2: power-down state before the command.
        DOWN_BEFORE = 2;
        /// Bit 3: power-down state after the command.
        DOWN_AFTER = 3;
    }
}

/// Whether firmware revision `revision` (as `$43` reports it, 149 = V1.4.9) has the `$45`
/// power-down mode: "(Version 1.46 and since Version 1.49)" (manual 8.6).
pub const fn power_down_supported(revision: u8) -> bool {
    revision == 146 || revision >= 149
}
