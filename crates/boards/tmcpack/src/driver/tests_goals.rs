//! Unit tests of stops, the start-up quiesce and reference searches (manual 8.3/8.4).

use core::time::Duration;

use tmcpack::{Action, CurrentLevel, MotorOptions, MotorType, Reply, Request, RequestFrame};

use super::bench::*;
use super::*;

fn rotate(motor: u8, velocity: i16) -> Request {
    Request::Rotate { motor, velocity }
}

/// Manual 8.4 $25: "The change to rotation happens immediately, even if the motor is still
/// active": a stop is `$25` velocity 0 whatever the driver believes, here of a motor its
/// polls show inactive.
#[test]
fn a_stop_reaches_the_wire_even_for_a_motor_the_driver_believes_idle() {
    let mut bench = Bench::new(config());
    bench.online();
    bench.serve(40, |m| position(m, 123, Action::Inactive));
    assert!(!bench.driver.channel(0).moving);
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Stop { decel: 160_000.0 })
        .expect("stop");
    let (_, w) = bench.next(20).expect("$25");
    // $25: motnr 0, velocity 0 (LSB first).
    assert_eq!(w, [0x01, 0x25, 0, 0, 0, 0, 0, 0, 0]);
    // The pack's amax (318, the floor of the axis limit) is no gentler than the floor of
    // the stop's: $25 went first, the exact (rounded up) amax right after it.
    assert_eq!(
        bench.request(),
        Request::VelocityAcceleration {
            motor: 0,
            amax: 319,
            vmax: 498
        }
    );
    bench.serve(60, |m| position(m, 123, Action::Inactive));
    assert!(!bench.driver.goals_pending());
}

#[test]
fn a_stop_at_a_harder_rate_than_the_pack_has_writes_amax_first() {
    let mut bench = Bench::new(config());
    bench.online();
    bench
        .driver
        .set_goal(
            bench.now,
            0,
            Goal::Velocity {
                velocity: 16_000.0,
                accel: 20_000.0,
            },
        )
        .expect("jog");
    bench.serve(40, |m| position(m, 0, Action::Rotation));
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Stop { decel: 160_000.0 })
        .expect("stop");
    assert_eq!(
        bench.request(),
        Request::VelocityAcceleration {
            motor: 0,
            amax: 319,
            vmax: 498
        }
    );
    assert_eq!(bench.request(), rotate(0, 0));
}

/// docs/ARCHITECTURE.md "Commands go before polls"; a stop also goes before other queued commands.
#[test]
fn a_stop_overtakes_the_queued_commands_of_other_motors() {
    let mut bench = Bench::new(config());
    bench.online();
    bench.serve(40, |m| position(m, 0, Action::Inactive));
    bench
        .driver
        .set_goal(bench.now, 2, Goal::Position { counts: 5000.0 })
        .expect("move");
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Stop { decel: 160_000.0 })
        .expect("stop");
    assert_eq!(bench.request(), rotate(0, 0));
}

#[test]
fn off_then_stop_energises_the_motor_again_to_hold() {
    let mut bench = Bench::new(config());
    bench.online();
    bench.driver.set_goal(bench.now, 0, Goal::Off).expect("off");
    let sent = bench.serve(200, |m| position(m, 0, Action::Inactive));
    assert!(sent.iter().any(|r| matches!(
        r,
        Request::CurrentControl {
            motor: 0,
            i0: CurrentLevel::Off,
            i1: CurrentLevel::Off,
            i2: CurrentLevel::Off,
            i3: CurrentLevel::Off,
            ..
        }
    )));
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Stop { decel: 160_000.0 })
        .expect("stop");
    let sent = bench.serve(200, |m| position(m, 0, Action::Inactive));
    let stop = sent.iter().position(|r| *r == rotate(0, 0));
    let on = sent.iter().position(|r| {
        *r == Request::CurrentControl {
            motor: 0,
            i0: CurrentLevel::P50,
            i1: CurrentLevel::P50,
            i2: CurrentLevel::P75,
            i3: CurrentLevel::P100,
            t0: 500,
        }
    });
    assert!(stop.is_some() && stop < on, "{sent:?}");
}

