//! Unit tests of the `$45` power-down mode on the fake clock (manual 8.6 "Power-Down
//! modus"): the start-up steps, what counts as referenced after a restore, the state
//! check while online, and the firmware revisions without `$45`.

use core::time::Duration;

use tmcpack::{Action, PowerDownRequest, PowerDownStatus, Reply, Request, RequestFrame};

use super::bench::*;
use super::*;
use crate::PowerDownMode;

pub(super) fn with(mode: PowerDownMode) -> TmcpackDriverConfig {
    TmcpackDriverConfig {
        power_down: mode,
        ..config()
    }
}

/// `$43` with the reset flag `reset` and firmware `revision`.
pub(super) fn unit_info(revision: u8, reset: bool) -> [u8; 9] {
    word(Reply::UnitInfo {
        firmware: revision,
        reset,
        temperature: 35,
        serial: 1001,
    })
}

/// Answers `$43` and the survey, then runs the configuration, answering each `$45` with
/// the next of `answers`; returns the bits of the `$45` requests, in order.
pub(super) fn start(
    bench: &mut Bench,
    info: [u8; 9],
    answers: &[PowerDownStatus],
) -> Vec<PowerDownRequest> {
    let (_, w) = bench.next(10).expect("$43");
    assert_eq!(w[1], 0x43);
    bench.now += 11 * MS;
    bench.rx(&info);
    bench.survey([Action::Inactive; 6]);
    let mut asked = Vec::new();
    for _ in 0..100 {
        if bench.driver.status().online {
            return asked;
        }
        if let Request::PowerDown { reply_to, flags } = bench.request() {
            assert_eq!(reply_to, 0xFE);
            let status = answers.get(asked.len()).copied().expect("an answer");
            asked.push(flags);
            bench.now += 11 * MS;
            bench.rx(&word(Reply::PowerDown { status }));
        }
    }
    panic!("not online after {asked:?}");
}

/// Serves for `ms` milliseconds: `$20` with `poll(motor)`, `$43` without the reset flag,
/// `$45` with `pd(flags)`; returns the `$45` bits asked.
pub(super) fn serve(
    bench: &mut Bench,
    ms: u32,
    mut poll: impl FnMut(u8) -> [u8; 9],
    mut pd: impl FnMut(PowerDownRequest) -> PowerDownStatus,
) -> Vec<PowerDownRequest> {
    let mut asked = Vec::new();
    let end = bench.now + ms * MS;
    while bench.now < end {
        let Some(w) = bench.tick() else { continue };
        match RequestFrame::decode(&w).expect("decodes").request {
            Request::QueryPosition { motor, .. } => {
                bench.now += 10 * MS;
                let reply = poll(motor);
                bench.rx(&reply);
            }
            Request::UnitInfo { .. } => {
                bench.now += 10 * MS;
                bench.rx(&unit_info(149, false));
            }
            Request::PowerDown { flags, .. } => {
                asked.push(flags);
                bench.now += 10 * MS;
                bench.rx(&word(Reply::PowerDown { status: pd(flags) }));
            }
            _ => {}
        }
    }
    asked
}

pub(super) fn at_rest(motor: u8) -> [u8; 9] {
    position(motor, 1234, Action::Inactive)
}

/// References `motors` with a set-position each (`$27`, confirmed by the next poll).
pub(super) fn reference(bench: &mut Bench, motors: &[usize]) {
    for &motor in motors {
        bench
            .driver
            .set_goal(bench.now, motor, Goal::SetPosition { counts: 1234.0 })
            .expect("set-position");
    }
    serve(bench, 200, at_rest, |_| NONE);
    for &motor in motors {
        assert!(bench.driver.channel(motor).homed, "motor {motor}");
    }
}

/// The pack goes silent until the driver declares it not responding, then answers again
/// after its boot; the start-up's `$45` get `answers`.
pub(super) fn lose_and_boot(
    bench: &mut Bench,
    answers: &[PowerDownStatus],
) -> Vec<PowerDownRequest> {
    for _ in 0..2000 {
        bench.tick();
        if bench.driver.status().fault == Some(DeviceFault::NotResponding) {
            break;
        }
    }
    assert_eq!(
        bench.driver.status().fault,
        Some(DeviceFault::NotResponding)
    );
    bench.now += RETRY_PERIOD;
    start(bench, unit_info(149, true), answers)
}

