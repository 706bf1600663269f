//! proptest strategies for every request and reply.
#![allow(dead_code)]

use proptest::prelude::*;
use tmcpack::{
    Action, CurrentLevel, MotorMask, MotorOptions, MotorType, PowerDownRequest, PowerDownStatus,
    RefInputs, ReferenceFlags, Reply, Request,
};

pub fn motor() -> impl Strategy<Value = u8> {
    0u8..=5
}

pub fn mask() -> impl Strategy<Value = MotorMask> {
    (0u8..=0x3F).prop_map(MotorMask::from_bits_retain)
}

pub fn level() -> impl Strategy<Value = CurrentLevel> {
    (0u8..=8).prop_map(|i| CurrentLevel::from_index(i).expect("0..=8"))
}

pub fn action() -> impl Strategy<Value = Action> {
    any::<u8>().prop_map(Action::from_u8)
}

pub fn request() -> impl Strategy<Value = Request> {
    let vel = 0u16..=511;
    prop_oneof![
        (motor(), any::<u8>()).prop_map(|(motor, value)| Request::PeakCurrent { motor, value }),
        (motor(), level(), level(), level(), level(), 1u16..).prop_map(
            |(motor, i0, i1, i2, i3, t0)| {
                Request::CurrentControl {
                    motor,
                    i0,
                    i1,
                    i2,
                    i3,
                    t0,
                }
            }
        ),
        (0u8..=31).prop_map(|clkdiv| Request::VelocitySetting { clkdiv }),
        (motor(), vel.clone(), 1u16..=511, 0u8..=3).prop_map(|(motor, vmin, vstart, div)| {
            Request::StartingVelocity {
                motor,
                vmin,
                vstart,
                div,
            }
        }),
        (motor(), 1u16..=32767, 1u16..=511)
            .prop_map(|(motor, amax, vmax)| Request::VelocityAcceleration { motor, amax, vmax }),
        (motor(), 0u32..=0x7FFF_FFFF, any::<u8>(), any::<u8>()).prop_map(
            |(motor, poslimit, t, o)| {
                Request::MotorParameters {
                    motor,
                    poslimit,
                    motor_type: MotorType::from_bits_retain(t),
                    options: MotorOptions::from_bits_retain(o),
                }
            }
        ),
        (motor(), 1u16..=511, any::<u16>(), any::<u8>()).prop_map(|(motor, vrefmax, m, f)| {
            Request::ReferenceParameters {
                motor,
                vrefmax,
                debounce_mask: m,
                flags: ReferenceFlags::from_bits_retain(f),
            }
        }),
        (prop::sample::select(vec![0u8, 4, 8, 12]), any::<[u8; 4]>())
            .prop_map(|(pointer, entries)| Request::MicrostepTable { pointer, entries }),
        (motor(), any::<i32>(), any::<u16>()).prop_map(|(motor, nulloffset, testnullrange)| {
            Request::NullOffset {
                motor,
                nulloffset,
                testnullrange,
            }
        }),
        (motor(), 1u8.., 1u16..=32767, 1u16..=32767, any::<u8>()).prop_map(
            |(motor, propdiv, intdiv, intclip, intinpclip)| Request::PiParameters {
                motor,
                propdiv,
                intdiv,
                intclip,
                intinpclip
            }
        ),
        (motor(), any::<u8>())
            .prop_map(|(motor, reply_to)| Request::QueryPosition { motor, reply_to }),
        (motor(), any::<u8>())
            .prop_map(|(motor, reply_to)| Request::QueryVelocity { motor, reply_to }),
        motor().prop_map(|motor| Request::ReferenceSearch { motor }),
        (motor(), any::<i32>()).prop_map(|(motor, target)| Request::StartRamp { motor, target }),
        (motor(), any::<i32>()).prop_map(|(motor, target)| Request::PiTarget { motor, target }),
        (motor(), -511i16..=511).prop_map(|(motor, velocity)| Request::Rotate { motor, velocity }),
        (motor(), any::<i32>()).prop_map(|(motor, target)| Request::SetTarget { motor, target }),
        (motor(), any::<i32>())
            .prop_map(|(motor, position)| Request::SetPosition { motor, position }),
        (any::<u8>(), mask()).prop_map(|(reply_to, delay_mask)| Request::QueryActions {
            reply_to,
            delay_mask
        }),
        mask().prop_map(|mask| Request::StartRampParallel { mask }),
        mask().prop_map(|mask| Request::Stop { mask }),
        (0u8..=7, any::<u8>())
            .prop_map(|(channel, reply_to)| Request::ReadInput { channel, reply_to }),
        (0u8..=7, any::<u16>(), any::<u16>()).prop_map(|(channel, left_min, right_max)| {
            Request::StopLimits {
                channel,
                left_min,
                right_max,
            }
        }),
        any::<[bool; 4]>().prop_map(|b| Request::Outputs {
            ttlout1: b[0],
            ttlio1_input: b[1],
            ttlio1: b[2],
            ttlout1_ready: b[3]
        }),
        (mask(), mask()).prop_map(|(active_mask, reference_mask)| Request::ReadyOutput {
            active_mask,
            reference_mask
        }),
        (1u16.., 1u16..=1000).prop_map(|(divisor, switchover)| Request::SetBaud {
            divisor,
            switchover
        }),
        (2u16..).prop_map(|timeout| Request::PacketTimeout { timeout }),
        any::<u8>().prop_map(|address| Request::SetAddress { address }),
        any::<u8>().prop_map(|reply_to| Request::UnitInfo { reply_to }),
        (any::<u8>(), any::<u8>(), 0u8..=8).prop_map(
            |(reply_to, rs232_reply_to, forward_count)| {
                Request::CanRs232 {
                    reply_to,
                    rs232_reply_to,
                    forward_count,
                }
            }
        ),
        (any::<u8>(), any::<u8>()).prop_map(|(reply_to, f)| Request::PowerDown {
            reply_to,
            flags: PowerDownRequest::from_bits_retain(f)
        }),
        Just(Request::HardwareReset),
        mask().prop_map(|mask| Request::Interpolate { mask }),
        (any::<u8>(), any::<u32>())
            .prop_map(|(reply_to, magic)| Request::FlashEnable { reply_to, magic }),
        any::<[u8; 7]>().prop_map(|data| Request::FlashProgram { data }),
        any::<u8>().prop_map(|reply_to| Request::FlashChecksum { reply_to }),
        any::<u8>().prop_map(|reply_to| Request::FlashRead { reply_to }),
        (any::<u8>(), any::<u16>(), any::<u16>(), any::<u16>()).prop_map(
            |(reply_to, magic, address, value)| {
                Request::EepromWrite {
                    reply_to,
                    magic,
                    address,
                    value,
                }
            }
        ),
        (any::<u8>(), any::<u16>(), any::<u16>(), any::<u16>()).prop_map(
            |(reply_to, magic, address, value)| {
                Request::EepromRead {
                    reply_to,
                    magic,
                    address,
                    value,
                }
            }
        ),
    ]
}

