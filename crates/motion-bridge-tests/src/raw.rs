//! A foreign peer's view: raw zenoh sessions, session openings and commands as bytes.

use core::time::Duration;

use motion_client::ipc::{CommandReply, CommandRequest};
use motion_wire::keys::{Keys, Origin, RequestMeta, SessionGrant, SessionOpen};
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

/// Opens a session as `identity`, its query sent at `sent_ns` on the remote's clock: the
/// grant, or the refusal's text.
pub fn open_session(
    session: &zenoh::Session,
    keys: &Keys,
    identity: &str,
    sent_ns: u64,
) -> Result<core::result::Result<SessionGrant, String>> {
    let replies = session
        .get(keys.session(identity))
        .payload(SessionOpen { sent_ns }.encode().to_vec())
        .timeout(Duration::from_secs(5))
        .wait()
        .z()?;
    let reply = replies
        .recv_timeout(DEADLINE)
        .z()?
        .ok_or("no answer to a session opening")?;
    Ok(match reply.result() {
        Ok(sample) => Ok(SessionGrant::decode(&sample.payload().to_bytes())
            .ok_or("a session grant of the wrong size")?),
        Err(error) => Err(error.payload().try_to_string()?.into_owned()),
    })
}

/// Sends `request` as `identity` with `meta` (none: no attachment); the reply's payload or
/// the refusal's text.
pub fn command(
    session: &zenoh::Session,
    keys: &Keys,
    identity: &str,
    request: &CommandRequest,
    meta: Option<RequestMeta>,
) -> Result<core::result::Result<(CommandReply, Origin), String>> {
    let mut get = session
        .get(keys.command(identity))
        .payload(wire::encode(request))
        .timeout(Duration::from_secs(5));
    if let Some(meta) = meta {
        get = get.attachment(meta.encode());
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