pub(super) const LOADED: PowerDownStatus =
    PowerDownStatus::LOADED.with(PowerDownStatus::VALID_IN_EEPROM, true);
pub(super) const VALID: PowerDownStatus = PowerDownStatus::VALID_IN_EEPROM;
pub(super) const NONE: PowerDownStatus = PowerDownStatus::EMPTY;
const DOWN: PowerDownStatus = PowerDownStatus::DOWN_BEFORE
    .with(PowerDownStatus::DOWN_AFTER, true)
    .with(PowerDownStatus::VALID_IN_EEPROM, true);

/// "restore" after a boot (`$43` "reset flag: during first read out 1"): bit 0 loads the
/// saved positions, then bits 2 + 3 arm the mode, then bit 1 invalidates what was loaded.
/// A driver that starts afresh knew no reference of before the outage: the axes show the
/// loaded positions but are not referenced (the pack saves positions, not references).
#[test]
fn restore_after_a_boot_loads_arms_and_invalidates() {
    let mut bench = Bench::new(with(PowerDownMode::Restore));
    let asked = start(&mut bench, unit_info(149, true), &[LOADED, VALID, NONE]);
    assert_eq!(
        asked,
        [
            PowerDownRequest::LOAD_POSITIONS,
            PowerDownRequest::ACTIVATE | PowerDownRequest::RESET_STATE,
            PowerDownRequest::INVALIDATE_POSITIONS,
        ]
    );
    assert!(bench.driver.status().online);
    assert_eq!(bench.driver.status().fault, None);
    assert_eq!(
        bench.driver.status().firmware(),
        "SIXpack V1.4.9 #1001 PD loaded"
    );
    serve(&mut bench, 100, at_rest, |_| VALID);
    for motor in [0, 2] {
        let state = bench.driver.channel(motor);
        assert!(!state.homed, "motor {motor}: no reference known before");
        assert_eq!(state.position, 1234.0);
    }
}

/// The server ran through the outage: an axis it knew as referenced when the pack went
/// silent is referenced again from the first poll after the pack said "loaded valid
/// position from EEprom"; one that was not, is not.
#[test]
fn an_axis_referenced_before_the_outage_is_referenced_after_the_restore() {
    let mut bench = Bench::new(with(PowerDownMode::Restore));
    start(&mut bench, unit_info(149, true), &[NONE, NONE, NONE]);
    reference(&mut bench, &[0]);
    assert!(!bench.driver.channel(2).homed);
    let asked = lose_and_boot(&mut bench, &[LOADED, VALID, NONE]);
    assert_eq!(asked[0], PowerDownRequest::LOAD_POSITIONS);
    // Not before the board's position is read.
    assert!(!bench.driver.channel(0).homed);
    serve(&mut bench, 100, at_rest, |_| NONE);
    assert!(bench.driver.channel(0).homed);
    assert_eq!(bench.driver.channel(0).position, 1234.0);
    assert!(!bench.driver.channel(2).homed, "never referenced");
    // Nothing valid loaded: nothing referenced, whatever was known.
    reference(&mut bench, &[0, 2]);
    lose_and_boot(&mut bench, &[NONE, NONE, NONE]);
    serve(&mut bench, 100, at_rest, |_| NONE);
    assert!(!bench.driver.channel(0).homed && !bench.driver.channel(2).homed);
}

/// The load found nothing valid ("1 = loaded valid position from EEprom" clear): nothing
/// is referenced, the mode is armed.
#[test]
fn a_load_without_valid_positions_references_nothing() {
    let mut bench = Bench::new(with(PowerDownMode::Restore));
    let asked = start(&mut bench, unit_info(149, true), &[NONE, NONE, NONE]);
    assert_eq!(asked.len(), 3);
    serve(&mut bench, 100, at_rest, |_| NONE);
    assert!(!bench.driver.channel(0).homed);
    assert!(!bench.driver.channel(2).homed);
    assert_eq!(
        bench.driver.status().firmware(),
        "SIXpack V1.4.9 #1001 PD armed"
    );
}

