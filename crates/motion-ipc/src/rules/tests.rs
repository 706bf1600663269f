//! The rulebook's verdicts, rule by rule, and the order in which the rules apply.

use super::*;

const ME: ClientId = ClientId::from_u128(7);
const OTHER: ClientId = ClientId::from_u128(9);

#[derive(Clone)]
struct World {
    estop: bool,
    shutting_down: bool,
    axes: Vec<AxisFacts>,
    signals: Vec<SignalFacts>,
}

impl Facts for World {
    fn estop(&self) -> bool {
        self.estop
    }
    fn shutting_down(&self) -> bool {
        self.shutting_down
    }
    fn axis(&self, index: usize) -> Option<AxisFacts> {
        self.axes.get(index).copied()
    }
    fn signal(&self, index: usize) -> Option<SignalFacts> {
        self.signals.get(index).copied()
    }
}

fn world() -> World {
    World {
        estop: false,
        shutting_down: false,
        axes: vec![AxisFacts::test_axis(-100.0, 100.0, 50.0, 500.0)],
        signals: vec![
            SignalFacts {
                kind: SignalKind::DigitalOut,
                claimed_by: ClientId::NONE,
                device: DeviceState::Online,
                link_up: true,
            },
            SignalFacts {
                kind: SignalKind::DigitalIn,
                claimed_by: ClientId::NONE,
                device: DeviceState::Online,
                link_up: true,
            },
        ],
    }
}

fn request(kind: CommandKind, values: [f64; 3]) -> CommandRequest {
    CommandRequest::new(ME, 1, 0, kind).with_values(values)
}

fn verdict(world: &World, kind: CommandKind, values: [f64; 3]) -> Verdict {
    judge(&request(kind, values), ME, world)
}

fn refused(world: &World, kind: CommandKind, values: [f64; 3]) -> Reason {
    match verdict(world, kind, values) {
        Verdict::Refused(reason) => reason,
        other => panic!("{kind:?} {values:?} accepted: {other:?}"),
    }
}

#[test]
fn identity_comes_from_the_transport() {
    let forged = CommandRequest::new(OTHER, 1, 0, CommandKind::Stop);
    assert_eq!(identify(&forged, Some(ME)), Err(Reason::IdentityMismatch));
    let blank = CommandRequest::new(ClientId::NONE, 1, 0, CommandKind::Stop);
    assert_eq!(identify(&blank, Some(ME)), Ok(ME));
    assert_eq!(
        identify(&forged, None),
        Ok(OTHER),
        "in-process: the payload"
    );
    let mut old = request(CommandKind::Stop, [0.0; 3]);
    old.schema_version = SCHEMA_VERSION + 1;
    assert_eq!(identify(&old, Some(ME)), Err(Reason::SchemaMismatch));
    let mut unknown = request(CommandKind::Stop, [0.0; 3]);
    unknown.kind = 200;
    assert_eq!(identify(&unknown, Some(ME)), Err(Reason::UnknownKind));
    let nan = request(CommandKind::Position, [f64::NAN, 0.0, 0.0]);
    assert_eq!(identify(&nan, Some(ME)), Err(Reason::NotFinite));
    // Schema before identity: an old client is told so, not that it lies.
    let mut both = forged;
    both.schema_version = 1;
    assert_eq!(identify(&both, Some(ME)), Err(Reason::SchemaMismatch));
}

#[test]
fn position_goals_stay_within_the_soft_limits() {
    let w = world();
    assert_eq!(
        refused(&w, CommandKind::Position, [100.5, 0.0, 0.0]),
        Reason::OutOfRange
    );
    assert_eq!(
        verdict(&w, CommandKind::Position, [100.0, 0.0, 0.0]),
        Verdict::Move {
            axis: 0,
            motion: Motion::Position { target: 100.0 }
        }
    );
    assert_eq!(
        refused(&w, CommandKind::SetPosition, [-101.0, 0.0, 0.0]),
        Reason::OutOfRange
    );
    assert_eq!(
        refused(&w, CommandKind::RampPosition, [101.0, 10.0, 10.0]),
        Reason::OutOfRange
    );
}

