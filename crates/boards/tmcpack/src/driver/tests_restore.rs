//! Unit tests on the fake clock of references across a restart of the server (module
//! `restore`; "SIXpack / QUADpack manual" V2.43, 8.6 "Power-Down modus" and `$43`): a
//! position the previous run saved, referenced and at rest, makes the axis referenced only
//! when the pack loaded valid positions from EEPROM after a boot ("P0 Bit 0: 1 = loaded
//! valid position from EEprom") or did not boot at all, and the first poll finds the motor
//! inactive at exactly the saved position, and `reference.restore` is not false. Each
//! refusal has its test.

use motion_drivers::SavedReference;
use tmcpack::{Action, PowerDownRequest};

use super::bench::*;
use super::tests_power_down::{
    LOADED, NONE, VALID, at_rest, lose_and_boot, serve, start, unit_info, with,
};
use super::*;
use crate::PowerDownMode;

/// A driver with `power_down = "restore"` given the previous run's `saved` (channel,
/// counts) before its start.
fn restarted(config: TmcpackDriverConfig, saved: &[(usize, i64)]) -> Bench {
    let mut bench = Bench::new(config);
    let saved: Vec<SavedReference> = saved
        .iter()
        .map(|&(channel, counts)| SavedReference { channel, counts })
        .collect();
    bench.driver.restore_references(&saved);
    bench
}

/// The pack booted and loaded valid positions: an axis saved at the position it now
/// reports is referenced from the first poll after the load, without a search.
#[test]
fn a_saved_axis_is_referenced_after_a_boot_that_loaded_its_position() {
    let mut bench = restarted(with(PowerDownMode::Restore), &[(0, 1234), (2, 1234)]);
    assert!(bench.driver.keeps_references());
    let asked = start(&mut bench, unit_info(149, true), &[LOADED, VALID, NONE]);
    assert_eq!(asked[0], PowerDownRequest::LOAD_POSITIONS);
    assert!(!bench.driver.channel(0).homed, "not before a poll");
    serve(&mut bench, 100, at_rest, |_| NONE);
    for motor in [0, 2] {
        let state = bench.driver.channel(motor);
        assert!(state.homed, "motor {motor}");
        assert_eq!(state.position, 1234.0);
    }
}

/// Booted, but nothing valid loaded (the mode was not armed, the EEPROM invalidated, a
/// `$CC`): refused, even when the position after the boot equals the saved one.
#[test]
fn a_boot_without_loaded_positions_refuses_the_saved_axis() {
    let mut bench = restarted(with(PowerDownMode::Restore), &[(0, 0)]);
    start(&mut bench, unit_info(149, true), &[NONE, NONE, NONE]);
    serve(
        &mut bench,
        100,
        |m| position(m, 0, Action::Inactive),
        |_| NONE,
    );
    assert_eq!(bench.driver.channel(0).position, 0.0);
    assert!(!bench.driver.channel(0).homed);
}

/// Loaded, but the pack reports another position than the one saved (the motor was moved
/// while the server was down and the pack still powered, then the pack saved that one):
/// refused for that axis only.
#[test]
fn a_position_other_than_the_saved_one_is_refused() {
    let mut bench = restarted(with(PowerDownMode::Restore), &[(0, 1234), (2, 1000)]);
    start(&mut bench, unit_info(149, true), &[LOADED, VALID, NONE]);
    serve(&mut bench, 100, at_rest, |_| NONE);
    assert!(bench.driver.channel(0).homed);
    assert!(!bench.driver.channel(2).homed, "1234 is not 1000");
}

/// The pack did not boot (no `$43` reset flag): it kept running, its registers with it. A
/// saved axis at the same position, inactive, is referenced; one elsewhere is not; no
/// position is loaded.
#[test]
fn a_pack_that_kept_running_keeps_the_saved_axis_at_the_same_position() {
    let mut bench = restarted(with(PowerDownMode::Restore), &[(0, 1234), (2, 999)]);
    let asked = start(&mut bench, unit_info(149, false), &[NONE, NONE]);
    assert!(!asked.contains(&PowerDownRequest::LOAD_POSITIONS));
    serve(&mut bench, 100, at_rest, |_| NONE);
    assert!(bench.driver.channel(0).homed);
    assert!(!bench.driver.channel(2).homed);
}

