//! Reference search, nulloffset / testnullrange, stop conditions and analogue inputs.

use super::host::*;

/// $22 reference search with the default flags (NullCenter, FastRef, zero point right):
/// the pack finds the switch, sets zero at its centre and drives back (8.4, 7.1).
#[test]
fn manual_8_4_reference_search_22_null_center() {
    let mut h = pack();
    h.send(1, Request::ReferenceSearch { motor: 0 });
    let mut saw = [false; 6];
    let mut dp = false;
    for _ in 0..20_000 {
        h.wait(2 * MS);
        let v = h.dev.motor(0).expect("m0");
        if let Action::ReferenceSearch(p) = v.action {
            saw[usize::from(p).min(5)] = true;
            dp |= h.dev.display().1;
        }
        if v.action == Action::Inactive {
            break;
        }
    }
    // Phase 0 (stopping) ends in the first tick for a motor at rest.
    assert!(saw[1] && saw[2] && saw[3] && saw[4], "phases {saw:?}");
    assert!(dp, "decimal point during the search");
    let v = h.dev.motor(0).expect("m0");
    assert_eq!(v.action, Action::Inactive);
    assert_eq!(v.position, 0);
    // Switch actuated 3200..=3519: the centre, within the slow approach's resolution.
    assert!(
        (v.physical - 3360).abs() <= 4,
        "zero at the centre: {}",
        v.physical
    );
}

/// $18 nulloffset with NullLeft (no NullCenter): zero lies nulloffset beyond the switch
/// edge; "stop after reference search" ($16 P5 bit 0) drives there.
#[test]
fn manual_8_3_nulloffset_18_null_left() {
    let mut h = pack();
    h.dev.set_ref_switch(
        1,
        Some(RefSwitch {
            from: -10_000,
            to: -2000,
            opener: true,
        }),
    );
    h.send(
        1,
        Request::MotorParameters {
            motor: 1,
            poslimit: 6400,
            motor_type: MotorType::NULL_LEFT | MotorType::FILTER_SWITCH,
            options: MotorOptions::FAST_REF | MotorOptions::NULL_POSITIVE,
        },
    );
    h.send(
        1,
        Request::NullOffset {
            motor: 1,
            nulloffset: 100,
            testnullrange: 240,
        },
    );
    h.send(
        1,
        Request::ReferenceParameters {
            motor: 1,
            vrefmax: 100,
            debounce_mask: 0x0FFF,
            flags: tmcpack::ReferenceFlags::STOP_AFTER_SEARCH,
        },
    );
    h.send(1, Request::ReferenceSearch { motor: 1 });
    h.wait(20_000 * MS);
    let v = h.dev.motor(1).expect("m1");
    assert_eq!((v.action, v.position), (Action::Inactive, 0));
    assert!(
        (v.physical - (-2000 - 100)).abs() <= 3,
        "zero 100 beyond the edge: {}",
        v.physical
    );
}

/// No switch within 125 % of poslimit: the search repeats (8.4).
#[test]
fn manual_8_4_reference_search_without_switch_repeats() {
    let mut h = pack();
    h.dev.set_ref_switch(2, None);
    h.send(1, Request::ReferenceSearch { motor: 2 });
    h.wait(10_000 * MS);
    let v = h.dev.motor(2).expect("m2");
    assert!(v.action.is_referencing());
    assert!(v.physical > 8000 * 2, "kept searching: {}", v.physical);
}

