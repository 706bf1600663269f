//! Golden vectors from the SIXpack/QUADpack manual (V2.43), quoting the sections.

use tmcpack::convert::{self, AmaxDivisor, StepClock, Variant};
use tmcpack::{
    Action, CanFrame, Command, CurrentLevel, Error, MotorMask, MotorOptions, MotorType,
    OptionsLayout, Reply, ReplyFrame, Request, RequestFrame,
};

const PACK: u8 = 1;

fn word(req: Request) -> [u8; 9] {
    RequestFrame::new(PACK, req)
        .to_word()
        .expect("valid request")
}

/// Manual 7.2 "Starting a two axis interpolated movement": `sendToPack(address);
/// sendToPack($26); sendToPack(0); sendToPack($E8); sendToPack($03); sendToPack($00);
/// sendToPack($00); sendToPack(0); sendToPack(0);` then the same for motor 1 with $D0 $07,
/// then `sendToPack($50); sendToPack($03)` and zeros.
#[test]
fn manual_7_2_two_axis_interpolated_movement() {
    let m0 = [PACK, 0x26, 0x00, 0xE8, 0x03, 0x00, 0x00, 0x00, 0x00];
    let m1 = [PACK, 0x26, 0x01, 0xD0, 0x07, 0x00, 0x00, 0x00, 0x00];
    let go = [PACK, 0x50, 0x03, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00];
    assert_eq!(
        word(Request::SetTarget {
            motor: 0,
            target: 1000
        }),
        m0
    );
    assert_eq!(
        word(Request::SetTarget {
            motor: 1,
            target: 2000
        }),
        m1
    );
    assert_eq!(
        word(Request::Interpolate {
            mask: MotorMask::M0 | MotorMask::M1
        }),
        go
    );
    for (w, r) in [
        (
            m0,
            Request::SetTarget {
                motor: 0,
                target: 1000,
            },
        ),
        (
            m1,
            Request::SetTarget {
                motor: 1,
                target: 2000,
            },
        ),
        (
            go,
            Request::Interpolate {
                mask: MotorMask::from_bits_retain(3),
            },
        ),
    ] {
        assert_eq!(RequestFrame::decode(&w), Ok(RequestFrame::new(PACK, r)));
    }
}

/// Manual 7.2 "Navigating the motor": address, $23, motnr, destination LSB … MSB, 0, 0.
#[test]
fn manual_7_2_navigating_the_motor_23() {
    let w = word(Request::StartRamp {
        motor: 2,
        target: 0x1234_5678,
    });
    assert_eq!(w, [PACK, 0x23, 2, 0x78, 0x56, 0x34, 0x12, 0, 0]);
    let neg = word(Request::StartRamp {
        motor: 5,
        target: -2,
    });
    assert_eq!(neg, [PACK, 0x23, 5, 0xFE, 0xFF, 0xFF, 0xFF, 0, 0]);
}

/// Manual 7.2 "Inquiring the actual position of a motor": address, $20, motnr, receiver,
/// zeros; the pack answers cmd $20, motnr, posakt byte1 (LSB) … byte4 (MSB), act_action,
/// stop (8.4: "bit 0: stop-status").
#[test]
fn manual_7_2_inquiring_position_20() {
    let receiver = 0xFE;
    assert_eq!(
        word(Request::QueryPosition {
            motor: 1,
            reply_to: receiver
        }),
        [PACK, 0x20, 1, receiver, 0, 0, 0, 0, 0]
    );
    let answer = [receiver, 0x20, 1, 0xD0, 0x07, 0x00, 0x00, 5, 1];
    assert_eq!(
        ReplyFrame::decode(&answer),
        Ok(ReplyFrame::new(
            receiver,
            Reply::Position {
                motor: 1,
                position: 2000,
                action: Action::Ramp,
                stopped: true
            }
        ))
    );
}

