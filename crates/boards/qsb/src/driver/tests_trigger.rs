//! Captures and the trigger output on the fake clock: what the start-up writes (DTR = the
//! compare position, MDR1 B4–B7, DIG I/O CONFIG B12 with bit 0 an output, the CAPTURE and
//! STR streams) and again after a reset; captures and pulses counted as events (the line
//! that starts a stream is none, two in one tick are two, a reset does not restart the
//! count); the compare position changed at run time; a home search and a set-position
//! that switch the triggers off while DTR is theirs.

use core::time::Duration;

use ::qsb::{ProductType, ResponseType, TICK};

use super::tests::{Bench, MD_DONE, MD_JOGGING};
use super::{CaptureInput, QsbDriverConfig, QsbIo, TriggerSetup};
use motion_drivers::{DeviceFault, Driver, Goal, GoalError, GoalKind, Pin};

/// -M pins: io0..io3, encoder, capture, trigger.
const M_CAPTURE: Pin = Pin(5);
const M_TRIGGER: Pin = Pin(6);
/// -D pins: io0, capture, trigger; -S: encoder, capture.
const D_TRIGGER: Pin = Pin(2);
const S_CAPTURE: Pin = Pin(1);

/// STR values: CEN and U/D (counting up, no latch), with CMP, with IDX.
const STR_QUIET: u32 = 0x0A;
const STR_CMP: u32 = 0x2A;
const STR_IDX: u32 = 0x1A;

/// A driving -M whose output pulses low when the count passes 5000 (DTR 0x1388), with a
/// capture on the rising edge of io3.
fn camera() -> QsbDriverConfig {
    QsbDriverConfig {
        io: QsbIo {
            capture: Some(CaptureInput {
                bit: 3,
                falling: false,
            }),
            ..QsbIo::default()
        },
        trigger: TriggerSetup {
            on_match: true,
            pulse: true,
            compare: Some(5000),
            ..TriggerSetup::default()
        },
        ..QsbDriverConfig::default()
    }
}

/// The start-up of [`camera`]: DTR before MDR0 (the compare position), MDR1 0x20 ("B5
/// Trigger on Match"), DIG I/O CONFIG 0x1180 (B12 "Trigger pulse enable", B8 bit 0 an
/// output, B7 the interrupt on io3, B3 0 "low-high"), the CAPTURE and STR streams before
/// READ ENCODER's.
const CAMERA_START_UP: [&str; 19] = [
    "W161", "R14", "W102710", "W164", "W155", "W000", "W081388", "W0343", "W0420", "W0B0", "W0C1",
    "W0F3E0", "R02", "W021180", "W162", "S13", "S05", "S06", "S0E",
];

fn started_camera() -> Bench {
    let mut bench = Bench::with_config(camera());
    bench.values.push((0x06, STR_QUIET));
    let mut lines = bench.run();
    // Once online, STR is cleared before a latch counts (MDR1 just switched the triggers
    // on).
    assert_eq!(lines.pop().as_deref(), Some("W093"), "{lines:?}");
    assert_eq!(lines, CAMERA_START_UP);
    assert!(bench.driver.status().online);
    bench
}

fn stream(bench: &mut Bench, lines: &[(u8, u32)]) {
    bench.advance(TICK);
    let mut bytes = Vec::new();
    for (register, data) in lines {
        bytes.extend(bench.line(ResponseType::Stream, *register, *data));
    }
    bytes.extend(bench.line(ResponseType::Stream, 0x0E, bench.counter as u32));
    bench.rx(&bytes);
}

#[test]
fn the_trigger_and_the_capture_are_written_at_start_up_and_again_after_a_reset() {
    let mut bench = started_camera();
    bench.tick(Some(MD_DONE));
    bench.configured = false;
    let bytes = bench.line(ResponseType::Stream, 0x0E, 0);
    bench.rx(&bytes);
    bench.rx(&bytes);
    assert_eq!(bench.driver.status().fault, Some(DeviceFault::Reset));
    let mut lines = bench.run();
    assert_eq!(lines.pop().as_deref(), Some("W093"));
    assert_eq!(
        lines, CAMERA_START_UP,
        "the compare position and triggers again"
    );
}

