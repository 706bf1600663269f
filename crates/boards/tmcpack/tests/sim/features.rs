//! The power-down mode over a power outage, firmware revisions without `$45`, the `$17`
//! table's coil currents and the PI controller following a target changed on the fly
//! (manual 8.3, 8.4, 8.6).

use super::host::*;

fn power_down(h: &mut Host<TmcpackSim>, flags: PowerDownRequest) -> PowerDownStatus {
    match h.query(
        1,
        Request::PowerDown {
            reply_to: HOST,
            flags,
        },
    ) {
        Some((
            _,
            ReplyFrame {
                reply: Reply::PowerDown { status },
                ..
            },
        )) => status,
        other => panic!("no $45 answer: {other:?}"),
    }
}

/// 8.6: "These versions store the actual motor positions as soon as the power supply goes
/// below 13V, if enabled. The motors are stopped, as soon as undervoltage is detected." An
/// outage with the mode activated: the motor stops where it was, its position survives
/// the boot in EEPROM and bit 0 copies it back; bit 1 invalidates it, and an outage
/// without the mode (a reset forgets bit 2) saves nothing.
#[test]
fn manual_8_6_positions_survive_an_outage_and_are_loaded_once_valid() {
    let mut h = pack();
    assert_eq!(
        power_down(&mut h, PowerDownRequest::ACTIVATE),
        PowerDownStatus::EMPTY
    );
    h.send(
        1,
        Request::StartRamp {
            motor: 2,
            target: 30_000,
        },
    );
    h.wait(400 * MS);
    let before = h.dev.motor(2).expect("m2");
    assert_eq!(before.action, Action::Ramp);
    let now = h.now;
    h.dev.power_outage(now);
    let saved = h.dev.saved_positions().expect("saved at the undervoltage");
    assert_eq!(saved[2], before.position);
    // Booting: a second deaf, then the reset flag, positions 0, the rotor where it stopped.
    h.wait(1100 * MS);
    let (_, info) = h
        .query(1, Request::UnitInfo { reply_to: HOST })
        .expect("$43");
    assert!(matches!(info.reply, Reply::UnitInfo { reset: true, .. }));
    let booted = h.dev.motor(2).expect("m2");
    assert_eq!(booted.position, 0);
    assert_eq!(booted.physical, before.physical);
    assert!(!h.dev.power_down_state());
    // Bit 0: "Read positions from EEprom, and copy them to the motor position registers,
    // if they contain valid values".
    assert_eq!(
        power_down(&mut h, PowerDownRequest::LOAD_POSITIONS),
        PowerDownStatus::LOADED | PowerDownStatus::VALID_IN_EEPROM
    );
    assert_eq!(position(&mut h, 2).0, before.position);
    // The register and the rotor agree again: a move lands where it says.
    h.send(
        1,
        Request::StartRamp {
            motor: 2,
            target: before.position + 1000,
        },
    );
    h.wait(2000 * MS);
    let after = h.dev.motor(2).expect("m2");
    assert_eq!(after.physical - before.physical, 1000);
    // Bit 1: "set positions in EEprom as invalid".
    assert_eq!(
        power_down(&mut h, PowerDownRequest::INVALIDATE_POSITIONS),
        PowerDownStatus::EMPTY
    );
    // The boot forgot bit 2: the next outage saves nothing, bit 0 loads nothing.
    let now = h.now;
    h.dev.power_outage(now);
    h.wait(1100 * MS);
    assert_eq!(
        power_down(&mut h, PowerDownRequest::LOAD_POSITIONS),
        PowerDownStatus::EMPTY
    );
    assert_eq!(position(&mut h, 2).0, 0);
}

/// 8.6: a dip below the level with the mode activated holds the motors (no current,
/// motion ignored) in the power-down state, which bit 3 resets "only … while the supply is
/// above the power down level".
#[test]
fn manual_8_6_the_power_down_state_holds_the_motors_until_bit_3() {
    let mut h = pack();
    power_down(&mut h, PowerDownRequest::ACTIVATE);
    h.send(
        1,
        Request::CurrentControl {
            motor: 0,
            i0: tmcpack::CurrentLevel::P50,
            i1: tmcpack::CurrentLevel::P50,
            i2: tmcpack::CurrentLevel::P75,
            i3: tmcpack::CurrentLevel::P100,
            t0: 500,
        },
    );
    h.wait(20 * MS);
    assert!(h.dev.motor(0).expect("m0").coil_current_amps > 0.0);
    let now = h.now;
    h.dev.set_supply_volts(now, 12.5);
    h.wait(10 * MS);
    assert!(h.dev.power_down_state());
    assert_eq!(h.dev.motor(0).expect("m0").coil_current_amps, 0.0);
    h.send(
        1,
        Request::Rotate {
            motor: 0,
            velocity: 100,
        },
    );
    h.wait(20 * MS);
    assert_eq!(h.dev.motor(0).expect("m0").action, Action::Inactive);
    // Still below: bit 3 cannot reset the state.
    let status = power_down(&mut h, PowerDownRequest::RESET_STATE);
    assert_eq!(
        status,
        PowerDownStatus::VALID_IN_EEPROM
            | PowerDownStatus::DOWN_BEFORE
            | PowerDownStatus::DOWN_AFTER
    );
    let now = h.now;
    h.dev.set_supply_volts(now, 24.0);
    let status = power_down(&mut h, PowerDownRequest::RESET_STATE);
    assert_eq!(
        status,
        PowerDownStatus::VALID_IN_EEPROM | PowerDownStatus::DOWN_BEFORE
    );
    h.wait(10 * MS);
    assert!(h.dev.motor(0).expect("m0").coil_current_amps > 0.0);
}

