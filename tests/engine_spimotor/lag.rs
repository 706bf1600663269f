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

/// Three times the lags above: beyond the driver's 100 ms reply margin.
fn tripled(lag: IoLag) -> IoLag {
    IoLag {
        write_delay: lag.write_delay * 3,
        runs_every: lag.runs_every * 3,
        ..lag
    }
}

#[test]
fn a_lag_beyond_the_reply_margin_is_harmless_reported_and_fatal_unreported() {
    for lag in [tripled(LATE_WRITES), tripled(STARVED)] {
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
