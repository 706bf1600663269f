//! Command → wire on the SPI_motor stepper (issue 18 item 2): a reversed jog (and a stop)
//! slows the board down from the tick that took it, even when the profile was updated in
//! that very tick: a deceleration is written with the rate of the next update. A speed-up
//! shows in the first tick whose profile rate has another 0.1 ms step delay (the profile
//! is never ahead of itself).

use super::*;
use crate::support::lag::PROMPT;
use crate::support::wire::{alternating, goal_to_wire_ticks};

/// Ticks from each goal to its first write, for jogs at `speeds` `apart + 0..6` ticks
/// apart (both phases of the 2 ms profile period).
fn jogs(rig: &mut Rig, speeds: &[f64], apart: usize) -> Vec<u64> {
    goal_to_wire_ticks(rig, speeds, Duration::from_millis(50), |request| {
        apart + request % 6
    })
}

#[test]
fn reversed_jogs_and_stops_reach_the_wire_in_the_tick_that_took_them() {
    let (mut rig, board, _) = stepper_rig(0x90);
    rig.stamp_io(PROMPT);
    wait_online(&mut rig, 1);
    // 500 steps/s at 20 000 steps/s²: 25 ms to stand, 25 more to cruise the other way.
    let reversals = alternating(24, 5.0, -5.0);
    let ticks = jogs(&mut rig, &reversals, 60);
    assert_eq!(ticks, vec![0; ticks.len()], "reversals");
    assert!(board.lock().unwrap().is_moving(), "jogging");
    let stop = rig.command(0, CommandKind::Stop, [0.0; 3]);
    assert_eq!(stop.result(), Ok(()));
    assert!(rig.run_until(Duration::from_millis(50), |frame| frame.wire[0].written()));
    assert_eq!(rig.frame.wire[0].wire_tick, stop.tick_applied, "the stop");
}

#[test]
fn a_speed_up_at_cruise_reaches_the_wire_in_the_first_tick_with_another_step_delay() {
    let (mut rig, _board, _) = stepper_rig(0x90);
    rig.stamp_io(PROMPT);
    wait_online(&mut rig, 1);
    let speeds = alternating(12, 3.0, 6.0);
    let ticks = jogs(&mut rig, &speeds, 60);
    // 300 → 600 steps/s at 20 000 steps/s²: +20 steps/s a tick. The step delay is whole
    // 0.1 ms (rounded up: never faster than the profile): 300 steps/s is 3.4 ms, 320 is
    // 3.2 ms — the first tick after the goal's has a change (the profile's update of the
    // goal's own tick integrated no time). Slowing down (600 → 300) is written at once.
    let tenths = |rate: f64| (10_000.0 / rate).ceil();
    let first_change = (0..)
        .find(|k: &u32| tenths(300.0 + 20.0 * f64::from(*k)) != tenths(300.0))
        .unwrap_or(0);
    assert_eq!(first_change, 1);
    for (request, ticks) in ticks.iter().enumerate() {
        let bound = if request % 2 == 0 {
            0
        } else {
            u64::from(first_change)
        };
        assert!(*ticks <= bound, "request {request}: {ticks} ticks");
    }
}
