//! Typed requests (host → pack), one variant per instruction of the section 9 table.

use crate::params::{
    PARAMS, assemble, bit0, byte, i16_at, i32_at, put, split_word, u16_at, u32_at, write_word,
};
use crate::types::{
    CurrentLevel, MotorMask, MotorOptions, MotorType, PowerDownRequest, ReferenceFlags, check_motor,
};
use crate::{Command, Error, Word};

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

/// A request, without its address byte. See [`RequestFrame`] for the whole 9-byte word.
///
/// Field names follow the manual; `reply_to` is the "response address" a query carries.
/// Unused parameter bytes are sent as zero and ignored when decoding.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Request {
    /// $10: peak current of the motor pair (only motors 0, 2, 4 are used by the pack).
    PeakCurrent {
        /// Motor number.
        motor: u8,
        /// 0..=255: SIXpack Imax = 0.8 A · value/256; QUADpack 1.5 A · value/256 · DIP.
        value: u8,
    },
    /// $11: current control.
    CurrentControl {
        /// Motor number.
        motor: u8,
        /// I0: power-down current.
        i0: CurrentLevel,
        /// I1: current at standstill.
        i1: CurrentLevel,
        /// I2: current at constant velocity.
        i2: CurrentLevel,
        /// I3: current while accelerating.
        i3: CurrentLevel,
        /// T0: power-down delay in 2 ms units, 1..=65535.
        t0: u16,
    },
    /// $12: global clock divider `clkdiv`, 0..=31.
    VelocitySetting {
        /// clkdiv.
        clkdiv: u8,
    },
    /// $13: starting velocity.
    StartingVelocity {
        /// Motor number.
        motor: u8,
        /// vmin 0..=511 (used with div 3 for the reference switch; 0 = automatic).
        vmin: u16,
        /// vstart 1..=511.
        vstart: u16,
        /// div_i 0..=3.
        div: u8,
    },
    /// $14: acceleration and maximum velocity.
    VelocityAcceleration {
        /// Motor number.
        motor: u8,
        /// amax 1..=32767 (amax/64 accumulated at 500 Hz).
        amax: u16,
        /// vmax 1..=511.
        vmax: u16,
    },
    /// $15: motor parameters.
    MotorParameters {
        /// Motor number.
        motor: u8,
        /// poslimit 0..=0x7FFF_FFFF microsteps.
        poslimit: u32,
        /// P5 motor type bits.
        motor_type: MotorType,
        /// P6 option bits.
        options: MotorOptions,
    },
    /// $16: reference search parameters.
    ReferenceParameters {
        /// Motor number.
        motor: u8,
        /// vrefmax 1..=511.
        vrefmax: u16,
        /// De-bounce mask ($0001 = 0 ms, $0003 = 2 ms, $FFFF = 30 ms).
        debounce_mask: u16,
        /// P5 flags.
        flags: ReferenceFlags,
    },
    /// $17: four entries of the microstep table.
    MicrostepTable {
        /// Start index 0, 4, 8 or 12.
        pointer: u8,
        /// Four table entries.
        entries: [u8; 4],
    },
    /// $18: null point offset and test range.
    NullOffset {
        /// Motor number.
        motor: u8,
        /// nulloffset: distance between zero point and reference switch.
        nulloffset: i32,
        /// testnullrange 0..=65535.
        testnullrange: u16,
    },
    /// $19: PI controller parameters.
    PiParameters {
        /// Motor number.
        motor: u8,
        /// propdiv 1..=255.
        propdiv: u8,
        /// intdiv 1..=32767.
        intdiv: u16,
        /// intclip 1..=32767.
        intclip: u16,
        /// intinpclip 0..=255.
        intinpclip: u8,
    },
    /// $20: query position and activity.
    QueryPosition {
        /// Motor number.
        motor: u8,
        /// Response address.
        reply_to: u8,
    },
    /// $21: query velocity and activity.
    QueryVelocity {
        /// Motor number.
        motor: u8,
        /// Response address.
        reply_to: u8,
    },
    /// $22: start the reference search.
    ReferenceSearch {
        /// Motor number.
        motor: u8,
    },
    /// $23: start a trapezoidal ramp (ignored by the pack while the motor is active).
    StartRamp {
        /// Motor number.
        motor: u8,
        /// Target position.
        target: i32,
    },
    /// $24: PI controller on a target position.
    PiTarget {
        /// Motor number.
        motor: u8,
        /// Target position.
        target: i32,
    },
    /// $25: rotation at a velocity.
    Rotate {
        /// Motor number.
        motor: u8,
        /// Velocity -511..=511.
        velocity: i16,
    },
    /// $26: set the target position on the fly.
    SetTarget {
        /// Motor number.
        motor: u8,
        /// Target position.
        target: i32,
    },
    /// $27: set the actual position.
    SetPosition {
        /// Motor number.
        motor: u8,
        /// New actual position.
        position: i32,
    },
    /// $28: query all actions, optionally delayed until the masked motors are inactive.
    QueryActions {
        /// Response address.
        reply_to: u8,
        /// Motors to wait for (empty: answer at once).
        delay_mask: MotorMask,
    },
    /// $29: start ramps in parallel to the targets set with $26.
    StartRampParallel {
        /// Motors to start.
        mask: MotorMask,
    },
    /// $2A: set the target of the masked motors to their actual position.
    Stop {
        /// Motors to stop.
        mask: MotorMask,
    },
    /// $30: read an analogue channel and the inputs.
    ReadInput {
        /// Channel 0..=7 (6 = external input, 7 = supply voltage).
        channel: u8,
        /// Response address.
        reply_to: u8,
    },
    /// $31: analogue stop limits.
    StopLimits {
        /// Channel 0..=7.
        channel: u8,
        /// Minimum for stop left (0 = no function).
        left_min: u16,
        /// Maximum for stop right (≥ 1023 = no function).
        right_max: u16,
    },
    /// $32: additional outputs (bit 0 of P0..P3).
    Outputs {
        /// P0: logic level at TTLOUT1.
        ttlout1: bool,
        /// P1: TTLIO1 direction, `true` = input, `false` = output.
        ttlio1_input: bool,
        /// P2: logic level at TTLIO1.
        ttlio1: bool,
        /// P3: TTLOUT1 works as ready output.
        ttlout1_ready: bool,
    },
    /// $33: which motors drive the ready output.
    ReadyOutput {
        /// Motors whose activity counts.
        active_mask: MotorMask,
        /// Motors whose reference search counts.
        reference_mask: MotorMask,
    },
    /// $40: baud rate divisor and transmitter switch-over delay.
    SetBaud {
        /// Divisor = 20 MHz / (16 · baud), ≥ 1.
        divisor: u16,
        /// Switch-over delay in 2 ms units, 1..=1000.
        switchover: u16,
    },
    /// $41: packet timeout in 2 ms units, 2..=65535.
    PacketTimeout {
        /// Timeout in 2 ms units.
        timeout: u16,
    },
    /// $42: new RS-232 / RS-485 address.
    SetAddress {
        /// New address.
        address: u8,
    },
    /// $43: read unit information.
    UnitInfo {
        /// Response address.
        reply_to: u8,
    },
    /// $44: configure / query RS-232 operation via CAN.
    CanRs232 {
        /// Response address.
        reply_to: u8,
        /// Response address (upper 8 bits) for bytes received on RS-232.
        rs232_reply_to: u8,
        /// Bytes to collect before forwarding, 0..=8 (0 = disabled).
        forward_count: u8,
    },
    /// $45: power-down mode.
    PowerDown {
        /// Response address.
        reply_to: u8,
        /// P1 bits.
        flags: PowerDownRequest,
    },
    /// $CC: complete hardware reset (about 1 s; parameters back to defaults).
    HardwareReset,
    /// $50: multi-dimensional linear interpolation to the targets set with $26.
    Interpolate {
        /// Motors taking part.
        mask: MotorMask,
    },
    /// $F2: enable erasing and writing the flash (service).
    FlashEnable {
        /// Response address.
        reply_to: u8,
        /// Magic code.
        magic: u32,
    },
    /// $F3: program seven flash bytes (service).
    FlashProgram {
        /// Data bytes.
        data: [u8; 7],
    },
    /// $F4: flash checksum, aborts programming (service).
    FlashChecksum {
        /// Response address.
        reply_to: u8,
    },
    /// $F5: read seven flash bytes (service).
    FlashRead {
        /// Response address.
        reply_to: u8,
    },
    /// $F6: write an EEPROM word (service).
    EepromWrite {
        /// Response address.
        reply_to: u8,
        /// Magic code 2.
        magic: u16,
        /// EEPROM address.
        address: u16,
        /// Value.
        value: u16,
    },
    /// $F7: read EEPROM (service; the manual tables the same parameters as $F6).
    EepromRead {
        /// Response address.
        reply_to: u8,
        /// Magic code 2.
        magic: u16,
        /// EEPROM address.
        address: u16,
        /// Value field as tabled.
        value: u16,
    },
}

