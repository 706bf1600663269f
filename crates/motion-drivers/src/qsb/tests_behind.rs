//! A new plan's request written behind a request in flight (module docs of `wire`): on
//! the wire in the same `poll_transmit`, answers matched oldest first, a replaced plan's
//! answer never advancing the new one, and nothing skipped on what an unanswered request
//! may still change.

use core::time::Duration;

use ::qsb::{ProductType, ResponseType};

use super::tests::{Bench, MD_DONE};
use crate::driver::Driver;
use crate::goal::Goal;

/// MD JOG RATE ±496 steps/s (5000 counts/s at 10 counts per step, in 16-step increments).
const JOG_PLUS: &[u8] = b"W121F0\r\n";
const JOG_MINUS: &[u8] = b"W12FFFFFE10\r\n";
const MOTOR_JOG: &[u8] = b"W169\r\n";

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

/// What `poll_transmit` writes now, with its `goal_starts`.
fn transmit(bench: &mut Bench) -> Option<(Vec<u8>, u8)> {
    let mut buf = [0u8; 256];
    let sent = bench.driver.poll_transmit(bench.now, &mut buf)?;
    assert!(sent.expects_reply);
    Some((buf[..sent.len].to_vec(), sent.goal_starts))
}

#[test]
fn a_new_goal_goes_out_behind_the_replaced_plans_request_in_the_same_poll() {
    let mut bench = online();
    bench
        .driver
        .set_goal(bench.now, 0, jog(5_000.0))
        .expect("jog");
    assert_eq!(transmit(&mut bench), Some((JOG_PLUS.to_vec(), 1)));
    bench.advance(Duration::from_micros(500));
    bench.answer(JOG_PLUS, 0);
    assert_eq!(transmit(&mut bench), Some((MOTOR_JOG.to_vec(), 0)));
    // The reverse jog while COMMAND 9 awaits its answer: its first request is on the
    // wire at once, and it is the goal's first (the frame's wire stamp).
    bench
        .driver
        .set_goal(bench.now, 0, jog(-5_000.0))
        .expect("reverse");
    assert_eq!(transmit(&mut bench), Some((JOG_MINUS.to_vec(), 1)));
    assert_eq!(
        transmit(&mut bench),
        None,
        "the plan's next step waits for its own answer"
    );
    // The old COMMAND 9 is answered first (the board answers in order): matched to it,
    // it does not advance the new plan.
    bench.advance(Duration::from_micros(500));
    bench.answer(MOTOR_JOG, 0);
    assert!(bench.driver.awaiting_reply());
    assert_eq!(transmit(&mut bench), None);
    bench.answer(JOG_MINUS, 0);
    assert_eq!(bench.run(), ["W169"]);
    assert_eq!(bench.driver.status().timeouts, 0);
    assert_eq!(bench.driver.status().bad_replies, 0, "every answer matched");
}

#[test]
fn a_register_write_in_flight_is_not_taken_as_held() {
    let mut bench = online();
    bench
        .driver
        .set_goal(bench.now, 0, jog(-5_000.0))
        .expect("jog");
    assert_eq!(bench.run(), ["W12FFFFFE10", "W169"]);
    // Forwards: its MD JOG RATE goes out and is not answered yet.
    bench
        .driver
        .set_goal(bench.now, 0, jog(5_000.0))
        .expect("forwards");
    assert_eq!(transmit(&mut bench), Some((JOG_PLUS.to_vec(), 1)));
    // Back again before that answer: the board held −496, but may yet take +496, so
    // −496 is written again (behind it), not skipped.
    bench
        .driver
        .set_goal(bench.now, 0, jog(-5_000.0))
        .expect("back");
    assert_eq!(transmit(&mut bench), Some((JOG_MINUS.to_vec(), 1)));
    bench.advance(Duration::from_micros(500));
    bench.answer(JOG_PLUS, 0);
    bench.answer(JOG_MINUS, 0);
    assert_eq!(
        bench.run(),
        ["W169"],
        "the jog runs at the rate written last"
    );
}

