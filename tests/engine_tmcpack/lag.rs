//! An I/O side that lags (issue 18): a healthy pack never looks dead, a silent one is still
//! found within the bound an unstamped rig finds it in.

use core::time::Duration;

use crate::single;
use crate::support::lag::{
    LATE_WRITES, STARVED, SilenceFound, not_responding_after, stays_healthy, unreported,
};

const ONLINE: Duration = Duration::from_secs(10);

#[test]
fn late_writes_or_a_starved_io_side_make_no_healthy_pack_look_dead() {
    for lag in [LATE_WRITES, STARVED] {
        let (mut rig, _, _) = single(1);
        rig.stamp_io(lag);
        stays_healthy(&mut rig, 2, ONLINE, Duration::from_secs(3));
    }
}

#[test]
fn unreported_the_same_lag_made_the_pack_look_dead() {
    for lag in [LATE_WRITES, STARVED] {
        let (mut rig, _, _) = single(1);
        rig.stamp_io(unreported(lag));
        assert!(not_responding_after(&mut rig, Duration::from_secs(5)).is_some());
    }
}

#[test]
fn a_pack_gone_silent_is_still_found_within_the_unstamped_bound() {
    let found = SilenceFound::measure(
        || {
            let (rig, _, faults) = single(1);
            (rig, faults)
        },
        ONLINE,
    );
    // Late writes: three unanswered queries in a row, each going out up to 100 ms late.
    // Starved: each timeout is seen at the I/O side's next run, up to 100 ms after the
    // deadline, and each query waits for the next run to go out.
    found.assert_within(Duration::from_millis(350), Duration::from_millis(650));
}