const fn range(ok: bool, field: &'static str) -> Result<(), Error> {
    if ok {
        Ok(())
    } else {
        Err(Error::OutOfRange { field })
    }
}

impl Request {
    /// The instruction code.
    pub const fn command(&self) -> Command {
        match self {
            Self::PeakCurrent { .. } => Command::PeakCurrent,
            Self::CurrentControl { .. } => Command::CurrentControl,
            Self::VelocitySetting { .. } => Command::VelocitySetting,
            Self::StartingVelocity { .. } => Command::StartingVelocity,
            Self::VelocityAcceleration { .. } => Command::VelocityAcceleration,
            Self::MotorParameters { .. } => Command::MotorParameters,
            Self::ReferenceParameters { .. } => Command::ReferenceParameters,
            Self::MicrostepTable { .. } => Command::MicrostepTable,
            Self::NullOffset { .. } => Command::NullOffset,
            Self::PiParameters { .. } => Command::PiParameters,
            Self::QueryPosition { .. } => Command::QueryPosition,
            Self::QueryVelocity { .. } => Command::QueryVelocity,
            Self::ReferenceSearch { .. } => Command::ReferenceSearch,
            Self::StartRamp { .. } => Command::StartRamp,
            Self::PiTarget { .. } => Command::PiTarget,
            Self::Rotate { .. } => Command::Rotate,
            Self::SetTarget { .. } => Command::SetTarget,
            Self::SetPosition { .. } => Command::SetPosition,
            Self::QueryActions { .. } => Command::QueryActions,
            Self::StartRampParallel { .. } => Command::StartRampParallel,
            Self::Stop { .. } => Command::Stop,
            Self::ReadInput { .. } => Command::ReadInput,
            Self::StopLimits { .. } => Command::StopLimits,
            Self::Outputs { .. } => Command::Outputs,
            Self::ReadyOutput { .. } => Command::ReadyOutput,
            Self::SetBaud { .. } => Command::SetBaud,
            Self::PacketTimeout { .. } => Command::PacketTimeout,
            Self::SetAddress { .. } => Command::SetAddress,
            Self::UnitInfo { .. } => Command::UnitInfo,
            Self::CanRs232 { .. } => Command::CanRs232,
            Self::PowerDown { .. } => Command::PowerDown,
            Self::HardwareReset => Command::HardwareReset,
            Self::Interpolate { .. } => Command::Interpolate,
            Self::FlashEnable { .. } => Command::FlashEnable,
            Self::FlashProgram { .. } => Command::FlashProgram,
            Self::FlashChecksum { .. } => Command::FlashChecksum,
            Self::FlashRead { .. } => Command::FlashRead,
            Self::EepromWrite { .. } => Command::EepromWrite,
            Self::EepromRead { .. } => Command::EepromRead,
        }
    }

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

