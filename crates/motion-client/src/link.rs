//! The connection to a bridge (feature `zenoh`): the zenoh session, its keys, feeds,
//! fetches and the command query. [`Client`](crate::Client) holds one when it is remote
//! (`remote.rs` connects it); this module knows nothing of `Client`.

use core::fmt;
use core::time::Duration;
use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::time::Instant;

use motion_ipc::{CommandKind, CommandReply, CommandRequest};
use motion_wire::keys::{
    KeyPair, Keys, Origin, Refusal, RequestMeta, SessionGrant, SessionId, SessionOpen, SessionToken,
};
use motion_wire::wire::{self, Payload};
use zenoh::Wait as _;
use zenoh::handlers::RingChannel;
use zenoh::liveliness::LivelinessToken;
use zenoh::sample::Sample;

use std::rc::Rc;

use iceoryx2::service::Service;
use motion_ipc::{MachineParams, ServerStats};

use crate::feed::{Feed, Owned};
use crate::received::LatestCache;
use crate::received::Received;
use crate::{ClientError, ConnectError, RemoteError, Unanswered};

/// Samples a feed keeps when the program does not read them (the oldest go first, as
/// over shared memory).
const FEED_DEPTH: usize = 32;
/// The identity a client uses when none is given.
pub const DEFAULT_IDENTITY: &str = motion_wire::keys::ANONYMOUS;

/// Where and as whom a remote client connects (remote when `endpoint` is set).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct RemoteOptions {
    pub(crate) endpoint: Option<String>,
    pub(crate) identity: String,
    pub(crate) zenoh_config: Option<PathBuf>,
}

impl Default for RemoteOptions {
    fn default() -> Self {
        Self {
            endpoint: None,
            identity: DEFAULT_IDENTITY.to_owned(),
            zenoh_config: None,
        }
    }
}

fn owned<T: Payload>(sample: &Sample, server: &str) -> Result<Owned<T>, ClientError> {
    Ok(owned_remote(sample, server)?)
}

/// [`owned`], with the codec's error as the transport's.
fn owned_remote<T: Payload>(sample: &Sample, server: &str) -> Result<Owned<T>, RemoteError> {
    let value = wire::decode_boxed::<T>(&sample.payload().to_bytes())
        .map_err(|error| RemoteError::payload(server, error))?;
    let origin = sample
        .attachment()
        .and_then(|bytes| Origin::decode(&bytes.to_bytes()))
        .unwrap_or_default();
    Ok(Owned {
        value,
        origin: origin.0,
    })
}

/// The session the bridge opened for this client (its public id, the secret both sides
/// agreed on), and the liveliness token that names it.
struct Granted {
    session: SessionId,
    secret: SessionToken,
    _token: LivelinessToken,
}

/// A connection to a bridge.
pub(crate) struct Link {
    session: zenoh::Session,
    keys: Keys,
    endpoint: String,
    identity: String,
    server: String,
    epoch: Instant,
    /// `None` until the bridge opened a session (it may refuse: an identity allowed only
    /// stop and e-stop, a full table); stop and e-stop go without one.
    granted: RefCell<Option<Granted>>,
    /// The last request counter used (every request of a session a new one).
    counter: core::cell::Cell<u64>,
}

impl fmt::Debug for Link {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Link")
            .field("endpoint", &self.endpoint)
            .field("identity", &self.identity)
            .field(
                "session",
                &self.granted.borrow().as_ref().map(|g| g.session),
            )
            .finish_non_exhaustive()
    }
}

fn bad_name(error: impl fmt::Display, name: &str) -> ConnectError {
    ConnectError::BadName {
        name: name.to_owned(),
        detail: error.to_string(),
    }
}

/// zenoh's config of a remote client: `base` (TLS, credentials) if given, client mode,
/// connecting to `endpoint`, no multicast scouting.
pub(crate) fn zenoh_config(
    base: Option<&Path>,
    endpoint: &str,
) -> Result<zenoh::Config, RemoteError> {
    let mut config = match base {
        Some(path) => zenoh::Config::from_file(path).map_err(|error| {
            RemoteError::zenoh(format!("read its config {}", path.display()), error)
        })?,
        None => zenoh::Config::default(),
    };
    let endpoints = format!("[\"{}\"]", endpoint.replace(['"', '\\'], ""));
    for (key, value) in [
        ("mode", "\"client\""),
        ("scouting/multicast/enabled", "false"),
        ("connect/endpoints", endpoints.as_str()),
    ] {
        config.insert_json5(key, value).map_err(|error| {
            RemoteError::zenoh(format!("set {key} = {value} in its config"), error)
        })?;
    }
    Ok(config)
}

