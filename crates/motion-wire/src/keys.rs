//! The network contract's names and small messages: zenoh key expressions, the attachments
//! that travel beside the payloads, and the bridge's own refusals.
//!
//! | key expression | what | payload | attachment |
//! |---|---|---|---|
//! | `motiond/<name>/frame` | put, every `1000 / frame_rate` ms of server ticks | [`MotionFrame`](motion_ipc::MotionFrame) | [`Origin`] |
//! | `motiond/<name>/info` | put on change; queryable (the newest) | [`ServerInfo`](motion_ipc::ServerInfo) | [`Origin`] |
//! | `motiond/<name>/stats` | put about 1 Hz; queryable | [`ServerStats`](motion_ipc::ServerStats) | [`Origin`] |
//! | `motiond/<name>/params` | queryable only (176 KiB) | [`MachineParams`](motion_ipc::MachineParams) | [`Origin`] |
//! | `motiond/<name>/state/json` | put at `json_rate` Hz | UTF-8 JSON (see the README) | – |
//! | `motiond/<name>/session/<identity>` (or `…/session`: identity `anonymous`) | queryable: opens a session | [`SessionOpen`] → [`SessionGrant`], or an error reply | – |
//! | `motiond/<name>/command/<identity>` (or `…/command`: identity `anonymous`) | queryable | [`CommandRequest`](motion_ipc::CommandRequest) → [`CommandReply`](motion_ipc::CommandReply), or an error reply `"<code>: <text>"` ([`Refusal`]) | request: [`RequestMeta`]; reply: [`Origin`] |
//! | `motiond/<name>/remote/<identity>/<session>` | liveliness token of a remote client (the public [`SessionId`] of its grant) | – | – |
//! | `motiond/<name>/bridge` | liveliness token of the bridge | – | – |
//!
//! Binary payloads are the `motion-ipc` C layouts, little-endian ([`crate::wire`]).
//!
//! A remote's session is the bridge's to give: a client asks `session/<identity>` once with
//! an X25519 public key of its own ([`SessionOpen`]) and gets a public [`SessionId`] (for its
//! liveliness token) and the bridge's public key ([`SessionGrant`]); both sides derive the
//! session's secret [`SessionToken`] from the two keys ([`KeyPair::agree`]), so it is in no
//! message. Every command carries the session id, a counter and a MAC made with the secret
//! over the identity, the request's
//! bytes and the rest of the attachment ([`RequestMeta`]), so a peer that sees a command
//! (a queryable of its own on the command keys, a log) learns nothing it can command with,
//! and a command replayed is refused. The session is bound to the identity it was opened
//! for, so a session id read from a liveliness key, or a MAC sent under another identity,
//! commands nothing. Stop and e-stop need no session.

use core::fmt;

use motion_ipc::ServiceNames;

/// The port a bridge listens on by default (zenoh's own).
pub const DEFAULT_PORT: u16 = 7447;

/// The identity of a remote that names none (a command sent to `motiond/<name>/command`,
/// or a client without `identity`).
pub const ANONYMOUS: &str = "anonymous";

/// Why a name cannot be one chunk of a key expression.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "`{name}` cannot be a {what}: use letters, digits, `-`, `_` or `.` (no `/`, `*`, `$`, \
     `?`, `#`, no leading `@`, not empty)"
)]
pub struct BadName {
    /// What the name was for ("server name", "remote identity").
    pub what: &'static str,
    /// The name given.
    pub name: String,
}

/// Checks that `name` is one plain chunk of a key expression.
pub fn check_chunk(what: &'static str, name: &str) -> Result<(), BadName> {
    let plain = !name.is_empty()
        && !name.starts_with('@')
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.' | '@' | '+' | '='));
    if plain {
        Ok(())
    } else {
        Err(BadName {
            what,
            name: name.to_owned(),
        })
    }
}

