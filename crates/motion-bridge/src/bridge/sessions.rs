//! Opening remote sessions: a query on `motiond/<name>/session/<identity>` gets a public
//! session id and a secret token drawn from the kernel's random source; zenoh sends the
//! reply to the querier alone, so the token is known to the remote that asked (and to the
//! links it crossed: TLS keeps it from the wire).

use std::io::Read as _;
use std::time::Instant;

use zenoh::Wait as _;
use zenoh::query::Query;

use super::{Bridge, refuse};
use motion_wire::keys::{Refusal, SessionGrant, SessionId, SessionOpen, SessionToken};

/// Attempts at drawing an id and token that are not taken (a clash of 128 random bits does
/// not happen; the loop only bounds the work if the random source were broken).
const DRAWS: usize = 4;

/// A fresh session id and token from `/dev/urandom`.
fn draw() -> std::io::Result<(SessionId, SessionToken)> {
    let mut bytes = [0u8; 32];
    std::fs::File::open("/dev/urandom")?.read_exact(&mut bytes)?;
    let mut id = [0u8; 16];
    let mut token = [0u8; 16];
    id.copy_from_slice(&bytes[..16]);
    token.copy_from_slice(&bytes[16..]);
    Ok((SessionId(u128::from_le_bytes(id)), SessionToken(token)))
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
                "opening a session needs its 9-byte payload (version 2, send time)",
            );
            return;
        };
        let now = received.saturating_duration_since(self.started);
        let mut drawn = None;
        for _ in 0..DRAWS {
            match draw() {
                Ok((id, token)) if !self.policy.session_taken(id, token) => {
                    drawn = Some((id, token));
                    break;
                }
                Ok(_) => {}
                Err(error) => {
                    tracing::error!(%error, "cannot read /dev/urandom for a session token");
                    break;
                }
            }
        }
        let outcome = match drawn {
            Some((id, token)) => self
                .policy
                .open_session(now, &identity, open, id, token)
                .map(|()| SessionGrant { session: id, token }),
            None => Err((
                Refusal::Busy,
                "the bridge cannot draw a session token now".to_owned(),
            )),
        };
        match outcome {
            Ok(grant) => {
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