impl Link {
    /// Opens a zenoh session to the bridge at `endpoint` for the instance `server`,
    /// retrying until `deadline`, and asks the bridge for a session (declaring this
    /// client's liveliness under it); without one (refused, or no bridge yet) stop and
    /// e-stop still go, and other commands ask again.
    pub(crate) fn open(
        options: &RemoteOptions,
        endpoint: &str,
        server: &str,
        deadline: Instant,
    ) -> Result<Self, ConnectError> {
        let keys = Keys::new(server).map_err(|error| bad_name(error, server))?;
        motion_wire::keys::check_chunk("remote identity", &options.identity)
            .map_err(|error| bad_name(error, &options.identity))?;
        let config = zenoh_config(options.zenoh_config.as_deref(), endpoint)?;
        let session = loop {
            match zenoh::open(config.clone()).wait() {
                Ok(session) => break session,
                Err(error) if Instant::now() >= deadline => {
                    return Err(ConnectError::NoBridge {
                        name: server.to_owned(),
                        endpoint: endpoint.to_owned(),
                        why: RemoteError::zenoh("open a session", error).into(),
                    });
                }
                Err(_) => std::thread::sleep(Duration::from_millis(100)),
            }
        };
        let link = Self {
            session,
            keys,
            endpoint: endpoint.to_owned(),
            identity: options.identity.clone(),
            server: server.to_owned(),
            epoch: Instant::now(),
            granted: RefCell::new(None),
            counter: core::cell::Cell::new(0),
        };
        let wait = deadline
            .saturating_duration_since(Instant::now())
            .clamp(Duration::from_millis(200), Duration::from_secs(2));
        // Not fatal: refused (an identity that may only stop, a full table) it goes on
        // without a session; unanswered, the description's fetch says no bridge answers.
        let _refused_or_unanswered = link.open_session(wait);
        Ok(link)
    }

    /// Asks the bridge for a session (waiting up to `timeout`) and declares this client's
    /// liveliness under its public id.
    fn open_session(&self, timeout: Duration) -> Result<(), ClientError> {
        let mut random = [0u8; 32];
        std::io::Read::read_exact(
            &mut std::fs::File::open("/dev/urandom").map_err(|error| {
                RemoteError::zenoh("read /dev/urandom for a session key", error)
            })?,
            &mut random,
        )
        .map_err(|error| RemoteError::zenoh("read /dev/urandom for a session key", error))?;
        let keys = KeyPair::from_random(random);
        let open = SessionOpen::new(
            self.clock_ns(),
            keys.public(),
            &self.session.zid().to_string(),
        );
        let key = self.keys.session(&self.identity);
        let replies = self
            .session
            .get(&key)
            .payload(open.encode().to_vec())
            .timeout(timeout)
            .express(true)
            .wait()
            .map_err(|error| RemoteError::zenoh("ask the bridge for a session", error))?;
        let answer = match replies.recv_timeout(timeout) {
            Ok(Some(answer)) => answer,
            Ok(None) | Err(_) => {
                return Err(ClientError::Network {
                    what: "open a session",
                    why: Unanswered::NoBridge {
                        key,
                        endpoint: self.endpoint.clone(),
                        hint: "",
                    },
                });
            }
        };
        let grant = match answer.result() {
            Ok(sample) => SessionGrant::decode(&sample.payload().to_bytes()).ok_or_else(|| {
                ClientError::Network {
                    what: "open a session",
                    why: Unanswered::NotA {
                        key: key.clone(),
                        payload: "session grant",
                    },
                }
            })?,
            Err(error) => {
                let text = error
                    .payload()
                    .try_to_string()
                    .map_or_else(|_| String::new(), |text| text.into_owned());
                return Err(refusal("session", &text, timeout));
            }
        };
        let secret = keys
            .agree(open.public, grant.public, grant.session)
            .ok_or_else(|| ClientError::Network {
                what: "open a session",
                why: Unanswered::NotA {
                    key: key.clone(),
                    payload: "session grant with a usable X25519 key",
                },
            })?;
        let token = self
            .session
            .liveliness()
            .declare_token(self.keys.remote_token(&self.identity, grant.session))
            .wait()
            .map_err(|error| RemoteError::zenoh("declare this client's liveliness", error))?;
        *self.granted.borrow_mut() = Some(Granted {
            session: grant.session,
            secret,
            _token: token,
        });
        Ok(())
    }

    /// This client's monotonic clock, ns since the link opened.
    fn clock_ns(&self) -> u64 {
        u64::try_from(self.epoch.elapsed().as_nanos()).unwrap_or(u64::MAX)
    }

