//! Unit tests of lines the pack runs itself: `$26` + `$50` (manual 8.7 "Start
//! multi-dimensional linear Interpolation").

use tmcpack::{Action, MotorMask, Request, StepClock};

use super::bench::*;
use super::*;
use motion_drivers::{LINE_RATE_TOLERANCE, LineLeg};

fn leg(channel: usize, counts: f64, velocity: f64, accel: f64) -> LineLeg {
    LineLeg {
        channel,
        counts,
        velocity,
        accel,
        rate_tolerance: LINE_RATE_TOLERANCE,
    }
}

/// Velocity units per count/s of motor `motor`.
fn hz_per_unit(bench: &Bench, motor: usize) -> f64 {
    let (clkdiv, div, _, _) = bench.driver.board_settings()[motor].expect("configured");
    StepClock::new(clkdiv, div).expect("clock").hz_per_unit()
}

/// The requests the driver sends before its next poll, skipping polls.
fn commands(bench: &mut Bench, limit: u32) -> Vec<Request> {
    bench
        .serve(limit, |motor| position(motor, 0, Action::Inactive))
        .into_iter()
        .filter(|r| {
            !matches!(
                r,
                Request::QueryPosition { .. }
                    | Request::ReadInput { .. }
                    | Request::UnitInfo { .. }
            )
        })
        .collect()
}

/// Manual 8.7: "The target position has to be set for each motor (with command $26)
/// before" `$50`, "The motors have to stand still before execution", "All motors reach the
/// target position at the same time".
#[test]
fn a_line_of_two_motors_at_rest_is_their_targets_then_one_interpolation() {
    let mut bench = Bench::new(config());
    bench.online();
    bench.serve(40, |motor| position(motor, 0, Action::Inactive));
    let slow = hz_per_unit(&bench, 2);
    // Motor 0 is the faster leg in the pack's velocity units (100, against about 80 of
    // motor 2, whose clock is divided further).
    let legs = [
        leg(0, 10_000.0, 6425.0, 160_000.0),
        leg(2, 2_000.0, 642.5, 32_000.0),
    ];
    assert!(6425.0 / hz_per_unit(&bench, 0) > 642.5 / slow);
    assert_eq!(bench.driver.lead_line(bench.now, &legs), Ok(true));
    assert!(bench.driver.goals_pending());
    assert!(!bench.driver.line_ready());
    let mut sent = commands(&mut bench, 60);
    // Prepared: the interpolation waits for the engine to start it (with the group's
    // boards on other links).
    assert!(bench.driver.line_ready());
    assert!(
        !sent
            .iter()
            .any(|r| matches!(r, Request::Interpolate { .. }))
    );
    bench.driver.start_line(bench.now);
    assert!(!bench.driver.line_ready());
    sent.extend(commands(&mut bench, 20));
    let slave_vmax = ((642.5 / slow).ceil() + 1.0) as u16;
    let position_of = |motor: u8| {
        sent.iter()
            .position(|r| matches!(r, Request::SetTarget { motor: m, .. } if *m == motor))
            .expect("$26 of each leg")
    };
    let interpolate = sent
        .iter()
        .position(|r| matches!(r, Request::Interpolate { .. }))
        .expect("$50");
    assert!(position_of(0) < interpolate && position_of(2) < interpolate);
    assert!(sent.contains(&Request::SetTarget {
        motor: 0,
        target: 10_000
    }));
    assert!(sent.contains(&Request::SetTarget {
        motor: 2,
        target: 2_000
    }));
    assert_eq!(
        sent[interpolate],
        Request::Interpolate {
            mask: MotorMask::from_bits_retain(0b101)
        }
    );
    // The master runs the leg's own velocity; the other leg is given a vmax above its share
    // so that it cannot be taken for the master.
    assert!(sent.iter().any(|r| matches!(
        r,
        Request::VelocityAcceleration {
            motor: 0,
            vmax: 100,
            ..
        }
    )));
    assert!(sent.iter().any(|r| matches!(
        r,
        Request::VelocityAcceleration { motor: 2, vmax, .. } if *vmax == slave_vmax
    )));
    // No `$23`: the interpolation starts them.
    assert!(!sent.iter().any(|r| matches!(r, Request::StartRamp { .. })));
    assert!(!bench.driver.goals_pending());
    // Arrival: polls after the `$50` show each motor at its target, inactive.
    bench.serve(60, |motor| {
        position(
            motor,
            if motor == 0 { 10_000 } else { 2_000 },
            Action::Inactive,
        )
    });
    assert!(bench.driver.channel(0).arrived);
    assert!(bench.driver.channel(2).arrived);
}

