//! The simulated pack under each reading of the two instructions the manual documents two
//! ways ("SIXpack / QUADpack manual" V2.43; docs/ARCHITECTURE.md): the `$14` divisor and
//! the `$15` P6 bit of StopNoRef. The default firmware follows the `$14` text and the `$15`
//! table.

use super::host::*;
use tmcpack::{AmaxDivisor, OptionsLayout};

fn firmware(amax_divisor: AmaxDivisor, options_layout: OptionsLayout) -> Host<TmcpackSim> {
    Host::new(TmcpackSim::new(TmcpackSimConfig {
        amax_divisor,
        options_layout,
        ..TmcpackSimConfig::default()
    }))
}

/// The velocity change per 2 ms tick of a rotation with amax 128 from rest, in 1/64 units,
/// once the motor is beyond vstart.
fn step_of_amax_128(h: &mut Host<TmcpackSim>) -> i64 {
    h.send(
        1,
        Request::StartingVelocity {
            motor: 0,
            vmin: 4,
            vstart: 5,
            div: 2,
        },
    );
    h.send(
        1,
        Request::VelocityAcceleration {
            motor: 0,
            amax: 128,
            vmax: 511,
        },
    );
    h.send(
        1,
        Request::Rotate {
            motor: 0,
            velocity: 511,
        },
    );
    h.wait(10 * MS);
    let before = h.dev.motor(0).expect("m0").velocity_q;
    h.wait(2 * MS);
    let after = h.dev.motor(0).expect("m0").velocity_q;
    assert!(before > 5 * 64, "beyond vstart: {before}");
    after - before
}

/// 8.3 `$14`: "1/64 amax is accumulated with 500Hz" (amax 128: +2 per tick) against 7.1
/// "Default Values": "amax=128; // increments v by 128/16=8 each 2 ms".
#[test]
fn manual_14_and_7_1_readings_of_amax_per_tick() {
    let mut text = firmware(AmaxDivisor::By64, OptionsLayout::Table);
    assert_eq!(step_of_amax_128(&mut text), 2 * 64);
    let mut defaults = firmware(AmaxDivisor::By16, OptionsLayout::Table);
    assert_eq!(step_of_amax_128(&mut defaults), 8 * 64);
    // The default firmware is the `$14` text's.
    assert_eq!(step_of_amax_128(&mut pack()), 2 * 64);
}

/// A left-moving motor 0 whose A_In (512) is below a left stop limit of 600: a stop
/// condition (8.5 `$31`). Returns the action after it with `$15` P6 = `options`.
fn action_after_a_stop_condition(h: &mut Host<TmcpackSim>, options: u8) -> Action {
    h.send(
        1,
        Request::MotorParameters {
            motor: 0,
            poslimit: 6400,
            motor_type: MotorType::EMPTY,
            options: MotorOptions::from_bits_retain(options),
        },
    );
    h.send(
        1,
        Request::StopLimits {
            channel: 0,
            left_min: 600,
            right_max: 1023,
        },
    );
    h.send(
        1,
        Request::Rotate {
            motor: 0,
            velocity: -100,
        },
    );
    h.wait(20 * MS);
    position(h, 0).1
}

/// 8.3 `$15` P6: the table's "Bit 5: StopNoRef" against the prose's "StopNoRef(P6, Bit
/// 6)". With StopNoRef the motor "just stops"; without it a stop condition starts a
/// reference search (action 20–29).
#[test]
fn manual_15_table_and_prose_readings_of_stop_no_ref() {
    let searching = |a: Action| matches!(a, Action::ReferenceSearch(_));
    let mut table = firmware(AmaxDivisor::By64, OptionsLayout::Table);
    assert_eq!(
        action_after_a_stop_condition(&mut table, 0b0010_0000),
        Action::Inactive
    );
    let mut table = firmware(AmaxDivisor::By64, OptionsLayout::Table);
    assert!(searching(action_after_a_stop_condition(
        &mut table,
        0b0100_0000
    )));
    let mut prose = firmware(AmaxDivisor::By64, OptionsLayout::Prose);
    assert_eq!(
        action_after_a_stop_condition(&mut prose, 0b0100_0000),
        Action::Inactive
    );
    // Under the prose, bit 5 is NullPositive: the search starts.
    let mut prose = firmware(AmaxDivisor::By64, OptionsLayout::Prose);
    assert!(searching(action_after_a_stop_condition(
        &mut prose,
        0b0010_0000
    )));
}