/// Manual 7.2 "Setting motor parameters" layout ($15, motor, poslimit LSB … MSB, P5, P6) with
/// the 7.1 default values: poslimit = 400·16, motortype = DelayedTest0 | NullCenter |
/// FilterSwitch | FastRef.
#[test]
fn manual_7_1_default_motor_parameters_15() {
    let req = Request::MotorParameters {
        motor: 0,
        poslimit: 400 * 16,
        motor_type: MotorType::NULL_CENTER | MotorType::FILTER_SWITCH,
        options: MotorOptions::DELAY_TEST_NULL | MotorOptions::FAST_REF,
    };
    assert_eq!(
        word(req),
        [PACK, 0x15, 0, 0x00, 0x19, 0x00, 0x00, 0xA0, 0x0A]
    );
}

/// Manual 7.1 defaults: "T0=500; I0=00%(!); I1=50%; I2=75%; I3=100%" as $11; "vmin=4;
/// vstart=5; div=2" as $13; "amax=128; vmax=511" as $14; "vrefmax=100", "De-bounce
/// mask=$0FFF" as $16; "propdiv=8; intdiv=129; intclip=129; intinpclip=1" as $19.
#[test]
fn manual_7_1_default_values() {
    let cc = Request::CurrentControl {
        motor: 3,
        i0: CurrentLevel::Off,
        i1: CurrentLevel::P50,
        i2: CurrentLevel::P75,
        i3: CurrentLevel::P100,
        t0: 500,
    };
    assert_eq!(word(cc), [PACK, 0x11, 3, 8, 2, 1, 0, 0xF4, 0x01]);
    let sv = Request::StartingVelocity {
        motor: 0,
        vmin: 4,
        vstart: 5,
        div: 2,
    };
    assert_eq!(word(sv), [PACK, 0x13, 0, 4, 0, 5, 0, 2, 0]);
    let va = Request::VelocityAcceleration {
        motor: 0,
        amax: 128,
        vmax: 511,
    };
    assert_eq!(word(va), [PACK, 0x14, 0, 128, 0, 0xFF, 0x01, 0, 0]);
    let rp = Request::ReferenceParameters {
        motor: 0,
        vrefmax: 100,
        debounce_mask: 0x0FFF,
        flags: tmcpack::ReferenceFlags::EMPTY,
    };
    assert_eq!(word(rp), [PACK, 0x16, 0, 100, 0, 0xFF, 0x0F, 0, 0]);
    let pi = Request::PiParameters {
        motor: 0,
        propdiv: 8,
        intdiv: 129,
        intclip: 129,
        intinpclip: 1,
    };
    assert_eq!(word(pi), [PACK, 0x19, 0, 8, 129, 0, 129, 0, 1]);
    assert_eq!(
        word(Request::VelocitySetting { clkdiv: 5 }),
        [PACK, 0x12, 5, 0, 0, 0, 0, 0, 0]
    );
}

/// Manual 7.1 defaults comments: "clkdiv=5; div=2; … vmax=511 // 26 kHz microstep-frequency",
/// "vstart=5 // starting with 254 Hz", "vmin=4 … // 102 Hz" (div 3), "vrefmax=100 // 5086 Hz".
#[test]
fn manual_8_2_microstep_frequency_matches_7_1_comments() {
    let c = StepClock::new(5, 2).expect("valid");
    assert_eq!(c.microstep_hz(511).expect("ok").round(), 25_991.0);
    assert_eq!(c.microstep_hz(5).expect("ok").round(), 254.0);
    assert_eq!(c.microstep_hz(100).expect("ok").round(), 5086.0);
    let slow = StepClock::new(5, 3).expect("valid");
    assert_eq!(slow.microstep_hz(4).expect("ok").round(), 102.0);
    assert_eq!(c.velocity_for_hz(5086.0), Ok(100));
    assert_eq!(c.microstep_hz(-511).map(f64::round), Ok(-25_991.0));
    // 8.2: "The microstep frequency must not exceed 200kHz" and v is -511..+511.
    let fast = StepClock::new(0, 0).expect("valid");
    assert_eq!(fast.microstep_hz(511), Err(Error::FrequencyTooHigh));
    assert!(fast.microstep_hz(163).is_ok());
    assert_eq!(
        c.microstep_hz(512),
        Err(Error::OutOfRange { field: "velocity" })
    );
    assert_eq!(
        StepClock::new(32, 0),
        Err(Error::OutOfRange { field: "clkdiv" })
    );
    assert_eq!(
        StepClock::new(0, 4),
        Err(Error::OutOfRange { field: "div" })
    );
    // $14: "1/64 amax is accumulated with 500Hz": amax 128 adds 2 per 2 ms = 1000 units/s.
    let a = c.accel_hz_per_s(128, AmaxDivisor::By64).expect("ok");
    assert!((a - 1000.0 * c.hz_per_unit()).abs() < 1e-6);
    assert_eq!(c.amax_for_accel(a, AmaxDivisor::By64), Ok(128));
    assert!(convert::check_ramp_relations(4, 5, 511, 100, 128, AmaxDivisor::By64).is_ok());
    assert!(convert::check_ramp_relations(4, 5, 511, 100, 321, AmaxDivisor::By64).is_err());
}

