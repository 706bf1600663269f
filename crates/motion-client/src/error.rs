//! Errors of the client: [`ConnectError`] when reaching a server, [`ClientError`] after.

use core::time::Duration;

use motion_ipc::{CommandKind, Reason};

/// Why [`ClientBuilder::connect`](crate::ClientBuilder::connect) failed.
#[derive(Debug, thiserror::Error)]
pub enum ConnectError {
    /// No server of that name runs (its frame service does not exist).
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
    /// The instance name does not make a valid iceoryx2 service or node name.
    #[error("\"{name}\" is not a valid server name: {detail}")]
    BadName {
        /// The name given.
        name: String,
        /// What iceoryx2 said.
        detail: String,
    },
    /// iceoryx2 failed to create a node, port or wait set.
    #[error("iceoryx2 could not {what}: {detail}")]
    Ipc {
        /// What was being done.
        what: &'static str,
        /// The iceoryx2 error.
        detail: String,
    },
}

/// Why a read, a command or a wait failed.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    /// No axis of that name on the server.
    #[error("no axis named \"{0}\" on this server (see `motionctl list`)")]
    UnknownAxis(String),
    /// The server refused a command.
    #[error("{kind} on {axis} refused: {reason}")]
    Refused {
        /// The command.
        kind: &'static str,
        /// The axis name, or "all axes".
        axis: String,
        /// The server's typed reason.
        reason: Reason,
        /// The tick in which the server refused it.
        tick: u64,
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
    /// A wait ended because the axis can no longer get there (stopped, faulted, e-stop).
    #[error("axis {axis} will not {what}: {why}")]
    WaitAborted {
        /// The axis name.
        axis: String,
        /// What was awaited.
        what: &'static str,
        /// Why, in words.
        why: String,
    },
    /// SIGINT or SIGTERM arrived while waiting (iceoryx2's signal handling is on).
    #[error("interrupted")]
    Interrupted,
    /// iceoryx2 failed to send, receive or wait.
    #[error("iceoryx2 could not {what}: {detail}")]
    Ipc {
        /// What was being done.
        what: &'static str,
        /// The iceoryx2 error.
        detail: String,
    },
}

impl ClientError {
    /// The server's reason when this is a refusal.
    pub fn reason(&self) -> Option<Reason> {
        match self {
            Self::Refused { reason, .. } => Some(*reason),
            _ => None,
        }
    }

    pub(crate) fn ipc(what: &'static str, error: impl core::fmt::Debug) -> Self {
        Self::Ipc {
            what,
            detail: format!("{error:?}"),
        }
    }

    pub(crate) fn refused(kind: u32, axis: String, reason: Reason, tick: u64) -> Self {
        Self::Refused {
            kind: CommandKind::try_from(kind).map_or("command", CommandKind::name),
            axis,
            reason,
            tick,
        }
    }
}

impl ConnectError {
    pub(crate) fn ipc(what: &'static str, error: impl core::fmt::Debug) -> Self {
        Self::Ipc {
            what,
            detail: format!("{error:?}"),
        }
    }
}
