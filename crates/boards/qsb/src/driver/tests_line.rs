//! Unit tests of a group's line on the QSB-M: the board's own position move, and a hold
//! with its own pause and resume (QSB Command List, COMMAND 16: "6 = Motor Pause - Pause
//! the motor using the MD ACCEL rate", "7 = Motor Resume - Resume motor operation if
//! previously stopped using the Motor Pause command").

use ::qsb::ProductType;

use super::tests::{Bench, MD_DONE, MD_JOGGING, MD_MOVING};
use motion_drivers::{Driver, Goal, LINE_RATE_TOLERANCE, LineLeg};

/// MD STATUS B2 "Paused", B4 "Motor Enabled".
const MD_PAUSED: u32 = 0x14;

fn leg(counts: f64) -> LineLeg {
    LineLeg {
        channel: 0,
        counts,
        velocity: 5_000.0,
        accel: 20_000.0,
        rate_tolerance: LINE_RATE_TOLERANCE,
    }
}

#[test]
fn a_line_is_the_boards_own_move_and_a_hold_pauses_and_resumes_it() {
    let mut bench = Bench::started(ProductType::M);
    bench.tick(Some(MD_DONE));
    bench.tick(None);
    assert_eq!(bench.driver.lead_line(bench.now, &[leg(1000.0)]), Ok(true));
    // MD ACCEL 2000 steps/s² = 0x7D0, MD STEP RATE 500 → 496 = 0x1F0; the move waits for
    // the engine's start (with the group's boards on other links).
    assert_eq!(bench.run(), ["W107D0", "W0F1F0"]);
    assert!(bench.driver.line_ready());
    bench.driver.start_line(bench.now);
    // 100 steps (0x64), COMMAND 8 "Motor Move".
    assert_eq!(bench.run(), ["W1164", "W168"]);
    assert!(!bench.driver.line_ready());
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
    assert_eq!(
        bench.driver.pause_line(bench.now, 0),
        Ok(false),
        "not started"
    );
    bench.driver.start_line(bench.now);
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

/// A goal that energises the drive (an enable line, active low on io3) by sending the DIG
/// I/O write itself keeps it energised: the signal outputs written next carry the enable
/// line too (they used to write it inactive again, and the move after an Off never ran).
#[test]
fn the_outputs_written_after_a_goal_enables_the_drive_keep_it_enabled() {
    let mut bench = Bench::started_with(super::QsbDriverConfig {
        enable: Some(super::EnableOutput {
            bit: 3,
            active_high: false,
        }),
        io: super::QsbIo {
            digital_out: 0b0001,
            ..super::QsbIo::default()
        },
        ..super::QsbDriverConfig::default()
    });
    bench.tick(Some(MD_DONE));
    bench.driver.set_goal(bench.now, 0, Goal::Off).expect("off");
    bench.run();
    bench.tick(Some(MD_DONE));
    assert_eq!(bench.driver.lead_line(bench.now, &[leg(1000.0)]), Ok(true));
    // As the engine does: the goal, then at once the transmit (no timeout handling
    // between them to settle the plan).
    let mut buf = [0u8; 256];
    let transmit = bench
        .driver
        .poll_transmit(bench.now, &mut buf)
        .expect("the enable write");
    let first = buf[..transmit.len].to_vec();
    bench.answer(&first, 0);
    let mut sent = vec![String::from_utf8_lossy(&first).trim_end().to_owned()];
    sent.extend(bench.run());
    for _ in 0..5 {
        bench.tick(Some(MD_DONE));
        sent.extend(bench.run());
    }
    assert!(bench.driver.line_ready(), "{sent:?}");
    bench.driver.start_line(bench.now);
    sent.extend(bench.run());
    let dig_io: Vec<u32> = sent
        .iter()
        .filter_map(|line| line.strip_prefix("W01"))
        .map(|data| u32::from_str_radix(data, 16).expect("hex"))
        .collect();
    assert!(!dig_io.is_empty(), "{sent:?}");
    assert!(dig_io.iter().all(|latch| latch & 0b1000 == 0), "{sent:?}");
    assert_eq!(sent.last().map(String::as_str), Some("W168"), "{sent:?}");
}

/// MD STEP RATE changes "in increments of 16 steps/second": a line at 67 steps/s would run
/// at 64 (4.5 % slow) and is left to the engine; one at 64 steps/s is taken.
#[test]
fn a_line_whose_rate_the_increments_miss_is_not_taken() {
    let mut bench = Bench::started(ProductType::M);
    bench.tick(Some(MD_DONE));
    bench.tick(None);
    // 10 counts per step (the default config).
    let at = |velocity: f64| LineLeg {
        channel: 0,
        counts: 1000.0,
        velocity,
        accel: 6_400.0,
        rate_tolerance: LINE_RATE_TOLERANCE,
    };
    assert_eq!(bench.driver.lead_line(bench.now, &[at(670.0)]), Ok(false));
    assert!(!bench.driver.goals_pending());
    // 64 steps/s a hair under (the path's arithmetic) still counts as 64.
    assert_eq!(
        bench
            .driver
            .lead_line(bench.now, &[at(640.0 * (1.0 - 1e-12))]),
        Ok(true)
    );
}

#[test]
fn an_axis_s_own_move_is_held_with_command_6_and_rests_until_command_7() {
    // `motionctl hold AXIS`: the engine asks the board to pause a plain position goal.
    let mut bench = Bench::started(ProductType::M);
    bench.tick(Some(MD_DONE));
    bench
        .driver
        .set_goal(
            bench.now,
            0,
            Goal::RampPosition {
                counts: 2000.0,
                velocity: 5_000.0,
                accel: 20_000.0,
            },
        )
        .expect("a move");
    // MD ACCEL, MD STEP RATE, MD MOVE STEPS 200 (0xC8), COMMAND 8.
    assert_eq!(bench.run(), ["W107D0", "W0F1F0", "W11C8", "W168"]);
    bench.counter = 400;
    bench.tick(Some(MD_MOVING));
    assert!(bench.driver.channel(0).moving);
    assert_eq!(bench.driver.pause_line(bench.now, 0), Ok(true));
    assert_eq!(bench.run(), ["W166"]);
    // At rest, paused: not moving (the engine's stop becomes its hold), not arrived.
    for _ in 0..10 {
        bench.tick(Some(MD_PAUSED));
    }
    let channel = bench.driver.channel(0);
    assert!(!channel.moving && !channel.arrived, "{channel:?}");
    assert_eq!(bench.driver.resume_line(bench.now, 0), Ok(true));
    assert_eq!(bench.run(), ["W167"]);
    bench.tick(Some(MD_MOVING));
    assert!(bench.driver.channel(0).moving);
    bench.counter = 2000;
    bench.tick(Some(MD_DONE));
    bench.tick(Some(MD_DONE));
    assert_eq!(bench.run(), Vec::<String>::new());
    assert!(bench.driver.channel(0).arrived);
}