/// The two readings of the `$14` divisor. 8.3 `$14`: "1/64 amax is accumulated with 500Hz
/// during acceleration to vact", "0 < amax <= vstart * 64 (default: amax =128)"; 7.1
/// "Default Values": "amax=128; // increments v by 128/16=8 each 2 ms".
#[test]
fn manual_8_3_and_7_1_amax_divisor_readings() {
    let c = StepClock::DEFAULT;
    assert_eq!(AmaxDivisor::default(), AmaxDivisor::By64);
    assert_eq!(AmaxDivisor::from_divisor(64), Some(AmaxDivisor::By64));
    assert_eq!(AmaxDivisor::from_divisor(16), Some(AmaxDivisor::By16));
    for d in [0, 1, 15, 17, 32, 63, 65, 128] {
        assert_eq!(AmaxDivisor::from_divisor(d), None, "{d}");
    }
    // 7.1: amax 128 increments v by 8 each 2 ms = 4000 units/s, 4× the $14 reading.
    let by16 = c.accel_hz_per_s(128, AmaxDivisor::By16).expect("ok");
    let by64 = c.accel_hz_per_s(128, AmaxDivisor::By64).expect("ok");
    assert!((by16 - 4000.0 * c.hz_per_unit()).abs() < 1e-6);
    assert!((by16 - 4.0 * by64).abs() < 1e-6);
    // The same acceleration asks for a quarter of the amax under the 7.1 reading.
    assert_eq!(c.amax_for_accel(by64, AmaxDivisor::By16), Ok(32));
    assert_eq!(c.amax_for_accel(by16, AmaxDivisor::By16), Ok(128));
    // One tick's change stays within vstart: vstart 5 allows amax 320 at /64, 80 at /16.
    assert!(convert::check_ramp_relations(4, 5, 511, 100, 320, AmaxDivisor::By64).is_ok());
    assert!(convert::check_ramp_relations(4, 5, 511, 100, 80, AmaxDivisor::By16).is_ok());
    assert_eq!(
        convert::check_ramp_relations(4, 5, 511, 100, 81, AmaxDivisor::By16),
        Err(Error::OutOfRange { field: "amax" })
    );
    // The 7.1 defaults themselves (vstart 5, amax 128) satisfy the relation only under /64.
    assert!(convert::check_ramp_relations(4, 5, 511, 100, 128, AmaxDivisor::By16).is_err());
}

