//! A foreign peer's view: raw zenoh sessions, session openings and commands as bytes.

use core::time::Duration;

use motion_client::ipc::{CommandReply, CommandRequest};
use motion_wire::keys::{
    KeyPair, Keys, Origin, RequestMeta, SessionGrant, SessionId, SessionOpen, SessionToken,
};
use motion_wire::wire;
use zenoh::Wait as _;

use crate::{DEADLINE, Result};

/// zenoh's errors as the tests' errors.
pub trait Z<T> {
    fn z(self) -> Result<T>;
}

impl<T> Z<T> for zenoh::Result<T> {
    fn z(self) -> Result<T> {
        self.map_err(|error| error.to_string().into())
    }
}

/// What a request's attachment is made of: a session's secret and id (made up, or a
/// grant's) and the send time; [`Sign::meta`] makes the MAC for the request it goes with,
/// as a client does (a fresh counter each time).
#[derive(Debug, Clone, Copy)]
pub struct Sign {
    pub token: SessionToken,
    pub session: SessionId,
    pub sent_ns: u64,
}

/// The tests' request counters: rising, never one twice.
static COUNTER: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

impl Sign {
    /// Requests of the session `grant` opened, sent at `sent_ns`.
    pub fn of(grant: &Granted, sent_ns: u64) -> Self {
        Self {
            token: grant.token,
            session: grant.session,
            sent_ns,
        }
    }

    /// The attachment of `payload` sent under `identity`.
    pub fn meta(&self, identity: &str, payload: &[u8]) -> RequestMeta {
        let counter = COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        RequestMeta::sign(
            self.token,
            identity,
            payload,
            self.session,
            counter,
            self.sent_ns,
        )
    }
}

pub fn session(endpoint: &str) -> Result<zenoh::Session> {
    let mut config = zenoh::Config::default();
    config.insert_json5("mode", "\"client\"").z()?;
    config
        .insert_json5("scouting/multicast/enabled", "false")
        .z()?;
    config
        .insert_json5("connect/endpoints", &format!("[\"{endpoint}\"]"))
        .z()?;
    zenoh::open(config).wait().z()
}

/// A session the bridge opened: its public id and the secret both sides agreed on.
#[derive(Debug, Clone, Copy)]
pub struct Granted {
    pub session: SessionId,
    pub token: SessionToken,
}

/// The tests' session keys: a new one for every opening (not random: a counter, hashed by
/// X25519 itself; these are tests).
static KEYS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

/// Opens a session as `identity`, its query sent at `sent_ns` on the remote's clock: the
/// session, or the refusal's text.
pub fn open_session(
    session: &zenoh::Session,
    keys: &Keys,
    identity: &str,
    sent_ns: u64,
) -> Result<core::result::Result<Granted, String>> {
    let mut random = [0x5a; 32];
    let n = KEYS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    random[..8].copy_from_slice(&n.to_le_bytes());
    random[8..16].copy_from_slice(&u64::from(std::process::id()).to_le_bytes());
    let pair = KeyPair::from_random(random);
    let open = SessionOpen::new(sent_ns, pair.public(), &session.zid().to_string());
    let replies = session
        .get(keys.session(identity))
        .payload(open.encode().to_vec())
        .timeout(Duration::from_secs(5))
        .wait()
        .z()?;
    let reply = replies
        .recv_timeout(DEADLINE)
        .z()?
        .ok_or("no answer to a session opening")?;
    Ok(match reply.result() {
        Ok(sample) => {
            let grant = SessionGrant::decode(&sample.payload().to_bytes())
                .ok_or("a session grant of the wrong size")?;
            let token = pair
                .agree(open.public, grant.public, grant.session)
                .ok_or("no secret agreed")?;
            Ok(Granted {
                session: grant.session,
                token,
            })
        }
        Err(error) => Err(error.payload().try_to_string()?.into_owned()),
    })
}

/// Sends `request` as `identity` with an attachment signed as `sign` says (none: no
/// attachment); the reply's payload or the refusal's text.
pub fn command(
    session: &zenoh::Session,
    keys: &Keys,
    identity: &str,
    request: &CommandRequest,
    sign: Option<Sign>,
) -> Result<core::result::Result<(CommandReply, Origin), String>> {
    let payload = wire::encode(request);
    let mut get = session
        .get(keys.command(identity))
        .payload(payload.clone())
        .timeout(Duration::from_secs(5));
    if let Some(sign) = sign {
        get = get.attachment(sign.meta(identity, &payload).encode());
    }
    let replies = get.wait().z()?;
    let reply = replies
        .recv_timeout(DEADLINE)
        .z()?
        .ok_or("no reply from the bridge")?;
    Ok(match reply.result() {
        Ok(sample) => {
            let origin = sample
                .attachment()
                .and_then(|bytes| Origin::decode(&bytes.to_bytes()))
                .ok_or("a reply without its origin")?;
            Ok((
                wire::decode::<CommandReply>(&sample.payload().to_bytes())?,
                origin,
            ))
        }
        Err(error) => Err(error.payload().try_to_string()?.into_owned()),
    })
}

/// Waits until the bridge has the server's description: until its subscriber gets the
/// server's sample, a moment after the bridge started, it answers every request
/// `no-server`.
pub fn wait_for_server(session: &zenoh::Session, keys: &Keys) -> Result {
    let until = std::time::Instant::now() + DEADLINE;
    loop {
        let reply = session
            .get(keys.info())
            .timeout(DEADLINE)
            .wait()
            .z()?
            .recv_timeout(DEADLINE)
            .z()?
            .ok_or("no answer for the description")?;
        match reply.into_result() {
            Ok(_) => return Ok(()),
            Err(error) => {
                let text = String::from_utf8_lossy(&error.payload().to_bytes()).into_owned();
                if !text.starts_with("no-server") || std::time::Instant::now() >= until {
                    return Err(format!("the bridge never had the server: {text}").into());
                }
                std::thread::sleep(Duration::from_millis(20));
            }
        }
    }
}
