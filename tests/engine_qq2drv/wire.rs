//! Command → wire on the QuadQuad2Drv (issue 18 item 2): a new goal's transaction goes out
//! in the tick that took it, before that tick's poll.

use super::*;
use crate::support::lag::PROMPT;

#[test]
fn reversed_jogs_reach_the_wire_in_the_tick_that_took_them() {
    let (mut rig, _board, _) = rig();
    rig.stamp_io(PROMPT);
    wait_online(&mut rig);
    let mut ticks = Vec::new();
    for request in 0..40_u32 {
        let velocity = if request % 2 == 0 { 10.0 } else { -10.0 };
        let reply = rig.command(0, CommandKind::Velocity, [velocity, 0.0, 0.0]);
        assert_eq!(reply.result(), Ok(()), "request {request}");
        let goal_tick = reply.tick_applied;
        assert!(
            rig.run_until(Duration::from_millis(50), |frame| {
                frame.wire[0].goal_tick == goal_tick && frame.wire[0].written()
            }),
            "request {request}: its transaction is written"
        );
        let wire = rig.frame.wire[0];
        assert!(wire.wire_tick >= goal_tick, "{wire:?}");
        ticks.push(wire.wire_tick - goal_tick);
        rig.run((request % 6) as usize);
    }
    assert_eq!(ticks, vec![0; ticks.len()]);
}
