//! The policy on fake time: allow-lists, rates, lateness, claims (sessions:
//! `tests_sessions.rs`).

use core::time::Duration;

use super::test_support::*;
use super::{KindSet, Policy, Verdict};
use motion_ipc::{
    AxisFlags, ClientId, CommandKind, CommandReply, CommandRequest, MotionFrame, Reason,
    SignalFlags, Target,
};
use motion_wire::keys::{Refusal, SessionId};

#[test]
fn names_and_groups_of_the_allow_list() {
    let moves = KindSet::from_name("move").expect("group");
    assert!(moves.contains(CommandKind::Position) && moves.contains(CommandKind::RampPosition));
    assert!(!moves.contains(CommandKind::Velocity));
    assert_eq!(
        KindSet::from_name("estop"),
        KindSet::from_name("e-stop"),
        "both spellings"
    );
    assert_eq!(KindSet::from_name("all"), Some(KindSet::all()));
    assert_eq!(KindSet::from_name("teleport"), None);
    assert!(KindSet::known_names().contains("set-output"));
    assert_eq!(
        KindSet::from_name("jog").expect("group").names(),
        ["velocity", "ramp-velocity"]
    );
}

#[test]
fn only_allowed_kinds_of_known_identities_pass_and_the_client_id_is_cleared() {
    let mut policy = Policy::new(
        vec![
            rule("panel", &["stop", "estop", "move"], 100.0, 10.0),
            rule("*", &["stop"], 100.0, 10.0),
        ],
        None,
    );
    let panel = remote("panel", 1);
    let stranger = remote("visitor", 2);
    match admit(
        &mut policy,
        &panel,
        ms(0),
        &request(CommandKind::RampPosition, 0),
    ) {
        Verdict::Forward(sent, from) => {
            assert_eq!(from.as_ref(), Some(&panel));
            assert!(sent.client.is_none(), "the server takes the bridge's node");
            assert_eq!(sent.kind, CommandKind::RampPosition as u32);
        }
        other => panic!("{other:?}"),
    }
    match admit(&mut policy, &panel, ms(1), &request(CommandKind::Home, 0)) {
        Verdict::Refuse(Refusal::NotAllowed, text) => {
            assert!(text.contains("`home`") && text.contains("panel"), "{text}");
            assert!(
                text.contains("stop, ramp-position") || text.contains("stop"),
                "{text}"
            );
        }
        other => panic!("{other:?}"),
    }
    // An identity without its own rule gets the `*` rule.
    assert!(forwarded(&admit(
        &mut policy,
        &stranger,
        ms(2),
        &request(CommandKind::Stop, 0)
    )));
    assert!(matches!(
        admit(
            &mut policy,
            &stranger,
            ms(3),
            &request(CommandKind::EStop, 0)
        ),
        Verdict::Refuse(Refusal::NotAllowed, _)
    ));
    // Without a `*` rule, an unknown identity may do nothing.
    let mut strict = Policy::new(vec![rule("panel", &["all"], 100.0, 10.0)], None);
    match admit(
        &mut strict,
        &stranger,
        ms(0),
        &request(CommandKind::Stop, 0),
    ) {
        Verdict::Refuse(Refusal::NotAllowed, text) => assert!(text.contains("visitor"), "{text}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn bad_kinds_and_schemas_are_answered_for_the_server() {
    let mut policy = Policy::new(vec![rule("*", &["all"], 100.0, 10.0)], None);
    let panel = remote("panel", 1);
    let mut unknown = request(CommandKind::Stop, 0);
    unknown.kind = 77;
    assert_eq!(
        admit(&mut policy, &panel, ms(0), &unknown),
        Verdict::Answer(Reason::UnknownKind)
    );
    let mut old = request(CommandKind::Stop, 0);
    old.schema_version = 1;
    assert_eq!(
        admit(&mut policy, &panel, ms(0), &old),
        Verdict::Answer(Reason::SchemaMismatch)
    );
}

#[test]
fn the_rate_limit_refuses_above_the_burst_refills_and_never_holds_back_a_stop() {
    let mut policy = Policy::new(
        vec![
            rule("panel", &["all"], 10.0, 3.0),
            rule("*", &["all"], 10.0, 3.0),
        ],
        None,
    );
    let panel = remote("panel", 1);
    let jog = request(CommandKind::Velocity, 0);
    // Opening the session takes one request of the burst of 3.
    open(&mut policy, &panel, ms(0), ms(0)).expect("opened");
    for _ in 0..2 {
        assert!(forwarded(&admit(&mut policy, &panel, ms(0), &jog)));
    }
    match admit(&mut policy, &panel, ms(0), &jog) {
        Verdict::Refuse(Refusal::RateLimited, text) => assert!(text.contains("10"), "{text}"),
        other => panic!("{other:?}"),
    }
    assert!(forwarded(&admit(
        &mut policy,
        &panel,
        ms(0),
        &request(CommandKind::Stop, 0)
    )));
    assert!(forwarded(&admit(
        &mut policy,
        &panel,
        ms(0),
        &request(CommandKind::EStop, 0)
    )));
    // 100 ms at 10/s is one token again.
    assert!(forwarded(&admit(&mut policy, &panel, ms(100), &jog)));
    assert!(!forwarded(&admit(&mut policy, &panel, ms(100), &jog)));
    // The bucket is the entry's: another session of `panel` shares it.
    assert!(!forwarded(&admit(
        &mut policy,
        &remote("panel", 2),
        ms(100),
        &jog
    )));
    // Identities under `*` share the wildcard's one bucket (opening a session takes from
    // it too): rotating names buys nothing.
    let mut passed = 0;
    for n in 0..50u128 {
        let name = format!("made-up-{n}");
        let stranger = remote(&name, 100 + n);
        if open(&mut policy, &stranger, ms(100), ms(100)).is_ok()
            && forwarded(&admit(&mut policy, &stranger, ms(100), &jog))
        {
            passed += 1;
        }
    }
    assert_eq!(
        passed, 1,
        "3 requests of the burst: one open and its jog, one more open"
    );
    match admit(&mut policy, &remote("made-up-0", 100), ms(100), &jog) {
        Verdict::Refuse(Refusal::RateLimited, text) => {
            assert!(
                text.contains("under `*`") && text.contains("made-up-0"),
                "{text}"
            );
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_request_held_up_in_the_network_is_refused_but_a_stop_is_not() {
    let mut policy = Policy::new(vec![rule("*", &["all"], 1000.0, 1000.0)], None);
    let panel = remote("panel", 1);
    let jog = request(CommandKind::Velocity, 0);
    // The client's clock is 5 s ahead of the bridge's; requests take 2 ms.
    let clock = |bridge: Duration| bridge + Duration::from_secs(5) - ms(2);
    let mut at = ms(1000);
    open(&mut policy, &panel, at, clock(at)).expect("opened");
    for _ in 0..10 {
        let verdict = judge(
            &mut policy,
            at,
            "panel",
            meta(&panel, clock(at)),
            &jog,
            DEADMAN,
        );
        assert!(forwarded(&verdict), "{verdict:?}");
        at += ms(33);
    }
    // A renewal sent 1 s ago arrives now (a network buffer let go).
    let late_sent = clock(at) - Duration::from_secs(1);
    match judge(
        &mut policy,
        at,
        "panel",
        meta(&panel, late_sent),
        &jog,
        DEADMAN,
    ) {
        Verdict::Refuse(Refusal::Late, text) => assert!(text.contains("200ms"), "{text}"),
        other => panic!("{other:?}"),
    }
    let stop = request(CommandKind::Stop, 0);
    assert!(forwarded(&judge(
        &mut policy,
        at,
        "panel",
        meta(&panel, late_sent),
        &stop,
        DEADMAN
    )));
    // Later than usual but within the deadman: passes.
    let slow = clock(at) - ms(150);
    assert!(forwarded(&judge(
        &mut policy,
        at,
        "panel",
        meta(&panel, slow),
        &jog,
        DEADMAN
    )));
    // One that says it was sent later than it could have been (a clock from the future)
    // is not applied either.
    match judge(
        &mut policy,
        at,
        "panel",
        meta(&panel, clock(at) + ms(5000)),
        &jog,
        DEADMAN,
    ) {
        Verdict::Refuse(Refusal::Late, text) => {
            assert!(text.contains("later than it could"), "{text}")
        }
        other => panic!("{other:?}"),
    }
    // Up to 2 s ahead passes, though: a prompt request after a slow opening looks so.
    assert!(forwarded(&judge(
        &mut policy,
        at,
        "panel",
        meta(&panel, clock(at) + ms(1500)),
        &jog,
        DEADMAN
    )));
    // A configured max_delay wins over the deadman; zero deadman and no config: 1 s.
    let mut strict = Policy::new(vec![rule("*", &["all"], 1000.0, 1000.0)], Some(ms(50)));
    open(&mut strict, &panel, at, clock(at)).expect("opened");
    assert!(forwarded(&judge(
        &mut strict,
        at,
        "panel",
        meta(&panel, clock(at)),
        &jog,
        DEADMAN
    )));
    assert!(!forwarded(&judge(
        &mut strict,
        at,
        "panel",
        meta(&panel, slow),
        &jog,
        DEADMAN
    )));
    let mut fallback = Policy::new(vec![rule("*", &["all"], 1000.0, 1000.0)], None);
    open(&mut fallback, &panel, at, clock(at)).expect("opened");
    assert!(forwarded(&judge(
        &mut fallback,
        at,
        "panel",
        meta(&panel, clock(at) - ms(900)),
        &jog,
        Duration::ZERO
    )));
    assert!(!forwarded(&judge(
        &mut fallback,
        at,
        "panel",
        meta(&panel, clock(at) - ms(2000)),
        &jog,
        Duration::ZERO
    )));
}

#[test]
fn clocks_drifting_apart_slowly_are_not_late() {
    let mut policy = Policy::new(vec![rule("*", &["all"], 1000.0, 1000.0)], None);
    let panel = remote("panel", 1);
    let jog = request(CommandKind::Velocity, 0);
    // The client's clock runs 500 ppm slow: after 1000 s it is 500 ms behind, more than
    // the deadman; the floor follows it.
    open(&mut policy, &panel, ms(0), ms(0)).expect("opened");
    for step in 0..=1000u64 {
        let bridge = Duration::from_secs(step);
        let client = Duration::from_secs_f64(step as f64 * (1.0 - 500e-6));
        let verdict = judge(
            &mut policy,
            bridge,
            "panel",
            meta(&panel, client),
            &jog,
            DEADMAN,
        );
        assert!(forwarded(&verdict), "step {step}: {verdict:?}");
    }
}

#[test]
fn claims_belong_to_the_remote_session_that_took_them() {
    let mut policy = Policy::new(vec![rule("*", &["all"], 1000.0, 1000.0)], None);
    let (a, b) = (remote("alice", 1), remote("bob", 2));
    let a_again = remote("alice", 3); // another process of the same identity
    let claim = request(CommandKind::Claim, 0);
    assert!(forwarded(&admit(&mut policy, &a, ms(0), &claim)));
    accept(&mut policy, &a, &claim);
    assert_eq!(policy.holder(Target::Axis, 0), Some(&a));

    for other in [&b, &a_again] {
        assert_eq!(
            admit(&mut policy, other, ms(1), &claim),
            Verdict::Answer(Reason::ClaimedByOther)
        );
        assert_eq!(
            admit(
                &mut policy,
                other,
                ms(1),
                &request(CommandKind::RampPosition, 0)
            ),
            Verdict::Answer(Reason::ClaimedByOther)
        );
        assert_eq!(
            admit(&mut policy, other, ms(1), &request(CommandKind::Off, 0)),
            Verdict::Answer(Reason::ClaimedByOther)
        );
        assert_eq!(
            admit(
                &mut policy,
                other,
                ms(1),
                &request(CommandKind::Off, CommandRequest::ALL_AXES)
            ),
            Verdict::Answer(Reason::ClaimedByOther)
        );
        assert_eq!(
            admit(&mut policy, other, ms(1), &request(CommandKind::Release, 0)),
            Verdict::Answer(Reason::NotClaimed)
        );
        // Anyone may stop any axis, and e-stop and reset.
        for kind in [CommandKind::Stop, CommandKind::EStop, CommandKind::Reset] {
            assert!(forwarded(&admit(
                &mut policy,
                other,
                ms(1),
                &request(kind, 0)
            )));
        }
        // Other axes are free.
        assert!(forwarded(&admit(
            &mut policy,
            other,
            ms(1),
            &request(CommandKind::Position, 1)
        )));
    }
    assert!(forwarded(&admit(
        &mut policy,
        &a,
        ms(2),
        &request(CommandKind::Position, 0)
    )));
    let release = request(CommandKind::Release, 0);
    assert!(forwarded(&admit(&mut policy, &a, ms(3), &release)));
    accept(&mut policy, &a, &release);
    assert!(forwarded(&admit(&mut policy, &b, ms(4), &claim)));
    // A refused claim is not noted.
    let refused = CommandReply::to(&claim, Reason::ClaimedByOther, 5);
    policy.on_reply(&b, &claim, &refused);
    assert_eq!(policy.holder(Target::Axis, 0), None);
}

#[test]
fn signal_claims_are_separate_from_axis_claims() {
    let mut policy = Policy::new(vec![rule("*", &["all"], 1000.0, 1000.0)], None);
    let (a, b) = (remote("alice", 1), remote("bob", 2));
    let claim = CommandRequest::for_signal(ClientId::NONE, 1, 0, CommandKind::Claim);
    accept(&mut policy, &a, &claim);
    let set = CommandRequest::for_signal(ClientId::NONE, 2, 0, CommandKind::SetOutput)
        .with_values([1.0, 0.0, 0.0]);
    assert_eq!(
        admit(&mut policy, &b, ms(0), &set),
        Verdict::Answer(Reason::ClaimedByOther)
    );
    assert!(forwarded(&admit(&mut policy, &a, ms(0), &set)));
    assert!(forwarded(&admit(
        &mut policy,
        &b,
        ms(0),
        &request(CommandKind::Position, 0)
    )));
}

#[test]
fn a_vanished_session_has_its_jogs_stopped_and_claims_released() {
    let mut policy = Policy::new(vec![rule("*", &["all"], 1000.0, 1000.0)], None);
    let (a, b) = (remote("alice", 1), remote("bob", 2));
    for who in [&a, &b] {
        open(&mut policy, who, ms(0), ms(0)).expect("opened");
    }
    accept(&mut policy, &a, &request(CommandKind::Velocity, 1));
    accept(&mut policy, &a, &request(CommandKind::Power, 3));
    accept(&mut policy, &a, &request(CommandKind::Claim, 2));
    accept(&mut policy, &a, &request(CommandKind::RampVelocity, 4));
    // Bob took axis 4 over with a move: not Alice's to stop any more.
    accept(&mut policy, &b, &request(CommandKind::RampPosition, 4));
    accept(&mut policy, &b, &request(CommandKind::Velocity, 5));

    // A token declared under Alice's id by Bob's identity ends nothing.
    assert!(policy.session_gone("bob", SessionId(2)).is_empty());
    let sent = policy.session_gone("alice", SessionId(2));
    let summary: Vec<(u32, u32, u32)> = sent.iter().map(|r| (r.kind, r.axis, r.target)).collect();
    assert_eq!(
        summary,
        [
            (CommandKind::Stop as u32, 1, 0),
            (CommandKind::Stop as u32, 3, 0),
            (CommandKind::Release as u32, 2, 0),
        ]
    );
    assert!(sent.iter().all(|r| r.client.is_none()));
    assert!(
        policy.session_gone("alice", SessionId(2)).is_empty(),
        "once"
    );
    // An e-stop ends every jog, even one sent without a session: nothing left to stop for
    // Bob.
    let estop = request(CommandKind::EStop, CommandRequest::ALL_AXES);
    policy.on_sessionless_reply(&estop, &CommandReply::to(&estop, Reason::Accepted, 1));
    assert!(policy.session_gone("bob", SessionId(3)).is_empty());
}

#[test]
fn claims_the_server_no_longer_holds_for_the_bridge_are_forgotten() {
    let mut policy = Policy::new(vec![rule("*", &["all"], 1000.0, 1000.0)], None);
    let a = remote("alice", 1);
    let bridge = ClientId::from_u128(500);
    for axis in 0..3 {
        accept(&mut policy, &a, &request(CommandKind::Claim, axis));
    }
    let signal_claim = CommandRequest::for_signal(ClientId::NONE, 1, 0, CommandKind::Claim);
    accept(&mut policy, &a, &signal_claim);
    let mut frame = MotionFrame::EMPTY;
    frame.axis_count = 3;
    frame.signal_count = 1;
    frame.axes[0].flags = AxisFlags::CLAIMED.0;
    frame.axes[0].claimed_by = bridge;
    frame.axes[1].flags = AxisFlags::CLAIMED.0;
    frame.axes[1].claimed_by = ClientId::from_u128(501); // a local client took it over
    frame.signals[0].flags = SignalFlags::CLAIMED.0;
    frame.signals[0].claimed_by = bridge;
    policy.reconcile(&frame, bridge);
    assert_eq!(policy.holder(Target::Axis, 0), Some(&a));
    assert_eq!(policy.holder(Target::Axis, 1), None);
    assert_eq!(policy.holder(Target::Axis, 2), None);
    assert_eq!(policy.holder(Target::Signal, 0), Some(&a));
    policy.server_restarted();
    assert_eq!(policy.holder(Target::Axis, 0), None);
}

#[test]
fn on_its_exit_the_bridge_stops_every_remote_jog() {
    let mut policy = Policy::new(vec![rule("*", &["all"], 1000.0, 1000.0)], None);
    let (a, b) = (remote("alice", 1), remote("bob", 2));
    accept(&mut policy, &a, &request(CommandKind::Velocity, 4));
    accept(&mut policy, &b, &request(CommandKind::Power, 2));
    accept(&mut policy, &b, &request(CommandKind::RampPosition, 3));
    accept(&mut policy, &a, &request(CommandKind::Claim, 1));
    let stops: Vec<(u32, u32)> = policy.shutdown().iter().map(|r| (r.kind, r.axis)).collect();
    assert_eq!(
        stops,
        [(CommandKind::Stop as u32, 2), (CommandKind::Stop as u32, 4)]
    );
    assert_eq!(policy.holder(Target::Axis, 1), None);
    assert!(policy.shutdown().is_empty());
}
