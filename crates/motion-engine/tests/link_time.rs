//! The instant a driver is given for received bytes (`Engine::handle_link_rx`): the tick's
//! `now`, or the instant the link's I/O side read them if that is later. A tick that woke
//! late runs at its deadline; the bytes it takes may have come after it, and a driver told
//! they came earlier would time its next request from before the board's answer ended
//! (manual 6.1 of the TMCM SIXpack / QUADpack: "The PACK continues to drive the line for a
//! pre-set time after transmitting a message" — a request inside that hold is lost).

mod support;

use core::time::Duration;

use support::*;

const MS: Duration = Duration::from_millis(1);

fn harness() -> (Harness, std::sync::Arc<std::sync::Mutex<BoardControl>>) {
    let (engine, mut controls) = two_link_engine();
    let mut harness = Harness::new(engine);
    harness.ticks(3);
    (harness, controls.remove(0))
}

#[test]
fn bytes_read_after_a_late_ticks_deadline_reach_the_driver_at_their_arrival() {
    let (mut harness, control) = harness();
    let now = harness.now;
    // The tick's deadline is `now`; it woke 4 ms late, and the answer's last byte was read
    // 3.2 ms after the deadline.
    let arrived = now + 3 * MS + MS / 5;
    harness
        .engine
        .handle_link_rx(0, now, arrived, &[0xFE, 0x43, 0x95]);
    let received = control.lock().expect("control").received.clone();
    assert_eq!(received, vec![(arrived, vec![0xFE, 0x43, 0x95])]);
}

#[test]
fn bytes_read_before_the_deadline_reach_the_driver_at_the_ticks_now() {
    let (mut harness, control) = harness();
    let now = harness.now;
    // Read 0.6 ms before this tick's deadline: the driver's clock does not go back.
    harness
        .engine
        .handle_link_rx(0, now, now - MS * 3 / 5, &[0x01]);
    harness.engine.handle_link_rx(0, now, now, &[0x02]);
    let received = control.lock().expect("control").received.clone();
    assert_eq!(received, vec![(now, vec![0x01]), (now, vec![0x02])]);
}
