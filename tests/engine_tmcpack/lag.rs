//! An I/O side that lags (issue 18): a healthy pack never looks dead, a silent one is still
//! found within the bound an unstamped rig finds it in.

use core::time::Duration;

use crate::single;
use crate::support::lag::{
    LATE_WRITES, PROMPT, STARVED, TICK, not_responding_after, silence_found_after, stays_healthy,
    unreported,
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
    let found = |lag| {
        let (mut rig, _, faults) = single(1);
        if let Some(lag) = lag {
            rig.stamp_io(lag);
        }
        silence_found_after(&mut rig, &faults, ONLINE)
    };
    let today = found(None);
    let prompt = found(Some(PROMPT));
    assert!(prompt <= today + 2 * TICK, "{prompt:?} vs {today:?}");
    // Three unanswered queries in a row: each goes out up to 100 ms late.
    let late = found(Some(LATE_WRITES));
    assert!(
        late <= today + Duration::from_millis(350),
        "{late:?} vs {today:?}"
    );
    // Each timeout is seen at the I/O side's next run, up to 100 ms after the deadline,
    // and each query waits for the next run to go out.
    let starved = found(Some(STARVED));
    assert!(
        starved <= today + Duration::from_millis(650),
        "{starved:?} vs {today:?}"
    );
}
