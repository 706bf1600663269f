//! The bridge's side of the network: one zenoh session (peer mode, listening), its
//! publishers, queryables and the liveliness of remote clients. Queries and liveliness
//! changes arrive on zenoh's threads and are handed to the bridge's loop as [`Event`]s.

use std::path::Path;
use std::sync::Arc;
use std::sync::mpsc::Sender;
use std::time::Instant;

use zenoh::Wait as _;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::{Publisher, Subscriber};
use zenoh::qos::CongestionControl;
use zenoh::query::Queryable;
use zenoh::sample::SampleKind;

use super::intake::Intake;
use super::{BridgeError, Event, Read};
use crate::config::BridgeConfig;
use crate::policy::RemoteRule;
use motion_wire::keys::Keys;

/// zenoh's config for a bridge: the file `base` (TLS, authentication, access control…) if
/// given, with `mode`, `listen` and `connect` set over it and multicast scouting off (peers
/// are named, nothing is sent to multicast groups).
pub fn zenoh_config(
    base: Option<&Path>,
    mode: &str,
    listen: &[String],
    connect: &[String],
) -> Result<zenoh::Config, BridgeError> {
    let mut config = match base {
        Some(path) => zenoh::Config::from_file(path).map_err(|error| {
            BridgeError::zenoh(format!("read its config {}", path.display()), error)
        })?,
        None => zenoh::Config::default(),
    };
    let list = |items: &[String]| {
        serde_json::to_string(items)
            .map_err(|error| BridgeError::zenoh("list the endpoints for its config", error))
    };
    let mut set = |key: &str, value: String| {
        config.insert_json5(key, &value).map_err(|error| {
            BridgeError::zenoh(format!("set {key} = {value} in its config"), error)
        })
    };
    set("mode", format!("\"{mode}\""))?;
    set("scouting/multicast/enabled", "false".to_owned())?;
    if !listen.is_empty() {
        set("listen/endpoints", list(listen)?)?;
    }
    if !connect.is_empty() {
        set("connect/endpoints", list(connect)?)?;
    }
    Ok(config)
}

/// How zenoh authenticates the remotes under `config`, if it does: users and passwords
/// checked against a dictionary, or TLS client certificates.
pub(crate) fn authentication(config: &zenoh::Config) -> Option<&'static str> {
    let set = |key: &str| {
        config
            .get_json(key)
            .is_ok_and(|value| !matches!(value.trim(), "null" | "false" | "\"\""))
    };
    if set("transport/auth/usrpwd/dictionary_file") {
        Some("user/password")
    } else if set("transport/link/tls/enable_mtls") {
        Some("TLS client certificates")
    } else {
        None
    }
}

/// Whether zenoh's access control is on under `config`.
pub(crate) fn access_control(config: &zenoh::Config) -> bool {
    config
        .get_json("access_control/enabled")
        .is_ok_and(|value| value.trim() == "true")
}

/// Refuses to start a bridge that lets remotes do more than stop and e-stop while zenoh
/// authenticates nobody (anyone who reaches the endpoint could claim any identity), unless
/// the config says `insecure` (`--insecure`); says so in the log when it does start so.
pub(super) fn check_exposure(
    config: &BridgeConfig,
    zenoh: &zenoh::Config,
) -> Result<(), BridgeError> {
    let wide: Vec<&RemoteRule> = config
        .remotes
        .iter()
        .filter(|rule| rule.allows_more_than_safety())
        .collect();
    if wide.is_empty() {
        return Ok(());
    }
    if let Some(how) = authentication(zenoh) {
        if !access_control(zenoh) {
            tracing::warn!(
                how,
                "zenoh authenticates users but has no access control: any user may send \
                 under any identity (crates/motion-bridge/README.md, \"Who is who\")"
            );
        }
        return Ok(());
    }
    let names = wide
        .iter()
        .map(|rule| format!("`{}`: {}", rule.identity, rule.allow.names().join(", ")))
        .collect::<Vec<_>>()
        .join("; ");
    if config.insecure {
        tracing::warn!(
            remotes = %names,
            "--insecure: zenoh authenticates nobody, so anyone who reaches {:?} may command \
             as these identities",
            config.listen
        );
        return Ok(());
    }
    Err(BridgeError::Insecure(format!(
        "the config lets remotes do more than stop and e-stop ({names}), but zenoh \
         authenticates nobody (no transport/auth/usrpwd dictionary_file, no TLS client \
         certificates in --zenoh-config): anyone who reaches {} could command as these \
         identities. Configure zenoh authentication and access control \
         (crates/motion-bridge/README.md, \"Who is who\"), or pass --insecure on a network \
         you trust",
        config.listen.join(", ")
    )))
}

/// The bridge's zenoh session and everything declared on it.
pub(crate) struct Net {
    pub(crate) session: zenoh::Session,
    pub(crate) frame: Publisher<'static>,
    pub(crate) info: Publisher<'static>,
    pub(crate) stats: Publisher<'static>,
    pub(crate) json: Publisher<'static>,
    _queryables: Vec<Queryable<()>>,
    _remotes: Subscriber<()>,
    _transports: zenoh::session::TransportEventsListener<()>,
    _token: LivelinessToken,
}

