//! The policy on fake time.

use core::time::Duration;

use motion_ipc::{
    AxisFlags, ClientId, CommandKind, CommandReply, CommandRequest, MotionFrame, Reason,
    SignalFlags, Target,
};

use super::{KindSet, MAX_SESSIONS, Policy, Remote, RemoteRule, Verdict};
use motion_wire::keys::{Refusal, RequestMeta, SessionId, SessionOpen, SessionToken};
use motion_wire::wire;

const DEADMAN: Duration = Duration::from_millis(200);

fn rule(identity: &str, allow: &[&str], rate: f64, burst: f64) -> RemoteRule {
    RemoteRule {
        identity: identity.to_owned(),
        allow: allow.iter().fold(KindSet::NONE, |set, name| {
            set.union(KindSet::from_name(name).expect("known name"))
        }),
        rate,
        burst,
        stop_burst: super::DEFAULT_STOP_BURST,
        sessions: MAX_SESSIONS,
    }
}

fn remote(identity: &str, session: u128) -> Remote {
    Remote {
        identity: identity.to_owned(),
        session: SessionId(session + 1),
    }
}

fn ms(ms: u64) -> Duration {
    Duration::from_millis(ms)
}

/// The secret the tests' bridge gave `remote`'s session.
fn token(remote: &Remote) -> SessionToken {
    SessionToken((remote.session.0 ^ 0x5eed_5eed).to_le_bytes())
}

/// Opens `remote`'s session at `now`, its opening query sent at `sent` on its clock.
fn open(
    policy: &mut Policy,
    remote: &Remote,
    now: Duration,
    sent: Duration,
) -> Result<(), (Refusal, String)> {
    let open = SessionOpen::new(sent.as_nanos() as u64, [9; 32], "");
    policy.open_session(now, &remote.identity, open, remote.session, token(remote))
}

/// What a test's request carries before it is signed: the session it names, the key its
/// MAC is made with, its send time.
#[derive(Debug, Clone, Copy)]
struct Unsigned {
    session: SessionId,
    key: SessionToken,
    sent: Duration,
}

/// A request of `remote`'s session sent at `sent` on the remote's clock.
fn meta(remote: &Remote, sent: Duration) -> Option<Unsigned> {
    Some(Unsigned {
        session: remote.session,
        key: token(remote),
        sent,
    })
}

/// Counters of the tests' requests: rising, never one twice.
static COUNTER: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

/// `meta` signed for `request` under `identity` with a fresh counter.
fn signed(identity: &str, meta: Option<Unsigned>, request: &CommandRequest) -> Option<RequestMeta> {
    meta.map(|meta| {
        RequestMeta::sign(
            meta.key,
            identity,
            &wire::encode(request),
            meta.session,
            COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            meta.sent.as_nanos() as u64,
        )
    })
}

/// [`Policy::admit`] of `request` under `identity`, `meta` signed as a client signs it.
fn judge(
    policy: &mut Policy,
    now: Duration,
    identity: &str,
    meta: Option<Unsigned>,
    request: &CommandRequest,
    deadman: Duration,
) -> Verdict {
    let bytes = wire::encode(request);
    let meta = signed(identity, meta, request);
    policy.admit(now, identity, meta, request, &bytes, deadman)
}

fn request(kind: CommandKind, axis: u32) -> CommandRequest {
    CommandRequest::new(ClientId::from_u128(99), 1, axis, kind)
}

/// Admits `request` from `remote`, sent and received at `now` (no network delay), opening
/// its session first if the policy lets it.
fn admit(policy: &mut Policy, remote: &Remote, now: Duration, request: &CommandRequest) -> Verdict {
    if !policy.session_taken(remote.session, token(remote)) {
        let _may_only_stop = open(policy, remote, now, now);
    }
    judge(
        policy,
        now,
        &remote.identity,
        meta(remote, now),
        request,
        DEADMAN,
    )
}

fn accept(policy: &mut Policy, remote: &Remote, request: &CommandRequest) {
    let reply = CommandReply::to(request, Reason::Accepted, 1);
    policy.on_reply(remote, request, &reply);
}

fn forwarded(verdict: &Verdict) -> bool {
    matches!(verdict, Verdict::Forward(..))
}

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
