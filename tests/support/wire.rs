//! Command → wire on the fake clock (issue 18 item 2), shared by the four boards' tests:
//! velocity goals one after another, and for each the ticks from the tick that took it
//! (`reply.tick_applied`) to its first write (`AxisWire::wire_tick`, axis 0).

use core::time::Duration;

use motion_ipc::CommandKind;

use super::rig::Rig;

/// Sends a Velocity goal for each of `speeds` to axis 0, waits up to `within` for its
/// first request to be written, then runs `pause(request)` ticks before the next one.
/// Returns the ticks from each goal to its first write.
pub fn goal_to_wire_ticks(
    rig: &mut Rig,
    speeds: &[f64],
    within: Duration,
    mut pause: impl FnMut(usize) -> usize,
) -> Vec<u64> {
    let mut ticks = Vec::with_capacity(speeds.len());
    for (request, speed) in speeds.iter().enumerate() {
        let reply = rig.command(0, CommandKind::Velocity, [*speed, 0.0, 0.0]);
        assert_eq!(reply.result(), Ok(()), "request {request}");
        let goal_tick = reply.tick_applied;
        assert!(
            rig.run_until(within, |frame| {
                frame.wire[0].goal_tick == goal_tick && frame.wire[0].written()
            }),
            "request {request}: its first request is written"
        );
        let wire = rig.frame.wire[0];
        assert!(wire.wire_tick >= goal_tick, "{wire:?}");
        ticks.push(wire.wire_tick - goal_tick);
        rig.run(pause(request));
    }
    ticks
}

/// `count` speeds alternating between `a` and `b`, starting with `a`.
pub fn alternating(count: usize, a: f64, b: f64) -> Vec<f64> {
    (0..count).map(|i| if i % 2 == 0 { a } else { b }).collect()
}