/// The key expressions of the motiond instance `name`. Frames, description, statistics,
/// parameters and commands travel under the names of their iceoryx2 services
/// ([`ServiceNames`], which spells them); the keys only the network has (the JSON state,
/// sessions, liveliness tokens) sit under the same prefix.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Keys {
    names: ServiceNames,
}

impl Keys {
    /// Keys of the instance `name` (`[server] name` of its config).
    pub fn new(name: &str) -> Result<Self, BadName> {
        check_chunk("server name", name)?;
        Ok(Self {
            names: ServiceNames::new(name),
        })
    }

    /// Frames, decimated.
    pub fn frame(&self) -> String {
        self.names.frame()
    }

    /// The server description.
    pub fn info(&self) -> String {
        self.names.info()
    }

    /// The server's statistics.
    pub fn stats(&self) -> String {
        self.names.stats()
    }

    /// The machine parameters (queryable only).
    pub fn params(&self) -> String {
        self.names.params()
    }

    /// The JSON state for tools.
    pub fn state_json(&self) -> String {
        self.names.under("state/json")
    }

    /// Where the remote `identity` sends commands.
    pub fn command(&self, identity: &str) -> String {
        format!("{}/{identity}", self.names.command())
    }

    /// What the bridge's command queryable answers: `motiond/<name>/command` and every
    /// identity below it (keys deeper than one identity are refused as bad requests).
    pub fn command_any(&self) -> String {
        format!("{}/**", self.names.command())
    }

    /// The identity a command key names, if it is one of this instance's: the chunk after
    /// `command/`, or [`ANONYMOUS`] for `motiond/<name>/command` itself.
    pub fn identity_of<'k>(&self, command_key: &'k str) -> Option<&'k str> {
        identity_below(&self.names.command(), command_key)
    }

    fn session_root(&self) -> String {
        self.names.under("session")
    }

    /// Where the remote `identity` opens a session.
    pub fn session(&self, identity: &str) -> String {
        format!("{}/{identity}", self.session_root())
    }

    /// What the bridge's session queryable answers (`session` and one identity below it).
    pub fn session_any(&self) -> String {
        format!("{}/**", self.session_root())
    }

    /// The identity a session key names (as [`Keys::identity_of`] for commands).
    pub fn identity_of_session<'k>(&self, session_key: &'k str) -> Option<&'k str> {
        identity_below(&self.session_root(), session_key)
    }

    /// The liveliness token of remote `identity`'s client session `session`.
    pub fn remote_token(&self, identity: &str, session: SessionId) -> String {
        self.names.under(&format!("remote/{identity}/{session}"))
    }

    /// Every remote client's liveliness token.
    pub fn remote_tokens(&self) -> String {
        self.names.under("remote/*/*")
    }

    /// The (identity, session) a remote token's key names.
    pub fn remote_of(&self, token_key: &str) -> Option<(String, SessionId)> {
        let rest = token_key.strip_prefix(&self.names.under("remote/"))?;
        let (identity, session) = rest.split_once('/')?;
        Some((identity.to_owned(), session.parse().ok()?))
    }

    /// The bridge's liveliness token.
    pub fn bridge_token(&self) -> String {
        self.names.under("bridge")
    }
}

/// The identity `key` names below `root`: [`ANONYMOUS`] for `root` itself, the one chunk
/// after `root/`, or `None` (another key, or deeper than one chunk).
fn identity_below<'k>(root: &str, key: &'k str) -> Option<&'k str> {
    let rest = key.strip_prefix(root)?;
    if rest.is_empty() {
        return Some(ANONYMOUS);
    }
    let identity = rest.strip_prefix('/')?;
    (!identity.is_empty() && !identity.contains('/')).then_some(identity)
}

/// A remote client's session as others may see it (its liveliness token names it): random,
/// issued by the bridge with the session's [`SessionToken`]; claims and jogs belong to one
/// session as they belong to one client process over shared memory. Never a credential.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct SessionId(pub u128);

impl fmt::Display for SessionId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:032x}", self.0)
    }
}