#[test]
fn ramps_refuse_negative_or_excessive_rates_and_take_zero_as_the_maximum() {
    let w = world();
    assert_eq!(
        refused(&w, CommandKind::RampVelocity, [10.0, -1.0, 0.0]),
        Reason::AccelLimit,
        "a negative acceleration"
    );
    assert_eq!(
        refused(&w, CommandKind::RampVelocity, [10.0, 501.0, 0.0]),
        Reason::AccelLimit
    );
    assert_eq!(
        refused(&w, CommandKind::RampVelocity, [51.0, 0.0, 0.0]),
        Reason::VelocityLimit
    );
    assert_eq!(
        refused(&w, CommandKind::RampPosition, [10.0, -5.0, 0.0]),
        Reason::VelocityLimit
    );
    assert_eq!(
        refused(&w, CommandKind::RampPosition, [10.0, 0.0, -5.0]),
        Reason::AccelLimit
    );
    assert_eq!(
        verdict(&w, CommandKind::RampPosition, [10.0, 0.0, 0.0]),
        Verdict::Move {
            axis: 0,
            motion: Motion::RampPosition {
                target: 10.0,
                velocity: 50.0,
                accel: 500.0
            }
        }
    );
    assert_eq!(
        verdict(&w, CommandKind::Home, [0.0; 3]),
        Verdict::Move {
            axis: 0,
            motion: Motion::Home {
                velocity: 50.0 * HOME_FRACTION_OF_MAX
            }
        }
    );
    assert_eq!(
        refused(&w, CommandKind::Home, [-1.0, 0.0, 0.0]),
        Reason::VelocityLimit
    );
    assert_eq!(
        refused(&w, CommandKind::Power, [1.5, 0.0, 0.0]),
        Reason::PowerLimit
    );
}

#[test]
fn a_velocity_that_cannot_stop_before_a_limit_is_refused() {
    let mut w = world();
    w.axes[0].position = 99.0;
    // 50 mm/s at 500 mm/s² needs 2.5 mm: from 99 it would pass 100.
    assert_eq!(
        refused(&w, CommandKind::Velocity, [50.0, 0.0, 0.0]),
        Reason::OutOfRange
    );
    assert!(matches!(
        verdict(&w, CommandKind::Velocity, [-50.0, 0.0, 0.0]),
        Verdict::Move { .. }
    ));
    // Power has no speed to stop from: only its sign and the position tolerance count.
    assert!(matches!(
        verdict(&w, CommandKind::Power, [0.5, 0.0, 0.0]),
        Verdict::Move { .. }
    ));
    w.axes[0].position = 99.995;
    assert_eq!(
        refused(&w, CommandKind::Power, [0.5, 0.0, 0.0]),
        Reason::OutOfRange
    );
    // A stale position cannot tell: the board's own limits must do.
    w.axes[0].position_fresh = false;
    assert!(matches!(
        verdict(&w, CommandKind::Velocity, [50.0, 0.0, 0.0]),
        Verdict::Move { .. }
    ));
}

#[test]
fn claims_bind_to_their_client() {
    let mut w = world();
    assert_eq!(
        verdict(&w, CommandKind::Claim, [0.0; 3]),
        Verdict::ClaimAxis(0)
    );
    assert_eq!(
        refused(&w, CommandKind::Release, [0.0; 3]),
        Reason::NotClaimed
    );
    w.axes[0].claimed_by = OTHER;
    assert_eq!(
        refused(&w, CommandKind::Claim, [0.0; 3]),
        Reason::ClaimedByOther
    );
    assert_eq!(
        refused(&w, CommandKind::Position, [1.0, 0.0, 0.0]),
        Reason::ClaimedByOther
    );
    assert_eq!(
        refused(&w, CommandKind::Off, [0.0; 3]),
        Reason::ClaimedByOther
    );
    assert_eq!(
        verdict(&w, CommandKind::Stop, [0.0; 3]),
        Verdict::StopAxis(0),
        "anyone may stop"
    );
    let anonymous = CommandRequest::new(ClientId::NONE, 1, 0, CommandKind::Claim);
    assert_eq!(
        judge(&anonymous, ClientId::NONE, &w),
        Verdict::Refused(Reason::NoClientId)
    );
}