/// A pack that did not boot kept its position registers (the server restarted, the pack
/// ran on): the EEPROM's positions would be stale, so none are loaded. "save" never loads.
#[test]
fn positions_are_loaded_only_after_a_boot_and_only_with_restore() {
    let arm = PowerDownRequest::ACTIVATE | PowerDownRequest::RESET_STATE;
    let mut kept = Bench::new(with(PowerDownMode::Restore));
    let asked = start(&mut kept, unit_info(149, false), &[NONE, NONE]);
    assert_eq!(asked, [arm, PowerDownRequest::INVALIDATE_POSITIONS]);
    let mut save = Bench::new(with(PowerDownMode::Save));
    let asked = start(&mut save, unit_info(149, true), &[VALID, NONE]);
    assert_eq!(asked, [arm, PowerDownRequest::INVALIDATE_POSITIONS]);
    serve(&mut save, 100, at_rest, |_| NONE);
    assert!(!save.driver.channel(0).homed);
    // "off": no $45 at all, and the description as before.
    let mut off = Bench::new(config());
    let sent = off.online();
    assert!(!sent.iter().any(|r| matches!(r, Request::PowerDown { .. })));
    assert_eq!(off.driver.status().firmware(), "SIXpack V1.4.9 s/n 1001");
    let asked = serve(&mut off, 3000, at_rest, |_| {
        panic!("no $45 with power_down off")
    });
    assert!(asked.is_empty());
}

/// `reference.restore = false`: the positions are loaded for every motor, but that axis
/// does not count as referenced (its load may have moved unpowered).
#[test]
fn reference_restore_false_leaves_that_axis_unreferenced() {
    let mut config = with(PowerDownMode::Restore);
    if let Some(Some(c)) = config.channels.get_mut(2) {
        c.restore = false;
    }
    let mut bench = Bench::new(config);
    start(&mut bench, unit_info(149, true), &[NONE, NONE, NONE]);
    reference(&mut bench, &[0, 2]);
    lose_and_boot(&mut bench, &[LOADED, VALID, NONE]);
    serve(&mut bench, 100, at_rest, |_| NONE);
    assert!(bench.driver.channel(0).homed);
    assert!(!bench.driver.channel(2).homed);
}

/// 8.6 "(Version 1.46 and since Version 1.49)": a V1.4.8 gets no `$45`; the mode the
/// config asks for is missing, a BoardError for as long as it runs.
#[test]
fn a_firmware_without_45_gets_none_and_is_a_board_error() {
    let mut bench = Bench::new(with(PowerDownMode::Restore));
    let asked = start(&mut bench, unit_info(148, true), &[]);
    assert!(asked.is_empty());
    let status = bench.driver.status();
    assert!(status.online);
    assert_eq!(status.fault, Some(DeviceFault::BoardError));
    assert_eq!(status.firmware(), "SIXpack V1.4.8 #1001 PD n/a");
    let asked = serve(&mut bench, 3000, at_rest, |_| panic!("no $45 on V1.4.8"));
    assert!(asked.is_empty());
    assert_eq!(bench.driver.status().fault, Some(DeviceFault::BoardError));
    // V1.4.6 has it.
    let mut old = Bench::new(with(PowerDownMode::Save));
    assert_eq!(
        start(&mut old, unit_info(146, true), &[NONE, NONE]).len(),
        2
    );
    assert_eq!(old.driver.status().fault, None);
}

