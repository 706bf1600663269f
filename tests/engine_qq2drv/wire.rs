//! Command → wire on the QuadQuad2Drv (issue 18 item 2): a new goal's transaction goes out
//! in the tick that took it, before that tick's poll.

use super::*;
use crate::support::lag::PROMPT;
use crate::support::wire::{alternating, goal_to_wire_ticks};

#[test]
fn reversed_jogs_reach_the_wire_in_the_tick_that_took_them() {
    let (mut rig, _board, _) = rig();
    rig.stamp_io(PROMPT);
    wait_online(&mut rig);
    let ticks = goal_to_wire_ticks(
        &mut rig,
        &alternating(40, 10.0, -10.0),
        Duration::from_millis(50),
        |request| request % 6,
    );
    assert_eq!(ticks, vec![0; ticks.len()]);
}
