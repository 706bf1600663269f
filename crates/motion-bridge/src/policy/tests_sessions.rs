//! The policy's sessions on fake time: the bridge's to give, bound to their identity and
//! transport, MAC'd and counted, a share of the table per entry.

use super::test_support::*;
use super::{MAX_SESSIONS, Policy, Verdict};
use core::time::Duration;
use motion_ipc::{CommandKind, CommandRequest};
use motion_wire::keys::{Refusal, SessionId, SessionToken};
use motion_wire::wire;

#[test]
fn made_up_sessions_never_grow_the_table_and_never_hold_back_a_stop() {
    let mut policy = Policy::new(vec![rule("*", &["all"], 1e9, 1e9)], None);
    let stop = request(CommandKind::Stop, 0);
    let estop = request(CommandKind::EStop, CommandRequest::ALL_AXES);
    let jog = request(CommandKind::Velocity, 0);
    // Stops under made-up tokens keep nothing.
    for n in 0..2 * MAX_SESSIONS as u128 {
        let made_up = remote("x", n);
        match judge(
            &mut policy,
            ms(0),
            "x",
            meta(&made_up, ms(0)),
            &stop,
            DEADMAN,
        ) {
            Verdict::Forward(_, None) => {}
            other => panic!("{other:?}"),
        }
    }
    assert_eq!(policy.session_count(), 0);
    for n in 0..MAX_SESSIONS as u128 {
        open(&mut policy, &remote("x", n), ms(0), ms(0)).expect("room");
    }
    // The session of the first one's liveliness token is there: never forgotten for room.
    policy.session_live("x", SessionId(1));
    // Full, and every session opened recently: a new one is refused...
    let late_comer = remote("x", 1 << 100);
    match open(&mut policy, &late_comer, ms(1000), ms(1000)) {
        Err((Refusal::Busy, text)) => assert!(text.contains("stop and e-stop"), "{text}"),
        other => panic!("{other:?}"),
    }
    // ... and needs one for a jog, but its stop and e-stop pass, sessionless.
    assert!(matches!(
        judge(
            &mut policy,
            ms(1000),
            "x",
            meta(&late_comer, ms(1000)),
            &jog,
            DEADMAN
        ),
        Verdict::Refuse(Refusal::NoSession, _)
    ));
    for request in [&stop, &estop] {
        assert!(matches!(
            judge(
                &mut policy,
                ms(1000),
                "x",
                meta(&late_comer, ms(1000)),
                request,
                DEADMAN
            ),
            Verdict::Forward(_, None)
        ));
        assert!(matches!(
            judge(&mut policy, ms(1000), "x", None, request, DEADMAN),
            Verdict::Forward(_, None)
        ));
    }
    // A known session still passes; after a minute of silence the others make room.
    assert!(forwarded(&judge(
        &mut policy,
        ms(30_000),
        "x",
        meta(&remote("x", 5), ms(30_000)),
        &jog,
        DEADMAN
    )));
    let later = Duration::from_secs(61);
    open(&mut policy, &late_comer, later, later).expect("room now");
    assert_eq!(
        policy.session_count(),
        3,
        "the live session 0, session 5 heard 31 s ago, and the new one"
    );
}