/// The two readings of `$15` P6. 8.3 `$15`, the table: "Bit 5: StopNoRef", "Bit 6:
/// NullPositive"; the prose under P5 bits 3 and 6: "if StopNoRef(P6, Bit 6)=0".
#[test]
fn manual_8_3_stop_no_ref_bit_readings() {
    assert_eq!(OptionsLayout::default(), OptionsLayout::Table);
    assert_eq!(
        OptionsLayout::from_stop_no_ref_bit(5),
        Some(OptionsLayout::Table)
    );
    assert_eq!(
        OptionsLayout::from_stop_no_ref_bit(6),
        Some(OptionsLayout::Prose)
    );
    for bit in [0, 1, 2, 3, 4, 7, 8, 255] {
        assert_eq!(OptionsLayout::from_stop_no_ref_bit(bit), None, "{bit}");
    }
    let options = MotorOptions::STOP_NO_REF | MotorOptions::FAST_REF | MotorOptions::STOP_SOFT;
    // FastRef bit 1, StopSoft bit 4, StopNoRef bit 5 (table) or 6 (prose).
    assert_eq!(OptionsLayout::Table.wire(options).bits(), 0b0011_0010);
    assert_eq!(OptionsLayout::Prose.wire(options).bits(), 0b0101_0010);
    // NullPositive moves the other way; both set, or neither, the byte is the same.
    assert_eq!(
        OptionsLayout::Prose
            .wire(MotorOptions::NULL_POSITIVE)
            .bits(),
        0b0010_0000
    );
    let both = MotorOptions::STOP_NO_REF | MotorOptions::NULL_POSITIVE;
    assert_eq!(OptionsLayout::Prose.wire(both), both);
    // On the wire: $15 motor 0, poslimit 6400, type 0, P6 as the prose reads it.
    let request = Request::MotorParameters {
        motor: 0,
        poslimit: 6400,
        motor_type: MotorType::EMPTY,
        options: OptionsLayout::Prose.wire(MotorOptions::STOP_NO_REF),
    };
    assert_eq!(
        word(request),
        [0x01, 0x15, 0x00, 0x00, 0x19, 0x00, 0x00, 0x00, 0x40]
    );
    // Every byte maps back to itself through the same reading.
    for bits in 0..=u8::MAX {
        let o = MotorOptions::from_bits_retain(bits);
        for layout in [OptionsLayout::Table, OptionsLayout::Prose] {
            assert_eq!(layout.wire(layout.wire(o)), o);
        }
    }
}

/// Manual 8.6 $40: "baud rate divisor=20MHz/(16*baud rate)"; 6.1: "pre-set to 6ms".
#[test]
fn manual_8_6_baud_divisor_40() {
    assert_eq!(convert::baud_divisor(19_200), Ok(65));
    assert_eq!(convert::nominal_baud(65), 19_200);
    assert_eq!(convert::baud_divisor(115_200), Ok(11));
    assert_eq!(
        convert::units(convert::DEFAULT_SWITCHOVER_UNITS).as_millis(),
        6
    );
    assert_eq!(
        word(Request::SetBaud {
            divisor: 65,
            switchover: 3
        }),
        [PACK, 0x40, 65, 0, 3, 0, 0, 0, 0]
    );
    assert!(
        RequestFrame::new(
            1,
            Request::SetBaud {
                divisor: 65,
                switchover: 0
            }
        )
        .to_word()
        .is_err()
    );
}

/// Manual 8.6 $40 gives the divisor formula, not a list: the rates a pack takes are the
/// standard ones the formula reaches within a UART's 2.5 %.
#[test]
fn the_rates_40_reaches_are_the_standard_ones_within_two_and_a_half_percent() {
    let listed: Vec<u32> = convert::listed_bauds().collect();
    for baud in [9_600, 19_200, 38_400, 57_600, 115_200, 250_000, 1_250_000] {
        assert!(listed.contains(&baud), "{baud}: {listed:?}");
        let divisor = convert::listed_baud_divisor(baud).expect("listed");
        let exact = convert::baud_of_divisor(divisor);
        assert!((exact - f64::from(baud)).abs() <= f64::from(baud) * 0.025);
    }
    assert_eq!(convert::listed_baud_divisor(115_200), Ok(11));
    // 230400: divisor 5 is 250000 baud, 8.5 % off; 100000 is no standard rate.
    for baud in [230_400, 100_000, 0, 460_800] {
        assert!(!listed.contains(&baud), "{baud}");
        assert!(convert::listed_baud_divisor(baud).is_err(), "{baud}");
    }
}

/// Manual 6.2: "The lower 3 address bits are fixed to 000 … Address range: $008 to $7F8";
/// 6.3: forwarding to RS-232 uses lower bits 001.
#[test]
fn manual_6_2_can_telegram() {
    let f = RequestFrame::new(
        0xFF,
        Request::SetTarget {
            motor: 0,
            target: 1000,
        },
    )
    .to_can();
    let f = f.expect("valid");
    assert_eq!(f.id, 0x7F8);
    assert_eq!(f.data, [0x26, 0x00, 0xE8, 0x03, 0, 0, 0, 0]);
    assert_eq!(RequestFrame::from_can(&f).map(|r| r.address), Ok(0xFF));
    assert!(
        RequestFrame::new(0, Request::HardwareReset)
            .to_can()
            .is_err()
    );
    let r = ReplyFrame::new(
        2,
        Reply::UnitInfo {
            firmware: 148,
            reset: true,
            temperature: -5,
            serial: 0x1234,
        },
    );
    let rc = r.to_can().expect("valid");
    assert_eq!(rc.id, 0x010);
    assert_eq!(rc.data, [0x43, 148, 1, 0xFB, 0x34, 0x12, 0, 0]);
    assert_eq!(ReplyFrame::from_can(&rc), Ok(r));
    let fw = CanFrame::rs232_forward(1, b"abc").expect("valid");
    assert_eq!((fw.id, fw.payload()), (0x009, &b"abc"[..]));
    assert!(RequestFrame::from_can(&fw).is_err());
}