    /// Writes P0..P6 (unused bytes zero). Validates first.
    pub fn encode_params(&self) -> Result<[u8; PARAMS], Error> {
        self.validate()?;
        let mut p = [0u8; PARAMS];
        if let Some(m) = self.motor() {
            p[0] = m;
        }
        match *self {
            Self::PeakCurrent { value, .. } => p[1] = value,
            Self::CurrentControl {
                i0, i1, i2, i3, t0, ..
            } => {
                put(&mut p, 1, &[i0.index(), i1.index(), i2.index(), i3.index()]);
                put(&mut p, 5, &t0.to_le_bytes());
            }
            Self::VelocitySetting { clkdiv } => p[0] = clkdiv,
            Self::StartingVelocity {
                vmin, vstart, div, ..
            } => {
                put(&mut p, 1, &vmin.to_le_bytes());
                put(&mut p, 3, &vstart.to_le_bytes());
                p[5] = div;
            }
            Self::VelocityAcceleration { amax, vmax, .. } => {
                put(&mut p, 1, &amax.to_le_bytes());
                put(&mut p, 3, &vmax.to_le_bytes());
            }
            Self::MotorParameters {
                poslimit,
                motor_type,
                options,
                ..
            } => {
                put(&mut p, 1, &poslimit.to_le_bytes());
                p[5] = motor_type.bits();
                p[6] = options.bits();
            }
            Self::ReferenceParameters {
                vrefmax,
                debounce_mask,
                flags,
                ..
            } => {
                put(&mut p, 1, &vrefmax.to_le_bytes());
                put(&mut p, 3, &debounce_mask.to_le_bytes());
                p[5] = flags.bits();
            }
            Self::MicrostepTable { pointer, entries } => {
                p[0] = pointer;
                put(&mut p, 1, &entries);
            }
            Self::NullOffset {
                nulloffset,
                testnullrange,
                ..
            } => {
                put(&mut p, 1, &nulloffset.to_le_bytes());
                put(&mut p, 5, &testnullrange.to_le_bytes());
            }
            Self::PiParameters {
                propdiv,
                intdiv,
                intclip,
                intinpclip,
                ..
            } => {
                p[1] = propdiv;
                put(&mut p, 2, &intdiv.to_le_bytes());
                put(&mut p, 4, &intclip.to_le_bytes());
                p[6] = intinpclip;
            }
            Self::QueryPosition { reply_to, .. } | Self::QueryVelocity { reply_to, .. } => {
                p[1] = reply_to;
            }
            Self::StartRamp { target, .. }
            | Self::PiTarget { target, .. }
            | Self::SetTarget { target, .. } => put(&mut p, 1, &target.to_le_bytes()),
            Self::SetPosition { position, .. } => put(&mut p, 1, &position.to_le_bytes()),
            Self::Rotate { velocity, .. } => put(&mut p, 1, &velocity.to_le_bytes()),
            Self::QueryActions {
                reply_to,
                delay_mask,
            } => {
                p[0] = reply_to;
                p[1] = delay_mask.bits();
            }
            Self::StartRampParallel { mask } | Self::Stop { mask } | Self::Interpolate { mask } => {
                p[0] = mask.bits();
            }
            Self::ReadInput { channel, reply_to } => {
                p[0] = channel;
                p[1] = reply_to;
            }
            Self::StopLimits {
                channel,
                left_min,
                right_max,
            } => {
                p[0] = channel;
                put(&mut p, 1, &left_min.to_le_bytes());
                put(&mut p, 3, &right_max.to_le_bytes());
            }
            Self::Outputs {
                ttlout1,
                ttlio1_input,
                ttlio1,
                ttlout1_ready,
            } => {
                p[0] = u8::from(ttlout1);
                p[1] = u8::from(ttlio1_input);
                p[2] = u8::from(ttlio1);
                p[3] = u8::from(ttlout1_ready);
            }
            Self::ReadyOutput {
                active_mask,
                reference_mask,
            } => {
                p[0] = active_mask.bits();
                p[1] = reference_mask.bits();
            }
            Self::SetBaud {
                divisor,
                switchover,
            } => {
                put(&mut p, 0, &divisor.to_le_bytes());
                put(&mut p, 2, &switchover.to_le_bytes());
            }
            Self::PacketTimeout { timeout } => put(&mut p, 0, &timeout.to_le_bytes()),
            Self::SetAddress { address } => p[0] = address,
            Self::UnitInfo { reply_to }
            | Self::FlashChecksum { reply_to }
            | Self::FlashRead { reply_to } => p[0] = reply_to,
            Self::CanRs232 {
                reply_to,
                rs232_reply_to,
                forward_count,
            } => {
                put(&mut p, 0, &[reply_to, rs232_reply_to, forward_count]);
            }
            Self::PowerDown { reply_to, flags } => put(&mut p, 0, &[reply_to, flags.bits()]),
            Self::FlashEnable { reply_to, magic } => {
                p[0] = reply_to;
                put(&mut p, 1, &magic.to_le_bytes());
            }
            Self::FlashProgram { data } => p = data,
            Self::EepromWrite {
                reply_to,
                magic,
                address,
                value,
            }
            | Self::EepromRead {
                reply_to,
                magic,
                address,
                value,
            } => {
                p[0] = reply_to;
                put(&mut p, 1, &magic.to_le_bytes());
                put(&mut p, 3, &address.to_le_bytes());
                put(&mut p, 5, &value.to_le_bytes());
            }
            Self::ReferenceSearch { .. } | Self::HardwareReset => {}
        }
        Ok(p)
    }

