//! Typed requests (host → pack), one variant per instruction of the section 9 table.

use crate::types::{
    CurrentLevel, MotorMask, MotorOptions, MotorType, PowerDownRequest, ReferenceFlags, check_motor,
};

use crate::Error;

/// Highest velocity value (manual 8.2: "range: -511..+511").
pub const MAX_VELOCITY: u16 = 511;
/// Highest `clkdiv` (manual 8.2: "range 0..31").
pub const MAX_CLKDIV: u8 = 31;
/// Highest `div_i` (manual 8.2: "range 0..3").
pub const MAX_DIV: u8 = 3;
/// Highest `amax` ($14: "1..32767").
pub const MAX_AMAX: u16 = 32767;
/// Highest `poslimit` ($15: "0..0x7FFFFFF"; we read the seven F's as a slip for the full
/// positive 32-bit range, see the crate docs).
pub const MAX_POSLIMIT: u32 = 0x7FFF_FFFF;
/// Highest transmitter switch-over delay in 2 ms units ($40: "1..1000").
pub const MAX_SWITCHOVER: u16 = 1000;
/// Highest analogue channel ($30: "0..7").
pub const MAX_CHANNEL: u8 = 7;

message_table! {
/// A request, without its address byte. See [`RequestFrame`] for the whole 9-byte word.
///
/// Field names follow the manual; `reply_to` is the "response address" a query carries.
/// Unused parameter bytes are sent as zero and ignored when decoding.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash)]
    pub enum Request {
    /// $10: peak current of the motor pair (only motors 0, 2, 4 are used by the pack).
    PeakCurrent {
        /// Motor number.
        motor: u8 = 0,
        /// 0..=255: SIXpack Imax = 0.8 A · value/256; QUADpack 1.5 A · value/256 · DIP.
        value: u8 = 1,
    },
    /// $11: current control.
    CurrentControl {
        /// Motor number.
        motor: u8 = 0,
        /// I0: power-down current.
        i0: CurrentLevel = 1,
        /// I1: current at standstill.
        i1: CurrentLevel = 2,
        /// I2: current at constant velocity.
        i2: CurrentLevel = 3,
        /// I3: current while accelerating.
        i3: CurrentLevel = 4,
        /// T0: power-down delay in 2 ms units, 1..=65535.
        t0: u16 = 5,
    },
    /// $12: global clock divider `clkdiv`, 0..=31.
    VelocitySetting {
        /// clkdiv.
        clkdiv: u8 = 0,
    },
    /// $13: starting velocity.
    StartingVelocity {
        /// Motor number.
        motor: u8 = 0,
        /// vmin 0..=511 (used with div 3 for the reference switch; 0 = automatic).
        vmin: u16 = 1,
        /// vstart 1..=511.
        vstart: u16 = 3,
        /// div_i 0..=3.
        div: u8 = 5,
    },
    /// $14: acceleration and maximum velocity.
    VelocityAcceleration {
        /// Motor number.
        motor: u8 = 0,
        /// amax 1..=32767 (amax/64 accumulated at 500 Hz).
        amax: u16 = 1,
        /// vmax 1..=511.
        vmax: u16 = 3,
    },
    /// $15: motor parameters.
    MotorParameters {
        /// Motor number.
        motor: u8 = 0,
        /// poslimit 0..=0x7FFF_FFFF microsteps.
        poslimit: u32 = 1,
        /// P5 motor type bits.
        motor_type: MotorType = 5,
        /// P6 option bits.
        options: MotorOptions = 6,
    },
    /// $16: reference search parameters.
    ReferenceParameters {
        /// Motor number.
        motor: u8 = 0,
        /// vrefmax 1..=511.
        vrefmax: u16 = 1,
        /// De-bounce mask ($0001 = 0 ms, $0003 = 2 ms, $FFFF = 30 ms).
        debounce_mask: u16 = 3,
        /// P5 flags.
        flags: ReferenceFlags = 5,
    },
    /// $17: four entries of the microstep table.
    MicrostepTable {
        /// Start index 0, 4, 8 or 12.
        pointer: u8 = 0,
        /// Four table entries.
        entries: [u8; 4] = 1,
    },
    /// $18: null point offset and test range.
    NullOffset {
        /// Motor number.
        motor: u8 = 0,
        /// nulloffset: distance between zero point and reference switch.
        nulloffset: i32 = 1,
        /// testnullrange 0..=65535.
        testnullrange: u16 = 5,
    },
    /// $19: PI controller parameters.
    PiParameters {
        /// Motor number.
        motor: u8 = 0,
        /// propdiv 1..=255.
        propdiv: u8 = 1,
        /// intdiv 1..=32767.
        intdiv: u16 = 2,
        /// intclip 1..=32767.
        intclip: u16 = 4,
        /// intinpclip 0..=255.
        intinpclip: u8 = 6,
    },
    /// $20: query position and activity.
    QueryPosition {
        /// Motor number.
        motor: u8 = 0,
        /// Response address.
        reply_to: u8 = 1,
    },
    /// $21: query velocity and activity.
    QueryVelocity {
        /// Motor number.
        motor: u8 = 0,
        /// Response address.
        reply_to: u8 = 1,
    },
    /// $22: start the reference search.
    ReferenceSearch {
        /// Motor number.
        motor: u8 = 0,
    },
    /// $23: start a trapezoidal ramp (ignored by the pack while the motor is active).
    StartRamp {
        /// Motor number.
        motor: u8 = 0,
        /// Target position.
        target: i32 = 1,
    },
    /// $24: PI controller on a target position.
    PiTarget {
        /// Motor number.
        motor: u8 = 0,
        /// Target position.
        target: i32 = 1,
    },
    /// $25: rotation at a velocity.
    Rotate {
        /// Motor number.
        motor: u8 = 0,
        /// Velocity -511..=511.
        velocity: i16 = 1,
    },
    /// $26: set the target position on the fly.
    SetTarget {
        /// Motor number.
        motor: u8 = 0,
        /// Target position.
        target: i32 = 1,
    },
    /// $27: set the actual position.
    SetPosition {
        /// Motor number.
        motor: u8 = 0,
        /// New actual position.
        position: i32 = 1,
    },
    /// $28: query all actions, optionally delayed until the masked motors are inactive.
    QueryActions {
        /// Response address.
        reply_to: u8 = 0,
        /// Motors to wait for (empty: answer at once).
        delay_mask: MotorMask = 1,
    },
    /// $29: start ramps in parallel to the targets set with $26.
    StartRampParallel {
        /// Motors to start.
        mask: MotorMask = 0,
    },
    /// $2A: set the target of the masked motors to their actual position.
    Stop {
        /// Motors to stop.
        mask: MotorMask = 0,
    },
    /// $30: read an analogue channel and the inputs.
    ReadInput {
        /// Channel 0..=7 (6 = external input, 7 = supply voltage).
        channel: u8 = 0,
        /// Response address.
        reply_to: u8 = 1,
    },
    /// $31: analogue stop limits.
    StopLimits {
        /// Channel 0..=7.
        channel: u8 = 0,
        /// Minimum for stop left (0 = no function).
        left_min: u16 = 1,
        /// Maximum for stop right (≥ 1023 = no function).
        right_max: u16 = 3,
    },
    /// $32: additional outputs (bit 0 of P0..P3).
    Outputs {
        /// P0: logic level at TTLOUT1.
        ttlout1: bool = 0,
        /// P1: TTLIO1 direction, `true` = input, `false` = output.
        ttlio1_input: bool = 1,
        /// P2: logic level at TTLIO1.
        ttlio1: bool = 2,
        /// P3: TTLOUT1 works as ready output.
        ttlout1_ready: bool = 3,
    },
    /// $33: which motors drive the ready output.
    ReadyOutput {
        /// Motors whose activity counts.
        active_mask: MotorMask = 0,
        /// Motors whose reference search counts.
        reference_mask: MotorMask = 1,
    },
    /// $40: baud rate divisor and transmitter switch-over delay.
    SetBaud {
        /// Divisor = 20 MHz / (16 · baud), ≥ 1.
        divisor: u16 = 0,
        /// Switch-over delay in 2 ms units, 1..=1000.
        switchover: u16 = 2,
    },
    /// $41: packet timeout in 2 ms units, 2..=65535.
    PacketTimeout {
        /// Timeout in 2 ms units.
        timeout: u16 = 0,
    },
    /// $42: new RS-232 / RS-485 address.
    SetAddress {
        /// New address.
        address: u8 = 0,
    },
    /// $43: read unit information.
    UnitInfo {
        /// Response address.
        reply_to: u8 = 0,
    },
    /// $44: configure / query RS-232 operation via CAN.
    CanRs232 {
        /// Response address.
        reply_to: u8 = 0,
        /// Response address (upper 8 bits) for bytes received on RS-232.
        rs232_reply_to: u8 = 1,
        /// Bytes to collect before forwarding, 0..=8 (0 = disabled).
        forward_count: u8 = 2,
    },
    /// $45: power-down mode.
    PowerDown {
        /// Response address.
        reply_to: u8 = 0,
        /// P1 bits.
        flags: PowerDownRequest = 1,
    },
    /// $CC: complete hardware reset (about 1 s; parameters back to defaults).
    HardwareReset,
    /// $50: multi-dimensional linear interpolation to the targets set with $26.
    Interpolate {
        /// Motors taking part.
        mask: MotorMask = 0,
    },
    /// $F2: enable erasing and writing the flash (service).
    FlashEnable {
        /// Response address.
        reply_to: u8 = 0,
        /// Magic code.
        magic: u32 = 1,
    },
    /// $F3: program seven flash bytes (service).
    FlashProgram {
        /// Data bytes.
        data: [u8; 7] = 0,
    },
    /// $F4: flash checksum, aborts programming (service).
    FlashChecksum {
        /// Response address.
        reply_to: u8 = 0,
    },
    /// $F5: read seven flash bytes (service).
    FlashRead {
        /// Response address.
        reply_to: u8 = 0,
    },
    /// $F6: write an EEPROM word (service).
    EepromWrite {
        /// Response address.
        reply_to: u8 = 0,
        /// Magic code 2.
        magic: u16 = 1,
        /// EEPROM address.
        address: u16 = 3,
        /// Value.
        value: u16 = 5,
    },
    /// $F7: read EEPROM (service; the manual tables the same parameters as $F6).
    EepromRead {
        /// Response address.
        reply_to: u8 = 0,
        /// Magic code 2.
        magic: u16 = 1,
        /// EEPROM address.
        address: u16 = 3,
        /// Value field as tabled.
        value: u16 = 5,
    },
}
}