/// A motor still running when the driver starts (left so by a previous server) is stopped
/// before `$12` ("change only with stopped motors!") and `$13`/`$16` reach it.
#[test]
fn motors_found_running_are_stopped_before_the_configuration() {
    let mut bench = Bench::new(config());
    bench.next(10).expect("$43");
    bench.now += 11 * MS;
    bench.rx(&UNIT_INFO);
    let mut actions = [Action::Inactive; 6];
    actions[2] = Action::Rotation;
    actions[4] = Action::Ramp; // not configured: left alone
    bench.survey(actions);
    assert_eq!(
        bench.driver.set_goal(bench.now, 0, Goal::Off),
        Err(GoalError::Starting)
    );
    // Motor 2's axis: 6400 µsteps/s² at 8.2's scale for its divider.
    let amax = bench.request();
    assert!(
        matches!(amax, Request::VelocityAcceleration { motor: 2, .. }),
        "{amax:?}"
    );
    assert_eq!(bench.request(), rotate(2, 0));
    let mut asked = 0;
    let mut configured = Vec::new();
    for _ in 0..2000 {
        let Some(w) = bench.tick() else { continue };
        let request = RequestFrame::decode(&w).expect("decodes").request;
        match request {
            Request::QueryVelocity { motor: 2, .. } => {
                asked += 1;
                bench.now += 10 * MS;
                // $21: vact decelerating to 0 over three answers.
                let velocity = (3 - asked).max(0) * 40;
                bench.rx(&word(Reply::Velocity {
                    motor: 2,
                    velocity,
                    action: Action::Rotation,
                }));
            }
            Request::QueryVelocity { .. } => panic!("only running motors are asked"),
            other => {
                configured.push(other);
                if bench.driver.status().online {
                    break;
                }
            }
        }
    }
    assert_eq!(asked, 3, "asked until vact read 0");
    assert!(
        matches!(configured[0], Request::SetBaud { .. }),
        "{configured:?}"
    );
    assert!(configured.contains(&Request::VelocitySetting { clkdiv: 18 }));
    assert!(bench.driver.status().online);
}

#[test]
fn a_motor_that_never_reads_zero_holds_the_configuration_back_only_for_a_bounded_time() {
    let mut bench = Bench::new(config());
    bench.next(10).expect("$43");
    bench.now += 11 * MS;
    bench.rx(&UNIT_INFO);
    let mut actions = [Action::Inactive; 6];
    actions[0] = Action::ReferenceSearch(1);
    bench.survey(actions);
    let started = bench.now;
    let mut configured_at = None;
    for _ in 0..20_000 {
        let at = bench.now;
        let Some(w) = bench.tick() else { continue };
        match RequestFrame::decode(&w).expect("decodes").request {
            Request::QueryVelocity { motor, .. } => {
                bench.now += 10 * MS;
                bench.rx(&word(Reply::Velocity {
                    motor,
                    velocity: 7,
                    action: Action::Rotation,
                }));
            }
            Request::SetBaud { .. } => {
                configured_at = Some(at);
                break;
            }
            _ => {}
        }
    }
    let waited = configured_at.expect("configured in the end") - started;
    // The bound: a stop from velocity 511 at amax 319 (511 · 64 / 319 + 2 ticks of 2 ms
    // = 209 ms), the two words, and 250 ms of margin.
    assert!(waited >= Duration::from_millis(459), "{waited:?}");
    assert!(waited < Duration::from_millis(600), "{waited:?}");
}

/// Manual 8.4 $22: "If the switch cannot be found again at slow speed where it had been
/// found before, or if no switch is seen during 125% of the drive limit-range, the whole
/// procedure repeats by first stopping again": the action code goes back.
#[test]
fn a_reference_search_that_starts_over_is_home_failed_and_stopped() {
    let mut bench = Bench::new(config());
    bench.online();
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Home { velocity: 6425.0 })
        .expect("home");
    let mut phase = [1u8, 3, 3, 0, 1].into_iter().cycle();
    let mut failed_at = None;
    let mut sent = Vec::new();
    for _ in 0..400 {
        let Some(w) = bench.tick() else { continue };
        let request = RequestFrame::decode(&w).expect("decodes").request;
        if let Request::QueryPosition { motor, .. } = request {
            bench.now += 10 * MS;
            let p = if motor == 0 {
                phase.next().unwrap_or(1)
            } else {
                0
            };
            bench.rx(&position(motor, 100, Action::ReferenceSearch(p)));
            if bench.driver.channel(0).fault == Some(DeviceFault::HomeFailed) {
                failed_at.get_or_insert(sent.len());
            }
        }
        sent.push(request);
    }
    let failed_at = failed_at.expect("HomeFailed reported");
    assert!(!bench.driver.channel(0).homed);
    assert!(
        sent[failed_at..].contains(&rotate(0, 0)),
        "the driver stops the search: {sent:?}"
    );
}

#[test]
fn a_stop_condition_during_the_search_is_home_failed() {
    let mut bench = Bench::new(config());
    bench.online();
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Home { velocity: 6425.0 })
        .expect("home");
    bench.serve(40, |m| position(m, 50, Action::ReferenceSearch(1)));
    // $20 P6 bit 0: "Stop-condition has occurred".
    bench.serve(20, |m| {
        word(Reply::Position {
            motor: m,
            position: 60,
            action: Action::ReferenceSearch(2),
            stopped: true,
        })
    });
    let state = bench.driver.channel(0);
    assert_eq!(state.fault, Some(DeviceFault::HomeFailed));
    assert!(!state.homed);
}

