//! Issue 39 item 4, shared by the boards' engine tests: a reply delayed on the host (the
//! server or the board's process starved for up to 200 ms: `SimFaults::hold`) is never a
//! reset or a not-answering verdict, and never drops a goal.

use core::time::Duration;

use motion_ipc::{AxisFlags, CommandKind, DeviceState};
use motion_link::sim::SimFaults;

use super::rig::{IoLag, Rig, accepted};

/// The holds every board survives.
pub const HOLDS: [Duration; 3] = [
    Duration::from_millis(50),
    Duration::from_millis(100),
    Duration::from_millis(200),
];

/// A prompt I/O side that reports its stamps (as motiond's does).
pub const PROMPT: IoLag = IoLag {
    write_delay: Duration::ZERO,
    runs_every: Duration::ZERO,
    report: true,
};

/// A move a held link must not disturb.
#[derive(Debug, Clone, Copy)]
pub struct HeldMove {
    /// The axis (index) that moves, on device 0.
    pub axis: usize,
    /// Where to, in its units.
    pub target: f64,
    /// How close it must end.
    pub tolerance: f64,
    /// How long it runs before the hold begins.
    pub before: Duration,
    /// How long it may take after that to arrive.
    pub within: Duration,
}

/// Sends the axis of `run` to its target, lets it run `before`, holds the board's link for
/// `hold`, and runs until the axis arrived (at most `within`): in every frame the axis has
/// no fault and its board stays online; the driver reaches no verdict, sees no reset, and
/// the axis ends within `tolerance` of the target.
pub fn move_survives_hold(rig: &mut Rig, faults: &SimFaults, run: HeldMove, hold: Duration) {
    let HeldMove {
        axis,
        target,
        tolerance,
        before,
        within,
    } = run;
    accepted(
        rig,
        u32::try_from(axis).expect("axis"),
        CommandKind::Position,
        [target, 0.0, 0.0],
    );
    let end = rig.now + before;
    while rig.now < end {
        rig.tick();
    }
    faults.hold(rig.now, hold);
    let end = rig.now + within;
    loop {
        rig.tick();
        let state = rig.axis(axis);
        assert_eq!(
            state.fault, 0,
            "hold {hold:?}: axis {axis} faulted at {:?}",
            rig.now
        );
        assert_eq!(
            rig.frame.device_state(0),
            DeviceState::Online,
            "hold {hold:?}: the board left the online state at {:?}",
            rig.now
        );
        if state.flags().contains(AxisFlags::ARRIVED) {
            break;
        }
        assert!(rig.now < end, "hold {hold:?}: not arrived: {state:?}");
    }
    let state = rig.axis(axis);
    assert!(
        (state.position - target).abs() <= tolerance,
        "hold {hold:?}: {state:?}"
    );
    let status = rig.engine.driver(0).expect("driver").status();
    assert_eq!(status.verdicts, 0, "hold {hold:?}: {:?}", status.verdict);
    assert_eq!(status.resets, 0, "hold {hold:?}");
    assert!(status.online);
}
