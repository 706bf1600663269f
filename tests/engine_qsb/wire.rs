//! Command → wire on the QSB (issue 18 item 2): a new goal's first request is written in
//! the tick that took the command, or — when the previous plan's request still awaits its
//! answer (the QSB takes one command at a time: "At the conclusion of the command
//! response, the QSB is ready to accept another command", QSB command list, Command
//! Acknowledgement Format) — in the tick that takes that answer in: one tick later at
//! 1 kHz and 230400 baud.

use core::time::Duration;

use motion_ipc::CommandKind;
use motion_sim::qsb::Variant;

use crate::support::lag::PROMPT;
use crate::{rig, still};

#[test]
fn reversed_jogs_reach_the_wire_within_the_answer_in_flight_at_every_phase_of_the_old_plan() {
    let mut qsb = rig(Variant::M, still(), Duration::from_millis(250));
    qsb.rig.stamp_io(PROMPT);
    assert!(
        qsb.rig
            .run_until(Duration::from_secs(10), |frame| crate::healthy(
                &frame.axes[0]
            )),
        "online"
    );
    let mut extra_ticks = Vec::new();
    for request in 0..60_u32 {
        let velocity = if request % 2 == 0 { 10.0 } else { -10.0 };
        let reply = qsb
            .rig
            .command(0, CommandKind::Velocity, [velocity, 0.0, 0.0]);
        assert_eq!(reply.result(), Ok(()), "request {request}");
        let goal_tick = reply.tick_applied;
        assert!(
            qsb.rig.run_until(Duration::from_millis(50), |frame| {
                frame.wire[0].goal_tick == goal_tick && frame.wire[0].written()
            }),
            "request {request}: its first request is written"
        );
        let wire = qsb.rig.frame.wire[0];
        assert!(wire.wire_tick >= goal_tick, "{wire:?}");
        extra_ticks.push(wire.wire_tick - goal_tick);
        // The next request lands 0–5 ticks after this one went out: while the plan's
        // MD JOG RATE or COMMAND 9 awaits its answer, or after.
        qsb.rig.run((request % 6) as usize);
    }
    assert!(
        extra_ticks.iter().all(|&ticks| ticks <= 1),
        "at most the answer in flight (one tick) between the goal and its first write: \
         {extra_ticks:?}"
    );
    let prompt = extra_ticks.iter().filter(|&&ticks| ticks == 0).count();
    assert!(
        prompt * 4 >= extra_ticks.len() * 3,
        "a goal with nothing in flight goes out in its own tick: {extra_ticks:?}"
    );
}