const fn range(ok: bool, field: &'static str) -> Result<(), Error> {
    if ok {
        Ok(())
    } else {
        Err(Error::OutOfRange { field })
    }
}

impl Request {
    /// The response address of a request that is answered, `None` for the others.
    /// (A $28 is answered too when its answer is delayed.)
    pub const fn reply_to(&self) -> Option<u8> {
        match *self {
            Self::QueryPosition { reply_to, .. }
            | Self::QueryVelocity { reply_to, .. }
            | Self::QueryActions { reply_to, .. }
            | Self::ReadInput { reply_to, .. }
            | Self::UnitInfo { reply_to }
            | Self::CanRs232 { reply_to, .. }
            | Self::PowerDown { reply_to, .. }
            | Self::FlashEnable { reply_to, .. }
            | Self::FlashChecksum { reply_to }
            | Self::FlashRead { reply_to }
            | Self::EepromWrite { reply_to, .. }
            | Self::EepromRead { reply_to, .. } => Some(reply_to),
            _ => None,
        }
    }

    /// The motor a single-motor request addresses.
    pub const fn motor(&self) -> Option<u8> {
        match *self {
            Self::PeakCurrent { motor, .. }
            | Self::CurrentControl { motor, .. }
            | Self::StartingVelocity { motor, .. }
            | Self::VelocityAcceleration { motor, .. }
            | Self::MotorParameters { motor, .. }
            | Self::ReferenceParameters { motor, .. }
            | Self::NullOffset { motor, .. }
            | Self::PiParameters { motor, .. }
            | Self::QueryPosition { motor, .. }
            | Self::QueryVelocity { motor, .. }
            | Self::ReferenceSearch { motor }
            | Self::StartRamp { motor, .. }
            | Self::PiTarget { motor, .. }
            | Self::Rotate { motor, .. }
            | Self::SetTarget { motor, .. }
            | Self::SetPosition { motor, .. } => Some(motor),
            _ => None,
        }
    }