/// "The motors have to stand still before execution": a motor that runs is not part of a
/// pack line; the engine follows the line itself.
#[test]
fn a_line_is_not_taken_while_a_motor_runs() {
    let mut bench = Bench::new(config());
    bench.online();
    bench.serve(40, |motor| position(motor, 0, Action::Inactive));
    bench
        .driver
        .set_goal(
            bench.now,
            2,
            Goal::Velocity {
                velocity: 800.0,
                accel: 6400.0,
            },
        )
        .expect("jog");
    bench.serve(40, |motor| position(motor, 50, Action::Rotation));
    let legs = [
        leg(0, 10_000.0, 6425.0, 160_000.0),
        leg(2, 2_000.0, 642.5, 6_400.0),
    ];
    assert_eq!(bench.driver.lead_line(bench.now, &legs), Ok(false));
    let sent = commands(&mut bench, 40);
    assert!(
        !sent
            .iter()
            .any(|r| matches!(r, Request::Interpolate { .. }))
    );
}

/// A stop of a leg before the `$50` went out cancels the line.
#[test]
fn a_stop_before_the_interpolation_went_out_cancels_it() {
    let mut bench = Bench::new(config());
    bench.online();
    bench.serve(40, |motor| position(motor, 0, Action::Inactive));
    let legs = [
        leg(0, 10_000.0, 6425.0, 160_000.0),
        leg(2, 2_000.0, 642.5, 6_400.0),
    ];
    assert_eq!(bench.driver.lead_line(bench.now, &legs), Ok(true));
    bench
        .driver
        .set_goal(bench.now, 2, Goal::Stop { decel: 6400.0 })
        .expect("stop");
    bench.driver.start_line(bench.now);
    let sent = commands(&mut bench, 80);
    assert!(
        !sent
            .iter()
            .any(|r| matches!(r, Request::Interpolate { .. }))
    );
    assert!(sent.contains(&Request::Rotate {
        motor: 2,
        velocity: 0
    }));
}

/// One leg is a plain ramp (manual 8.4: `$26`, then, at the start, `$23` with the same
/// target).
#[test]
fn a_line_of_one_motor_is_a_ramp() {
    let mut bench = Bench::new(config());
    bench.online();
    bench.serve(40, |motor| position(motor, 0, Action::Inactive));
    assert_eq!(
        bench
            .driver
            .lead_line(bench.now, &[leg(0, 10_000.0, 6425.0, 160_000.0)]),
        Ok(true)
    );
    let mut sent = commands(&mut bench, 40);
    assert!(sent.contains(&Request::SetTarget {
        motor: 0,
        target: 10_000
    }));
    assert!(!sent.iter().any(|r| matches!(r, Request::StartRamp { .. })));
    bench.driver.start_line(bench.now);
    sent.extend(commands(&mut bench, 20));
    assert!(sent.contains(&Request::StartRamp {
        motor: 0,
        target: 10_000
    }));
    assert!(
        !sent
            .iter()
            .any(|r| matches!(r, Request::Interpolate { .. }))
    );
}

/// Legs the pack cannot run are refused whole, before any script changes.
#[test]
fn unusable_legs_are_refused_whole() {
    let mut bench = Bench::new(config());
    bench.online();
    bench.serve(40, |motor| position(motor, 0, Action::Inactive));
    let nan = [
        leg(0, 10_000.0, 6425.0, 160_000.0),
        leg(2, 2_000.0, f64::NAN, 32_000.0),
    ];
    assert!(bench.driver.lead_line(bench.now, &nan).is_err());
    let twice = [
        leg(0, 10_000.0, 6425.0, 160_000.0),
        leg(0, 2_000.0, 1285.0, 32_000.0),
    ];
    assert!(bench.driver.lead_line(bench.now, &twice).is_err());
    let missing = [
        leg(0, 10_000.0, 6425.0, 160_000.0),
        leg(1, 2_000.0, 1285.0, 32_000.0),
    ];
    assert!(bench.driver.lead_line(bench.now, &missing).is_err());
    let beyond = [
        leg(0, 1e12, 6425.0, 160_000.0),
        leg(2, 2_000.0, 642.5, 6_400.0),
    ];
    assert!(bench.driver.lead_line(bench.now, &beyond).is_err());
    assert!(!bench.driver.goals_pending());
}

/// One line at a time: a second one while the first is prepared is followed by the engine.
#[test]
fn a_second_line_while_one_is_prepared_is_not_taken() {
    let mut bench = Bench::new(config());
    bench.online();
    bench.serve(40, |motor| position(motor, 0, Action::Inactive));
    assert_eq!(
        bench
            .driver
            .lead_line(bench.now, &[leg(0, 10_000.0, 6425.0, 160_000.0)]),
        Ok(true)
    );
    assert_eq!(
        bench
            .driver
            .lead_line(bench.now, &[leg(2, 2_000.0, 642.5, 32_000.0)]),
        Ok(false)
    );
}

/// A line whose pace the pack's units cannot represent within 2 % (here 1.4 velocity units,
/// which would run as 1: 30 % slow) is left to the engine, which follows it by segments.
#[test]
fn a_line_too_slow_for_the_packs_units_is_not_taken() {
    let mut bench = Bench::new(config());
    bench.online();
    bench.serve(40, |motor| position(motor, 0, Action::Inactive));
    let slow = 1.4 * hz_per_unit(&bench, 0);
    assert_eq!(
        bench
            .driver
            .lead_line(bench.now, &[leg(0, 500.0, slow, 160_000.0)]),
        Ok(false)
    );
    assert!(!bench.driver.goals_pending());
}
