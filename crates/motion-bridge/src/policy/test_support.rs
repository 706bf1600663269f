//! What the policy's tests share: rules, remotes, sessions opened and requests signed as a
//! client signs them, on fake time.

use core::time::Duration;

use motion_ipc::{ClientId, CommandKind, CommandReply, CommandRequest, Reason};

use super::{KindSet, MAX_SESSIONS, Policy, Remote, RemoteRule, Verdict};
use motion_wire::keys::{Refusal, RequestMeta, SessionId, SessionOpen, SessionToken};
use motion_wire::wire;

pub(super) const DEADMAN: Duration = Duration::from_millis(200);

pub(super) fn rule(identity: &str, allow: &[&str], rate: f64, burst: f64) -> RemoteRule {
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

pub(super) fn remote(identity: &str, session: u128) -> Remote {
    Remote {
        identity: identity.to_owned(),
        session: SessionId(session + 1),
    }
}

pub(super) fn ms(ms: u64) -> Duration {
    Duration::from_millis(ms)
}

/// The secret the tests' bridge gave `remote`'s session.
pub(super) fn token(remote: &Remote) -> SessionToken {
    SessionToken((remote.session.0 ^ 0x5eed_5eed).to_le_bytes())
}

/// Opens `remote`'s session at `now`, its opening query sent at `sent` on its clock.
pub(super) fn open(
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
pub(super) struct Unsigned {
    pub(super) session: SessionId,
    pub(super) key: SessionToken,
    pub(super) sent: Duration,
}

/// A request of `remote`'s session sent at `sent` on the remote's clock.
pub(super) fn meta(remote: &Remote, sent: Duration) -> Option<Unsigned> {
    Some(Unsigned {
        session: remote.session,
        key: token(remote),
        sent,
    })
}

/// Counters of the tests' requests: rising, never one twice.
static COUNTER: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

/// `meta` signed for `request` under `identity` with a fresh counter.
pub(super) fn signed(
    identity: &str,
    meta: Option<Unsigned>,
    request: &CommandRequest,
) -> Option<RequestMeta> {
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
pub(super) fn judge(
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

pub(super) fn request(kind: CommandKind, axis: u32) -> CommandRequest {
    CommandRequest::new(ClientId::from_u128(99), 1, axis, kind)
}

/// Admits `request` from `remote`, sent and received at `now` (no network delay), opening
/// its session first if the policy lets it.
pub(super) fn admit(
    policy: &mut Policy,
    remote: &Remote,
    now: Duration,
    request: &CommandRequest,
) -> Verdict {
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

pub(super) fn accept(policy: &mut Policy, remote: &Remote, request: &CommandRequest) {
    let reply = CommandReply::to(request, Reason::Accepted, 1);
    policy.on_reply(remote, request, &reply);
}

pub(super) fn forwarded(verdict: &Verdict) -> bool {
    matches!(verdict, Verdict::Forward(..))
}
