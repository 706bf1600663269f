//! Unit tests of the drive functions beyond the ramp on the fake clock: the `$24` PI
//! controller in the PI position mode with its `$19` parameters, the `$13` starting velocity
//! and the `$17` motor characteristics table (manual 8.3, 8.4).

use tmcpack::{Action, Request, RequestFrame};

use super::bench::*;
use super::*;
use crate::PositionMode;
use motion_drivers::Follow;

/// Motor 0 in the PI position mode; motor 2 on ramps.
fn pi_config() -> TmcpackDriverConfig {
    let mut config = config();
    if let Some(Some(c)) = config.channels.get_mut(0) {
        c.position_mode = PositionMode::Pi;
    }
    config
}

fn online(config: TmcpackDriverConfig) -> (Bench, Vec<Request>) {
    let mut bench = Bench::new(config);
    let sent = bench.online();
    bench.serve(40, |m| position(m, 0, Action::Inactive));
    (bench, sent)
}

/// Motor 0 in the PI controller at `p`, the others idle at 0.
fn pi_or_idle(motor: u8, p: i32) -> [u8; 9] {
    if motor == 0 {
        position(0, p, Action::PiController)
    } else {
        position(motor, 0, Action::Inactive)
    }
}

fn goal(bench: &mut Bench, channel: usize, goal: Goal) {
    bench
        .driver
        .set_goal(bench.now, channel, goal)
        .expect("goal taken");
}

/// The next command (anything but a poll), answering the polls before it with `answer`.
fn command(bench: &mut Bench, mut answer: impl FnMut(u8) -> [u8; 9]) -> Request {
    for _ in 0..200 {
        let Some(w) = bench.tick() else { continue };
        match RequestFrame::decode(&w).expect("decodes").request {
            Request::QueryPosition { motor, .. } => {
                bench.now += 10 * MS;
                let reply = answer(motor);
                bench.rx(&reply);
            }
            Request::UnitInfo { .. } => {
                bench.now += 10 * MS;
                let mut info = UNIT_INFO;
                info[3] = 0;
                bench.rx(&info);
            }
            other => return other,
        }
    }
    panic!("no command");
}

/// "propdiv=8; intdiv=129; intclip=129; intinpclip=1" (7.1) go out as `$19` for the motor
/// in the PI mode; the motor on ramps gets none (the pack keeps its own).
#[test]
fn the_pi_mode_writes_19_at_start_up() {
    let (_, sent) = online(pi_config());
    assert!(sent.contains(&Request::PiParameters {
        motor: 0,
        propdiv: 8,
        intdiv: 129,
        intclip: 129,
        intinpclip: 1,
    }));
    assert!(
        !sent
            .iter()
            .any(|r| matches!(r, Request::PiParameters { motor: 2, .. }))
    );
    // Configured parameters are written as given.
    let mut given = pi_config();
    if let Some(Some(c)) = given.channels.get_mut(0) {
        c.pi = Some(PiParams {
            propdiv: 20,
            intdiv: 500,
            intclip: 40,
            intinpclip: 0,
        });
    }
    let (_, sent) = online(given);
    assert!(sent.contains(&Request::PiParameters {
        motor: 0,
        propdiv: 20,
        intdiv: 500,
        intclip: 40,
        intinpclip: 0,
    }));
    // Without the PI mode or keys: no $19 (today's start-up).
    let (_, sent) = online(config());
    assert!(
        !sent
            .iter()
            .any(|r| matches!(r, Request::PiParameters { .. }))
    );
}

