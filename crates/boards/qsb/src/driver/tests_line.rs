//! Unit tests of a group's line on the QSB-M: the board's own position move, and a hold
//! with its own pause and resume (QSB Command List, COMMAND 16: "6 = Motor Pause - Pause
//! the motor using the MD ACCEL rate", "7 = Motor Resume - Resume motor operation if
//! previously stopped using the Motor Pause command").

use ::qsb::ProductType;

use super::tests::{Bench, MD_DONE, MD_JOGGING, MD_MOVING};
use motion_drivers::{Driver, Goal, LineLeg};

/// MD STATUS B2 "Paused", B4 "Motor Enabled".
const MD_PAUSED: u32 = 0x14;

fn leg(counts: f64) -> LineLeg {
    LineLeg {
        channel: 0,
        counts,
        velocity: 5_000.0,
        accel: 20_000.0,
    }
}

#[test]
fn a_line_is_the_boards_own_move_and_a_hold_pauses_and_resumes_it() {
    let mut bench = Bench::started(ProductType::M);
    bench.tick(Some(MD_DONE));
    bench.tick(None);
    assert_eq!(bench.driver.lead_line(bench.now, &[leg(1000.0)]), Ok(true));
    let sent = bench.run();
    assert_eq!(
        sent.last().map(String::as_str),
        Some("W168"),
        "COMMAND 8 Motor Move"
    );
    // Nothing to pause before the drive runs the move.
    bench.counter = 200;
    bench.tick(Some(MD_MOVING));
    assert_eq!(bench.driver.pause_line(bench.now, 0), Ok(true));
    assert_eq!(bench.run(), ["W166"]);
    bench.counter = 260;
    bench.tick(Some(MD_PAUSED));
    // Paused: the driver waits, it neither moves again nor calls the move done.
    bench.tick(Some(MD_PAUSED));
    assert_eq!(bench.run(), Vec::<String>::new());
    assert!(bench.driver.goals_pending());
    assert!(!bench.driver.channel(0).arrived);
    assert_eq!(bench.driver.resume_line(bench.now, 0), Ok(true));
    assert_eq!(bench.run(), ["W167"]);
    bench.tick(Some(MD_MOVING));
    bench.counter = 1000;
    bench.tick(Some(MD_DONE));
    bench.tick(Some(MD_DONE));
    assert_eq!(bench.run(), Vec::<String>::new());
    assert!(bench.driver.channel(0).arrived);
    assert!(!bench.driver.goals_pending());
}

#[test]
fn only_a_running_move_is_paused_and_only_a_paused_one_resumed() {
    let mut bench = Bench::started(ProductType::M);
    bench.tick(Some(MD_DONE));
    assert_eq!(bench.driver.resume_line(bench.now, 0), Ok(false));
    bench
        .driver
        .set_goal(
            bench.now,
            0,
            Goal::Velocity {
                velocity: 1000.0,
                accel: 10_000.0,
            },
        )
        .expect("jog");
    bench.run();
    bench.tick(Some(MD_JOGGING));
    // A jog is not a move the board can resume to its end: the engine holds it itself.
    assert_eq!(bench.driver.pause_line(bench.now, 0), Ok(false));
    assert!(bench.driver.pause_line(bench.now, 1).is_err());
    assert_eq!(
        bench.driver.lead_line(bench.now, &[leg(1.0), leg(2.0)]),
        Ok(false)
    );
}

#[test]
fn a_board_without_a_motor_drive_leads_no_line() {
    let mut bench = Bench::started(ProductType::D);
    bench.tick(None);
    assert_eq!(bench.driver.lead_line(bench.now, &[leg(1000.0)]), Ok(false));
}

/// A stop while paused replaces the paused move: COMMAND 4, and no resume follows.
#[test]
fn a_stop_while_paused_ends_the_move() {
    let mut bench = Bench::started(ProductType::M);
    bench.tick(Some(MD_DONE));
    bench.tick(None);
    assert_eq!(bench.driver.lead_line(bench.now, &[leg(1000.0)]), Ok(true));
    bench.run();
    bench.tick(Some(MD_MOVING));
    assert_eq!(bench.driver.pause_line(bench.now, 0), Ok(true));
    bench.run();
    bench.tick(Some(MD_PAUSED));
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Stop { decel: 20_000.0 })
        .expect("stop");
    let sent = bench.run();
    assert!(sent.iter().any(|l| l == "W164"), "{sent:?}");
    assert!(!sent.iter().any(|l| l == "W167"));
    assert_eq!(bench.driver.resume_line(bench.now, 0), Ok(false));
}
