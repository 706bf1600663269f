//! Command → wire on the QSB (issue 18 item 2): a new goal's first request is written in
//! the tick that took the command, or — when the previous plan's request still awaits its
//! answer (the QSB takes one command at a time: "At the conclusion of the command
//! response, the QSB is ready to accept another command", QSB command list, Command
//! Acknowledgement Format) — in the tick that takes that answer in: one tick later at
//! 1 kHz and 230400 baud.

use core::time::Duration;

use board_qsb::sim::Variant;

use crate::support::lag::PROMPT;
use crate::support::wire::{alternating, goal_to_wire_ticks};
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
    // The next request lands 0–5 ticks after this one went out: while the plan's MD JOG
    // RATE or COMMAND 9 awaits its answer, or after.
    let extra_ticks = goal_to_wire_ticks(
        &mut qsb.rig,
        &alternating(60, 10.0, -10.0),
        Duration::from_millis(50),
        |request| request % 6,
    );
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
