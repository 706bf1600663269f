//! Opening remote sessions: a query on `motiond/<name>/session/<identity>` carrying the
//! client's X25519 public key gets a public session id drawn from the kernel's random source
//! and the bridge's public key for this opening; both sides agree on the session's secret
//! from the two keys (`motion_wire::keys::KeyPair`), so it travels nowhere — not in the
//! reply, not in a log.

use std::io::Read as _;
use std::time::Instant;

use zenoh::Wait as _;
use zenoh::query::Query;

use super::{Bridge, refuse};
use motion_wire::keys::{KeyPair, Refusal, SessionGrant, SessionId, SessionOpen, SessionToken};

/// Attempts at drawing an id and token that are not taken (a clash of 128 random bits does
/// not happen; the loop only bounds the work if the random source were broken).
const DRAWS: usize = 4;

/// A fresh session id and key pair from `/dev/urandom`.
fn draw() -> std::io::Result<(SessionId, KeyPair)> {
    let mut bytes = [0u8; 48];
    std::fs::File::open("/dev/urandom")?.read_exact(&mut bytes)?;
    let mut id = [0u8; 16];
    let mut secret = [0u8; 32];
    id.copy_from_slice(&bytes[..16]);
    secret.copy_from_slice(&bytes[16..]);
    Ok((
        SessionId(u128::from_le_bytes(id)),
        KeyPair::from_random(secret),
    ))
}

impl Bridge {
    /// Answers a session-opening query with a grant, or refuses it.
    pub(super) fn on_open(&mut self, query: Query, received: Instant) {
        let key = query.key_expr().as_str();
        let Some(identity) = self.keys.identity_of_session(key).map(str::to_owned) else {
            refuse(
                Some(&query),
                Refusal::BadRequest,
                "not a session key of this bridge",
            );
            return;
        };
        let Some(open) = query
            .payload()
            .and_then(|bytes| SessionOpen::decode(&bytes.to_bytes()))
        else {
            refuse(
                Some(&query),
                Refusal::BadRequest,
                "opening a session needs its 41-byte payload (version 3, send time, X25519 \
                 public key)",
            );
            return;
        };
        let now = received.saturating_duration_since(self.started);
        let mut drawn: Option<(SessionId, SessionToken, [u8; 32])> = None;
        for _ in 0..DRAWS {
            match draw() {
                Ok((id, keys)) => {
                    let Some(token) = keys.agree(open.public, keys.public(), id) else {
                        self.counters.refused += 1;
                        self.intake.refuse(
                            query,
                            &identity,
                            Refusal::BadRequest,
                            "the opening's key is no usable X25519 public key",
                        );
                        return;
                    };
                    if !self.policy.session_taken(id, token) {
                        drawn = Some((id, token, keys.public()));
                        break;
                    }
                }
                Err(error) => {
                    tracing::error!(%error, "cannot read /dev/urandom for a session token");
                    break;
                }
            }
        }
        let outcome = match drawn {
            Some((id, token, public)) => self
                .policy
                .open_session(now, &identity, open, id, token)
                .map(|()| SessionGrant {
                    session: id,
                    public,
                }),
            None => Err((
                Refusal::Busy,
                "the bridge cannot draw a session token now".to_owned(),
            )),
        };
        match outcome {
            Ok(grant) => {
                // Bound to the client's own transport when it is connected to the bridge
                // directly (behind a router, its liveliness token alone says it is there).
                if let Some(zid) = open.zid()
                    && self.transports.contains(zid)
                {
                    self.policy.bind_transport(grant.session, zid);
                    tracing::debug!(%identity, session = %grant.session, %zid, "session bound to its transport");
                }
                tracing::debug!(%identity, session = %grant.session, "session opened");
                if let Err(error) = query
                    .reply(query.key_expr().clone(), grant.encode().to_vec())
                    .wait()
                {
                    tracing::debug!(%error, "cannot send a session grant");
                }
            }
            Err((refusal, text)) => {
                self.counters.refused += 1;
                self.intake.refuse(query, &identity, refusal, &text);
            }
        }
    }
}