/// Online, the state is read every second (`$45` with no bit). In the power-down state
/// ("Power down – status after Command") the pack is a BoardError, an axis that moved since
/// the last check loses its reference; bit 3 is asked every second until the supply is
/// back, then the fault clears and bit 1 invalidates the positions saved at the dip.
#[test]
fn an_undervoltage_while_online_faults_the_pack_until_bit_3_re_enables_it() {
    let mut bench = Bench::new(with(PowerDownMode::Restore));
    start(&mut bench, unit_info(149, true), &[NONE, NONE, NONE]);
    reference(&mut bench, &[0, 2]);
    // Both referenced; motor 0 moves, motor 2 stands.
    let mut p0 = 0;
    let asked = serve(
        &mut bench,
        1200,
        |motor| {
            if motor == 0 {
                p0 += 50;
                position(0, p0, Action::Ramp)
            } else {
                at_rest(motor)
            }
        },
        |_| NONE,
    );
    assert_eq!(asked.len(), 1, "one check in 1.2 s: {asked:?}");
    assert!(bench.driver.channel(0).homed && bench.driver.channel(2).homed);
    // The supply dips: the pack stopped both motors and saved their positions; it stays
    // below the level for two checks.
    let mut checks = Vec::new();
    for _ in 0..2 {
        let asked = serve(&mut bench, 1000, at_rest, |_| DOWN);
        assert_eq!(asked.len(), 1, "{asked:?}");
        checks.extend(asked);
        let status = bench.driver.status();
        assert_eq!(status.fault, Some(DeviceFault::BoardError));
        assert_eq!(status.firmware(), "SIXpack V1.4.9 #1001 PD DOWN");
        assert!(
            !bench.driver.channel(0).homed,
            "it moved: steps may be lost"
        );
        assert!(bench.driver.channel(2).homed, "it stood");
    }
    // Back above the level: bit 3 re-enables the motors.
    let asked = serve(&mut bench, 1000, at_rest, |flags| {
        if flags.contains(PowerDownRequest::RESET_STATE) {
            VALID | PowerDownStatus::DOWN_BEFORE
        } else {
            NONE
        }
    });
    checks.extend(asked);
    assert_eq!(
        checks[..4],
        [
            PowerDownRequest::EMPTY,
            PowerDownRequest::RESET_STATE,
            PowerDownRequest::RESET_STATE,
            PowerDownRequest::INVALIDATE_POSITIONS,
        ]
    );
    assert_eq!(bench.driver.status().fault, None);
    assert_eq!(
        bench.driver.status().firmware(),
        "SIXpack V1.4.9 #1001 PD armed"
    );
    assert!(bench.driver.channel(2).homed);
}

/// The pack stops answering while a motor runs and comes back booted (the supply went
/// away): the positions it loads are not trusted for the motor the driver last saw
/// moving, which may have been stopped abruptly from speed.
#[test]
fn a_motor_seen_moving_when_the_pack_was_lost_is_not_referenced_by_the_restore() {
    let mut bench = Bench::new(with(PowerDownMode::Restore));
    start(&mut bench, unit_info(149, true), &[NONE, NONE, NONE]);
    reference(&mut bench, &[0, 2]);
    let mut p0 = 0;
    serve(
        &mut bench,
        300,
        |motor| {
            if motor == 0 {
                p0 += 50;
                position(0, p0, Action::Ramp)
            } else {
                at_rest(motor)
            }
        },
        |_| NONE,
    );
    // Silence: three timeouts, not responding; back after its boot.
    let asked = lose_and_boot(&mut bench, &[LOADED, VALID, NONE]);
    assert_eq!(asked[0], PowerDownRequest::LOAD_POSITIONS);
    serve(&mut bench, 100, at_rest, |_| NONE);
    assert!(!bench.driver.channel(0).homed, "seen moving");
    assert!(bench.driver.channel(2).homed, "seen at rest");
}

/// The start-up is interrupted after the `$43` that read the reset flag (which reads 0
/// from then on): the boot is remembered, and the restore still happens.
#[test]
fn the_boot_is_remembered_across_an_interrupted_start_up() {
    let mut bench = Bench::new(with(PowerDownMode::Restore));
    bench.next(10).expect("$43");
    bench.now += 11 * MS;
    bench.rx(&unit_info(149, true));
    // The survey goes unanswered three times: not responding, asked again.
    for _ in 0..2000 {
        bench.tick();
        if bench.driver.status().fault == Some(DeviceFault::NotResponding) {
            break;
        }
    }
    bench.now += RETRY_PERIOD + Duration::from_millis(1);
    let asked = start(&mut bench, unit_info(149, false), &[LOADED, VALID, NONE]);
    assert_eq!(asked[0], PowerDownRequest::LOAD_POSITIONS);
}
