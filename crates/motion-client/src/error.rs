//! Errors of the client: [`ConnectError`] when reaching a server, [`ClientError`] after,
//! [`EstopError`] when no path could deliver an e-stop.

use core::fmt;
use core::time::Duration;

use motion_ipc::{CommandKind, DeviceState, FaultCode, Reason};

use crate::{GroupAborted, GroupRefusal, Iceoryx2Error, TrajectoryError, Unanswered};

/// Why [`ClientBuilder::connect`](crate::ClientBuilder::connect) failed.
#[derive(Debug, thiserror::Error)]
pub enum ConnectError {
    /// No server of that name runs (its services do not exist).
    #[error(
        "no motiond server named \"{name}\" is running (waited {waited:?} for service \
         {service}); start one with `motiond --config config/sim.toml`, or pick another \
         name with --server"
    )]
    NoServer {
        /// The instance name asked for.
        name: String,
        /// The service that was missing.
        service: String,
        /// How long the client retried.
        waited: Duration,
    },
    /// The server runs but published no [`ServerInfo`](motion_ipc::ServerInfo) in time.
    #[error(
        "motiond \"{name}\" published no server description on {service} within {waited:?}; \
         is it still starting up?"
    )]
    NoInfo {
        /// The instance name.
        name: String,
        /// The info service.
        service: String,
        /// How long the client waited.
        waited: Duration,
    },
    /// The server was built against another version of the shared-memory contract.
    #[error(
        "motiond \"{name}\" speaks another motion-ipc schema (server {server}, this client \
         {client}; 0 = payload types differ): rebuild the client or the server from the same \
         source"
    )]
    SchemaMismatch {
        /// The instance name.
        name: String,
        /// The server's schema version; 0 when the payload types themselves differ.
        server: u32,
        /// This client's schema version.
        client: u32,
    },
    /// The instance name does not make a valid network key (remote clients, feature
    /// `zenoh`).
    #[error("\"{name}\" is not a valid server name: {detail}")]
    BadName {
        /// The name given.
        name: String,
        /// Why not, in words.
        detail: String,
    },
    /// The instance name, or the node name, does not make a valid iceoryx2 service or node
    /// name.
    #[error("\"{name}\" is not a valid iceoryx2 {kind} name")]
    InvalidName {
        /// The name given.
        name: String,
        /// "service" or "node".
        kind: &'static str,
        /// iceoryx2's error.
        #[source]
        source: Iceoryx2Error,
    },
    /// Every port of a kind that the server's service allows is taken by other clients.
    #[error(
        "the server's service {service} has no free {port} ([server] max_clients is reached): \
         end another client or raise max_clients"
    )]
    PortsExhausted {
        /// The service.
        service: String,
        /// The kind of port ("subscriber slot", "client slot").
        port: &'static str,
    },
    /// iceoryx2 failed to create a node, port or wait set.
    #[error("iceoryx2 could not {what}")]
    Ipc {
        /// What was being done ("create a node", "open an event service").
        what: &'static str,
        /// iceoryx2's error.
        #[source]
        source: Iceoryx2Error,
    },
    /// The server's description could not be read while connecting.
    #[error("could not read the server description")]
    Description(#[source] Box<ClientError>),
    /// No `motion-bridge` for the instance answered at the endpoint (remote clients,
    /// feature `zenoh`).
    #[error(
        "no motion-bridge for motiond \"{name}\" answers at {endpoint}: {why} (is the bridge \
         running with --server {name}, and the endpoint reachable?)"
    )]
    NoBridge {
        /// The instance name.
        name: String,
        /// The zenoh endpoint tried.
        endpoint: String,
        /// Why no answer came.
        why: Unanswered,
    },
    /// zenoh or the wire codec failed (remote clients, feature `zenoh`): their error kept.
    #[error(transparent)]
    Remote(#[from] crate::RemoteError),
}

/// The server that answered is not the one this client was talking to: it restarted (a new
/// process on the same instance name). Its goals, claims and jogs ended with the old server;
/// the new one starts every axis stopped. Carried by [`ClientError::ServerRestarted`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Restart {
    /// The instance name.
    pub server: String,
    /// Process id of the server this client knew (0 when unknown).
    pub old_pid: u32,
    /// Process id of the new server, once its description was read.
    pub new_pid: Option<u32>,
    /// How many restarts this client has seen, this one included.
    pub count: u64,
    /// Where it was seen: "server description", "frame", "command reply", "tick".
    pub seen_in: &'static str,
}