    /// The newest `T` on `key`, asked of the bridge until it has one or `deadline` passes.
    pub(crate) fn first<T: Payload>(
        &self,
        key: &str,
        deadline: Instant,
    ) -> Result<Owned<T>, Unanswered> {
        loop {
            let remaining = deadline.saturating_duration_since(Instant::now());
            let attempt = remaining.clamp(Duration::from_millis(200), Duration::from_secs(1));
            match self.fetch::<T>(key, attempt) {
                Ok(value) => return Ok(value),
                Err(why) if Instant::now() >= deadline => return Err(why),
                Err(_) => std::thread::sleep(Duration::from_millis(50)),
            }
        }
    }

    /// The newest `T` on `key`, asked of the bridge.
    pub(crate) fn fetch<T: Payload>(
        &self,
        key: &str,
        timeout: Duration,
    ) -> Result<Owned<T>, Unanswered> {
        let replies = self
            .session
            .get(key)
            .timeout(timeout)
            .wait()
            .map_err(|error| RemoteError::zenoh(format!("ask {key}"), error))?;
        match replies.recv_timeout(timeout + Duration::from_millis(100)) {
            Ok(Some(reply)) => match reply.result() {
                Ok(sample) => Ok(owned_remote::<T>(sample, &self.server)?),
                Err(error) => Err(Unanswered::Refused(
                    error
                        .payload()
                        .try_to_string()
                        .map_or_else(|_| "(not text)".to_owned(), |text| text.into_owned()),
                )),
            },
            Ok(None) => Err(Unanswered::NoAnswer {
                key: key.to_owned(),
                waited: timeout,
            }),
            Err(_) => Err(Unanswered::NoBridge {
                key: key.to_owned(),
                endpoint: self.endpoint.clone(),
                hint: "",
            }),
        }
    }

    /// A feed of `key`: subscribed when `subscribe`, else filled only by [`Feed::push`].
    pub(crate) fn feed<T: Payload>(
        &self,
        key: &str,
        subscribe: bool,
    ) -> Result<Feed<T>, RemoteError> {
        let subscriber = if subscribe {
            Some(
                self.session
                    .declare_subscriber(key)
                    .with(RingChannel::new(FEED_DEPTH))
                    .wait()
                    .map_err(|error| RemoteError::zenoh(format!("subscribe to {key}"), error))?,
            )
        } else {
            None
        };
        Ok(Feed::new(subscriber, self.server.clone(), owned::<T>))
    }

    /// The key of `what` ("frame", "info", "stats", "params").
    pub(crate) fn keys(&self) -> &Keys {
        &self.keys
    }

    /// The endpoint this client connected to.
    pub(crate) fn endpoint(&self) -> &str {
        &self.endpoint
    }

    /// The identity this client sends commands as.
    pub(crate) fn identity(&self) -> &str {
        &self.identity
    }

    /// Sends `request` through the bridge and waits up to `timeout` for the reply; the
    /// reply and the node of the server that sent it. A command other than stop and e-stop
    /// first opens a session if there is none, and once more if the bridge no longer knows
    /// this one (it restarted, or forgot it): the refused request never reached the server.
    pub(crate) fn command(
        &self,
        request: &CommandRequest,
        timeout: Duration,
    ) -> Result<(CommandReply, u128), ClientError> {
        let safety = matches!(request.kind(), Ok(CommandKind::Stop | CommandKind::EStop));
        if !safety && self.granted.borrow().is_none() {
            match self.open_session(timeout) {
                // An identity that may only stop gets no session: the command itself is
                // refused with what this identity may do.
                Err(ClientError::BridgeRefused { code, .. })
                    if code == Refusal::NotAllowed.code() => {}
                other => other?,
            }
        }
        match self.send(request, timeout) {
            Err(ClientError::BridgeRefused { code, .. })
                if !safety && code == Refusal::NoSession.code() =>
            {
                *self.granted.borrow_mut() = None;
                self.open_session(timeout)?;
                self.send(request, timeout)
            }
            outcome => outcome,
        }
    }

