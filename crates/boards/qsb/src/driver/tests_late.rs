//! One command at a time, and answers judged on their own time (issue 39 item 3): an
//! answer just inside its reply window is paired; one the board streams past is lost,
//! counted, the request sent again, and the late answer, should it still come, is
//! recognised by its time stamp and never taken for the retry's; an answer held up on
//! the host (a silent link) is waited for, however long, up to `silence_ms`.

use core::time::Duration;

use ::qsb::{ProductType, ResponseType, TICK};

use super::tests::{Bench, MD_DONE};
use motion_drivers::{Driver, Goal};

const JOG: Goal = Goal::Velocity {
    velocity: 5_000.0,
    accel: 100_000.0,
};

/// A started -M with a jog set: its first request, the jog rate, is in flight (sent at
/// `bench.now`). Returns the bench and the board's time stamp when it executed it.
fn jog_rate_in_flight() -> (Bench, u32) {
    let mut bench = Bench::started(ProductType::M);
    bench.tick(Some(MD_DONE));
    bench.driver.set_goal(bench.now, 0, JOG).expect("jog");
    bench.expect(b"W121F0\r\n");
    let executed = bench.ts;
    (bench, executed)
}

/// The jog rate's echo with the time stamp `ts`.
fn echo(bench: &mut Bench, ts: u32) -> Vec<u8> {
    let now_ts = bench.ts;
    bench.ts = ts;
    let line = bench.line(ResponseType::Write, 0x12, 0x1F0);
    bench.ts = now_ts;
    line
}

#[test]
fn an_answer_just_inside_its_window_is_paired() {
    let (mut bench, _) = jog_rate_in_flight();
    let deadline = bench.driver.poll_timeout().expect("deadline");
    // The stream goes on; the command reached the board late (the host's write), and its
    // answer, made after those lines, comes 10 µs before the deadline.
    while bench.now + TICK < deadline {
        bench.tick(None);
    }
    bench.advance(deadline - bench.now - Duration::from_micros(10));
    let ts = bench.ts;
    let line = echo(&mut bench, ts);
    bench.rx(&line);
    assert!(!bench.driver.awaiting_reply());
    assert_eq!(bench.driver.status().timeouts, 0);
    assert_eq!(bench.driver.late_answers_seen(), 0);
    bench.expect(b"W169\r\n");
}

/// Streams past the deadline of the request in flight until just before a reply window
/// has passed since the first line after it (nothing sent, nothing counted), then one
/// more line: just outside.
fn stream_past_the_window(bench: &mut Bench) {
    let deadline = bench.driver.poll_timeout().expect("deadline");
    let window = bench.driver.config().reply_timeout();
    while bench.now < deadline {
        bench.tick(None);
        assert_eq!(bench.sent(), None);
    }
    let first_after = bench.now;
    while bench.now + TICK < first_after + window {
        bench.tick(None);
        assert_eq!(bench.sent(), None, "at {:?}", bench.now);
        assert_eq!(bench.driver.status().timeouts, 0);
    }
    bench.tick(None);
    // (The engine lets the driver pass time after it took the tick's bytes in.)
    bench.driver.handle_timeout(bench.now);
    assert_eq!(bench.driver.status().timeouts, 1, "counted as a timeout");
}

#[test]
fn an_answer_the_board_streamed_past_is_lost_and_a_late_copy_is_never_paired() {
    let (mut bench, _) = jog_rate_in_flight();
    // The jog is replaced by a stop while its rate awaits its answer.
    let stop = Goal::Stop { decel: 100_000.0 };
    bench.driver.set_goal(bench.now, 0, stop).expect("stop");
    assert_eq!(bench.sent(), None, "one command at a time");
    stream_past_the_window(&mut bench);
    // The next command: the stop's.
    bench.expect(b"W164\r\n");
    // The jog rate's echo comes after all (the board got it late): it answers a request
    // declared lost, not the stop, which still awaits its own answer.
    let ts = bench.ts;
    let line = echo(&mut bench, ts);
    bench.rx(&line);
    assert_eq!(bench.driver.late_answers_seen(), 1);
    assert!(bench.driver.awaiting_reply());
    assert_eq!(bench.sent(), None);
    bench.advance(Duration::from_micros(500));
    let line = bench.line(ResponseType::Write, 0x16, 4);
    bench.rx(&line);
    assert!(!bench.driver.awaiting_reply());
    let status = bench.driver.status();
    assert_eq!((status.verdicts, status.resets), (0, 0));
}

