//! Replies judged on their own time (issue 39 items 3, 4): the AS-2 answers each request
//! once, in order, and sends nothing unasked (README "Commands"). A reply held up on the
//! host for 50, 100, 200 ms is waited for and paired — no verdict, the goal not lost; a
//! reply just inside its window is paired; one whose place a line that answers nothing
//! took is lost (counted, the goal sent again), and the reply that comes after all is
//! recognised as late, never paired.

use core::time::Duration;

use motion_drivers::{Driver, Goal};

use super::tests::Bench;

const MS: Duration = Duration::from_millis(1);

#[test]
fn a_reply_held_up_on_the_host_is_waited_for_and_the_move_arrives() {
    for hold in [50u64, 100, 200] {
        let mut bench = Bench::new().online();
        bench.goal(0, Goal::Position { counts: 3000.0 });
        bench.run(100);
        bench.hold_until = Some(bench.now + Duration::from_millis(hold));
        let mut written = 0;
        for _ in 0..hold {
            bench.tick();
            written += usize::from(bench.driver.awaiting_reply());
        }
        assert!(written > 0, "a request awaits its reply through the hold");
        bench.run(4000);
        let status = bench.driver.status();
        assert_eq!((status.verdicts, status.timeouts), (0, 0), "hold {hold} ms");
        let channel = bench.driver.channel(0);
        assert!(channel.arrived, "hold {hold} ms: {channel:?}");
        assert_eq!(bench.board.position(0), Some(3000));
    }
}

#[test]
fn a_reply_just_inside_its_window_is_paired() {
    let mut bench = Bench::new().online();
    bench.silent = true;
    bench.goal(0, Goal::Stop { decel: 1000.0 });
    let written = bench.now;
    bench.tick();
    let deadline = written + bench.driver.config().reply_timeout();
    while bench.now + MS < deadline {
        bench.tick();
    }
    bench.driver.handle_rx(deadline - MS / 10, b"OK\r");
    assert!(!bench.driver.goals_pending(), "paired");
    assert_eq!(bench.driver.status().timeouts, 0);
}

#[test]
fn a_reply_whose_place_garbage_took_is_lost_and_its_late_copy_recognised() {
    let mut bench = Bench::new().online();
    bench.silent = true;
    bench.goal(0, Goal::Stop { decel: 1000.0 });
    let written = bench.now;
    bench.tick();
    assert!(bench.driver.awaiting_reply());
    // A line that is no reply (a `P` line cut short) arrives where the reply was due.
    bench.driver.handle_rx(bench.now, b"P0 x\r");
    let deadline = written + bench.driver.config().reply_timeout();
    while bench.now < deadline {
        assert_eq!(bench.driver.status().timeouts, 0);
        bench.tick();
    }
    // The first tick at or past the deadline.
    bench.tick();
    assert_eq!(bench.driver.status().timeouts, 1, "counted as a timeout");
    // The stop goes again; the first one's reply comes after all, then the second's.
    assert!(bench.driver.awaiting_reply(), "sent again");
    bench.driver.handle_rx(bench.now, b"OK\r");
    assert!(!bench.driver.awaiting_reply());
    bench.driver.handle_rx(bench.now, b"OK\r");
    assert_eq!(bench.driver.late_replies(), 1);
    let status = bench.driver.status();
    assert_eq!(status.verdicts, 0);
}
