//! Command → wire on a Trinamic pack (issue 18 item 2): the pack must never get a second
//! request before its answer (manual 7.1 "Interlacing of Requests"), so a new goal waits
//! for at most the one exchange in flight — a 9-byte query, the switch-over, the 9-byte
//! answer, the switch-over again (6.1) — and the tick that takes the answer in.

use super::*;
use crate::support::lag::PROMPT;

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
    let mut ticks = Vec::new();
    for request in 0..40_u32 {
        let velocity = if request % 2 == 0 { 10.0 } else { -10.0 };
        let reply = rig.command(0, CommandKind::Velocity, [velocity, 0.0, 0.0]);
        assert_eq!(reply.result(), Ok(()), "request {request}");
        let goal_tick = reply.tick_applied;
        assert!(
            rig.run_until(Duration::from_millis(100), |frame| {
                frame.wire[0].goal_tick == goal_tick && frame.wire[0].written()
            }),
            "request {request}: its `$25` is written"
        );
        let wire = rig.frame.wire[0];
        assert!(wire.wire_tick >= goal_tick, "{wire:?}");
        ticks.push(wire.wire_tick - goal_tick);
        // Every phase of the polls' exchanges.
        rig.run((request * 7 % 17) as usize);
    }
    assert!(
        ticks.iter().all(|t| *t <= bound),
        "{ticks:?} beyond {bound}"
    );
    assert!(
        ticks.contains(&0),
        "a free line takes a goal at once: {ticks:?}"
    );
}