impl core::str::FromStr for SessionId {
    type Err = core::num::ParseIntError;
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        u128::from_str_radix(text, 16).map(Self)
    }
}

/// The attachment of a published sample or a command reply: the iceoryx2 node id of the
/// server that wrote it (16 bytes, little-endian), so that a remote client notices a server
/// restart as a local one does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Origin(pub u128);

impl Origin {
    /// Bytes on the wire.
    pub const SIZE: usize = 16;

    /// The 16 bytes.
    pub fn encode(self) -> [u8; 16] {
        self.0.to_le_bytes()
    }

    /// From the attachment's bytes; `None` when they are not 16.
    pub fn decode(bytes: &[u8]) -> Option<Self> {
        <[u8; 16]>::try_from(bytes)
            .ok()
            .map(|b| Self(u128::from_le_bytes(b)))
    }
}

/// The secret of a session: 16 bytes both sides derive from the opening's X25519 keys
/// ([`KeyPair::agree`]), never sent; every command of the session carries a MAC made with it
/// ([`RequestMeta`]). All zero: no session.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct SessionToken(pub [u8; 16]);

impl SessionToken {
    /// No session.
    pub const NONE: Self = Self([0; 16]);

    /// Whether this is [`SessionToken::NONE`].
    pub fn is_none(self) -> bool {
        self == Self::NONE
    }
}

impl fmt::Debug for SessionToken {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // A secret: never in a log.
        f.write_str(if self.is_none() {
            "SessionToken(none)"
        } else {
            "SessionToken(…)"
        })
    }
}

/// Version byte of [`SessionOpen`], [`SessionGrant`] and [`RequestMeta`] (3: requests carry
/// a MAC instead of the session's secret).
pub const CONTRACT_VERSION: u8 = 3;

/// The payload of a session-opening query on `motiond/<name>/session/<identity>`: version
/// (u8, 3), the client's CLOCK_MONOTONIC when it sent the query (u64 LE, ns), the client's
/// X25519 public key for this opening (32 bytes) and the client's zenoh id as zenoh prints
/// it (ASCII hex, zero-padded to 32 bytes). 73 bytes. The bridge judges the session's later
/// time stamps against its own clock from here on, and ends the session when the transport
/// of that zenoh id closes (when the client is connected to it directly).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SessionOpen {
    /// The client's monotonic clock at sending, ns.
    pub sent_ns: u64,
    /// The client's X25519 public key ([`KeyPair`]).
    pub public: [u8; 32],
    /// The client's zenoh id as zenoh prints it, zero-padded ([`SessionOpen::zid`]).
    pub zid: [u8; 32],
}

impl SessionOpen {
    /// Bytes on the wire.
    pub const SIZE: usize = 73;

    /// An opening sent at `sent_ns` with the key `public` by the zenoh session `zid` (as
    /// zenoh prints it; more than 32 bytes are cut).
    pub fn new(sent_ns: u64, public: [u8; 32], zid: &str) -> Self {
        let mut padded = [0; 32];
        let len = zid.len().min(32);
        padded[..len].copy_from_slice(&zid.as_bytes()[..len]);
        Self {
            sent_ns,
            public,
            zid: padded,
        }
    }

    /// The client's zenoh id; `None` when the field holds none (or no ASCII).
    pub fn zid(&self) -> Option<&str> {
        let len = self.zid.iter().position(|&b| b == 0).unwrap_or(32);
        let zid = core::str::from_utf8(&self.zid[..len]).ok()?;
        (!zid.is_empty() && zid.is_ascii()).then_some(zid)
    }

    /// The 73 bytes.
    pub fn encode(self) -> [u8; 73] {
        let mut out = [0; 73];
        out[0] = CONTRACT_VERSION;
        out[1..9].copy_from_slice(&self.sent_ns.to_le_bytes());
        out[9..41].copy_from_slice(&self.public);
        out[41..73].copy_from_slice(&self.zid);
        out
    }