/// Manual 6.2 jumper table (JP1, JP2): X X = 1 Mbit/s, - X = 500k, X - = 125k, - - = 250k.
#[test]
fn manual_6_2_can_bitrate_jumpers() {
    use tmcpack::{CanBitrate, RefInputs};
    assert_eq!(RefInputs::EMPTY.can_bitrate(), CanBitrate::Kbit250);
    assert_eq!(
        (RefInputs::JUMPER1 | RefInputs::JUMPER2).can_bitrate(),
        CanBitrate::Mbit1
    );
    assert_eq!(RefInputs::JUMPER2.can_bitrate(), CanBitrate::Kbit500);
    assert_eq!(RefInputs::JUMPER1.can_bitrate(), CanBitrate::Kbit125);
}

/// Section 9 table: every instruction decodes, and the tabled responses are the ones with a
/// reply.
#[test]
fn section_9_instruction_table_complete() {
    let codes = [
        0x10, 0x11, 0x12, 0x13, 0x14, 0x15, 0x16, 0x17, 0x18, 0x19, 0x20, 0x21, 0x22, 0x23, 0x24,
        0x25, 0x26, 0x27, 0x28, 0x29, 0x2A, 0x30, 0x31, 0x32, 0x33, 0x40, 0x41, 0x42, 0x43, 0x44,
        0x45, 0xCC, 0x50, 0xF2, 0xF3, 0xF4, 0xF5, 0xF6, 0xF7,
    ];
    assert_eq!(Command::ALL.len(), codes.len());
    for c in codes {
        assert_eq!(Command::from_u8(c).map(Command::code), Ok(c));
    }
    let replies: Vec<u8> = Command::ALL
        .iter()
        .filter(|c| c.has_reply())
        .map(|c| c.code())
        .collect();
    assert_eq!(
        replies,
        [
            0x20, 0x21, 0x28, 0x30, 0x43, 0x44, 0x45, 0xF2, 0xF4, 0xF5, 0xF6, 0xF7
        ]
    );
    assert_eq!(Command::from_u8(0x2B), Err(Error::UnknownCommand(0x2B)));
    assert_eq!(
        ReplyFrame::decode(&[0, 0x23, 0, 0, 0, 0, 0, 0, 0]),
        Err(Error::NoReply(0x23))
    );
}

/// Manual 8.4 $28 response: "P0..P5 current action (0..5)"; 8.5 $30 response layout;
/// 8.6 $43 and $45 responses.
#[test]
fn manual_8_responses_layout() {
    let a = ReplyFrame::decode(&[9, 0x28, 0, 5, 10, 15, 23, 30, 0]).expect("valid");
    assert_eq!(
        a.reply,
        Reply::Actions {
            actions: [
                Action::Inactive,
                Action::Ramp,
                Action::PiController,
                Action::Rotation,
                Action::ReferenceSearch(3),
                Action::MechanicalReference
            ]
        }
    );
    let inp = ReplyFrame::decode(&[9, 0x30, 7, 0x10, 0x02, 1, 0x41, 1, 0]).expect("valid");
    assert!(matches!(
        inp.reply,
        Reply::Input {
            channel: 7,
            value: 528,
            reference: true,
            ttlio1: true,
            ..
        }
    ));
    assert_eq!(convert::supply_volts(528), 24.0);
    assert!(ReplyFrame::decode(&[9, 0x30, 7, 0x00, 0x04, 1, 0x41, 1, 0]).is_err());
    let pd = ReplyFrame::decode(&[9, 0x45, 0b1010, 0, 0, 0, 0, 0, 0]).expect("valid");
    assert!(matches!(pd.reply, Reply::PowerDown { status } if status.bits() == 0b1010));
    assert_eq!(Variant::SixPack.peak_current_amps(128, 0), 0.4);
    assert_eq!(Variant::QuadPack.motors(), 4);
}