/// 8.6 `$45` "(Version 1.46 and since Version 1.49)": V1.4.7 and V1.4.8 do not answer it
/// (nor act on it); V1.4.6 does.
#[test]
fn manual_8_6_power_down_only_on_the_revisions_that_have_it() {
    for (revision, answers) in [(145, false), (146, true), (147, false), (148, false)] {
        let mut h = Host::new(TmcpackSim::new(TmcpackSimConfig {
            firmware_revision: revision,
            ..TmcpackSimConfig::default()
        }));
        let reply = h.query(
            1,
            Request::PowerDown {
                reply_to: HOST,
                flags: PowerDownRequest::ACTIVATE,
            },
        );
        assert_eq!(reply.is_some(), answers, "V{revision}");
        let now = h.now;
        h.dev.set_supply_volts(now, 10.0);
        assert_eq!(h.dev.saved_positions().is_some(), answers, "V{revision}");
    }
}

/// 8.3 `$17`: "The lower 5 bits of the position counter … are used as a pointer into the
/// symmetrical characteristics table and determine the current for coil A … coil B … by a
/// pointer shifted by 16 steps"; "Default-table: 255 * SIN([0.5..15.5]/32*PI)"; "e.g.
/// table=255, 255,…, 255 -> full step". `$CC` brings the default back.
#[test]
fn manual_8_3_the_table_sets_the_coil_currents() {
    let mut h = pack();
    assert_eq!(h.dev.microstep_table(), tmcpack::table::SINE_TABLE);
    assert_eq!(h.dev.motor(1).expect("m1").coils, (13, 255));
    for request in tmcpack::table::table_requests(&tmcpack::table::FULL_STEP_TABLE) {
        h.send(1, request);
    }
    h.wait(5 * MS);
    assert_eq!(h.dev.microstep_table(), [255; 16]);
    // Common to all motors.
    assert_eq!(h.dev.motor(1).expect("m1").coils, (255, 255));
    assert_eq!(h.dev.motor(4).expect("m4").coils, (255, 255));
    h.send(
        1,
        Request::StartRamp {
            motor: 1,
            target: 20,
        },
    );
    h.wait(500 * MS);
    assert_eq!(h.dev.motor(1).expect("m1").position, 20);
    assert_eq!(h.dev.motor(1).expect("m1").coils, (255, -255));
    // A table with its own curve: entry 3 answers at pointer 3 and at its mirror, 28.
    let mut custom = tmcpack::table::SINE_TABLE;
    custom[3] = 100;
    for request in tmcpack::table::table_requests(&custom) {
        h.send(1, request);
    }
    h.send(
        1,
        Request::SetPosition {
            motor: 1,
            position: 28,
        },
    );
    h.wait(5 * MS);
    assert_eq!(h.dev.motor(1).expect("m1").coils.0, 100);
    h.send(1, Request::HardwareReset);
    h.wait(1100 * MS);
    assert_eq!(h.dev.microstep_table(), tmcpack::table::SINE_TABLE);
}

/// 8.4 `$24`: "When the PI-controller was already active the target position will be
/// reprogrammed immediately." A target changed while the motor runs towards the first is
/// followed without a stop in between; the motor stays in the PI controller (action 10)
/// when it holds the target.
#[test]
fn manual_8_4_the_pi_controller_follows_a_target_changed_on_the_fly() {
    let mut h = pack();
    h.send(
        1,
        Request::PiParameters {
            motor: 0,
            propdiv: 8,
            intdiv: 129,
            intclip: 129,
            intinpclip: 1,
        },
    );
    h.send(
        1,
        Request::PiTarget {
            motor: 0,
            target: 20_000,
        },
    );
    h.wait(200 * MS);
    let first = h.dev.motor(0).expect("m0");
    assert!(first.velocity > 0 && first.position > 0, "{first:?}");
    h.send(
        1,
        Request::PiTarget {
            motor: 0,
            target: 8_000,
        },
    );
    let mut lowest_speed = i16::MAX;
    let mut last = first.position;
    for _ in 0..200 {
        h.wait(10 * MS);
        let v = h.dev.motor(0).expect("m0");
        if v.position >= 7_000 {
            break;
        }
        lowest_speed = lowest_speed.min(v.velocity);
        assert!(v.position >= last, "never backwards on the way");
        last = v.position;
    }
    assert!(lowest_speed > 0, "no stop between the targets");
    h.wait(3000 * MS);
    let v = h.dev.motor(0).expect("m0");
    assert!((v.position - 8_000).abs() <= 8, "{}", v.position);
    assert_eq!(v.action, Action::PiController);
}
