//! The simulated board answering the README's commands.

use core::time::Duration;

use motion_link::sim::StreamDevice;

use super::{ExampleSim, ExampleSimConfig};

/// Sends `line` at `at` and returns the reply that started by `at` + 1 ms.
fn ask(board: &mut ExampleSim, at: Duration, line: &[u8]) -> String {
    board.receive(at, line);
    let mut out = [0u8; 64];
    let len = board.transmit(at + Duration::from_millis(1), &mut out);
    String::from_utf8_lossy(&out[..len]).into_owned()
}

fn ms(ms: u64) -> Duration {
    Duration::from_millis(ms)
}

#[test]
fn a_move_is_acknowledged_and_reaches_its_target() {
    let mut board = ExampleSim::new(ExampleSimConfig::default());
    assert_eq!(ask(&mut board, ms(0), b"?\r"), "AS2 1.4\r");
    assert_eq!(ask(&mut board, ms(2), b"M1 -400 1000 10000\r"), "OK\r");
    let moving = ask(&mut board, ms(100), b"P1?\r");
    assert!(
        moving.starts_with("P1 -") && moving.ends_with(" M\r"),
        "{moving}"
    );
    // 400 steps: 0.1 s to 1000 steps/s (50 steps), 0.3 s cruise, 0.1 s down: ~0.5 s.
    assert_eq!(ask(&mut board, ms(600), b"P1?\r"), "P1 -400 0 I\r");
    assert_eq!(ask(&mut board, ms(602), b"P0?\r"), "P0 0 0 I\r");
}

#[test]
fn a_jog_runs_until_a_stop_and_the_counter_can_be_set() {
    let mut board = ExampleSim::new(ExampleSimConfig::default());
    assert_eq!(ask(&mut board, ms(0), b"V0 800 8000\r"), "OK\r");
    let running = ask(&mut board, ms(500), b"P0?\r");
    assert!(running.contains(" 800 M"), "{running}");
    assert_eq!(ask(&mut board, ms(502), b"S0 8000\r"), "OK\r");
    let stopped = ask(&mut board, ms(700), b"P0?\r");
    assert!(stopped.ends_with(" 0 I\r"), "{stopped}");
    assert_eq!(ask(&mut board, ms(702), b"Z0 5\r"), "OK\r");
    assert_eq!(ask(&mut board, ms(704), b"P0?\r"), "P0 5 0 I\r");
    assert_eq!(ask(&mut board, ms(706), b"O0\r"), "OK\r");
    assert_eq!(ask(&mut board, ms(708), b"P0?\r"), "P0 5 0 O\r");
}

#[test]
fn garbage_and_bad_values_get_error_replies() {
    let mut board = ExampleSim::new(ExampleSimConfig::default());
    assert_eq!(ask(&mut board, ms(0), b"\xff\x00hello\r"), "E1\r");
    assert_eq!(ask(&mut board, ms(2), b"P7?\r"), "E2\r");
    assert_eq!(ask(&mut board, ms(4), b"M0 1 0 100\r"), "E3\r");
    assert_eq!(ask(&mut board, ms(6), &[b'x'; 100]), "");
    assert_eq!(ask(&mut board, ms(8), b"\r"), "E1\r");
    assert_eq!(board.stats().errors, 4);
    assert_eq!(board.position(0), Some(0), "nothing moved");
}

#[test]
fn replies_wait_for_the_processing_time_and_keep_their_order_under_jitter() {
    let mut board = ExampleSim::new(ExampleSimConfig {
        jitter: Duration::from_micros(500),
        seed: 7,
        ..ExampleSimConfig::default()
    });
    board.receive(ms(0), b"P0?\rP1?\r?\r");
    let first = board.next_event(ms(0)).expect("a reply is scheduled");
    assert!(first >= Duration::from_micros(200), "{first:?}");
    let mut out = [0u8; 64];
    assert_eq!(board.transmit(first - Duration::from_nanos(1), &mut out), 0);
    let len = board.transmit(ms(1), &mut out);
    assert_eq!(&out[..len], b"P0 0 0 I\rP1 0 0 I\rAS2 1.4\r");
    assert_eq!(board.next_event(ms(1)), None);
}

#[test]
fn a_request_before_the_previous_reply_left_is_counted() {
    // README "Commands": "One request at a time: the host waits for the reply before it
    // sends the next." At 115200 baud a byte takes 86.8 µs; `AS2 1.4\r` (8 bytes) leaves
    // 200 µs + 694 µs after the `?`'s `\r`.
    let mut board = ExampleSim::new(ExampleSimConfig::default());
    board.line_rate(115_200);
    board.receive(ms(0), b"?\r");
    // A request whose first byte arrives 0.5 ms later: the reply is still leaving.
    board.receive(ms(0) + Duration::from_micros(500), b"P0?\r");
    assert_eq!(board.stats().interlaced, 1);
    // One that begins after both replies left is not.
    board.receive(ms(5), b"P1?\r");
    assert_eq!(board.stats().interlaced, 1);
    // Both were answered in turn all the same.
    let mut out = [0u8; 64];
    let len = board.transmit(ms(6), &mut out);
    assert_eq!(&out[..len], b"AS2 1.4\rP0 0 0 I\rP1 0 0 I\r");
}
