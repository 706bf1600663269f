//! Why an answer a client waited for is missing: the server's service does not exist, it
//! published nothing in time, no bridge answered, the bridge refused, or zenoh failed — kept
//! as a type (zenoh's and the codec's errors as their [`RemoteError`]), never as a string a
//! caller would have to parse.

use core::time::Duration;

use crate::RemoteError;

/// Why an answer is missing. Carried by [`ClientError::NotPublished`],
/// [`ClientError::Network`] and [`ConnectError::NoBridge`].
///
/// [`ClientError::NotPublished`]: crate::ClientError::NotPublished
/// [`ClientError::Network`]: crate::ClientError::Network
/// [`ConnectError::NoBridge`]: crate::ConnectError::NoBridge
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Unanswered {
    /// The server has no such service: it is older than the `motion-ipc` schema that added
    /// it.
    #[error("the service does not exist (a server older than motion-ipc schema {schema}?)")]
    NoService {
        /// The schema version that added the service.
        schema: u32,
    },
    /// Nothing arrived within the time allowed.
    #[error("nothing arrived within {0:?}")]
    Timeout(Duration),
    /// The server that runs now has published none (the one seen before restarted).
    #[error("none received from the server that runs now")]
    NotFromThisServer,
    /// A bridge was reached but did not answer on the key in time.
    #[error("no answer on {key} within {waited:?}")]
    NoAnswer {
        /// The zenoh key asked.
        key: String,
        /// The time allowed.
        waited: Duration,
    },
    /// No motion-bridge answers on the key at the endpoint.
    #[error("no motion-bridge answers on {key} at {endpoint}{hint}")]
    NoBridge {
        /// The zenoh key asked.
        key: String,
        /// The zenoh endpoint.
        endpoint: String,
        /// What to check (may be empty).
        hint: &'static str,
    },
    /// The bridge answered with a refusal; its words as it sent them.
    #[error("the bridge refused: {0}")]
    Refused(String),
    /// The bridge's answer is not the payload asked for.
    #[error("the bridge's answer on {key} is not a {payload}")]
    NotA {
        /// The zenoh key asked.
        key: String,
        /// The payload expected ("session grant").
        payload: &'static str,
    },
    /// The connection has no such thing (a client through a bridge has no tick event).
    #[error("{0}")]
    NotOnThisConnection(&'static str),
    /// zenoh or the wire codec failed: their error kept.
    #[error(transparent)]
    Remote(#[from] RemoteError),
}