/// The start-up's `$28` survey finds motor 0 active (another master started it while the
/// server was down): its saved record is dropped before anything else happens; motor 2,
/// inactive, keeps its own.
#[test]
fn a_motor_the_survey_finds_active_is_refused() {
    let mut bench = restarted(with(PowerDownMode::Restore), &[(0, 1234), (2, 1234)]);
    let (_, w) = bench.next(10).expect("$43");
    assert_eq!(w[1], 0x43);
    bench.now += 11 * MS;
    bench.rx(&unit_info(149, false));
    let saved =
        |bench: &Bench, motor: usize| bench.driver.channels[motor].as_ref().and_then(|c| c.saved);
    assert_eq!(saved(&bench, 0), Some(1234));
    let mut actions = [Action::Inactive; 6];
    actions[0] = Action::Ramp;
    bench.survey(actions);
    assert_eq!(saved(&bench, 0), None, "found running");
    assert_eq!(saved(&bench, 2), Some(1234));
}

/// The first poll finds the motor in a reference search (never one the start-up stop
/// leaves): refused, even at the saved position.
#[test]
fn a_motor_found_searching_is_refused() {
    let mut bench = restarted(with(PowerDownMode::Restore), &[(0, 1234)]);
    start(&mut bench, unit_info(149, false), &[NONE, NONE]);
    serve(
        &mut bench,
        30,
        |m| position(m, 1234, Action::ReferenceSearch(1)),
        |_| NONE,
    );
    serve(&mut bench, 100, at_rest, |_| NONE);
    assert!(!bench.driver.channel(0).homed);
}

/// `reference.restore = false`: that axis is never referenced from a saved record.
#[test]
fn reference_restore_false_refuses_the_saved_axis() {
    let mut config = with(PowerDownMode::Restore);
    if let Some(Some(c)) = config.channels.get_mut(2) {
        c.restore = false;
    }
    let mut bench = restarted(config, &[(0, 1234), (2, 1234)]);
    start(&mut bench, unit_info(149, true), &[LOADED, VALID, NONE]);
    serve(&mut bench, 100, at_rest, |_| NONE);
    assert!(bench.driver.channel(0).homed);
    assert!(!bench.driver.channel(2).homed);
}

/// Without `power_down = "restore"` the driver asks for nothing to be kept and ignores
/// what it is given.
#[test]
fn save_and_off_keep_nothing() {
    let saved = [SavedReference {
        channel: 0,
        counts: 1234,
    }];
    let mut save = Bench::new(with(PowerDownMode::Save));
    assert!(!save.driver.keeps_references());
    save.driver.restore_references(&saved);
    start(&mut save, unit_info(149, false), &[NONE, NONE]);
    serve(&mut save, 100, at_rest, |_| NONE);
    assert!(!save.driver.channel(0).homed);
    let mut off = Bench::new(config());
    assert!(!off.driver.keeps_references());
    off.driver.restore_references(&saved);
    off.online();
    serve(&mut off, 100, at_rest, |_| NONE);
    assert!(!off.driver.channel(0).homed);
}

/// A saved record counts for the first configuration only: a pack that loaded nothing then
/// and loads valid positions after a later boot does not make the axis referenced (the
/// running driver never knew it referenced); nor does a record for a channel the config
/// does not have.
#[test]
fn a_saved_record_counts_for_the_first_configuration_only() {
    let mut bench = restarted(with(PowerDownMode::Restore), &[(0, 1234), (5, 1234)]);
    start(&mut bench, unit_info(149, true), &[NONE, NONE, NONE]);
    serve(&mut bench, 100, at_rest, |_| NONE);
    assert!(!bench.driver.channel(0).homed);
    lose_and_boot(&mut bench, &[LOADED, VALID, NONE]);
    serve(&mut bench, 100, at_rest, |_| NONE);
    assert!(!bench.driver.channel(0).homed);
}