#[test]
fn motor_numbers_above_5_are_rejected() {
    assert_eq!(
        RequestFrame::decode(&[1, 0x23, 6, 0, 0, 0, 0, 0, 0]),
        Err(Error::InvalidMotor(6))
    );
    assert_eq!(
        RequestFrame::new(
            1,
            Request::Rotate {
                motor: 0,
                velocity: 512
            }
        )
        .to_word(),
        Err(Error::OutOfRange { field: "velocity" })
    );
    let mut short = [0u8; 8];
    assert_eq!(
        RequestFrame::new(1, Request::HardwareReset).encode(&mut short),
        Err(Error::BufferTooSmall { needed: 9 })
    );
    assert_eq!(
        RequestFrame::decode(&[1, 0x23]),
        Err(Error::WrongLength {
            expected: 9,
            got: 2
        })
    );
}

/// Manual 8.3 $16: "mask for reference switch de-bouncing ($0001=0ms,$0003=2ms,$FFFF=30ms)";
/// 7.1 "De-bounce mask=$0FFF … Filter delay 12-1 cycles = 22 ms".
#[test]
fn manual_8_3_debounce_mask_16() {
    assert_eq!(convert::debounce_mask(0), Ok(0x0001));
    assert_eq!(convert::debounce_mask(2), Ok(0x0003));
    assert_eq!(convert::debounce_mask(22), Ok(0x0FFF));
    assert_eq!(convert::debounce_mask(30), Ok(0xFFFF));
    for ms in (0..=30).step_by(2) {
        let mask = convert::debounce_mask(ms).expect("in range");
        assert_eq!(convert::debounce_ms(mask), ms);
    }
    assert!(convert::debounce_mask(3).is_err(), "2 ms steps");
    assert!(convert::debounce_mask(32).is_err(), "30 ms at most");
    let w = word(Request::ReferenceParameters {
        motor: 0,
        vrefmax: 100,
        debounce_mask: convert::debounce_mask(22).expect("22 ms"),
        flags: tmcpack::ReferenceFlags::EMPTY,
    });
    assert_eq!(w, [PACK, 0x16, 0, 100, 0, 0xFF, 0x0F, 0, 0]);
}

/// Manual 8.3 $10 "value (0..255): Sixpack: Imax=0,8A * value/256"; 7.1 "Peak current=128
/// … define 100% curr. control as 400 mA"; $11 levels "(0=100%, 75, 50, 38, 25, 19, [13,
/// 9,] 0%)".
#[test]
fn manual_8_3_peak_current_10_and_levels_11() {
    assert_eq!(convert::peak_value(50.0), Ok(128));
    assert_eq!(Variant::SixPack.peak_current_amps(128, 100), 0.4);
    assert_eq!(convert::peak_value(100.0), Ok(255), "256 does not fit: 255");
    assert_eq!(convert::peak_value(0.0), Ok(0));
    assert!(convert::peak_value(100.5).is_err());
    assert!(convert::peak_value(f64::NAN).is_err());
    assert_eq!(convert::peak_percent(128), 50.0);
    let percents: Vec<u8> = CurrentLevel::ALL.iter().map(|l| l.percent()).collect();
    assert_eq!(percents, [100, 75, 50, 38, 25, 19, 13, 9, 0]);
    for (index, level) in CurrentLevel::ALL.iter().enumerate() {
        assert_eq!(level.index() as usize, index);
        assert_eq!(CurrentLevel::from_percent(level.percent()), Some(*level));
    }
    assert_eq!(CurrentLevel::from_percent(40), None);
    // "Power consumption can be reduced drastically when power-down current (I0) is set to
    // 0%, i.e. P1=8".
    assert_eq!(
        CurrentLevel::from_percent(0).map(CurrentLevel::index),
        Some(8)
    );
    assert_eq!(convert::units_of_ms(1000), Some(500));
    assert_eq!(convert::units_of_ms(3), None);
}