#[test]
fn estop_shutdown_and_faults_refuse_motion_but_never_a_stop() {
    let mut w = world();
    w.estop = true;
    assert_eq!(
        refused(&w, CommandKind::Position, [1.0, 0.0, 0.0]),
        Reason::EstopLatched
    );
    assert_eq!(
        verdict(&w, CommandKind::Stop, [0.0; 3]),
        Verdict::StopAxis(0)
    );
    assert_eq!(verdict(&w, CommandKind::Reset, [0.0; 3]), Verdict::Reset);
    w.shutting_down = true;
    assert_eq!(
        refused(&w, CommandKind::Position, [1.0, 0.0, 0.0]),
        Reason::ShuttingDown,
        "shutdown before e-stop"
    );
    assert_eq!(
        refused(&w, CommandKind::Reset, [0.0; 3]),
        Reason::ShuttingDown
    );
    let mut w = world();
    w.axes[0].fault = FaultCode::FollowingError;
    assert_eq!(
        refused(&w, CommandKind::Position, [1.0, 0.0, 0.0]),
        Reason::AxisFaulted
    );
    w.axes[0].fault = FaultCode::LinkDown;
    assert_eq!(
        refused(&w, CommandKind::Position, [1.0, 0.0, 0.0]),
        Reason::LinkDown
    );
}

#[test]
fn beyond_a_limit_only_a_way_back_is_accepted() {
    let mut w = world();
    w.axes[0].fault = FaultCode::LimitExceeded;
    w.axes[0].position = 103.0;
    assert!(matches!(
        verdict(&w, CommandKind::Position, [50.0, 0.0, 0.0]),
        Verdict::Move { .. }
    ));
    assert!(matches!(
        verdict(&w, CommandKind::Velocity, [-10.0, 0.0, 0.0]),
        Verdict::Move { .. }
    ));
    assert_eq!(
        refused(&w, CommandKind::Velocity, [10.0, 0.0, 0.0]),
        Reason::OutOfRange,
        "further out cannot stop before the limit it is already past"
    );
    assert_eq!(
        refused(&w, CommandKind::Home, [0.0; 3]),
        Reason::AxisFaulted
    );
}

#[test]
fn readiness_of_the_device_comes_before_the_goal() {
    let mut w = world();
    w.axes[0].device = DeviceState::Starting;
    assert_eq!(
        refused(&w, CommandKind::Position, [1000.0, 0.0, 0.0]),
        Reason::DeviceStarting
    );
    w.axes[0].device = DeviceState::Offline;
    assert_eq!(
        refused(&w, CommandKind::Position, [1.0, 0.0, 0.0]),
        Reason::DeviceOffline
    );
    w.axes[0].link_up = false;
    assert_eq!(
        refused(&w, CommandKind::Position, [1.0, 0.0, 0.0]),
        Reason::LinkDown
    );
}

#[test]
fn unsupported_kinds_and_unknown_targets() {
    let mut w = world();
    w.axes[0].capabilities = Capabilities::NONE.with(CommandKind::Stop);
    assert_eq!(
        refused(&w, CommandKind::Position, [1.0, 0.0, 0.0]),
        Reason::Unsupported
    );
    assert_eq!(refused(&w, CommandKind::Off, [0.0; 3]), Reason::Unsupported);
    let far = CommandRequest::new(ME, 1, 5, CommandKind::Position);
    assert_eq!(judge(&far, ME, &w), Verdict::Refused(Reason::UnknownAxis));
    assert_eq!(
        refused(&w, CommandKind::SetOutput, [1.0, 0.0, 0.0]),
        Reason::UnknownTarget,
        "an output is a signal"
    );
    let mut bad_target = request(CommandKind::Stop, [0.0; 3]);
    bad_target.target = 9;
    assert_eq!(
        judge(&bad_target, ME, &w),
        Verdict::Refused(Reason::UnknownTarget)
    );
}