#[test]
fn an_active_high_trigger_rests_low_and_a_qsb_d_pulses_its_one_bit() {
    let mut bench = Bench::with_config(QsbDriverConfig {
        variant: ProductType::D,
        motor_drive: false,
        trigger: TriggerSetup {
            index: true,
            underflow: true,
            overflow: true,
            pulse: true,
            active_high: true,
            ..TriggerSetup::default()
        },
        ..QsbDriverConfig::default()
    });
    let lines = bench.run();
    // No DTR (no match): MDR1 0xD0 (B4 index, B6 underflow, B7 overflow), DIG I/O CONFIG
    // 0x1100 (B12, bit 0 an output), DIG I/O 0xE: bit 0 low between pulses ("The output
    // pulse polarity depends on the initial output state of digital I/O bit 0"), CAPTURE
    // streamed (B4 also captures at the index), then STR.
    assert_eq!(
        lines,
        [
            "W161", "R14", "W155", "W000", "W0343", "W04D0", "W0B0", "W0C1", "R02", "W021100",
            "W01E", "S05", "S06", "S0E", "W093"
        ]
    );
    let reading = bench.driver.read_pin(D_TRIGGER).expect("the trigger pin");
    assert_eq!(reading.value, 0.0, "no compare position");
    assert!(reading.refreshed_at.is_some());
    assert_eq!(
        bench.driver.set_pin_value(bench.now, D_TRIGGER, 100.0),
        Err(GoalError::NoSuchPin(D_TRIGGER)),
        "no match: nothing to set"
    );
}

#[test]
fn a_qsb_s_captures_at_the_index() {
    let mut bench = Bench::with_config(QsbDriverConfig {
        variant: ProductType::S,
        motor_drive: false,
        trigger: TriggerSetup {
            index: true,
            ..TriggerSetup::default()
        },
        ..QsbDriverConfig::default()
    });
    // MDR1 0x10 "Trigger/Capture on Index", no DIG I/O (the -S has none), CAPTURE
    // streamed; no STR (no pulse to count).
    assert_eq!(
        bench.run(),
        [
            "W161", "R14", "W155", "W000", "W0343", "W0410", "W0B0", "W0C1", "S05", "S0E"
        ]
    );
    stream(&mut bench, &[(0x05, 1234)]);
    let reading = bench.driver.read_pin(S_CAPTURE).expect("the capture pin");
    assert_eq!((reading.value, reading.events), (1234.0, 1));
}

#[test]
fn captures_count_as_events_two_in_one_tick_are_two_and_a_reset_keeps_the_count() {
    let mut bench = started_camera();
    // The `s 05` answer of the start-up carried CAPTURE as it was: no capture.
    let reading = bench.driver.read_pin(M_CAPTURE).expect("the capture pin");
    assert_eq!((reading.value, reading.events), (0.0, 0));
    stream(&mut bench, &[(0x05, 700)]);
    let reading = bench.driver.read_pin(M_CAPTURE).expect("read");
    assert_eq!((reading.value, reading.events), (700.0, 1));
    assert_eq!(reading.refreshed_at, Some(bench.now));
    // Two captures taken in before the engine looks again: two events, the newer count.
    stream(&mut bench, &[(0x05, 810)]);
    stream(&mut bench, &[(0x05, (-20i32) as u32)]);
    let reading = bench.driver.read_pin(M_CAPTURE).expect("read");
    assert_eq!((reading.value, reading.events), (-20.0, 3));
    // The board resets: CAPTURE is 0 again and the new `s 05` answer is no capture; the
    // count goes on from 3.
    bench.tick(Some(MD_DONE));
    bench.configured = false;
    let bytes = bench.line(ResponseType::Stream, 0x0E, 0);
    bench.rx(&bytes);
    bench.rx(&bytes);
    bench.run();
    assert!(bench.driver.status().online);
    assert_eq!(bench.driver.read_pin(M_CAPTURE).map(|r| r.events), Some(3));
    stream(&mut bench, &[(0x05, 42)]);
    let reading = bench.driver.read_pin(M_CAPTURE).expect("read");
    assert_eq!((reading.value, reading.events), (42.0, 4));
}

