//! Issue 39 item 4: the QuadQuad2Drv's MISO held back on the host (an SPI socket peer or
//! the server starved: `SimFaults::hold`) for 50, 100, 200 ms while a move runs is no
//! verdict, no fault, and the move arrives — with the I/O side reporting its stamps, as
//! motiond's does, and without.

use core::time::Duration;

use crate::support::hold::{HOLDS, HeldMove, PROMPT, move_survives_hold};
use crate::{COUNTS_PER_MM, TOLERANCE_MM, rig, wait_online};

#[test]
fn a_held_link_during_a_move_is_no_verdict_and_the_move_arrives() {
    for stamped in [false, true] {
        for hold in HOLDS {
            let (mut rig, board, faults) = rig();
            if stamped {
                rig.stamp_io(PROMPT);
            }
            wait_online(&mut rig);
            let run = HeldMove {
                axis: 0,
                target: 20.0,
                tolerance: TOLERANCE_MM,
                before: Duration::from_millis(300),
                within: Duration::from_secs(3),
            };
            move_survives_hold(&mut rig, &faults, run, hold);
            let sim = board.lock().expect("board");
            let counter = sim.counter(0).expect("channel");
            assert!((f64::from(counter) / COUNTS_PER_MM - 20.0).abs() <= TOLERANCE_MM);
            // Every packet was read out entirely before the next request.
            assert_eq!(sim.stats().interlaced, 0);
        }
    }
}
