//! The shell's typed errors: what went wrong setting up the server, each with the text an
//! operator reads (and what to do about it).

use std::io;

/// A real-time set-up step that could not be done (the server may go on without it).
#[derive(Debug, thiserror::Error)]
pub enum RtError {
    /// `/dev/cpu_dma_latency` could not be opened.
    #[error("/dev/cpu_dma_latency: {0} (needs root or a udev rule)")]
    DmaLatencyOpen(#[source] io::Error),
    /// `/dev/cpu_dma_latency` could not be written.
    #[error("/dev/cpu_dma_latency: write: {0}")]
    DmaLatencyWrite(#[source] io::Error),
    /// `PR_SET_TIMERSLACK` failed.
    #[error("PR_SET_TIMERSLACK: {0}")]
    TimerSlack(#[source] nix::Error),
    /// `sched_setscheduler(SCHED_FIFO)` failed.
    #[error(
        "SCHED_FIFO priority {priority}: {source} (needs CAP_SYS_NICE or `ulimit -r {priority}`)"
    )]
    Fifo {
        /// The priority asked for.
        priority: u8,
        /// The system's answer.
        #[source]
        source: io::Error,
    },
    /// The configured core is not available to this process.
    #[error("cpu {0}: no such core available to this process")]
    NoSuchCpu(usize),
    /// `sched_setaffinity` failed.
    #[error("cpu {0}: sched_setaffinity failed")]
    Affinity(usize),
    /// `mlockall` failed.
    #[error("mlockall: {0} (raise RLIMIT_MEMLOCK, e.g. `ulimit -l unlimited`, or run as root)")]
    LockMemory(#[source] nix::Error),
}

/// The iceoryx2 services of an instance could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum ServiceError {
    /// A node or service name iceoryx2 refuses.
    #[error("{what} name {name:?}: {detail}")]
    Name {
        /// "node" or "service".
        what: &'static str,
        /// The name.
        name: String,
        /// iceoryx2's reason.
        detail: String,
    },
    /// The iceoryx2 node could not be created.
    #[error("iceoryx2 node: {0}")]
    Node(String),
    /// Another live motiond serves the instance.
    #[error(
        "another motiond (process {pid}) is serving instance `{instance}`; stop it or pick another [server] name"
    )]
    AnotherServer {
        /// Its process.
        pid: u32,
        /// The instance name.
        instance: String,
    },
    /// A service or one of its ports could not be made.
    #[error("service {service}: {detail}{hint}")]
    Service {
        /// The service name.
        service: String,
        /// iceoryx2's reason.
        detail: String,
        /// What to do about it ("" when nothing specific is known).
        hint: &'static str,
    },
}

impl ServiceError {
    /// Why `service` could not be made, with what to do about it.
    pub fn service(service: &str, error: impl core::fmt::Debug) -> Self {
        let detail = format!("{error:?}");
        let hint = if detail.contains("Incompatible") || detail.contains("incompatible") {
            " — the service exists with other settings (clients of a previous server still hold it, and this config changed max_clients or a payload): stop those clients, or keep the previous settings"
        } else if detail.contains("ExceedsMax") {
            " — its port slots are all taken (by clients of a previous server?)"
        } else {
            ""
        };
        Self::Service {
            service: service.to_owned(),
            detail,
            hint,
        }
    }
}

/// `$NOTIFY_SOCKET` is set but unusable.
#[derive(Debug, thiserror::Error)]
pub enum NotifyError {
    /// Not valid UTF-8.
    #[error("NOTIFY_SOCKET is not UTF-8")]
    NotUtf8,
    /// Neither `/path` nor `@name`.
    #[error("NOTIFY_SOCKET={0:?}: neither an absolute path nor an @abstract name")]
    BadTarget(String),
    /// The address could not be made.
    #[error("NOTIFY_SOCKET={target:?}: {source}")]
    Address {
        /// The value.
        target: String,
        /// The system's answer.
        #[source]
        source: io::Error,
    },
    /// No socket could be created.
    #[error("NOTIFY_SOCKET: cannot create a socket: {0}")]
    Socket(#[source] io::Error),
}

/// The tick thread could not start.
#[derive(Debug, thiserror::Error)]
pub enum StartError {
    /// The services could not be made.
    #[error(transparent)]
    Services(#[from] ServiceError),
    /// `--require-rt` and the real-time set-up is incomplete.
    #[error("--require-rt: real-time set-up incomplete ({summary}); {missing}")]
    RtIncomplete {
        /// What was achieved.
        summary: String,
        /// What is missing: the config key to set, or the steps that failed.
        missing: String,
    },
}