    /// From the payload; `None` for another size or version.
    pub fn decode(bytes: &[u8]) -> Option<Self> {
        let bytes = <&[u8; 73]>::try_from(bytes).ok()?;
        if bytes[0] != CONTRACT_VERSION {
            return None;
        }
        Some(Self {
            sent_ns: u64::from_le_bytes(bytes[1..9].try_into().ok()?),
            public: bytes[9..41].try_into().ok()?,
            zid: bytes[41..73].try_into().ok()?,
        })
    }
}

/// The bridge's answer to [`SessionOpen`]: version (u8, 3), the public [`SessionId`] (u128
/// LE, never zero) and the bridge's X25519 public key for this opening (32 bytes). 49
/// bytes. The session's secret is agreed from the two keys ([`KeyPair::agree`]); it never
/// travels, not even here.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SessionGrant {
    /// The session's public id (the client's liveliness token names it).
    pub session: SessionId,
    /// The bridge's X25519 public key.
    pub public: [u8; 32],
}

impl SessionGrant {
    /// Bytes on the wire.
    pub const SIZE: usize = 49;

    /// The 49 bytes.
    pub fn encode(self) -> [u8; 49] {
        let mut out = [0; 49];
        out[0] = CONTRACT_VERSION;
        out[1..17].copy_from_slice(&self.session.0.to_le_bytes());
        out[17..49].copy_from_slice(&self.public);
        out
    }

    /// From the reply's payload; `None` for another size or version, or a zero id.
    pub fn decode(bytes: &[u8]) -> Option<Self> {
        let bytes = <&[u8; 49]>::try_from(bytes).ok()?;
        if bytes[0] != CONTRACT_VERSION {
            return None;
        }
        let grant = Self {
            session: SessionId(u128::from_le_bytes(bytes[1..17].try_into().ok()?)),
            public: bytes[17..49].try_into().ok()?,
        };
        (grant.session.0 != 0).then_some(grant)
    }
}

/// One side's X25519 key pair for one session opening, made from 32 random bytes the caller
/// draws (this crate does no I/O). The session's secret ([`SessionToken`]) is agreed from
/// both sides' keys: anyone who sees the opening (a log, a peer on the path) sees the public
/// keys only. An active peer that answers the opening in the bridge's place is not kept out
/// by this (zenoh authentication and access control are: README, "Who is who").
pub struct KeyPair {
    secret: x25519_dalek::StaticSecret,
    public: [u8; 32],
}

impl fmt::Debug for KeyPair {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("KeyPair")
            .field("public", &self.public)
            .finish_non_exhaustive()
    }
}

/// The domain of the session's secret (so it is never the hash of anything else).
const SESSION_DOMAIN: &[u8] = b"motiond-session-v3";

impl KeyPair {
    /// The key pair of the 32 random bytes `random`.
    pub fn from_random(random: [u8; 32]) -> Self {
        let secret = x25519_dalek::StaticSecret::from(random);
        let public = x25519_dalek::PublicKey::from(&secret).to_bytes();
        Self { secret, public }
    }

    /// This side's public key.
    pub fn public(&self) -> [u8; 32] {
        self.public
    }

    /// The secret of session `session` opened with the client's key `client` and the
    /// bridge's key `bridge` (one of them this pair's): the first 16 bytes of SHA3-256 over
    /// `"motiond-session-v3"`, the X25519 shared secret, `client`, `bridge` and the session
    /// id (u128 LE). `None` when the other key is no usable public key (the shared secret
    /// is all zero) or the result is zero.
    pub fn agree(
        &self,
        client: [u8; 32],
        bridge: [u8; 32],
        session: SessionId,
    ) -> Option<SessionToken> {
        use sha3::Digest as _;
        let theirs = if client == self.public {
            bridge
        } else {
            client
        };
        let shared = self
            .secret
            .diffie_hellman(&x25519_dalek::PublicKey::from(theirs));
        if !shared.was_contributory() {
            return None;
        }
        let digest = sha3::Sha3_256::new()
            .chain_update(SESSION_DOMAIN)
            .chain_update(shared.as_bytes())
            .chain_update(client)
            .chain_update(bridge)
            .chain_update(session.0.to_le_bytes())
            .finalize();
        let mut token = [0; 16];
        token.copy_from_slice(&digest[..16]);
        let token = SessionToken(token);
        (!token.is_none()).then_some(token)
    }
}

