//! Issue 39 item 4: the SPI_motor's MISO held back on the host (an SPI socket peer or the
//! server starved: `SimFaults::hold`) for 50, 100, 200 ms while a move runs is no
//! verdict, no fault, and the move arrives — with the I/O side reporting its stamps, as
//! motiond's does, and without.

use core::time::Duration;

use crate::support::hold::{HOLDS, HeldMove, PROMPT, move_survives_hold};
use crate::{STEPS_PER_MM, stepper_rig, wait_online};

#[test]
fn a_held_link_during_a_move_is_no_verdict_and_the_move_arrives() {
    for stamped in [false, true] {
        for hold in HOLDS {
            let (mut rig, board, faults) = stepper_rig(0x90);
            if stamped {
                rig.stamp_io(PROMPT);
            }
            wait_online(&mut rig, 1);
            let run = HeldMove {
                axis: 0,
                target: 20.0,
                tolerance: 0.01,
                before: Duration::from_millis(300),
                within: Duration::from_secs(3),
            };
            move_survives_hold(&mut rig, &faults, run, hold);
            let rotor = board.lock().expect("board").rotor_steps();
            assert_eq!(rotor, (20.0 * STEPS_PER_MM) as i64, "hold {hold:?}");
            let status = rig.engine.driver(0).expect("driver").status();
            assert_eq!(status.timeouts, 0, "hold {hold:?}");
        }
    }
}