/// 8.4 `$24`: "Switching to PI-controller happens immediately, even if the motor is
/// inactive. When the PI-controller was already active the target position will be
/// reprogrammed immediately." A Position goal is one `$24`; a new target while it runs is
/// one more, without a stop; a `$24` waits for a poll after the last one.
#[test]
fn a_position_goal_is_a_pi_target_reprogrammed_on_the_fly() {
    let (mut bench, _) = online(pi_config());
    goal(&mut bench, 0, Goal::Position { counts: 5000.0 });
    assert_eq!(
        command(&mut bench, |m| position(m, 0, Action::Inactive)),
        Request::PiTarget {
            motor: 0,
            target: 5000
        }
    );
    // On its way: a new target right away waits for one poll, then goes alone.
    goal(&mut bench, 0, Goal::Position { counts: 7000.0 });
    let (_, w) = bench.next(50).expect("next message");
    assert!(
        matches!(
            RequestFrame::decode(&w).expect("decodes").request,
            Request::QueryPosition { .. } | Request::ReadInput { .. }
        ),
        "a poll between two $24"
    );
    bench.now += 10 * MS;
    bench.rx(&pi_or_idle(w[2], 1500));
    assert_eq!(
        command(&mut bench, |m| pi_or_idle(m, 2500)),
        Request::PiTarget {
            motor: 0,
            target: 7000
        }
    );
    // Targets streamed faster than the line: only the newest goes.
    for target in [7100.0, 7200.0, 7300.0] {
        goal(&mut bench, 0, Goal::Position { counts: target });
    }
    assert_eq!(
        command(&mut bench, |m| pi_or_idle(m, 4000)),
        Request::PiTarget {
            motor: 0,
            target: 7300
        }
    );
    // Motor 2 keeps the ramp.
    goal(&mut bench, 2, Goal::Position { counts: 300.0 });
    let mut sent = Vec::new();
    for _ in 0..2 {
        sent.push(command(&mut bench, |m| pi_or_idle(m, 7300)));
    }
    assert!(sent.contains(&Request::StartRamp {
        motor: 2,
        target: 300
    }));
}

/// The PI controller holds its target with action 10 ("PI-controller"): two polls at the
/// target are rest and arrival; before that the axis is moving.
#[test]
fn the_pi_controller_holding_its_target_is_at_rest_and_arrived() {
    let (mut bench, _) = online(pi_config());
    goal(&mut bench, 0, Goal::Position { counts: 800.0 });
    command(&mut bench, |m| position(m, 0, Action::Inactive));
    let mut seen = Vec::new();
    let mut p = 0;
    bench.serve(200, |m| {
        if m == 0 {
            p = (p + 200).min(800);
            position(0, p, Action::PiController)
        } else {
            position(m, 0, Action::Inactive)
        }
    });
    let state = bench.driver.channel(0);
    seen.push((state.moving, state.arrived));
    assert_eq!(state.position, 800.0);
    assert!(!state.moving && state.arrived, "{state:?}");
    // Pushed off its target (the PI controller works back): moving, not arrived.
    let mut q = 780;
    bench.serve(60, |m| {
        q += 5;
        position(m, if m == 0 { q } else { 0 }, Action::PiController)
    });
    let state = bench.driver.channel(0);
    assert!(state.moving && !state.arrived, "{state:?}");
}

/// A motor that rotates is stopped before the PI controller takes it (the manual does not
/// say how it takes over a moving motor): `$25` 0, rest, `$23`, then `$24`.
#[test]
fn a_rotating_motor_is_stopped_before_the_pi_controller_takes_it() {
    let (mut bench, _) = online(pi_config());
    goal(
        &mut bench,
        0,
        Goal::Velocity {
            velocity: 3000.0,
            accel: 160_000.0,
        },
    );
    let rotate = command(&mut bench, |m| position(m, 0, Action::Inactive));
    assert!(matches!(rotate, Request::Rotate { motor: 0, velocity } if velocity > 0));
    goal(&mut bench, 0, Goal::Position { counts: 100.0 });
    let mut sent = Vec::new();
    for _ in 0..8 {
        let request = command(&mut bench, |m| position(m, 500, Action::Rotation));
        sent.push(request);
        if matches!(request, Request::PiTarget { .. }) {
            break;
        }
    }
    let stop = sent.iter().position(|r| {
        *r == Request::Rotate {
            motor: 0,
            velocity: 0,
        }
    });
    let pi = sent
        .iter()
        .position(|r| matches!(r, Request::PiTarget { target: 100, .. }));
    assert!(
        matches!((stop, pi), (Some(s), Some(p)) if s < p),
        "{sent:?}"
    );
}