    fn send(
        &self,
        request: &CommandRequest,
        timeout: Duration,
    ) -> Result<(CommandReply, u128), ClientError> {
        let kind = request.kind().map_or("command", CommandKind::name);
        // The session's secret never travels: a MAC made with it over the request does.
        let payload = wire::encode(request);
        let sent_ns = self.clock_ns();
        let meta = match self.granted.borrow().as_ref() {
            Some(granted) => {
                let counter = self.counter.get() + 1;
                self.counter.set(counter);
                RequestMeta::sign(
                    granted.secret,
                    &self.identity,
                    &payload,
                    granted.session,
                    counter,
                    sent_ns,
                )
            }
            None => RequestMeta::sessionless(sent_ns),
        };
        let key = self.keys.command(&self.identity);
        let replies = self
            .session
            .get(&key)
            .payload(payload)
            .attachment(meta.encode())
            .timeout(timeout)
            .express(true)
            .wait()
            .map_err(|error| RemoteError::zenoh("send a command", error))?;
        let answer = match replies.recv_timeout(timeout) {
            Ok(Some(answer)) => answer,
            Ok(None) => {
                return Err(ClientError::NoReply {
                    kind,
                    waited: timeout,
                });
            }
            Err(_) => {
                return Err(ClientError::Network {
                    what: "reach the bridge",
                    why: Unanswered::NoBridge {
                        key,
                        endpoint: self.endpoint.clone(),
                        hint: " (is it running, for this server? does zenoh's access control \
                               let this user send on that key?)",
                    },
                });
            }
        };
        match answer.result() {
            Ok(sample) => {
                let reply = wire::decode::<CommandReply>(&sample.payload().to_bytes())
                    .map_err(|error| RemoteError::payload(&self.server, error))?;
                let origin = sample
                    .attachment()
                    .and_then(|bytes| Origin::decode(&bytes.to_bytes()))
                    .unwrap_or_default();
                Ok((reply, origin.0))
            }
            Err(error) => {
                let text = error
                    .payload()
                    .try_to_string()
                    .map_or_else(|_| String::new(), |text| text.into_owned());
                Err(refusal(kind, &text, timeout))
            }
        }
    }
}

impl Link {
    /// The statistics feed: subscribed, with the bridge's newest first.
    pub(crate) fn stats_cache<S: Service>(
        &self,
        timeout: Duration,
    ) -> Option<LatestCache<S, ServerStats>> {
        let key = self.keys.stats();
        let feed = self.feed::<ServerStats>(&key, true).ok()?;
        if let Ok(newest) = self.fetch::<ServerStats>(&key, timeout.min(Duration::from_millis(300)))
        {
            feed.push(newest);
        }
        Some(LatestCache::remote(feed))
    }

    /// The machine parameters, asked of the bridge on every call (they are not published
    /// on the network: 176 KiB); the last ones received if the bridge has none now.
    pub(crate) fn machine_params<S: Service>(
        &self,
        slot: &RefCell<Option<Rc<LatestCache<S, MachineParams>>>>,
        timeout: Duration,
    ) -> Result<Received<S, MachineParams>, ClientError> {
        let key = self.keys.params();
        let cache = match slot.borrow().as_ref() {
            Some(cache) => Some(Rc::clone(cache)),
            None => None,
        };
        let cache = match cache {
            Some(cache) => cache,
            None => {
                let cache = Rc::new(LatestCache::remote(
                    self.feed::<MachineParams>(&key, false)?,
                ));
                *slot.borrow_mut() = Some(Rc::clone(&cache));
                cache
            }
        };
        // A bridge whose own subscriber has not yet received the server's sample (it
        // connected a moment ago) answers "no-server"; like the local client, wait up to the
        // reply timeout for it before saying the server published nothing.
        let started = std::time::Instant::now();
        let mut fetched = self.fetch::<MachineParams>(&key, timeout);
        while cache.current().is_none()
            && fetched.as_ref().is_err_and(|why| {
                matches!(why, Unanswered::Refused(text)
                        if matches!(Refusal::parse(text), Some((Refusal::NoServer, _))))
            })
            && started.elapsed() < timeout
        {
            std::thread::sleep(Duration::from_millis(10));
            fetched = self.fetch::<MachineParams>(&key, timeout.saturating_sub(started.elapsed()));
        }
        match fetched {
            Ok(params) => {
                if let Some(feed) = cache.feed() {
                    feed.push(params);
                }
            }
            Err(why) if cache.current().is_none() => {
                return Err(ClientError::NotPublished {
                    what: "machine parameters",
                    service: key,
                    why,
                });
            }
            Err(_) => {}
        }
        cache.refresh()?.ok_or_else(|| ClientError::NotPublished {
            what: "machine parameters",
            service: self.keys.params(),
            why: Unanswered::Timeout(timeout),
        })
    }
}

/// The error of a bridge's refusal text.
fn refusal(kind: &'static str, text: &str, waited: Duration) -> ClientError {
    match Refusal::parse(text) {
        Some((Refusal::NoServer, _)) => ClientError::NoServer { kind },
        Some((Refusal::NoReply, _)) => ClientError::NoReply { kind, waited },
        Some((refusal, message)) => ClientError::BridgeRefused {
            kind,
            code: refusal.code(),
            message: message.to_owned(),
        },
        None => ClientError::BridgeRefused {
            kind,
            code: "error",
            message: text.to_owned(),
        },
    }
}