#[test]
fn a_goal_goes_out_behind_a_liveness_probe_and_both_answers_are_matched() {
    let mut bench = online();
    // The stream goes quiet: the driver asks for VERSION.
    let budget = bench.driver.refresh_budget();
    bench.advance(budget + Duration::from_millis(1));
    let (probe, _) = transmit(&mut bench).expect("probe");
    assert_eq!(probe, b"R14\r\n");
    bench
        .driver
        .set_goal(bench.now, 0, jog(5_000.0))
        .expect("jog");
    assert_eq!(transmit(&mut bench), Some((JOG_PLUS.to_vec(), 1)));
    // Samples came meanwhile (the board did not lose its settings), then both answers.
    bench.tick(Some(MD_DONE));
    let version = bench.version;
    bench.answer(&probe, version);
    bench.answer(JOG_PLUS, 0);
    assert_eq!(bench.run(), ["W169"]);
    assert!(bench.driver.status().online);
    assert_eq!(bench.driver.status().fault, None);
    assert_eq!(bench.driver.status().bad_replies, 0);
}

#[test]
fn an_answer_to_the_request_behind_means_the_older_ones_answer_was_lost() {
    let mut bench = online();
    bench
        .driver
        .set_goal(bench.now, 0, jog(5_000.0))
        .expect("jog");
    assert_eq!(bench.run(), ["W121F0", "W169"]);
    // Stop it and take the first request out, unanswered, then reverse behind it.
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Stop { decel: 100_000.0 })
        .expect("stop");
    let (stop, _) = transmit(&mut bench).expect("stop");
    assert_eq!(stop, b"W164\r\n");
    bench
        .driver
        .set_goal(bench.now, 0, jog(-5_000.0))
        .expect("reverse");
    assert_eq!(transmit(&mut bench), Some((JOG_MINUS.to_vec(), 1)));
    // COMMAND 4's answer is lost on the line; MD JOG RATE's comes.
    bench.advance(Duration::from_micros(500));
    bench.answer(JOG_MINUS, 0);
    assert_eq!(
        bench.driver.status().timeouts,
        1,
        "the stop's answer counts as lost"
    );
    assert_eq!(bench.run(), ["W169"]);
}

#[test]
fn at_most_one_request_goes_behind_and_never_during_start_up() {
    let mut bench = online();
    bench
        .driver
        .set_goal(bench.now, 0, jog(5_000.0))
        .expect("jog");
    assert_eq!(transmit(&mut bench), Some((JOG_PLUS.to_vec(), 1)));
    bench
        .driver
        .set_goal(bench.now, 0, jog(-5_000.0))
        .expect("reverse");
    assert_eq!(transmit(&mut bench), Some((JOG_MINUS.to_vec(), 1)));
    // A third goal while two requests await their answers: it waits for room.
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Stop { decel: 100_000.0 })
        .expect("stop");
    assert_eq!(transmit(&mut bench), None, "two in flight at the most");
    bench.advance(Duration::from_micros(500));
    bench.answer(JOG_PLUS, 0);
    assert_eq!(
        transmit(&mut bench),
        Some((b"W164\r\n".to_vec(), 1)),
        "behind the replaced plan's MD JOG RATE"
    );
    bench.answer(JOG_MINUS, 0);
    bench.answer(b"W164\r\n", 0);
    bench.tick(Some(MD_DONE));
    assert_eq!(bench.run(), Vec::<String>::new());
    assert!(!bench.driver.goals_pending());

    // A board that resets: its start-up is one request at a time again.
    let mut fresh = Bench::new(ProductType::M);
    let (first, _) = transmit(&mut fresh).expect("start-up");
    assert_eq!(first, b"W161\r\n");
    assert_eq!(transmit(&mut fresh), None);
    let line = fresh.line(ResponseType::Write, 0x16, 1);
    fresh.rx(&line);
    assert_eq!(
        transmit(&mut fresh).map(|(l, _)| l),
        Some(b"R14\r\n".to_vec())
    );
}
