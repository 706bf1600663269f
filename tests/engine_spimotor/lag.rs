//! An I/O side that lags (issue 18): a healthy board never looks dead, a silent one is still
//! found within the bound an unstamped rig finds it in.

use core::time::Duration;

use crate::stepper_rig;
use crate::support::lag::{
    LATE_WRITES, STARVED, SilenceFound, not_responding_after, stays_healthy, unreported,
};
use crate::support::rig::IoLag;

const ONLINE: Duration = Duration::from_secs(10);

#[test]
fn late_writes_or_a_starved_io_side_make_no_healthy_board_look_dead() {
    for lag in [LATE_WRITES, STARVED] {
        let (mut rig, _, _) = stepper_rig(0x90);
        rig.stamp_io(lag);
        stays_healthy(&mut rig, 1, ONLINE, Duration::from_secs(3));
    }
}

/// The lags above `times` over.
fn times(lag: IoLag, factor: u32) -> IoLag {
    IoLag {
        write_delay: lag.write_delay * factor,
        runs_every: lag.runs_every * factor,
        ..lag
    }
}

#[test]
fn a_lag_below_silence_ms_is_harmless_reported_or_not() {
    // 300 ms: MISO that has not come back is waited for up to `silence_ms` (500 ms), so
    // even an engine that is not told sees no silence (issue 39).
    for lag in [times(LATE_WRITES, 3), times(STARVED, 3)] {
        let (mut rig, _, _) = stepper_rig(0x90);
        rig.stamp_io(lag);
        stays_healthy(&mut rig, 1, ONLINE, Duration::from_secs(3));
        let (mut rig, _, _) = stepper_rig(0x90);
        rig.stamp_io(unreported(lag));
        stays_healthy(&mut rig, 1, ONLINE, Duration::from_secs(3));
    }
}

#[test]
fn a_lag_beyond_silence_ms_is_harmless_reported_and_fatal_unreported() {
    for lag in [times(LATE_WRITES, 6), times(STARVED, 6)] {
        let (mut rig, _, _) = stepper_rig(0x90);
        rig.stamp_io(lag);
        stays_healthy(&mut rig, 1, ONLINE, Duration::from_secs(3));
        let (mut rig, _, _) = stepper_rig(0x90);
        rig.stamp_io(unreported(lag));
        assert!(not_responding_after(&mut rig, Duration::from_secs(5)).is_some());
    }
}

#[test]
fn a_board_gone_silent_is_still_found_within_the_unstamped_bound() {
    let found = SilenceFound::measure(
        || {
            let (rig, _, faults) = stepper_rig(0x90);
            (rig, faults)
        },
        ONLINE,
    );
    // Late writes: three all-0xFF polls in a row, each waiting for the MISO of the one
    // before, which goes out 100 ms late.
    // Starved: each poll goes out at one run of the I/O side and is read at the next.
    found.assert_within(Duration::from_millis(250), Duration::from_millis(450));
}
