//! An I/O side that lags (issue 18): a healthy board never looks dead, a silent one is still
//! found within the bound an unstamped rig finds it in.

use core::time::Duration;

use board_qsb::sim::Variant;
use motion_ipc::CommandKind;

use crate::support::lag::{
    LATE_WRITES, PROMPT, STARVED, SilenceFound, not_responding_after, stays_healthy, unreported,
};
use crate::{Qsb, rig, still};

const ONLINE: Duration = Duration::from_secs(10);

fn fresh_qsb() -> Qsb {
    let mut qsb = rig(Variant::M, still(), Duration::from_millis(250));
    qsb.rig.log_wire = false;
    qsb
}

#[test]
fn late_writes_or_a_starved_io_side_make_no_healthy_board_look_dead() {
    for lag in [LATE_WRITES, STARVED] {
        let mut qsb = fresh_qsb();
        qsb.rig.stamp_io(lag);
        stays_healthy(&mut qsb.rig, 1, ONLINE, Duration::from_secs(3));
    }
}

#[test]
fn unreported_late_writes_still_make_the_board_look_dead() {
    // Each request reaches the wire 100 ms after the driver believes it did, while the
    // stream keeps coming: past its deadline the board is heard streaming on without
    // the answer, which is then not coming (module `liveness`) — three in a row.
    let mut qsb = fresh_qsb();
    qsb.rig.stamp_io(unreported(LATE_WRITES));
    assert!(not_responding_after(&mut qsb.rig, Duration::from_secs(5)).is_some());
}

#[test]
fn unreported_a_starved_io_side_no_longer_does() {
    // Issue 39: the I/O side reads only every 100 ms, so every answer comes up to 200 ms
    // after its request, in a burst with the lines before it. A silent link is waited
    // for (`silence_ms`), and a burst holds the answer before anything made after it:
    // even an engine that is not told sees no reset and no silence.
    let mut qsb = fresh_qsb();
    qsb.rig.stamp_io(unreported(STARVED));
    stays_healthy(&mut qsb.rig, 1, ONLINE, Duration::from_secs(3));
    let status = qsb.rig.engine.driver(0).expect("driver").status();
    assert_eq!(status.verdicts, 0, "{:?}", status.verdict);
}

#[test]
fn a_board_gone_silent_is_still_found_within_the_unstamped_bound() {
    let found = SilenceFound::measure(
        || {
            let qsb = fresh_qsb();
            (qsb.rig, qsb.faults)
        },
        ONLINE,
    );
    // Late writes: the stream's silence brings a probe, and three unanswered requests in
    // a row are needed, each going out up to 100 ms late.
    // Starved: each request goes out at one run of the I/O side; its timeout is seen at
    // the next.
    found.assert_within(Duration::from_millis(350), Duration::from_millis(450));
}

#[test]
fn the_frame_says_when_a_goal_reached_the_wire() {
    for (lag, late_by) in [(PROMPT, 0), (LATE_WRITES, 100)] {
        let mut qsb = fresh_qsb();
        qsb.rig.stamp_io(lag);
        assert!(
            qsb.rig
                .run_until(ONLINE, |frame| crate::healthy(&frame.axes[0])),
            "online"
        );
        let reply = qsb.rig.command(0, CommandKind::Position, [1.0, 0.0, 0.0]);
        assert_eq!(reply.result(), Ok(()));
        let goal_tick = reply.tick_applied;
        assert_eq!(qsb.rig.frame.wire[0].goal_tick, goal_tick);
        assert!(
            qsb.rig
                .run_until(Duration::from_secs(1), |frame| frame.wire[0].written()),
            "the goal's first request is written"
        );
        let wire = qsb.rig.frame.wire[0];
        assert_eq!(wire.goal_tick, goal_tick, "{wire:?}");
        // Written in the tick that took the command (plus the lag), at most a reply's
        // round trip later if a request was in flight.
        let earliest = goal_tick + late_by;
        assert!(
            (earliest..=earliest + 2).contains(&wire.wire_tick),
            "{wire:?} for a goal of tick {goal_tick}"
        );
        // The rig's clock starts at 0 and its ticks are 1 ms apart.
        assert_eq!(wire.wire_ns, wire.wire_tick * 1_000_000, "{wire:?}");
    }
}
