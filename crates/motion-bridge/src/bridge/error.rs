//! Why the bridge could not start or go on: the zenoh and iceoryx2 errors kept as their
//! sources, with what the bridge was doing.

use motion_wire::keys::BadName;

/// An error of a library the bridge calls, as the source of a [`BridgeError`].
pub type Source = Box<dyn std::error::Error + Send + Sync + 'static>;

/// Why the bridge could not start or run.
#[derive(Debug, thiserror::Error)]
pub enum BridgeError {
    /// The key expressions cannot be made from the server name.
    #[error(transparent)]
    Name(#[from] BadName),
    /// iceoryx2 refused a node, a service or a port, or a send or receive failed.
    #[error("iceoryx2 could not {what}: {source}")]
    Ipc {
        /// What the bridge was doing ("open motiond/demo/frame").
        what: String,
        /// iceoryx2's error.
        source: Source,
    },
    /// zenoh could not be configured or opened, or refused a declaration.
    #[error("zenoh could not {what}: {source}")]
    Zenoh {
        /// What the bridge was doing ("declare the command queryable").
        what: String,
        /// zenoh's error (or serde_json's, writing an endpoint list for zenoh's config).
        source: Source,
    },
    /// The thread that waits on the server's tick event could not start.
    #[error("cannot start the bridge's tick thread: {0}")]
    Thread(#[source] std::io::Error),
    /// The allow-list lets remotes do more than stop and e-stop, but zenoh authenticates
    /// nobody, and `--insecure` was not given.
    #[error("{0}")]
    Insecure(String),
}

impl BridgeError {
    /// iceoryx2's `source`, met doing `what`.
    pub(crate) fn ipc(
        what: impl Into<String>,
        source: impl std::error::Error + Send + Sync + 'static,
    ) -> Self {
        Self::Ipc {
            what: what.into(),
            source: Box::new(source),
        }
    }

    /// zenoh's `source`, met doing `what`.
    pub(crate) fn zenoh(what: impl Into<String>, source: impl Into<Source>) -> Self {
        Self::Zenoh {
            what: what.into(),
            source: source.into(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_library_error_stays_the_source() {
        let io = std::io::Error::new(std::io::ErrorKind::AddrInUse, "port taken");
        let error = BridgeError::zenoh("open the zenoh session", io);
        assert_eq!(
            error.to_string(),
            "zenoh could not open the zenoh session: port taken"
        );
        let source = std::error::Error::source(&error).expect("a source");
        assert_eq!(
            source
                .downcast_ref::<std::io::Error>()
                .map(std::io::Error::kind),
            Some(std::io::ErrorKind::AddrInUse)
        );
    }
}
