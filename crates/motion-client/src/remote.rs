//! The zenoh transport (feature `zenoh`): the same [`Client`](crate::Client) API over a
//! network to a `motion-bridge` in front of a motiond on another host.
//!
//! [`ClientBuilder::remote`](crate::ClientBuilder::remote) makes a client that reads the
//! server's description, frames, statistics and machine parameters from the bridge's zenoh
//! key expressions (the `motion-ipc` C layouts, little-endian: `motion_wire::wire`) and
//! sends commands through the bridge's command queryable under an identity
//! ([`ClientBuilder::identity`](crate::ClientBuilder::identity)) whose allow-list the bridge
//! applies. Payloads are copies (nothing is in shared memory here); everything else —
//! handles, waits, jog and claim guards, restart detection (the bridge passes the server's
//! node id along with every sample and reply) — behaves as over shared memory.
//!
//! Session: on connecting the client asks the bridge for a session (`motiond/<name>/session/
//! <identity>`) with an X25519 key of its own: a public id, named by this client's zenoh
//! liveliness token, and the bridge's key; both derive the session's secret, which never
//! travels — every command carries a MAC made with it and a counter
//! (`motion_wire::keys::RequestMeta`). Stop and e-stop go without
//! one (an identity allowed only those gets none; a bridge with its session table full
//! answers `busy` to other commands and still takes them); another command asks again when
//! the client has none, or once more when the bridge answers `no-session` (it restarted).
//!
//! Identity: the server sees the bridge's iceoryx2 node as the sender of every request, so
//! [`Client::id`](crate::Client::id) (this process's own node) is not what appears in
//! `claimed_by`; the bridge keeps claims apart between its remote clients.
//!
//! Differences: [`Client::tick_listener`](crate::Client::tick_listener) is not available
//! (there is no event to attach to a `WaitSet`), frames arrive at the bridge's
//! `frame_rate` (every 10th tick by default) rather than every tick, and the bridge may
//! refuse a command itself ([`ClientError::BridgeRefused`]): not on this identity's
//! allow-list, over its rate limit, or held up in the network for longer than the bridge
//! accepts.

use std::time::Instant;

use iceoryx2::service::Service;
use motion_ipc::{ServerInfo, ServiceNames};

use crate::client::check_schema;
pub use crate::link::DEFAULT_IDENTITY;
use crate::link::Link;
use crate::received::LatestCache;
use crate::session::Session;
use crate::{Client, ClientBuilder, ClientError, ConnectError};

impl<S: Service> Client<S> {
    /// Connects through the bridge of `remote` (see [`ClientBuilder::remote`]).
    pub(crate) fn connect_remote(
        options: &ClientBuilder,
        endpoint: &str,
    ) -> Result<Self, ConnectError> {
        let deadline = Instant::now() + options.connect_timeout;
        let server = options.server.clone();
        let names = ServiceNames::new(&server);
        let node = Self::make_node(options)?;
        let link = Link::open(&options.remote, endpoint, &server, deadline)?;
        let info_key = link.keys().info();
        // Subscribe first, so that no description published meanwhile is missed.
        let feed = link.feed::<ServerInfo>(&info_key, true)?;
        let first = link
            .first::<ServerInfo>(&info_key, deadline)
            .map_err(|why| ConnectError::NoBridge {
                name: server.clone(),
                endpoint: endpoint.to_owned(),
                why,
            })?;
        check_schema(&server, first.value.schema_version)?;
        let axis_count = first.value.axes().len();
        let session = Session::new(
            &server,
            first.origin,
            first.value.server_pid,
            first.value.start_time_ns,
        );
        feed.push(first);
        let info = LatestCache::remote(feed);
        info.refresh().map_err(|error| match error {
            ClientError::Remote(error) => ConnectError::Remote(error),
            ClientError::Connect(error) => error,
            other => ConnectError::Description(Box::new(other)),
        })?;
        let mut client = Self::assemble(options, server, node, names, info, session, axis_count);
        client.remote = Some(link);
        Ok(client)
    }

    /// The zenoh endpoint of the bridge this client talks through, when remote.
    pub fn remote_endpoint(&self) -> Option<&str> {
        self.remote.as_ref().map(Link::endpoint)
    }

    /// The identity this client sends commands as, when remote.
    pub fn remote_identity(&self) -> Option<&str> {
        self.remote.as_ref().map(Link::identity)
    }
}