/// The attachment of a command query, 49 bytes: version (u8, 3), the public [`SessionId`]
/// (u128 LE; zero without a session: stop and e-stop only), a counter (u64 LE, rising with
/// every request of the session), the client's CLOCK_MONOTONIC when it sent the request (u64
/// LE, ns), and a MAC (16 bytes): the first 16 bytes of HMAC-SHA3-256 keyed by the
/// session's [`SessionToken`] over `"motiond-request-v3"`, the identity the request is sent
/// under (its UTF-8 bytes, then a zero byte), the request's payload as sent (the
/// `CommandRequest`'s 64 bytes) and bytes 1 to 32 of this attachment (id, counter, time).
///
/// The secret never travels with a command: a peer that sees one cannot make another. The
/// bridge refuses a counter it has seen (or one more than 1024 below the highest it has
/// seen) — a command replayed is not applied twice — and judges the send time against the
/// session's own clock as it learnt it when the session opened: a request that arrives more
/// than the bridge's `max_delay` later than the session's fastest (a renewal held up in a
/// network buffer must not restart a jog after the network came back), or that says it was
/// sent that much (at least 2 s) later than it could have been, is refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RequestMeta {
    /// The session ([`SessionId`] zero: none).
    pub session: SessionId,
    /// The session's request counter.
    pub counter: u64,
    /// The client's monotonic clock at sending, ns.
    pub sent_ns: u64,
    /// The MAC ([`RequestMeta::sign`]).
    pub mac: [u8; 16],
}

/// The domain of the request MAC (so it is never the MAC of anything else).
const MAC_DOMAIN: &[u8] = b"motiond-request-v3";

impl RequestMeta {
    /// Bytes on the wire.
    pub const SIZE: usize = 49;

    /// The attachment of a request without a session (stop and e-stop).
    pub const fn sessionless(sent_ns: u64) -> Self {
        Self {
            session: SessionId(0),
            counter: 0,
            sent_ns,
            mac: [0; 16],
        }
    }

    /// The attachment of `request` (its payload's bytes as sent) under `identity`, signed
    /// with `token`.
    pub fn sign(
        token: SessionToken,
        identity: &str,
        request: &[u8],
        session: SessionId,
        counter: u64,
        sent_ns: u64,
    ) -> Self {
        let mut meta = Self {
            session,
            counter,
            sent_ns,
            mac: [0; 16],
        };
        meta.mac = meta.mac_with(token, identity, request);
        meta
    }

    /// Whether the MAC is that of `request` under `identity` with `token` (compared in
    /// constant time).
    pub fn verify(&self, token: SessionToken, identity: &str, request: &[u8]) -> bool {
        let expected = self.mac_with(token, identity, request);
        expected
            .iter()
            .zip(self.mac)
            .fold(0u8, |acc, (a, b)| acc | (a ^ b))
            == 0
    }

    fn mac_with(&self, token: SessionToken, identity: &str, request: &[u8]) -> [u8; 16] {
        use hmac::{Mac as _, SimpleHmac};
        let mut mac = SimpleHmac::<sha3::Sha3_256>::new_from_slice(&token.0)
            .expect("HMAC takes a key of any length");
        mac.update(MAC_DOMAIN);
        mac.update(identity.as_bytes());
        mac.update(&[0]);
        mac.update(request);
        mac.update(&self.encode()[1..33]);
        let full = mac.finalize().into_bytes();
        let mut out = [0; 16];
        out.copy_from_slice(&full[..16]);
        out
    }

