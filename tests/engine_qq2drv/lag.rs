//! An I/O side that lags (issue 18): a healthy board never looks dead, a silent one is still
//! found within the bound an unstamped rig finds it in.

use core::time::Duration;

use crate::rig;
use crate::support::lag::{
    LATE_WRITES, STARVED, SilenceFound, not_responding_after, stays_healthy, unreported,
};

const ONLINE: Duration = Duration::from_secs(10);

#[test]
fn late_writes_or_a_starved_io_side_make_no_healthy_board_look_dead() {
    for lag in [LATE_WRITES, STARVED] {
        let (mut rig, _, _) = rig();
        rig.stamp_io(lag);
        stays_healthy(&mut rig, 2, ONLINE, Duration::from_secs(3));
    }
}

#[test]
fn unreported_the_same_lag_no_longer_makes_the_board_look_dead() {
    // Issue 39: the board streams; a stream that comes late, or in bursts, is never
    // `silence_ms` without a valid packet, so even an engine that is not told reaches no
    // verdict (unreported late writes still make requests look lost: their replies come
    // 100 ms after the driver believes they were written).
    for lag in [LATE_WRITES, STARVED] {
        let (mut rig, _, _) = rig();
        rig.stamp_io(unreported(lag));
        assert_eq!(not_responding_after(&mut rig, Duration::from_secs(5)), None);
        let status = rig.engine.driver(0).expect("driver").status();
        assert_eq!(status.verdicts, 0, "{lag:?}: {:?}", status.verdict);
        assert!(status.online);
    }
}

#[test]
fn a_board_gone_silent_is_still_found_within_the_unstamped_bound() {
    let found = SilenceFound::measure(
        || {
            let (rig, _, faults) = rig();
            (rig, faults)
        },
        ONLINE,
    );
    // Late writes: silence is judged from the last valid packet; the polls that would
    // have carried the next ones go out 100 ms late.
    // Starved: polls go out in bursts at each run of the I/O side and their MISO bytes
    // are read at the next: the silence shows two to three runs later.
    found.assert_within(Duration::from_millis(150), Duration::from_millis(350));
}
