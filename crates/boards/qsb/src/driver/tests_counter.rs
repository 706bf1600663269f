//! The counter modes on the fake clock: what the start-up writes (DTR before MDR0, again
//! after a reset), a home search in another count mode, the position and velocity of a
//! modulo-n counter through its wrap, and a set-position that must not lose the limit.

use core::time::Duration;

use ::qsb::{CountMode, CycleMode, IndexMode, ProductType, ResponseType, TICK};

use super::tests::{Bench, MD_DONE};
use super::{CounterSetup, QsbDriverConfig};
use motion_drivers::{DeviceFault, Driver, Goal, GoalError, GoalKind};

/// A -D measuring a 500-cycle encoder in x1, modulo 500, the index resetting the count.
fn modulo_d() -> QsbDriverConfig {
    QsbDriverConfig {
        variant: ProductType::D,
        motor_drive: false,
        counter: CounterSetup {
            count: CountMode::X1,
            cycle: CycleMode::ModuloN,
            limit: 499,
            index: IndexMode::ResetCntr,
            synchronous_index: true,
        },
        ..QsbDriverConfig::default()
    }
}

/// The -D's start-up: COMMAND 1, VERSION, EOR, MODE, DTR 499 ("W081F3", the command
/// list's DTR example), MDR0 0x6D (B6 sync index, B5 B4 = 10 "reset CNTR", B3 B2 = 11
/// "modulo-n", B1 B0 = 01 "x1"), MDR1, THRESHOLD, INTERVAL RATE, the stream.
const MODULO_START_UP: [&str; 10] = [
    "W161", "R14", "W155", "W000", "W081F3", "W036D", "W040", "W0B0", "W0C1", "S0E",
];

#[test]
fn a_modulo_n_mode_is_written_dtr_first_at_start_up_and_again_after_a_reset() {
    let mut bench = Bench::with_config(modulo_d());
    assert_eq!(bench.run(), MODULO_START_UP);
    assert!(bench.driver.status().online);
    bench.tick(None);
    // The board rebooted (factory MDR0 0x4F, DTR 0x1F3): two lines in the factory format.
    bench.configured = false;
    let bytes = bench.line(ResponseType::Stream, 0x0E, 0);
    bench.rx(&bytes);
    bench.rx(&bytes);
    assert_eq!(bench.driver.status().fault, Some(DeviceFault::Reset));
    assert_eq!(bench.run(), MODULO_START_UP, "the mode again");
}

#[test]
fn the_count_mode_is_kept_by_a_home_search_and_its_return_to_normal() {
    let x2 = QsbDriverConfig {
        counter: CounterSetup {
            count: CountMode::X2,
            ..CounterSetup::default()
        },
        ..QsbDriverConfig::default()
    };
    let mut bench = Bench::with_config(x2);
    let lines = bench.run();
    assert!(lines.contains(&"W0342".to_owned()), "{lines:?}");
    bench.tick(Some(MD_DONE));
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Home { velocity: 2_000.0 })
        .expect("home");
    // x2 with the index resetting CNTR (0x62), then back to x2 free-running (0x42).
    assert_eq!(bench.run(), ["W12FFFFFF40", "W0362", "W093", "S06", "W169"]);
    bench.advance(TICK);
    let mut bytes = bench.line(ResponseType::Stream, 0x06, 0x18);
    bench.counter = 0;
    bytes.extend(bench.line(ResponseType::Stream, 0x0E, 0));
    bench.rx(&bytes);
    assert!(bench.driver.channel(0).homed);
    assert_eq!(bench.run(), ["W0342", "W164", "R06"]);
}

#[test]
fn a_step_direction_counter_has_an_asynchronous_index() {
    let steps = QsbDriverConfig {
        counter: CounterSetup {
            count: CountMode::NonQuadrature,
            ..CounterSetup::default()
        },
        ..QsbDriverConfig::default()
    };
    let mut bench = Bench::with_config(steps);
    let lines = bench.run();
    // "Asynchronous index mode is set in non-quadrature modes": B6 = 0, B1 B0 = 00.
    assert!(lines.contains(&"W030".to_owned()), "{lines:?}");
}

#[test]
fn a_modulo_n_position_wraps_and_its_velocity_goes_on_through_the_wrap() {
    let mut bench = Bench::with_config(modulo_d());
    bench.counter = 300;
    bench.run();
    bench.tick(None);
    let mut bad_before = 0;
    let mut wraps = 0;
    for k in 0..200 {
        if k == 20 {
            // (A start at once beyond max_accel is held a sample or two: module `guard`.)
            bad_before = bench.driver.status().bad_replies;
        }
        let before = bench.counter;
        bench.counter = (bench.counter + 9) % 500;
        wraps += usize::from(bench.counter < before);
        bench.tick(None);
        let channel = bench.driver.channel(0);
        assert!((0.0..500.0).contains(&channel.position), "{channel:?}");
    }
    assert!(wraps >= 3);
    let channel = bench.driver.channel(0);
    assert_eq!(channel.position, f64::from(bench.counter));
    assert_eq!(channel.velocity, 9.0 / TICK.as_secs_f64());
    assert_eq!(
        bench.driver.status().bad_replies - bad_before,
        0,
        "no sample of the wraps is held"
    );
}

#[test]
fn a_set_position_in_modulo_n_loads_through_dtr_and_puts_the_limit_back() {
    let mut bench = Bench::started_with(modulo_d());
    bench.tick(None);
    assert!(bench.driver.capabilities(0).contains(GoalKind::SetPosition));
    bench
        .driver
        .set_goal(bench.now, 0, Goal::SetPosition { counts: 123.0 })
        .expect("set-position");
    assert_eq!(bench.run(), ["W087B", "W0A0", "W081F3"]);
    for counts in [500.0, -1.0] {
        assert_eq!(
            bench
                .driver
                .set_goal(bench.now, 0, Goal::SetPosition { counts }),
            Err(GoalError::OutOfBoardRange(GoalKind::SetPosition)),
            "{counts}"
        );
    }
    bench.advance(Duration::from_millis(1));
    assert!(bench.run().is_empty(), "nothing sent for a refused value");
}
