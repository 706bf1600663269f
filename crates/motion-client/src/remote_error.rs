//! What the zenoh transport (feature `zenoh`) failed at, with the library's own error kept
//! as the source: zenoh's (not `Clone`, so boxed) or the wire codec's
//! (`motion_wire::wire::WireError`, reached with `downcast_ref`).

/// The error of a library under the remote transport.
pub type RemoteSource = Box<dyn std::error::Error + Send + Sync + 'static>;

/// Why the zenoh transport of a remote client failed. Carried by
/// [`ClientError::Remote`](crate::ClientError::Remote) and
/// [`ConnectError::Remote`](crate::ConnectError::Remote).
#[derive(Debug, thiserror::Error)]
pub enum RemoteError {
    /// zenoh refused: its config, the session, a subscription, a query, a liveliness token.
    #[error("zenoh could not {what}: {source}")]
    Zenoh {
        /// What the client was doing ("open a session", "read zenoh's config f.json5").
        what: String,
        /// zenoh's error.
        source: RemoteSource,
    },
    /// The bridge sent a payload this build cannot read (another size: the server or the
    /// bridge was built against another `motion-ipc` schema).
    #[error(
        "motiond \"{server}\" sent a payload this client cannot read ({source}): rebuild the \
         client, the bridge or the server from the same source"
    )]
    Payload {
        /// The instance name.
        server: String,
        /// The codec's error (`motion_wire::wire::WireError`): which payload, how many bytes.
        source: RemoteSource,
    },
}

#[cfg(feature = "zenoh")]
impl RemoteError {
    /// zenoh's `source`, met doing `what`.
    pub(crate) fn zenoh(what: impl Into<String>, source: impl Into<RemoteSource>) -> Self {
        Self::Zenoh {
            what: what.into(),
            source: source.into(),
        }
    }

    /// A payload of `server` the codec refused.
    pub(crate) fn payload(server: &str, source: motion_wire::wire::WireError) -> Self {
        Self::Payload {
            server: server.to_owned(),
            source: Box::new(source),
        }
    }
}

#[cfg(all(test, feature = "zenoh"))]
mod tests {
    use motion_ipc::CommandReply;
    use motion_wire::wire::{self, WireError};

    use super::*;

    #[test]
    fn the_codec_error_stays_the_source() {
        let short = wire::decode::<CommandReply>(&[0; 3]).expect_err("3 bytes are no reply");
        let error = RemoteError::payload("demo", short);
        assert!(
            error.to_string().contains("CommandReply of 3 bytes"),
            "{error}"
        );
        let source = std::error::Error::source(&error).expect("a source");
        assert_eq!(source.downcast_ref::<WireError>(), Some(&short));
    }
}