impl fmt::Display for Restart {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "motiond \"{}\" restarted (pid {}",
            self.server, self.old_pid
        )?;
        match self.new_pid {
            Some(pid) => write!(f, " → {pid}")?,
            None => f.write_str(" → a new process")?,
        }
        write!(
            f,
            ", seen in a {}): this client's goals, claims and jogs ended with the old server and \
             the new one starts every axis stopped; nothing is sent on their behalf",
            self.seen_in
        )
    }
}

/// One device and where it is in its life.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DeviceStatus {
    /// Device index (config order).
    pub index: usize,
    /// Device name.
    pub name: String,
    /// Its state in the newest frame.
    pub state: DeviceState,
}

impl fmt::Display for DeviceStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "device `{}` is {}", self.name, self.state.name())?;
        f.write_str(match self.state {
            DeviceState::Starting => {
                " (waiting for the board's first answer, its configuration and its start-up stop)"
            }
            DeviceState::Offline => " (its board is not answering or its link is down)",
            DeviceState::Faulted => {
                " (a board-level fault is latched: reset once its cause is gone)"
            }
            DeviceState::Online => "",
        })
    }
}

fn not_ready_text(devices: &[DeviceStatus], waited: &Duration) -> String {
    let list = devices
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join("; ");
    if devices
        .iter()
        .any(|device| device.state == DeviceState::Faulted)
    {
        format!("not ready: {list}")
    } else {
        format!("not ready within {waited:?}: {list}")
    }
}

fn known_groups(known: &[String]) -> String {
    if known.is_empty() {
        "the server has no groups ([[group]] in its config)".to_owned()
    } else {
        format!("its groups: {}", known.join(", "))
    }
}

fn refusal_text(reason: &Reason, detail: &Option<String>) -> String {
    detail
        .clone()
        .unwrap_or_else(|| reason.message().to_owned())
}

