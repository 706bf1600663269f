//! Command → wire on a Trinamic pack (issue 18 item 2): the pack must never get a second
//! request before its answer (manual 7.1 "Interlacing of Requests"), so a new goal waits
//! for at most the one exchange in flight — a 9-byte query, the switch-over, the 9-byte
//! answer, the switch-over again (6.1) — and the tick that takes the answer in.

use super::*;
use crate::support::lag::PROMPT;
use crate::support::wire::{alternating, goal_to_wire_ticks};

/// One query exchange at 19200 baud with the driver's `$40` of 2 ms: two 9-byte words
/// (10 bits a byte) and the switch-over on both sides of the answer.
fn exchange() -> Duration {
    let word = Duration::from_secs_f64(90.0 / f64::from(BAUD));
    2 * word + 2 * Duration::from_millis(2)
}

#[test]
fn a_goal_waits_for_at_most_the_one_exchange_in_flight_and_the_tick_that_takes_it_in() {
    let (mut rig, _board, _) = single(1);
    rig.stamp_io(PROMPT);
    wait_online(&mut rig, 2);
    let bound = 2 + exchange().as_millis() as u64 + 1;
    // Every phase of the polls' exchanges.
    let ticks = goal_to_wire_ticks(
        &mut rig,
        &alternating(40, 10.0, -10.0),
        Duration::from_millis(100),
        |request| request * 7 % 17,
    );
    assert!(
        ticks.iter().all(|t| *t <= bound),
        "{ticks:?} beyond {bound}"
    );
    assert!(
        ticks.contains(&0),
        "a free line takes a goal at once: {ticks:?}"
    );
}