#[test]
fn a_search_that_ends_away_from_the_zero_point_is_home_failed() {
    let mut bench = Bench::new(config());
    bench.online();
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Home { velocity: 6425.0 })
        .expect("home");
    bench.serve(40, |m| position(m, 50, Action::ReferenceSearch(1)));
    bench.serve(20, |m| position(m, 777, Action::Inactive));
    assert_eq!(bench.driver.channel(0).fault, Some(DeviceFault::HomeFailed));
    assert!(!bench.driver.channel(0).homed);
}

#[test]
fn stopping_a_search_neither_homes_nor_fails_the_axis() {
    let mut bench = Bench::new(config());
    bench.online();
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Home { velocity: 6425.0 })
        .expect("home");
    bench.serve(40, |m| position(m, 50, Action::ReferenceSearch(1)));
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Stop { decel: 160_000.0 })
        .expect("stop");
    bench.serve(200, |m| position(m, 300, Action::Inactive));
    let state = bench.driver.channel(0);
    assert!(!state.homed);
    assert_eq!(state.fault, None);
}

#[test]
fn the_home_position_is_set_with_27_after_the_search() {
    let mut cfg = config();
    if let Some(c) = cfg.channels[0].as_mut() {
        c.home_position = -1600;
    }
    let mut bench = Bench::new(cfg);
    bench.online();
    bench
        .driver
        .set_goal(bench.now, 0, Goal::Home { velocity: 6425.0 })
        .expect("home");
    let sent = bench.serve(80, |m| position(m, 50, Action::ReferenceSearch(1)));
    assert!(sent.contains(&Request::ReferenceSearch { motor: 0 }));
    // The search ends inactive at the new zero point; the $27 follows.
    let sent = bench.serve(40, |m| position(m, 0, Action::Inactive));
    assert!(
        sent.contains(&Request::SetPosition {
            motor: 0,
            position: -1600
        }),
        "{sent:?}"
    );
    bench.serve(40, |m| position(m, -1600, Action::Inactive));
    assert!(bench.driver.channel(0).homed);
    assert_eq!(bench.driver.channel(0).position, -1600.0);
}

#[test]
fn a_rotary_axis_measures_velocity_across_the_wrap_of_its_position() {
    let mut cfg = config();
    if let Some(c) = cfg.channels[0].as_mut() {
        c.motor_type = c.motor_type | MotorType::ROTARY;
        c.poslimit = 3200;
    }
    let mut bench = Bench::new(cfg);
    bench.online();
    let mut at = 3000;
    bench.serve(100, |m| {
        at = (at + 150) % 3200;
        position(m, at, Action::Rotation)
    });
    assert!(bench.driver.channel(0).velocity > 0.0);
}

#[test]
fn the_start_up_writes_analogue_stops_and_never_lets_the_pack_search_on_its_own() {
    let mut cfg = config();
    if let Some(c) = cfg.channels[0].as_mut() {
        c.analog_stop = (100, 900);
        c.options = c.options | MotorOptions::STOP_SOFT;
        c.motor_type = c.motor_type | MotorType::STOP_NULL | MotorType::PI_MODE;
    }
    let mut bench = Bench::new(cfg);
    let sent = bench.online();
    // Manual 8.5 $31: P0 channel, P1,2 minimum for stop left, P3,4 maximum for stop right.
    let w31 = RequestFrame::new(
        1,
        Request::StopLimits {
            channel: 0,
            left_min: 100,
            right_max: 900,
        },
    )
    .to_word()
    .expect("valid");
    assert_eq!(w31, [0x01, 0x31, 0, 100, 0, 0x84, 0x03, 0, 0]);
    assert!(sent.contains(&Request::StopLimits {
        channel: 0,
        left_min: 100,
        right_max: 900
    }));
    assert!(sent.contains(&Request::StopLimits {
        channel: 2,
        left_min: 0,
        right_max: 1023
    }));
    let (motor_type, options) = sent
        .iter()
        .find_map(|r| match r {
            Request::MotorParameters {
                motor: 0,
                motor_type,
                options,
                ..
            } => Some((*motor_type, *options)),
            _ => None,
        })
        .expect("$15");
    assert!(motor_type.contains(MotorType::STOP_NULL));
    assert!(!motor_type.contains(MotorType::PI_MODE));
    assert!(options.contains(MotorOptions::STOP_NO_REF));
    assert!(options.contains(MotorOptions::STOP_SOFT));
}