impl core::fmt::Debug for Net {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Net")
            .field("zid", &self.session.zid())
            .finish_non_exhaustive()
    }
}

impl Net {
    /// Opens the session with `config` and declares the bridge's keys; queries go to
    /// `intake`, remote liveliness to `events`.
    pub(crate) fn open(
        config: zenoh::Config,
        keys: &Keys,
        events: &Sender<Event>,
        intake: &Arc<Intake>,
    ) -> Result<Self, BridgeError> {
        let session = zenoh::open(config)
            .wait()
            .map_err(|error| BridgeError::zenoh("open the session", error))?;
        let publisher = |key: String, droppable: bool| {
            session
                .declare_publisher(key.clone())
                .congestion_control(if droppable {
                    CongestionControl::Drop
                } else {
                    CongestionControl::Block
                })
                .express(true)
                .wait()
                .map_err(|error| BridgeError::zenoh(format!("declare a publisher on {key}"), error))
        };
        let frame = publisher(keys.frame(), true)?;
        let json = publisher(keys.state_json(), true)?;
        let info = publisher(keys.info(), false)?;
        let stats = publisher(keys.stats(), false)?;

        let mut queryables = Vec::new();
        let commands = Arc::clone(intake);
        queryables.push(
            session
                .declare_queryable(keys.command_any())
                .callback(move |query| commands.command(query))
                .wait()
                .map_err(|error| BridgeError::zenoh("declare the command queryable", error))?,
        );
        let opens = Arc::clone(intake);
        queryables.push(
            session
                .declare_queryable(keys.session_any())
                .callback(move |query| {
                    let received = Instant::now();
                    opens.hand_over(Event::Open(query, received));
                })
                .wait()
                .map_err(|error| BridgeError::zenoh("declare the session queryable", error))?,
        );
        for (key, read) in [
            (keys.info(), Read::Info),
            (keys.stats(), Read::Stats),
            (keys.params(), Read::Params),
            (keys.frame(), Read::Frame),
        ] {
            let reads = Arc::clone(intake);
            queryables.push(
                session
                    .declare_queryable(key.clone())
                    .callback(move |query| reads.hand_over(Event::Read(read, query)))
                    .wait()
                    .map_err(|error| {
                        BridgeError::zenoh(format!("declare a queryable on {key}"), error)
                    })?,
            );
        }
        let remotes_events = events.clone();
        let remotes = session
            .liveliness()
            .declare_subscriber(keys.remote_tokens())
            .history(true)
            .callback(move |sample| {
                let _ = remotes_events.send(Event::Remote {
                    key: sample.key_expr().as_str().to_owned(),
                    alive: sample.kind() == SampleKind::Put,
                });
            })
            .wait()
            .map_err(|error| BridgeError::zenoh("watch remote clients' liveliness", error))?;
        // Which remotes are connected to the bridge itself: a session opened through one of
        // these transports ends when it closes.
        let transport_events = events.clone();
        let transports = session
            .info()
            .transport_events_listener()
            .history(true)
            .callback(move |event| {
                let _ = transport_events.send(Event::Transport {
                    zid: event.transport().zid().to_string(),
                    alive: event.kind() == SampleKind::Put,
                });
            })
            .wait()
            .map_err(|error| BridgeError::zenoh("watch the transports of remotes", error))?;
        let token = session
            .liveliness()
            .declare_token(keys.bridge_token())
            .wait()
            .map_err(|error| BridgeError::zenoh("declare the bridge's liveliness", error))?;
        Ok(Self {
            session,
            frame,
            info,
            stats,
            json,
            _queryables: queryables,
            _remotes: remotes,
            _transports: transports,
            _token: token,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn config(json5: &str) -> zenoh::Config {
        let mut config = zenoh::Config::default();
        for line in json5.lines().filter(|line| !line.trim().is_empty()) {
            let (key, value) = line.split_once('=').expect("key = value");
            config
                .insert_json5(key.trim(), value.trim())
                .expect("a zenoh config key");
        }
        config
    }

    #[test]
    fn authentication_is_a_dictionary_of_users_or_client_certificates() {
        assert_eq!(authentication(&zenoh::Config::default()), None);
        assert!(!access_control(&zenoh::Config::default()));
        // A user and password of the bridge's own authenticate nobody else.
        let own = config(
            "transport/auth/usrpwd/user = \"bridge\"\ntransport/auth/usrpwd/password = \"x\"",
        );
        assert_eq!(authentication(&own), None);
        let users = config("transport/auth/usrpwd/dictionary_file = \"/etc/users.txt\"");
        assert_eq!(authentication(&users), Some("user/password"));
        let certificates = config("transport/link/tls/enable_mtls = true");
        assert_eq!(
            authentication(&certificates),
            Some("TLS client certificates")
        );
        assert!(access_control(&config("access_control/enabled = true")));
    }
}
