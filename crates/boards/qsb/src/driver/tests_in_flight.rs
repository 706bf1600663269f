//! One command at a time (module docs, "Wire, liveness and resets"): "At the conclusion of
//! the command response, the QSB is ready to accept another command" (QSB command list,
//! Command Acknowledgement Format). A new plan waits for the answer in flight, goes out as
//! soon as it came, and never skips a step on what that unanswered request may still
//! change.

use core::time::Duration;

use ::qsb::ProductType;

use super::tests::{Bench, MD_DONE};
use motion_drivers::{Driver, Goal};

/// MD JOG RATE ±496 steps/s (5000 counts/s at 10 counts per step, in 16-step increments).
const JOG_PLUS: &[u8] = b"W121F0\r\n";
const JOG_MINUS: &[u8] = b"W12FFFFFE10\r\n";
const MOTOR_JOG: &[u8] = b"W169\r\n";
const MOTOR_STOP: &[u8] = b"W164\r\n";

fn jog(velocity: f64) -> Goal {
    Goal::Velocity {
        velocity,
        accel: 100_000.0,
    }
}

fn online() -> Bench {
    let mut bench = Bench::started(ProductType::M);
    bench.tick(Some(MD_DONE));
    bench
}

/// Sets axis 0's goal (accepted).
fn set(bench: &mut Bench, goal: Goal) {
    let now = bench.now;
    bench.driver.set_goal(now, 0, goal).expect("goal accepted");
}

/// 500 µs later, the board's answer to `line`.
fn answer_later(bench: &mut Bench, line: &[u8]) {
    bench.advance(Duration::from_micros(500));
    bench.answer(line, 0);
}

/// What `poll_transmit` writes now, with its `goal_starts`.
fn transmit(bench: &mut Bench) -> Option<(Vec<u8>, u8)> {
    let mut buf = [0u8; 256];
    let sent = bench.driver.poll_transmit(bench.now, &mut buf)?;
    assert!(sent.expects_reply);
    Some((buf[..sent.len].to_vec(), sent.goal_starts))
}

#[test]
fn a_new_goal_waits_for_the_answer_in_flight_then_goes_out_first() {
    let mut bench = online();
    set(&mut bench, jog(5_000.0));
    assert_eq!(transmit(&mut bench), Some((JOG_PLUS.to_vec(), 1)));
    answer_later(&mut bench, JOG_PLUS);
    assert_eq!(transmit(&mut bench), Some((MOTOR_JOG.to_vec(), 0)));
    // The reverse jog while COMMAND 9 awaits its answer: nothing more on the line until
    // that answer (the board is not ready for another command before it).
    set(&mut bench, jog(-5_000.0));
    assert_eq!(transmit(&mut bench), None, "one command at a time");
    answer_later(&mut bench, MOTOR_JOG);
    // The old plan's answer does not advance the new one; the new one goes out at once,
    // and it is the goal's first write (the frame's wire stamp).
    assert_eq!(transmit(&mut bench), Some((JOG_MINUS.to_vec(), 1)));
    assert_eq!(transmit(&mut bench), None);
    bench.answer(JOG_MINUS, 0);
    assert_eq!(bench.run(), ["W169"]);
    assert_eq!(bench.driver.status().timeouts, 0);
    assert_eq!(bench.driver.status().bad_replies, 0, "every answer matched");
}

#[test]
fn a_register_write_in_flight_is_not_taken_as_held() {
    let mut bench = online();
    set(&mut bench, jog(-5_000.0));
    assert_eq!(bench.run(), ["W12FFFFFE10", "W169"]);
    // Forwards: its MD JOG RATE goes out and is not answered yet.
    set(&mut bench, jog(5_000.0));
    assert_eq!(transmit(&mut bench), Some((JOG_PLUS.to_vec(), 1)));
    // Back again before that answer: the board held −496 but may yet take +496, so the
    // plan must not drop its MD JOG RATE step as already done (the jog would then run
    // forwards at the rate written last).
    set(&mut bench, jog(-5_000.0));
    assert_eq!(transmit(&mut bench), None, "one command at a time");
    answer_later(&mut bench, JOG_PLUS);
    assert_eq!(transmit(&mut bench), Some((JOG_MINUS.to_vec(), 1)));
    bench.answer(JOG_MINUS, 0);
    assert_eq!(bench.run(), ["W169"], "the jog runs backwards");
}

#[test]
fn a_stop_set_while_a_jog_command_is_unanswered_is_sent_after_its_answer() {
    let mut bench = online();
    set(&mut bench, jog(5_000.0));
    assert_eq!(transmit(&mut bench), Some((JOG_PLUS.to_vec(), 1)));
    bench.answer(JOG_PLUS, 0);
    assert_eq!(transmit(&mut bench), Some((MOTOR_JOG.to_vec(), 0)));
    // MD STATUS still says done (the jog has not shown yet): with COMMAND 9 unanswered the
    // drive is not taken as done, so the stop is not skipped.
    set(&mut bench, Goal::Stop { decel: 100_000.0 });
    bench.tick(Some(MD_DONE));
    assert_eq!(transmit(&mut bench), None, "one command at a time");
    bench.answer(MOTOR_JOG, 0);
    assert_eq!(transmit(&mut bench), Some((MOTOR_STOP.to_vec(), 1)));
}