#[test]
fn signals() {
    let mut w = world();
    let set = |index: u32, value: f64| {
        CommandRequest::for_signal(ME, 1, index, CommandKind::SetOutput)
            .with_values([value, 0.0, 0.0])
    };
    assert_eq!(
        judge(&set(0, 1.0), ME, &w),
        Verdict::SetOutput {
            signal: 0,
            on: true
        }
    );
    assert_eq!(
        judge(&set(1, 1.0), ME, &w),
        Verdict::Refused(Reason::NotAnOutput)
    );
    assert_eq!(
        judge(&set(2, 1.0), ME, &w),
        Verdict::Refused(Reason::UnknownSignal)
    );
    w.estop = true;
    assert_eq!(
        judge(&set(0, 1.0), ME, &w),
        Verdict::Refused(Reason::EstopLatched)
    );
    w.estop = false;
    w.signals[0].claimed_by = OTHER;
    assert_eq!(
        judge(&set(0, 0.0), ME, &w),
        Verdict::Refused(Reason::ClaimedByOther)
    );
    w.signals[0].claimed_by = ClientId::NONE;
    w.signals[0].device = DeviceState::Starting;
    assert_eq!(
        judge(&set(0, 0.0), ME, &w),
        Verdict::Refused(Reason::DeviceStarting)
    );
}

#[test]
fn a_digital_output_takes_0_or_1_and_nothing_else() {
    let w = world();
    let set = |value: f64| {
        CommandRequest::for_signal(ME, 1, 0, CommandKind::SetOutput).with_values([value, 0.0, 0.0])
    };
    for (value, on) in [(0.0, false), (-0.0, false), (1.0, true)] {
        assert_eq!(
            judge(&set(value), ME, &w),
            Verdict::SetOutput { signal: 0, on },
            "{value}"
        );
    }
    for value in [0.5, 2.0, -1.0, 5e-324, 1.0 + f64::EPSILON, 0.999_999] {
        assert_eq!(
            judge(&set(value), ME, &w),
            Verdict::Refused(Reason::OutOfRange),
            "{value:e}"
        );
    }
}

#[test]
fn rates_below_the_board_s_smallest_step_are_refused() {
    let mut w = world();
    w.axes[0].min_velocity = 0.5;
    w.axes[0].min_profile_velocity = 0.2;
    w.axes[0].min_accel = 10.0;
    use CommandKind::{Home, RampPosition, RampVelocity, Velocity};
    for (kind, values, reason) in [
        (RampVelocity, [0.2, 0.0, 0.0], Reason::VelocityLimit),
        (RampVelocity, [-0.49, 0.0, 0.0], Reason::VelocityLimit),
        (Velocity, [5e-324, 0.0, 0.0], Reason::VelocityLimit),
        (RampVelocity, [5.0, 5e-324, 0.0], Reason::AccelLimit),
        (RampVelocity, [5.0, 9.99, 0.0], Reason::AccelLimit),
        (RampPosition, [10.0, 0.19, 0.0], Reason::VelocityLimit),
        (RampPosition, [10.0, 0.0, 5e-324], Reason::AccelLimit),
        (Home, [0.1, 0.0, 0.0], Reason::VelocityLimit),
    ] {
        assert_eq!(refused(&w, kind, values), reason, "{kind:?} {values:?}");
    }
    // At the floor, and a velocity of 0 (stand in velocity mode), are taken.
    for (kind, values) in [
        (RampVelocity, [0.5, 10.0, 0.0]),
        (RampVelocity, [-0.5, 0.0, 0.0]),
        (Velocity, [0.0, 0.0, 0.0]),
        (RampPosition, [10.0, 0.2, 10.0]),
        (RampPosition, [10.0, 0.4, 10.0]),
        (Home, [0.5, 0.0, 0.0]),
    ] {
        assert!(
            matches!(verdict(&w, kind, values), Verdict::Move { .. }),
            "{kind:?} {values:?}"
        );
    }
    // Without a floor, only positive is asked of a rate.
    let w = world();
    assert!(matches!(
        verdict(&w, RampPosition, [10.0, 1e-300, 5e-324]),
        Verdict::Move { .. }
    ));
}