    /// Checks every parameter against the range its table gives.
    pub fn validate(&self) -> Result<(), Error> {
        if let Some(m) = self.motor() {
            check_motor(m)?;
        }
        match *self {
            Self::CurrentControl { t0, .. } => range(t0 >= 1, "T0"),
            Self::VelocitySetting { clkdiv } => range(clkdiv <= MAX_CLKDIV, "clkdiv"),
            Self::StartingVelocity {
                vmin, vstart, div, ..
            } => {
                range(vmin <= MAX_VELOCITY, "vmin")?;
                range((1..=MAX_VELOCITY).contains(&vstart), "vstart")?;
                range(div <= MAX_DIV, "div")
            }
            Self::VelocityAcceleration { amax, vmax, .. } => {
                range((1..=MAX_AMAX).contains(&amax), "amax")?;
                range((1..=MAX_VELOCITY).contains(&vmax), "vmax")
            }
            Self::MotorParameters { poslimit, .. } => range(poslimit <= MAX_POSLIMIT, "poslimit"),
            Self::ReferenceParameters { vrefmax, .. } => {
                range((1..=MAX_VELOCITY).contains(&vrefmax), "vrefmax")
            }
            Self::MicrostepTable { pointer, .. } => {
                range(matches!(pointer, 0 | 4 | 8 | 12), "pointer")
            }
            Self::PiParameters {
                propdiv,
                intdiv,
                intclip,
                ..
            } => {
                range(propdiv >= 1, "propdiv")?;
                range((1..=MAX_AMAX).contains(&intdiv), "intdiv")?;
                range((1..=MAX_AMAX).contains(&intclip), "intclip")
            }
            Self::Rotate { velocity, .. } => {
                range(velocity.unsigned_abs() <= MAX_VELOCITY, "velocity")
            }
            Self::QueryActions { delay_mask: m, .. }
            | Self::StartRampParallel { mask: m }
            | Self::Stop { mask: m }
            | Self::Interpolate { mask: m } => m.check("mask").map(|_| ()),
            Self::ReadyOutput {
                active_mask,
                reference_mask,
            } => {
                active_mask.check("active mask")?;
                reference_mask.check("reference mask").map(|_| ())
            }
            Self::ReadInput { channel, .. } | Self::StopLimits { channel, .. } => {
                range(channel <= MAX_CHANNEL, "channel")
            }
            Self::SetBaud {
                divisor,
                switchover,
            } => {
                range(divisor >= 1, "baud rate divisor")?;
                range(
                    (1..=MAX_SWITCHOVER).contains(&switchover),
                    "switch-over delay",
                )
            }
            Self::PacketTimeout { timeout } => range(timeout >= 2, "timeout"),
            Self::CanRs232 { forward_count, .. } => range(forward_count <= 8, "forward count"),
            _ => Ok(()),
        }
    }
}

word_frame! {
    /// A whole request word: the pack's address, the command and P0..P6 (manual 6.1).
    RequestFrame {
        /// Address of the pack (rotary switches, or $42).
        address,
        /// The request.
        request: Request,
    }
    /// A request to the pack at `address`.
    new
}
