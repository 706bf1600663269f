//! Issue 39 item 4: a reply delayed on the host is never a reset and never drops a goal.
//! The simulated board's link is held (`SimFaults::hold`: nothing reaches the host for
//! 50, 100, 200 ms, then everything at once, in order) while a move runs, and while the
//! board is idle: no verdict, no fault, the move arrives.

use core::time::Duration;

use motion_ipc::{AxisFlags, CommandKind, Reason};

use crate::{Qsb, TOLERANCE, flags};

const HOLDS_MS: [u64; 3] = [50, 100, 200];

fn verdicts(qsb: &Qsb) -> u32 {
    qsb.rig.engine.driver(0).expect("driver").status().verdicts
}

#[test]
fn a_held_link_during_a_move_is_no_reset_and_the_move_arrives() {
    for hold in HOLDS_MS {
        let mut qsb = Qsb::m();
        assert_eq!(
            qsb.command(CommandKind::Position, [20.0, 0.0, 0.0]),
            Reason::Accepted
        );
        qsb.rig.run(300);
        let now = qsb.rig.now;
        qsb.faults.hold(now, Duration::from_millis(hold));
        let end = qsb.rig.now + Duration::from_secs(4);
        while !flags(&qsb.axis()).contains(AxisFlags::ARRIVED) {
            assert!(qsb.rig.now < end, "hold {hold} ms: {:?}", qsb.axis());
            qsb.rig.tick();
            let axis = qsb.axis();
            assert_eq!(
                axis.fault, 0,
                "hold {hold} ms: faulted at {:?}",
                qsb.rig.now
            );
        }
        let axis = qsb.axis();
        assert!((axis.position - 20.0).abs() <= TOLERANCE, "{axis:?}");
        let status = qsb.rig.engine.driver(0).expect("driver").status();
        assert_eq!(verdicts(&qsb), 0, "hold {hold} ms: {:?}", status.verdict);
        assert_eq!((status.resets, status.timeouts), (0, 0));
        // One command at a time throughout: none reached the board before the answer to
        // the previous one had left it.
        assert_eq!(qsb.sim.lock().expect("sim").stats().interlaced, 0);
    }
}

#[test]
fn a_held_link_while_idle_is_no_reset() {
    for hold in HOLDS_MS {
        let mut qsb = Qsb::m();
        qsb.rig.run(100);
        let now = qsb.rig.now;
        qsb.faults.hold(now, Duration::from_millis(hold));
        qsb.rig.run(1000);
        let status = qsb.rig.engine.driver(0).expect("driver").status();
        assert_eq!(verdicts(&qsb), 0, "hold {hold} ms: {:?}", status.verdict);
        assert_eq!(status.resets, 0);
        assert!(crate::healthy(&qsb.axis()));
        assert_eq!(qsb.sim.lock().expect("sim").stats().interlaced, 0);
    }
}