#[test]
fn a_retry_takes_the_first_equal_echo_and_counts_the_second_late() {
    let (mut bench, _) = jog_rate_in_flight();
    stream_past_the_window(&mut bench);
    bench.expect(b"W121F0\r\n");
    // Two equal echoes come: the first (of either write) answers the retry — the board
    // holds the rate either way —, the second is late.
    for _ in 0..2 {
        bench.advance(Duration::from_micros(200));
        let ts = bench.ts;
        let line = echo(&mut bench, ts);
        bench.rx(&line);
    }
    assert_eq!(bench.driver.late_answers_seen(), 1);
    bench.expect(b"W169\r\n");
    let status = bench.driver.status();
    assert_eq!((status.verdicts, status.resets), (0, 0));
}

#[test]
fn an_echo_older_than_the_lines_seen_before_its_request_is_not_its_answer() {
    // On one UART lines come in the order they were made: an answer older than a line the
    // driver had before it wrote the request answers an earlier request. (The stamp guard
    // holds such a line first: module `guard`.)
    let (mut bench, executed) = jog_rate_in_flight();
    bench.tick(None);
    let line = echo(&mut bench, executed - 3);
    bench.rx(&line);
    assert!(bench.driver.awaiting_reply());
    let ts = bench.ts;
    let line = echo(&mut bench, ts);
    bench.rx(&line);
    assert!(!bench.driver.awaiting_reply());
    bench.expect(b"W169\r\n");
}

#[test]
fn an_answer_held_up_on_the_host_is_waited_for_and_paired() {
    for hold_ms in [50u64, 100, 200] {
        let (mut bench, executed) = jog_rate_in_flight();
        let start = bench.now;
        let hold = Duration::from_millis(hold_ms);
        // Nothing reaches the host: the deadline passes, nothing is sent or declared.
        while bench.now < start + hold {
            bench.advance(Duration::from_millis(1));
            assert_eq!(bench.sent(), None, "hold {hold_ms} ms at {:?}", bench.now);
        }
        // Then everything the board sent meanwhile, in its order: the line of the tick
        // before the write, the echo, and the stream since.
        let mut burst = bench.line(ResponseType::Stream, 0x0E, 0);
        let ts_now = bench.ts;
        bench.ts = executed;
        burst.extend(bench.line(ResponseType::Stream, 0x0E, 0));
        burst.extend(echo(&mut bench, executed));
        for ts in executed + 1..=ts_now {
            bench.ts = ts;
            burst.extend(bench.line(ResponseType::Stream, 0x0E, 0));
        }
        bench.ts = ts_now;
        bench.rx(&burst);
        let status = bench.driver.status();
        assert_eq!(status.timeouts, 0, "hold {hold_ms} ms");
        assert_eq!((status.verdicts, status.resets), (0, 0));
        assert!(status.online);
        assert_eq!(bench.driver.late_answers_seen(), 0);
        bench.expect(b"W169\r\n");
    }
}

#[test]
fn the_next_command_waits_for_the_answer_s_eor() {
    // Behind USB the `!` that completes the line and the EOR's LF can come a frame apart:
    // the response has not concluded before its EOR ("Command Response … '!' <EOR>").
    let (mut bench, _) = jog_rate_in_flight();
    bench.advance(Duration::from_micros(500));
    let ts = bench.ts;
    let line = echo(&mut bench, ts);
    let (body, eor) = line.split_at(line.len() - 1);
    assert_eq!(eor, b"\n");
    bench.rx(body);
    assert!(!bench.driver.awaiting_reply(), "answered at its `!`");
    assert_eq!(bench.driver.wants_transmit(bench.now), None);
    assert_eq!(bench.sent(), None, "not while its EOR is on the wire");
    bench.advance(Duration::from_millis(1));
    bench.rx(eor);
    bench.expect(b"W169\r\n");
}