/// Why a read, a command or a wait failed.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// No axis of that name on the server.
    #[error("no axis named \"{0}\" on this server (see `motionctl list`)")]
    UnknownAxis(String),
    /// No signal of that name on the server.
    #[error("no signal named \"{0}\" on this server (see `motionctl io list`)")]
    UnknownSignal(String),
    /// No device of that name on the server.
    #[error("no device named \"{0}\" on this server (see `motionctl list`)")]
    UnknownDevice(String),
    /// No group of that name on the server.
    #[error("no group named \"{name}\" on this server; {}", known_groups(.known))]
    UnknownGroup {
        /// The name asked for.
        name: String,
        /// The groups the server has, in config order.
        known: Vec<String>,
    },
    /// The server refused a command to a group; the refusal names the point, the axis and
    /// the figures of a path, the axis and its holder of a claim.
    #[error("{0}")]
    GroupRefused(Box<GroupRefusal>),
    /// A group's motion ended before its end (a wait for it).
    #[error("{0}")]
    GroupAborted(Box<GroupAborted>),
    /// A wait for a group's motion to end ran out of time.
    #[error("group {group} did not finish within {waited:?} (it is {motion})")]
    GroupTimeout {
        /// The group's name.
        group: String,
        /// The time allowed.
        waited: core::time::Duration,
        /// Its motion when the time ran out ("moving", "held").
        motion: &'static str,
    },
    /// A wait for a group's motion ended because another motion replaced it, or the group
    /// went idle without ending it.
    #[error("group {group}: {why}")]
    GroupWaitAborted {
        /// The group's name.
        group: String,
        /// Why, in words.
        why: String,
    },
    /// A trajectory or a line's targets cannot be built or do not fit the group.
    #[error(transparent)]
    Trajectory(#[from] TrajectoryError),
    /// A path could not be published on the server's `paths` service.
    #[error("the path for group {group} was not sent: {why}")]
    PathNotSent {
        /// The group's name.
        group: String,
        /// Why, in words.
        why: String,
    },
    /// The feature needs shared memory: not through a bridge (remote clients).
    #[error(
        "{what} works only on the server's host for now (shared memory): connect without \
         --remote / ClientBuilder::remote"
    )]
    LocalOnly {
        /// What ("groups").
        what: &'static str,
    },
    /// The server sent an enumeration value this client does not know.
    #[error(
        "the server sent {what} {value}, which this client does not know (client and server \
         schema differ?)"
    )]
    UnknownValue {
        /// What it was ("group motion").
        what: &'static str,
        /// The raw value.
        value: u32,
    },
    /// The server refused a command.
    #[error("{kind} on {target} refused: {}", refusal_text(.reason, .detail))]
    Refused {
        /// The command.
        kind: &'static str,
        /// What it was about: "axis x", "signal lamp", "all axes".
        target: String,
        /// The server's typed reason.
        reason: Reason,
        /// The tick in which the server refused it.
        tick: u64,
        /// The reason in the words of this case ("device `six` is starting: …", the fault
        /// sentence of a faulted axis), when the client could say more than the reason code.
        detail: Option<String>,
    },
    /// No server listens on the command service any more.
    #[error("{kind} not sent: no motiond serves the command service any more (did it stop?)")]
    NoServer {
        /// The command.
        kind: &'static str,
    },
    /// The server did not answer a command in time.
    #[error("no reply from the server to {kind} within {waited:?}; is motiond still running?")]
    NoReply {
        /// The command.
        kind: &'static str,
        /// How long the client waited.
        waited: Duration,
    },
    /// No frame arrived in time.
    #[error("no frame from the server within {0:?}; is motiond still running?")]
    NoFrame(Duration),
    /// The server accepted an e-stop, but no frame of that tick or later showed it latched
    /// (another client's reset in between, or frames stopped).
    #[error(
        "the server accepted the e-stop in tick {tick}, but no frame showed it latched within \
         {waited:?} ({}); check the machine",
        match .newest { Some(tick) => format!("newest frame: tick {tick}"), None => "no frame came".to_owned() }
    )]
    EstopNotSeen {
        /// The tick the server accepted it in.
        tick: u64,
        /// How long frames were watched.
        waited: Duration,
        /// The newest frame's tick, if any came.
        newest: Option<u64>,
    },
    /// The server restarted under this client (see [`Restart`]). Goals are not sent to the
    /// new server until [`Client::acknowledge_restart`](crate::Client::acknowledge_restart);
    /// stops, e-stops and offs always are.
    #[error("{0}")]
    ServerRestarted(Restart),
    /// A wait for a condition on an axis ran out of time.
    #[error("axis {axis} did not {what} within {waited:?}")]
    WaitTimeout {
        /// The axis name.
        axis: String,
        /// What was awaited ("arrive", "finish homing").
        what: &'static str,
        /// The time allowed.
        waited: Duration,
    },
    /// A wait ended because the axis can no longer get there (stopped, e-stop, shutdown).
    #[error("axis {axis} will not {what}: {why}")]
    WaitAborted {
        /// The axis name.
        axis: String,
        /// What was awaited.
        what: &'static str,
        /// Why, in words.
        why: String,
    },
    /// The axis is faulted (a wait ended, or a goal was refused, because of it).
    #[error("{text}")]
    AxisFaulted {
        /// The axis name.
        axis: String,
        /// The fault.
        fault: FaultCode,
        /// The sentence of [`FaultCode::explain`]: the axis, the figure and the tolerance.
        text: String,
    },
    /// Devices were not online within the time allowed, or one is faulted.
    #[error("{}", not_ready_text(.devices, .waited))]
    NotReady {
        /// The devices that are not online.
        devices: Vec<DeviceStatus>,
        /// The time allowed.
        waited: Duration,
    },
    /// A wait for a signal value ran out of time.
    #[error("signal {signal} did not become {wanted} within {waited:?} (last value {last})")]
    SignalTimeout {
        /// The signal name.
        signal: String,
        /// What was awaited ("on", "1.25 bar ± 0.01").
        wanted: String,
        /// The last value seen ("off", "0.98 bar", "stale").
        last: String,
        /// The time allowed.
        waited: Duration,
    },
    /// The server does not publish something this client asked for.
    #[error("motiond published no {what} on {service}: {why}")]
    NotPublished {
        /// What ("machine parameters").
        what: &'static str,
        /// The service.
        service: String,
        /// Why: the service does not exist, or nothing arrived in time.
        why: Unanswered,
    },
    /// A service could not be opened (the server is gone, or its port slots are taken).
    #[error(transparent)]
    Connect(#[from] ConnectError),
    /// SIGINT or SIGTERM arrived while waiting (iceoryx2's signal handling is on).
    #[error("interrupted")]
    Interrupted,
    /// iceoryx2 failed to send, receive or wait.
    #[error("iceoryx2 could not {what}")]
    Ipc {
        /// What was being done ("send a command", "receive a sample").
        what: &'static str,
        /// iceoryx2's error.
        #[source]
        source: Iceoryx2Error,
    },
    /// The bridge between this client and the server refused the command itself (remote
    /// clients, feature `zenoh`); the server never saw it. `code` says why: `not-allowed`
    /// (not on this identity's allow-list), `rate-limited`, `late` (held up in the network
    /// longer than the bridge accepts), `bad-request`, `busy`.
    #[error("{kind} refused by the bridge ({code}): {message}")]
    BridgeRefused {
        /// The command.
        kind: &'static str,
        /// The bridge's refusal code.
        code: &'static str,
        /// The bridge's words.
        message: String,
    },
    /// The network transport failed (remote clients, feature `zenoh`).
    #[error("could not {what}: {why}")]
    Network {
        /// What was being done.
        what: &'static str,
        /// Why no answer came.
        why: Unanswered,
    },
    /// zenoh or the wire codec failed (remote clients, feature `zenoh`): their error kept.
    #[error(transparent)]
    Remote(#[from] crate::RemoteError),
}

impl ClientError {
    /// The server's reason when this is a refusal.
    pub fn reason(&self) -> Option<Reason> {
        match self {
            Self::Refused { reason, .. } => Some(*reason),
            Self::GroupRefused(refusal) => Some(refusal.reason),
            _ => None,
        }
    }

    /// The restart when this error reports one.
    pub fn restart(&self) -> Option<&Restart> {
        match self {
            Self::ServerRestarted(restart) => Some(restart),
            _ => None,
        }
    }

    pub(crate) fn ipc(what: &'static str, error: impl Into<Iceoryx2Error>) -> Self {
        Self::Ipc {
            what,
            source: error.into(),
        }
    }

    pub(crate) fn refused(
        kind: u32,
        target: String,
        reason: Reason,
        tick: u64,
        detail: Option<String>,
    ) -> Self {
        Self::Refused {
            kind: CommandKind::try_from(kind).map_or("command", CommandKind::name),
            target,
            reason,
            tick,
            detail,
        }
    }
}

impl ConnectError {
    pub(crate) fn ipc(what: &'static str, error: impl Into<Iceoryx2Error>) -> Self {
        Self::Ipc {
            what,
            source: error.into(),
        }
    }
}

/// `error` and its sources, joined by ": " (the words of every layer, iceoryx2's last).
pub(crate) fn with_causes(error: &dyn std::error::Error) -> String {
    let mut text = error.to_string();
    let mut cause = error.source();
    while let Some(inner) = cause {
        text.push_str(": ");
        text.push_str(&inner.to_string());
        cause = inner.source();
    }
    text
}

/// No path delivered an e-stop (see [`estop`](crate::estop)): what each one hit.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}", self.describe())]
pub struct EstopError {
    /// The instance name.
    pub server: String,
    /// Why the command path failed.
    pub command: String,
    /// Why the event path failed.
    pub event: String,
    /// Why the signal path failed.
    pub signal: String,
    /// Whether any trace of the server was found (a service or its node); `false` means no
    /// server of that name runs.
    pub server_found: bool,
    /// Set when the e-stop was sent by this path but no frame of the server showed it
    /// latched, with why: it may or may not have latched, so it is not reported as done.
    pub unconfirmed: Option<Box<(crate::EstopPath, String)>>,
}

impl EstopError {
    /// Sent by `path`, never seen latched (`why`).
    pub(crate) fn unconfirmed(server: &str, path: crate::EstopPath, why: String) -> Self {
        Self {
            server: server.to_owned(),
            command: String::new(),
            event: String::new(),
            signal: String::new(),
            server_found: true,
            unconfirmed: Some(Box::new((path, why))),
        }
    }

    fn describe(&self) -> String {
        match self.unconfirmed.as_deref() {
            Some((path, why)) => format!(
                "e-stop of motiond \"{}\" sent via {path} but NOT confirmed: {why}; check the \
                 machine and `motionctl status` before trusting it",
                self.server
            ),
            None => format!(
                "e-stop of motiond \"{}\" NOT delivered: command service: {}; estop event: {}; \
                 SIGUSR1: {}",
                self.server, self.command, self.event, self.signal
            ),
        }
    }
}