/// A SetPosition while the PI controller holds the motor would make it drive to its old
/// target in the new coordinates: it is stopped (and left) first.
#[test]
fn set_position_leaves_the_pi_controller_first() {
    let (mut bench, _) = online(pi_config());
    goal(&mut bench, 0, Goal::Position { counts: 800.0 });
    command(&mut bench, |m| position(m, 0, Action::Inactive));
    bench.serve(100, |m| position(m, 800, Action::PiController));
    goal(&mut bench, 0, Goal::SetPosition { counts: 0.0 });
    let mut sent = Vec::new();
    for _ in 0..5 {
        let request = command(&mut bench, |m| position(m, 800, Action::Rotation));
        sent.push(request);
        if matches!(request, Request::SetPosition { .. }) {
            break;
        }
    }
    assert_eq!(
        sent[0],
        Request::Rotate {
            motor: 0,
            velocity: 0
        }
    );
    assert_eq!(
        sent.last(),
        Some(&Request::SetPosition {
            motor: 0,
            position: 0
        })
    );
    assert!(sent.contains(&Request::StartRamp {
        motor: 0,
        target: 800
    }));
}

/// The engine follows a path on a PI motor with a target per change (`Follow::Setpoints`),
/// on a ramp motor with segments.
#[test]
fn a_pi_motor_follows_paths_with_setpoints() {
    let bench = Bench::new(pi_config());
    assert_eq!(bench.driver.follow(0), Follow::Setpoints);
    assert_eq!(bench.driver.follow(2), Follow::Segments);
}

/// 8.3 `$13` "vstart (1..511): starting and ending velocity for acceleration ramp": the
/// `start_velocity` rounded down to the motor's units; never below one tick's change at
/// the axis's amax ("0 < amax <= vstart * 64").
#[test]
fn start_velocity_sets_vstart_and_never_below_the_amax_relation() {
    // Motor 0: 64.25 µsteps/s per unit (clkdiv 18, div 0); 160000 µsteps/s² needs 5.
    let mut fast = config();
    if let Some(Some(c)) = fast.channels.get_mut(0) {
        c.start_velocity = Some(3000.0);
    }
    let (bench, sent) = online(fast);
    assert!(sent.contains(&Request::StartingVelocity {
        motor: 0,
        vmin: 0,
        vstart: 46, // 3000 / 64.25 = 46.7
        div: 0
    }));
    // The amax the axis limit gives is unchanged; a home at 40 units is now refused
    // ($16: vrefmax >= vstart).
    assert_eq!(bench.driver.board_settings()[0], Some((18, 0, 498, 318)));
    let mut bench = bench;
    assert_eq!(
        bench.driver.set_goal(
            bench.now,
            0,
            Goal::Home {
                velocity: 40.0 * 64.25
            }
        ),
        Err(GoalError::OutOfBoardRange(motion_drivers::GoalKind::Home))
    );
    // Below the relation's minimum: the minimum.
    let mut low = config();
    if let Some(Some(c)) = low.channels.get_mut(0) {
        c.start_velocity = Some(10.0);
    }
    let (_, sent) = online(low);
    assert!(sent.contains(&Request::StartingVelocity {
        motor: 0,
        vmin: 0,
        vstart: 5,
        div: 0
    }));
}

/// 8.3 `$17`: the configured table goes out as four requests (pointers 0, 4, 8, 12) with
/// the configuration, before the motors' parameters; none without the key.
#[test]
fn the_microstep_table_goes_out_at_start_up() {
    let mut table = tmcpack::table::SINE_TABLE;
    table[15] = 250;
    let with_table = TmcpackDriverConfig {
        microstep_table: Some(table),
        ..config()
    };
    let (_, sent) = online(with_table);
    let written: Vec<Request> = sent
        .iter()
        .copied()
        .filter(|r| matches!(r, Request::MicrostepTable { .. }))
        .collect();
    assert_eq!(written, tmcpack::table::table_requests(&table));
    let first = sent
        .iter()
        .position(|r| matches!(r, Request::MicrostepTable { .. }));
    let motors = sent
        .iter()
        .position(|r| matches!(r, Request::CurrentControl { .. }));
    assert!(first < motors);
    let (_, plain) = online(config());
    assert!(
        !plain
            .iter()
            .any(|r| matches!(r, Request::MicrostepTable { .. }))
    );
}