/// StopNull + testnullrange: the switch seen far from zero while driving towards it stops
/// the motor (abruptly, or with amax when StopSoft) and sets the stop bit, read once by $20
/// (8.3); without StopNoRef a reference search follows.
#[test]
fn manual_8_3_stop_null_outside_testnullrange() {
    let mut h = pack();
    for (motor, options) in [
        (0u8, MotorOptions::STOP_NO_REF),
        (1, MotorOptions::STOP_NO_REF | MotorOptions::STOP_SOFT),
        (2, MotorOptions::EMPTY),
    ] {
        h.send(
            1,
            Request::MotorParameters {
                motor,
                poslimit: 6400,
                motor_type: MotorType::STOP_NULL,
                options,
            },
        );
        h.send(
            1,
            Request::StartRamp {
                motor,
                target: 10_000,
            },
        );
    }
    h.wait(3000 * MS);
    let (hard, action, stopped) = position(&mut h, 0);
    assert_eq!(action, Action::Inactive);
    assert!(stopped, "stop bit");
    assert!(
        (3200..3260).contains(&hard),
        "stopped at the switch: {hard}"
    );
    assert!(!position(&mut h, 0).2, "cleared after read");
    let (soft, action, stopped) = position(&mut h, 1);
    assert_eq!((action, stopped), (Action::Inactive, true));
    assert!(
        soft > hard + 100 && soft < 10_000,
        "decelerated with amax: {soft}"
    );
    // Motor 2 (no StopNoRef) referenced itself, then resumed its ramp to 10000, which lies
    // beyond the new zero point: the switch stops it again, as the real pack would
    // ("The reference search requires proper poslimit settings", 7.1).
    let (_, action, stopped) = position(&mut h, 2);
    assert!(
        (stopped && action.is_referencing()) || action == Action::Ramp,
        "{action:?}"
    );
    h.send(
        1,
        Request::ReferenceParameters {
            motor: 2,
            vrefmax: 100,
            debounce_mask: 0x0FFF,
            flags: tmcpack::ReferenceFlags::STOP_AFTER_SEARCH,
        },
    );
    h.send(1, Request::ReferenceSearch { motor: 2 });
    h.wait(10_000 * MS);
    let v = h.dev.motor(2).expect("m2");
    assert_eq!((v.position, v.action), (0, Action::Inactive));
    assert!(
        (v.physical - 3200).abs() <= 2,
        "homed to the switch edge: {}",
        v.physical
    );
}

/// $30 analogue channels (ch 7 = supply, 1 V = 22) and the inverted reference inputs; $31
/// stop limit stops a motor running right.
#[test]
fn manual_8_5_analogue_inputs_30_31() {
    let mut h = pack();
    let (_, f) = h
        .query(
            1,
            Request::ReadInput {
                channel: 7,
                reply_to: HOST,
            },
        )
        .expect("reply");
    let Reply::Input { value, inputs, .. } = f.reply else {
        panic!("{f:?}")
    };
    assert!((527..=529).contains(&value), "24 V: {value}");
    assert_eq!(
        inputs.bits() & 0x3F,
        0,
        "no switch actuated, inputs inverted"
    );
    h.dev.set_analog(3, 800);
    let (_, f) = h
        .query(
            1,
            Request::ReadInput {
                channel: 3,
                reply_to: HOST,
            },
        )
        .expect("reply");
    assert!(matches!(
        f.reply,
        Reply::Input {
            channel: 3,
            value: 799..=801,
            reference: false,
            ..
        }
    ));
    h.send(
        1,
        Request::StopLimits {
            channel: 3,
            left_min: 0,
            right_max: 700,
        },
    );
    h.send(
        1,
        Request::MotorParameters {
            motor: 3,
            poslimit: 6400,
            motor_type: MotorType::EMPTY,
            options: MotorOptions::STOP_NO_REF,
        },
    );
    h.send(
        1,
        Request::Rotate {
            motor: 3,
            velocity: 100,
        },
    );
    h.wait(50 * MS);
    let (_, action, stopped) = position(&mut h, 3);
    assert_eq!((action, stopped), (Action::Inactive, true));
    h.send(
        1,
        Request::Rotate {
            motor: 3,
            velocity: -100,
        },
    );
    h.wait(50 * MS);
    assert_eq!(
        h.dev.motor(3).expect("m3").action,
        Action::Rotation,
        "left is allowed"
    );
}