    /// The 49 bytes.
    pub fn encode(&self) -> [u8; 49] {
        let mut out = [0; 49];
        out[0] = CONTRACT_VERSION;
        out[1..17].copy_from_slice(&self.session.0.to_le_bytes());
        out[17..25].copy_from_slice(&self.counter.to_le_bytes());
        out[25..33].copy_from_slice(&self.sent_ns.to_le_bytes());
        out[33..49].copy_from_slice(&self.mac);
        out
    }

    /// From the attachment's bytes; `None` for another size or version.
    pub fn decode(bytes: &[u8]) -> Option<Self> {
        let bytes = <&[u8; 49]>::try_from(bytes).ok()?;
        if bytes[0] != CONTRACT_VERSION {
            return None;
        }
        Some(Self {
            session: SessionId(u128::from_le_bytes(bytes[1..17].try_into().ok()?)),
            counter: u64::from_le_bytes(bytes[17..25].try_into().ok()?),
            sent_ns: u64::from_le_bytes(bytes[25..33].try_into().ok()?),
            mac: bytes[33..49].try_into().ok()?,
        })
    }
}

/// Why the bridge itself refused a command (the server never saw it). Travels as the error
/// reply `"<code>: <text>"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Refusal {
    /// The bridge's config does not allow this command for this remote.
    NotAllowed,
    /// The remote sent more requests than its rate limit allows.
    RateLimited,
    /// The request arrived later than the bridge's `max_delay` after it was sent.
    Late,
    /// No motiond runs behind the bridge (or it is not answering).
    NoServer,
    /// The server did not answer in time.
    NoReply,
    /// The request is not a `CommandRequest` of this schema, or lacks its attachment.
    BadRequest,
    /// Too many requests are waiting for the server, or too many sessions are open; retry.
    Busy,
    /// The request needs a session and its attachment names none this bridge opened for
    /// the identity (open one on `motiond/<name>/session/<identity>`).
    NoSession,
}

impl Refusal {
    /// Every refusal.
    pub const ALL: [Self; 8] = [
        Self::NotAllowed,
        Self::RateLimited,
        Self::Late,
        Self::NoServer,
        Self::NoReply,
        Self::BadRequest,
        Self::Busy,
        Self::NoSession,
    ];

    /// The code that starts the error reply.
    pub const fn code(self) -> &'static str {
        match self {
            Self::NotAllowed => "not-allowed",
            Self::RateLimited => "rate-limited",
            Self::Late => "late",
            Self::NoServer => "no-server",
            Self::NoReply => "no-reply",
            Self::BadRequest => "bad-request",
            Self::Busy => "busy",
            Self::NoSession => "no-session",
        }
    }

    /// The error reply's text: `"<code>: <message>"`.
    pub fn reply_text(self, message: &str) -> String {
        format!("{}: {message}", self.code())
    }

    /// The refusal and its message from an error reply's text; `None` when it does not
    /// start with a known code.
    pub fn parse(text: &str) -> Option<(Self, &str)> {
        let (code, message) = text.split_once(": ")?;
        let refusal = Self::ALL.into_iter().find(|r| r.code() == code)?;
        Some((refusal, message))
    }
}