    /// Parses P0..P6 for `command` and validates the result.
    pub fn decode_params(command: Command, p: &[u8; PARAMS]) -> Result<Self, Error> {
        let motor = byte(p, 0);
        let mask = |i| MotorMask::from_bits_retain(byte(p, i));
        let level = |i| CurrentLevel::from_index(byte(p, i));
        let req = match command {
            Command::PeakCurrent => Self::PeakCurrent {
                motor,
                value: byte(p, 1),
            },
            Command::CurrentControl => Self::CurrentControl {
                motor,
                i0: level(1)?,
                i1: level(2)?,
                i2: level(3)?,
                i3: level(4)?,
                t0: u16_at(p, 5),
            },
            Command::VelocitySetting => Self::VelocitySetting { clkdiv: motor },
            Command::StartingVelocity => Self::StartingVelocity {
                motor,
                vmin: u16_at(p, 1),
                vstart: u16_at(p, 3),
                div: byte(p, 5),
            },
            Command::VelocityAcceleration => Self::VelocityAcceleration {
                motor,
                amax: u16_at(p, 1),
                vmax: u16_at(p, 3),
            },
            Command::MotorParameters => Self::MotorParameters {
                motor,
                poslimit: u32_at(p, 1),
                motor_type: MotorType::from_bits_retain(byte(p, 5)),
                options: MotorOptions::from_bits_retain(byte(p, 6)),
            },
            Command::ReferenceParameters => Self::ReferenceParameters {
                motor,
                vrefmax: u16_at(p, 1),
                debounce_mask: u16_at(p, 3),
                flags: ReferenceFlags::from_bits_retain(byte(p, 5)),
            },
            Command::MicrostepTable => Self::MicrostepTable {
                pointer: motor,
                entries: [byte(p, 1), byte(p, 2), byte(p, 3), byte(p, 4)],
            },
            Command::NullOffset => Self::NullOffset {
                motor,
                nulloffset: i32_at(p, 1),
                testnullrange: u16_at(p, 5),
            },
            Command::PiParameters => Self::PiParameters {
                motor,
                propdiv: byte(p, 1),
                intdiv: u16_at(p, 2),
                intclip: u16_at(p, 4),
                intinpclip: byte(p, 6),
            },
            Command::QueryPosition => Self::QueryPosition {
                motor,
                reply_to: byte(p, 1),
            },
            Command::QueryVelocity => Self::QueryVelocity {
                motor,
                reply_to: byte(p, 1),
            },
            Command::ReferenceSearch => Self::ReferenceSearch { motor },
            Command::StartRamp => Self::StartRamp {
                motor,
                target: i32_at(p, 1),
            },
            Command::PiTarget => Self::PiTarget {
                motor,
                target: i32_at(p, 1),
            },
            Command::Rotate => Self::Rotate {
                motor,
                velocity: i16_at(p, 1),
            },
            Command::SetTarget => Self::SetTarget {
                motor,
                target: i32_at(p, 1),
            },
            Command::SetPosition => Self::SetPosition {
                motor,
                position: i32_at(p, 1),
            },
            Command::QueryActions => Self::QueryActions {
                reply_to: byte(p, 0),
                delay_mask: mask(1),
            },
            Command::StartRampParallel => Self::StartRampParallel { mask: mask(0) },
            Command::Stop => Self::Stop { mask: mask(0) },
            Command::ReadInput => Self::ReadInput {
                channel: byte(p, 0),
                reply_to: byte(p, 1),
            },
            Command::StopLimits => Self::StopLimits {
                channel: byte(p, 0),
                left_min: u16_at(p, 1),
                right_max: u16_at(p, 3),
            },
            Command::Outputs => Self::Outputs {
                ttlout1: bit0(p, 0),
                ttlio1_input: bit0(p, 1),
                ttlio1: bit0(p, 2),
                ttlout1_ready: bit0(p, 3),
            },
            Command::ReadyOutput => Self::ReadyOutput {
                active_mask: mask(0),
                reference_mask: mask(1),
            },
            Command::SetBaud => Self::SetBaud {
                divisor: u16_at(p, 0),
                switchover: u16_at(p, 2),
            },
            Command::PacketTimeout => Self::PacketTimeout {
                timeout: u16_at(p, 0),
            },
            Command::SetAddress => Self::SetAddress {
                address: byte(p, 0),
            },
            Command::UnitInfo => Self::UnitInfo {
                reply_to: byte(p, 0),
            },
            Command::CanRs232 => Self::CanRs232 {
                reply_to: byte(p, 0),
                rs232_reply_to: byte(p, 1),
                forward_count: byte(p, 2),
            },
            Command::PowerDown => Self::PowerDown {
                reply_to: byte(p, 0),
                flags: PowerDownRequest::from_bits_retain(byte(p, 1)),
            },
            Command::HardwareReset => Self::HardwareReset,
            Command::Interpolate => Self::Interpolate { mask: mask(0) },
            Command::FlashEnable => Self::FlashEnable {
                reply_to: byte(p, 0),
                magic: u32_at(p, 1),
            },
            Command::FlashProgram => Self::FlashProgram { data: *p },
            Command::FlashChecksum => Self::FlashChecksum {
                reply_to: byte(p, 0),
            },
            Command::FlashRead => Self::FlashRead {
                reply_to: byte(p, 0),
            },
            Command::EepromWrite => Self::EepromWrite {
                reply_to: byte(p, 0),
                magic: u16_at(p, 1),
                address: u16_at(p, 3),
                value: u16_at(p, 5),
            },
            Command::EepromRead => Self::EepromRead {
                reply_to: byte(p, 0),
                magic: u16_at(p, 1),
                address: u16_at(p, 3),
                value: u16_at(p, 5),
            },
        };
        req.validate()?;
        Ok(req)
    }
}

/// A whole request word: the pack's address, the command and P0..P6 (manual 6.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct RequestFrame {
    /// Address of the pack (rotary switches, or $42).
    pub address: u8,
    /// The request.
    pub request: Request,
}

impl RequestFrame {
    /// A request to the pack at `address`.
    pub const fn new(address: u8, request: Request) -> Self {
        Self { address, request }
    }

    /// The 9-byte word.
    pub fn to_word(&self) -> Result<Word, Error> {
        let p = self.request.encode_params()?;
        Ok(assemble(self.address, self.request.command(), &p))
    }

    /// Encodes the 9-byte word into `buf`; returns 9.
    pub fn encode(&self, buf: &mut [u8]) -> Result<usize, Error> {
        write_word(&self.to_word()?, buf)
    }

    /// Decodes exactly one 9-byte word.
    pub fn decode(bytes: &[u8]) -> Result<Self, Error> {
        let (address, command, p) = split_word(bytes)?;
        Ok(Self {
            address,
            request: Request::decode_params(command, &p)?,
        })
    }
}
