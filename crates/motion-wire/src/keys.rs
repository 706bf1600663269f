//! The network contract's names and small messages: zenoh key expressions, the attachments
//! that travel beside the payloads, and the bridge's own refusals.
//!
//! | key expression | what | payload | attachment |
//! |---|---|---|---|
//! | `motiond/<name>/frame` | put, every `1000 / frame_rate` ms of server ticks | [`MotionFrame`](motion_ipc::MotionFrame) | [`Origin`] |
//! | `motiond/<name>/info` | put on change; queryable (the newest) | [`ServerInfo`](motion_ipc::ServerInfo) | [`Origin`] |
//! | `motiond/<name>/stats` | put about 1 Hz; queryable | [`ServerStats`](motion_ipc::ServerStats) | [`Origin`] |
//! | `motiond/<name>/params` | queryable only (176 KiB) | [`MachineParams`](motion_ipc::MachineParams) | [`Origin`] |
//! | `motiond/<name>/state/json` | put at `json_rate` Hz | UTF-8 JSON (`crates/motion-bridge/README.md`, "The network contract") | – |
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

mod session;

pub use session::{
    CONTRACT_VERSION, KeyPair, RequestMeta, SessionGrant, SessionOpen, SessionToken,
};

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

    #[test]
    fn the_origin_is_16_bytes() {
        assert_eq!(Origin::decode(&Origin(77).encode()), Some(Origin(77)));
        assert_eq!(Origin::decode(&[1, 2, 3]), None);
    }

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