#[test]
fn a_trigger_takes_its_compare_position_and_a_capture_takes_nothing() {
    let mut w = world();
    for kind in [SignalKind::Trigger, SignalKind::Capture] {
        w.signals.push(SignalFacts {
            kind,
            claimed_by: ClientId::NONE,
            device: DeviceState::Online,
            link_up: true,
        });
    }
    let set = |index: u32, value: f64| {
        CommandRequest::for_signal(ME, 1, index, CommandKind::SetOutput)
            .with_values([value, 0.0, 0.0])
    };
    for value in [-12.5, 0.0, 0.5, 1e6] {
        assert_eq!(
            judge(&set(2, value), ME, &w),
            Verdict::SetValue { signal: 2, value },
            "any position: the board says what it can hold"
        );
    }
    assert_eq!(
        judge(&set(3, 1.0), ME, &w),
        Verdict::Refused(Reason::NotAnOutput)
    );
    w.signals[2].claimed_by = OTHER;
    assert_eq!(
        judge(&set(2, 5.0), ME, &w),
        Verdict::Refused(Reason::ClaimedByOther)
    );
    w.signals[2].claimed_by = ClientId::NONE;
    w.estop = true;
    assert_eq!(
        judge(&set(2, 5.0), ME, &w),
        Verdict::Refused(Reason::EstopLatched)
    );
}

#[test]
fn hold_and_resume_of_an_axis_follow_the_motion_rules() {
    let mut w = world();
    assert_eq!(
        verdict(&w, CommandKind::Hold, [0.0; 3]),
        Verdict::HoldAxis(0)
    );
    assert_eq!(
        verdict(&w, CommandKind::Resume, [0.0; 3]),
        Verdict::ResumeAxis(0)
    );
    w.axes[0].group_motion = true;
    assert_eq!(refused(&w, CommandKind::Hold, [0.0; 3]), Reason::GroupBusy);
    w.axes[0].group_motion = false;
    w.axes[0].claimed_by = OTHER;
    assert_eq!(
        refused(&w, CommandKind::Resume, [0.0; 3]),
        Reason::ClaimedByOther
    );
    w.axes[0].claimed_by = ClientId::NONE;
    w.axes[0].capabilities = Capabilities::NONE.with(CommandKind::Stop);
    assert_eq!(
        refused(&w, CommandKind::Hold, [0.0; 3]),
        Reason::Unsupported
    );
    w = world();
    w.axes[0].fault = FaultCode::LimitExceeded;
    assert_eq!(
        verdict(&w, CommandKind::Hold, [0.0; 3]),
        Verdict::HoldAxis(0),
        "holding never leads further out"
    );
    assert_eq!(
        refused(&w, CommandKind::Resume, [0.0; 3]),
        Reason::AxisFaulted
    );
    w.axes[0].fault = FaultCode::FollowingError;
    assert_eq!(
        refused(&w, CommandKind::Hold, [0.0; 3]),
        Reason::AxisFaulted
    );
    w = world();
    w.estop = true;
    assert_eq!(
        refused(&w, CommandKind::Resume, [0.0; 3]),
        Reason::EstopLatched
    );
    w.estop = false;
    w.axes[0].device = DeviceState::Starting;
    assert_eq!(
        refused(&w, CommandKind::Hold, [0.0; 3]),
        Reason::DeviceStarting
    );
    // Feed, cancel, run and stream stay a group's.
    let w = world();
    for kind in [CommandKind::Feed, CommandKind::Cancel, CommandKind::Stream] {
        assert_eq!(
            refused(&w, kind, [0.0; 3]),
            Reason::UnknownTarget,
            "{kind:?}"
        );
    }
}