impl fmt::Display for Refusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.code())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_of_an_instance() -> Result<(), BadName> {
        let keys = Keys::new("demo")?;
        assert_eq!(keys.frame(), "motiond/demo/frame");
        assert_eq!(keys.state_json(), "motiond/demo/state/json");
        assert_eq!(keys.command("panel"), "motiond/demo/command/panel");
        assert_eq!(
            keys.identity_of("motiond/demo/command/panel"),
            Some("panel")
        );
        assert_eq!(keys.identity_of("motiond/other/command/panel"), None);
        assert_eq!(keys.identity_of("motiond/demo/command/a/b"), None);
        assert_eq!(keys.identity_of("motiond/demo/command"), Some(ANONYMOUS));
        assert_eq!(keys.identity_of("motiond/demo/commands"), None);
        assert_eq!(keys.session("panel"), "motiond/demo/session/panel");
        assert_eq!(
            keys.identity_of_session("motiond/demo/session/panel"),
            Some("panel")
        );
        assert_eq!(
            keys.identity_of_session("motiond/demo/session"),
            Some(ANONYMOUS)
        );
        assert_eq!(keys.identity_of_session("motiond/demo/command/panel"), None);
        assert_eq!(keys.identity_of_session("motiond/demo/sessions"), None);
        let token = keys.remote_token("panel", SessionId(0xab));
        assert_eq!(
            token,
            "motiond/demo/remote/panel/000000000000000000000000000000ab"
        );
        assert_eq!(
            keys.remote_of(&token),
            Some(("panel".to_owned(), SessionId(0xab)))
        );
        assert!(Keys::new("a/b").is_err());
        assert!(Keys::new("*").is_err());
        assert!(Keys::new("").is_err());
        assert!(check_chunk("remote identity", "@admin").is_err());
        assert!(check_chunk("remote identity", "op.alice-2").is_ok());
        Ok(())
    }

    /// The MAC of a known request, worked out independently of [`RequestMeta::sign`] (HMAC
    /// from its definition over SHA3-256, block 136 bytes): Python's
    /// `hmac.new(bytes([7]*16), msg, "sha3_256")` gives the same (python/tests/test_remote.py
    /// pins the same bytes).
    #[test]
    fn the_request_mac_is_hmac_sha3_256_of_the_documented_bytes() {
        use sha3::Digest as _;
        let token = SessionToken([7; 16]);
        let request: Vec<u8> = (0u8..64).collect();
        let meta = RequestMeta::sign(token, "panel", &request, SessionId(0x0102), 5, 1_000);
        let bytes = meta.encode();
        assert_eq!(bytes.len(), RequestMeta::SIZE);
        assert_eq!(bytes[0], 3);
        assert_eq!(&bytes[1..3], &[0x02, 0x01]);
        assert_eq!(&bytes[17..25], &5u64.to_le_bytes());
        assert_eq!(&bytes[25..33], &1_000u64.to_le_bytes());
        // HMAC by hand.
        let mut key = [0u8; 136];
        key[..16].copy_from_slice(&token.0);
        let pad = |byte: u8| key.iter().map(|k| k ^ byte).collect::<Vec<u8>>();
        let mut message = b"motiond-request-v3panel\0".to_vec();
        message.extend_from_slice(&request);
        message.extend_from_slice(&bytes[1..33]);
        let inner = sha3::Sha3_256::new()
            .chain_update(pad(0x36))
            .chain_update(&message)
            .finalize();
        let outer = sha3::Sha3_256::new()
            .chain_update(pad(0x5c))
            .chain_update(inner)
            .finalize();
        assert_eq!(&bytes[33..49], &outer[..16]);
        assert_eq!(
            hex(&bytes[33..49]),
            GOLDEN_MAC,
            "the golden MAC Python's test pins"
        );
        assert!(meta.verify(token, "panel", &request));
        // Another identity, request, counter or token: not the MAC.
        assert!(!meta.verify(token, "other", &request));
        let mut changed = request.clone();
        changed[8] ^= 1;
        assert!(!meta.verify(token, "panel", &changed));
        assert!(!meta.verify(SessionToken([8; 16]), "panel", &request));
        let replayed_later = RequestMeta { counter: 6, ..meta };
        assert!(!replayed_later.verify(token, "panel", &request));
        assert!(
            !format!("{meta:?}").contains("7, 7, 7"),
            "the secret is nowhere in it"
        );
    }

    /// The MAC of the test above, in hex (python/tests/test_remote.py has the same).
    const GOLDEN_MAC: &str = "e761b1d15721ac41efb5c765052e2456";

    fn hex(bytes: &[u8]) -> String {
        bytes.iter().map(|b| format!("{b:02x}")).collect()
    }

    #[test]
    fn attachments_round_trip_and_refuse_other_sizes() {
        let meta = RequestMeta::sign(SessionToken([7; 16]), "panel", &[1; 64], SessionId(9), 1, 2);
        let bytes = meta.encode();
        assert_eq!(bytes[0], 3);
        assert_eq!(RequestMeta::decode(&bytes), Some(meta));
        assert_eq!(RequestMeta::decode(&bytes[..48]), None);
        let mut other = bytes;
        other[0] = 2;
        assert_eq!(RequestMeta::decode(&other), None, "the old attachment");
        assert_eq!(
            RequestMeta::decode(&[2; 25]),
            None,
            "the old 25-byte attachment"
        );
        let none = RequestMeta::sessionless(77);
        assert_eq!(RequestMeta::decode(&none.encode()), Some(none));
        assert_eq!(Origin::decode(&Origin(77).encode()), Some(Origin(77)));
        assert_eq!(Origin::decode(&[1, 2, 3]), None);

        let open = SessionOpen::new(99, [3; 32], "a1b2c3");
        assert_eq!(open.zid(), Some("a1b2c3"));
        assert_eq!(SessionOpen::decode(&open.encode()), Some(open));
        assert_eq!(SessionOpen::decode(&open.encode()[..72]), None);
        assert_eq!(SessionOpen::new(1, [3; 32], "").zid(), None);
        assert_eq!(SessionOpen::decode(&[2; 9]), None, "the old opening");
        let grant = SessionGrant {
            session: SessionId(u128::MAX - 1),
            public: [0xa5; 32],
        };
        let bytes = grant.encode();
        assert_eq!(bytes.len(), SessionGrant::SIZE);
        assert_eq!(SessionGrant::decode(&bytes), Some(grant));
        let zero = SessionGrant {
            session: SessionId(0),
            ..grant
        };
        assert_eq!(SessionGrant::decode(&zero.encode()), None, "no zero id");
        assert_eq!(
            format!("{:?}", SessionToken([1; 16])),
            "SessionToken(…)",
            "never logged"
        );
    }

    /// Both sides agree on the session's secret from the two public keys; it is in neither
    /// message. Golden: the bridge's and the client's keys of bytes 1..=32 and 33..=64
    /// (python/tests/test_remote.py derives the same secret with `cryptography`'s X25519).
    #[test]
    fn both_sides_agree_on_a_secret_that_never_travels() {
        let client = KeyPair::from_random(core::array::from_fn(|i| i as u8 + 1));
        let bridge = KeyPair::from_random(core::array::from_fn(|i| i as u8 + 33));
        let session = SessionId(0x0102);
        let open = SessionOpen::new(5, client.public(), "c0ffee");
        let grant = SessionGrant {
            session,
            public: bridge.public(),
        };
        let on_client = client.agree(client.public(), grant.public, session);
        let on_bridge = bridge.agree(open.public, bridge.public(), session);
        assert!(on_client.is_some());
        assert_eq!(on_client, on_bridge);
        let token = on_client.expect("agreed");
        assert_eq!(hex(&token.0), GOLDEN_SECRET);
        for message in [&open.encode()[..], &grant.encode()[..]] {
            assert!(
                !message.windows(16).any(|window| window == token.0),
                "the secret is in a message"
            );
        }
        // Another session id: another secret; a key of all zeros (a low-order point): none.
        assert_ne!(
            client.agree(client.public(), grant.public, SessionId(3)),
            on_client
        );
        assert_eq!(bridge.agree([0; 32], bridge.public(), session), None);
    }

    /// The secret of the test above, in hex.
    const GOLDEN_SECRET: &str = "8b426f0d029361820a9f12a653f823b0";

    #[test]
    fn refusals_parse_back() {
        for refusal in Refusal::ALL {
            let text = refusal.reply_text("why: and more");
            assert_eq!(Refusal::parse(&text), Some((refusal, "why: and more")));
        }
        assert_eq!(Refusal::parse("nonsense"), None);
        assert_eq!(Refusal::parse("other: text"), None);
    }
}