#[test]
fn a_session_is_good_for_its_own_identity_only_and_a_public_id_is_no_token() {
    let mut policy = Policy::new(vec![rule("*", &["all"], 1000.0, 1000.0)], None);
    let alice = remote("alice", 1);
    let bob = remote("bob", 2);
    open(&mut policy, &alice, ms(0), ms(0)).expect("opened");
    open(&mut policy, &bob, ms(0), ms(0)).expect("opened");
    let claim = request(CommandKind::Claim, 0);
    assert!(forwarded(&admit(&mut policy, &alice, ms(1), &claim)));
    accept(&mut policy, &alice, &claim);
    let jog = request(CommandKind::Velocity, 0);
    // Bob sends Alice's token under his own identity: refused.
    match judge(
        &mut policy,
        ms(2),
        "bob",
        meta(&alice, ms(2)),
        &jog,
        DEADMAN,
    ) {
        Verdict::Refuse(Refusal::NoSession, text) => {
            assert!(text.contains("another identity"), "{text}");
        }
        other => panic!("{other:?}"),
    }
    // Alice's public session id (her liveliness key shows it) is not her token.
    let public = Some(Unsigned {
        session: alice.session,
        key: SessionToken(alice.session.0.to_le_bytes()),
        sent: ms(2),
    });
    assert!(matches!(
        judge(&mut policy, ms(2), "alice", public, &jog, DEADMAN),
        Verdict::Refuse(Refusal::NoSession, _)
    ));
    // Without an attachment: no session either.
    assert!(matches!(
        judge(&mut policy, ms(2), "alice", None, &jog, DEADMAN),
        Verdict::Refuse(Refusal::NoSession, _)
    ));
    // A stop under a copied token passes, as nobody's.
    assert!(matches!(
        judge(
            &mut policy,
            ms(2),
            "bob",
            meta(&alice, ms(2)),
            &request(CommandKind::Stop, 0),
            DEADMAN
        ),
        Verdict::Forward(_, None)
    ));
    // Alice herself goes on.
    assert!(matches!(
        judge(
            &mut policy,
            ms(3),
            "alice",
            meta(&alice, ms(3)),
            &jog,
            DEADMAN
        ),
        Verdict::Forward(_, Some(_))
    ));
    // An identity that may only stop gets no session (it needs none).
    let mut viewer = Policy::new(vec![rule("*", &["stop", "estop"], 1000.0, 1000.0)], None);
    match open(&mut viewer, &alice, ms(0), ms(0)) {
        Err((Refusal::NotAllowed, text)) => assert!(text.contains("need no session"), "{text}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn each_entry_has_its_share_of_the_session_table() {
    let mut flood = rule("flood", &["all"], 1e9, 1e9);
    flood.sessions = 3;
    let mut wildcard = rule("*", &["all"], 1e9, 1e9);
    wildcard.sessions = 2;
    let mut policy = Policy::new(
        vec![flood, wildcard, rule("panel", &["all"], 1e9, 1e9)],
        None,
    );
    for n in 0..3 {
        open(&mut policy, &remote("flood", n), ms(0), ms(0)).expect("its share");
    }
    match open(&mut policy, &remote("flood", 3), ms(0), ms(0)) {
        Err((Refusal::Busy, text)) => assert!(
            text.contains("remote `flood` has its 3 sessions open") && text.contains("`sessions`"),
            "{text}"
        ),
        other => panic!("a fourth session of `flood`: {other:?}"),
    }
    // Made-up names under `*` share the wildcard's two.
    open(&mut policy, &remote("anon-1", 10), ms(0), ms(0)).expect("room");
    open(&mut policy, &remote("anon-2", 11), ms(0), ms(0)).expect("room");
    match open(&mut policy, &remote("anon-3", 12), ms(0), ms(0)) {
        Err((Refusal::Busy, text)) => assert!(text.contains("under `*`"), "{text}"),
        other => panic!("a third session under `*`: {other:?}"),
    }
    // The panel's own share is untouched.
    open(&mut policy, &remote("panel", 20), ms(0), ms(0)).expect("the panel's share");
    assert_eq!(
        (
            policy.sessions_of_entry("flood"),
            policy.sessions_of_entry("*")
        ),
        (3, 2)
    );
    // A session that ends frees its slot; idle ones of the entry make room after a minute.
    assert!(policy.session_gone("flood", SessionId(1)).is_empty());
    open(&mut policy, &remote("flood", 4), ms(10), ms(10)).expect("a freed slot");
    policy.session_live("flood", SessionId(2));
    let later = Duration::from_secs(61);
    open(&mut policy, &remote("flood", 5), later, later).expect("idle ones forgotten");
    // The live one and the new one; the wildcard's idle sessions were not the flood's to
    // forget.
    assert_eq!(policy.sessions_of_entry("flood"), 2);
    assert_eq!(policy.session_count(), 5);
}

#[test]
fn a_command_someone_else_saw_cannot_be_replayed_or_altered() {
    let mut policy = Policy::new(vec![rule("*", &["all"], 1000.0, 1000.0)], None);
    let alice = remote("alice", 1);
    open(&mut policy, &alice, ms(0), ms(0)).expect("opened");
    let jog = request(CommandKind::Velocity, 0).with_values([5.0, 0.0, 0.0]);
    let bytes = wire::encode(&jog);
    let seen = signed("alice", meta(&alice, ms(1)), &jog);
    assert!(forwarded(&policy.admit(
        ms(1),
        "alice",
        seen,
        &jog,
        &bytes,
        DEADMAN
    )));
    // The same bytes again (a peer with a queryable on the command keys kept them).
    match policy.admit(ms(2), "alice", seen, &jog, &bytes, DEADMAN) {
        Verdict::Refuse(Refusal::Late, text) => assert!(text.contains("replay"), "{text}"),
        other => panic!("a replay: {other:?}"),
    }
    // Its attachment on another request: the MAC does not fit.
    let faster = request(CommandKind::Velocity, 0).with_values([500.0, 0.0, 0.0]);
    match policy.admit(
        ms(2),
        "alice",
        seen,
        &faster,
        &wire::encode(&faster),
        DEADMAN,
    ) {
        Verdict::Refuse(Refusal::NoSession, text) => assert!(text.contains("MAC"), "{text}"),
        other => panic!("an altered request: {other:?}"),
    }
    // A stop with a copied attachment passes, as nobody's (a stop needs no session).
    let stop = request(CommandKind::Stop, 0);
    assert!(matches!(
        policy.admit(ms(3), "alice", seen, &stop, &wire::encode(&stop), DEADMAN),
        Verdict::Forward(_, None)
    ));
    // Alice's own next request goes on.
    assert!(forwarded(&judge(
        &mut policy,
        ms(4),
        "alice",
        meta(&alice, ms(4)),
        &jog,
        DEADMAN
    )));
}

#[test]
fn a_session_bound_to_its_transport_ends_with_it() {
    let mut policy = Policy::new(vec![rule("*", &["all"], 1000.0, 1000.0)], None);
    let alice = remote("alice", 1);
    let bob = remote("bob", 2);
    open(&mut policy, &alice, ms(0), ms(0)).expect("opened");
    open(&mut policy, &bob, ms(0), ms(0)).expect("opened");
    policy.bind_transport(alice.session, "a1");
    policy.bind_transport(bob.session, "b2");
    let claim = request(CommandKind::Claim, 0);
    assert!(forwarded(&admit(&mut policy, &alice, ms(1), &claim)));
    accept(&mut policy, &alice, &claim);
    let jog = request(CommandKind::Velocity, 1);
    assert!(forwarded(&admit(&mut policy, &alice, ms(1), &jog)));
    accept(&mut policy, &alice, &jog);
    // Alice's liveliness key stays declared (a copy of another peer's); her transport closes.
    policy.session_live("alice", alice.session);
    assert!(policy.transport_gone("zz").is_empty(), "nobody's transport");
    let sent = policy.transport_gone("a1");
    let kinds: Vec<_> = sent
        .iter()
        .map(|r| (r.kind().expect("a kind"), r.axis))
        .collect();
    assert_eq!(kinds, [(CommandKind::Stop, 1), (CommandKind::Release, 0)]);
    assert_eq!(policy.holder(motion_ipc::Target::Axis, 0), None);
    // Her session is gone (a request of it names none); Bob's goes on.
    assert_eq!(policy.session_count(), 1);
    assert!(matches!(
        judge(
            &mut policy,
            ms(2),
            "alice",
            meta(&alice, ms(2)),
            &jog,
            DEADMAN
        ),
        Verdict::Refuse(Refusal::NoSession, _)
    ));
    assert!(forwarded(&admit(&mut policy, &bob, ms(2), &jog)));
}