#[test]
fn a_pulse_is_an_enabled_latch_in_str_and_str_is_cleared_to_see_the_next() {
    let mut bench = started_camera();
    let pulses = |bench: &Bench| bench.driver.read_pin(M_TRIGGER).map(|r| r.events);
    stream(&mut bench, &[(0x06, STR_QUIET)]);
    assert_eq!(pulses(&bench), Some(0));
    // The index latch is no source of this trigger (match only).
    stream(&mut bench, &[(0x06, STR_IDX)]);
    assert_eq!(pulses(&bench), Some(0));
    stream(&mut bench, &[(0x06, STR_CMP | STR_IDX)]);
    assert_eq!(pulses(&bench), Some(1));
    // CLEAR REG 3 re-arms the count; until it is answered a latch is the same pulse.
    let clear = bench.sent().expect("the clear");
    assert_eq!(clear, b"W093\r\n");
    stream(&mut bench, &[(0x06, STR_CMP)]);
    assert_eq!(pulses(&bench), Some(1));
    bench.answer(&clear, 0);
    stream(&mut bench, &[(0x06, STR_QUIET)]);
    stream(&mut bench, &[(0x06, STR_CMP)]);
    assert_eq!(pulses(&bench), Some(2));
    assert_eq!(bench.run(), ["W093"]);
    assert!(!bench.driver.goals_pending(), "a clear is no goal");
}

#[test]
fn the_compare_position_changes_at_run_time() {
    let mut bench = started_camera();
    bench.tick(Some(MD_DONE));
    let reading = bench.driver.read_pin(M_TRIGGER).expect("the trigger pin");
    assert_eq!(reading.value, 5000.0);
    bench
        .driver
        .set_pin_value(bench.now, M_TRIGGER, 6000.4)
        .expect("a new compare position");
    assert_eq!(bench.run(), ["W081770"], "DTR 6000");
    let reading = bench.driver.read_pin(M_TRIGGER).expect("read");
    assert_eq!(reading.value, 6000.0);
    assert_eq!(reading.refreshed_at, Some(bench.now));
    assert_eq!(
        bench.driver.set_pin_value(bench.now, M_TRIGGER, 3e9),
        Err(GoalError::OutOfBoardRange(GoalKind::Position)),
        "beyond the 32-bit counter"
    );
    assert_eq!(
        bench.driver.set_pin_value(bench.now, M_CAPTURE, 1.0),
        Err(GoalError::NoSuchPin(M_CAPTURE))
    );
}

#[test]
fn a_home_search_switches_the_triggers_off_and_puts_them_back() {
    let mut bench = started_camera();
    bench.tick(Some(MD_DONE));
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Home { velocity: 2_000.0 })
        .expect("home");
    // MDR1 without B5 first; a compare position asked for meanwhile waits.
    bench
        .driver
        .set_pin_value(bench.now, M_TRIGGER, 7000.0)
        .expect("compare");
    assert_eq!(
        bench.run(),
        ["W040", "W12FFFFFF40", "W0363", "W093", "S06", "W169"]
    );
    bench.tick(Some(MD_JOGGING));
    // The index (the search's, with MDR1 B5 off): no pulse counted.
    bench.advance(TICK);
    let mut bytes = bench.line(ResponseType::Stream, 0x06, STR_IDX | STR_CMP);
    bench.counter = 0;
    bytes.extend(bench.line(ResponseType::Stream, 0x0E, 0));
    bench.rx(&bytes);
    assert!(bench.driver.channel(0).homed);
    assert_eq!(bench.driver.read_pin(M_TRIGGER).map(|r| r.events), Some(0));
    // Normal operation: MDR0, DTR = the new compare position, MDR1 with B5, STR cleared;
    // STR keeps streaming (the pulses are counted).
    assert_eq!(bench.run(), ["W0343", "W164", "W081B58", "W0420", "W093"]);
    assert_eq!(
        bench.driver.read_pin(M_TRIGGER).map(|r| r.value),
        Some(7000.0)
    );
}

#[test]
fn a_set_position_switches_the_triggers_off_while_dtr_holds_its_value() {
    let mut bench = started_camera();
    bench.tick(Some(MD_DONE));
    bench
        .driver
        .set_goal(bench.now, 0, Goal::SetPosition { counts: 100.0 })
        .expect("set-position");
    // MDR1 without B5, DTR 100, LOAD REG 0 (CNTR = DTR: no pulse), DTR back to the
    // compare position, MDR1 with B5, STR cleared.
    assert_eq!(
        bench.run(),
        ["W040", "W0864", "W0A0", "W081388", "W0420", "W093"]
    );
    bench.advance(Duration::from_millis(1));
    assert!(bench.run().is_empty());
}