pub fn reply() -> impl Strategy<Value = Reply> {
    prop_oneof![
        (motor(), any::<i32>(), action(), any::<bool>()).prop_map(
            |(motor, position, action, stopped)| {
                Reply::Position {
                    motor,
                    position,
                    action,
                    stopped,
                }
            }
        ),
        (motor(), any::<i16>(), action()).prop_map(|(motor, velocity, action)| Reply::Velocity {
            motor,
            velocity,
            action
        }),
        prop::array::uniform6(action()).prop_map(|actions| Reply::Actions { actions }),
        (
            0u8..=7,
            0u16..=1023,
            any::<bool>(),
            any::<u8>(),
            any::<bool>()
        )
            .prop_map(|(channel, value, reference, i, ttlio1)| Reply::Input {
                channel,
                value,
                reference,
                inputs: RefInputs::from_bits_retain(i),
                ttlio1
            }),
        (any::<u8>(), any::<bool>(), any::<i8>(), any::<u16>()).prop_map(
            |(firmware, reset, temperature, serial)| Reply::UnitInfo {
                firmware,
                reset,
                temperature,
                serial
            }
        ),
        (any::<u8>(), any::<bool>())
            .prop_map(|(tx_pending, cts)| Reply::CanRs232 { tx_pending, cts }),
        any::<u8>().prop_map(|s| Reply::PowerDown {
            status: PowerDownStatus::from_bits_retain(s)
        }),
        any::<bool>().prop_map(|ok| Reply::FlashEnable { ok }),
        any::<u16>().prop_map(|checksum| Reply::FlashChecksum { checksum }),
        any::<[u8; 7]>().prop_map(|data| Reply::FlashData { data }),
        any::<bool>().prop_map(|ok| Reply::EepromWrite { ok }),
        any::<bool>().prop_map(|ok| Reply::EepromRead { ok }),
    ]
}
