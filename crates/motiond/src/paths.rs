//! The `paths` service: paths that clients send their groups (`GroupPath`, ≈400 KB each,
//! zero-copy), held until a `Run` command of the same node takes one.
//!
//! Every tick, before the engine steps, the inbox takes what arrived and notes for each
//! sample the node of the publisher that sent it — from the service's dynamic config,
//! written by iceoryx2 when the port connected, never from the payload. The engine then
//! asks for the newest path of an id from the node that sent the `Run`
//! (`CommandPort::take_path`). At most [`PATHS_HELD`] samples are held (the oldest goes);
//! nothing is copied and nothing allocated after start-up.

use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2::sample::Sample;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory;
use motion_ipc::{ClientId, GroupPath};

use crate::error::ServiceError;
use crate::services::Ipc;

/// Paths held between their arrival and their `Run` (newest kept).
pub const PATHS_HELD: usize = 3;

/// Paths a publisher may have queued for the server before it takes them (each tick).
pub const PATHS_BUFFER: usize = 2;

type PathSample = Sample<Ipc, GroupPath, ()>;

/// The `paths` service's port factory.
pub type PathsFactory = PortFactory<Ipc, GroupPath, ()>;

/// The server's subscriber to `paths` and the samples it holds.
#[derive(Debug)]
pub struct PathInbox {
    subscriber: Subscriber<Ipc, GroupPath, ()>,
    /// (sender's node, sample), oldest first.
    held: Vec<(ClientId, PathSample)>,
    /// The path the engine took last (alive until the next take).
    taken: Option<PathSample>,
    /// Samples dropped: no room, or their publisher's node unknown.
    pub dropped: u64,
}

/// Creates (or opens) `name` with room for `max_clients` publishers and the server.
pub fn create(
    node: &Node<Ipc>,
    name: &str,
    max_clients: usize,
) -> Result<(PathInbox, PathsFactory), ServiceError> {
    // The samples held, the one taken, and one being received.
    let (subscriber, factory) =
        crate::inbox::create(node, name, max_clients, PATHS_BUFFER, PATHS_HELD + 2)?;
    let inbox = PathInbox {
        subscriber,
        held: Vec::with_capacity(PATHS_HELD),
        taken: None,
        dropped: 0,
    };
    Ok((inbox, factory))
}

impl PathInbox {
    /// Takes every path that arrived since the last tick, each with its sender's node.
    pub fn receive(&mut self, factory: &PathsFactory) {
        while let Ok(Some(sample)) = self.subscriber.receive() {
            let publisher = sample.header().publisher_id().value();
            let Some(node) = crate::inbox::publisher_node(factory, publisher) else {
                // Its publisher left before we looked: nobody may run it.
                self.dropped += 1;
                continue;
            };
            if self.held.len() == PATHS_HELD {
                self.held.remove(0);
                self.dropped += 1;
            }
            self.held.push((node, sample));
        }
    }

    /// Whether a path `id` from `client` is held.
    pub fn holds(&self, client: ClientId, id: u64) -> bool {
        self.held
            .iter()
            .any(|(from, sample)| *from == client && sample.payload().id == id)
    }

    /// The newest path `id` from `client`, taken (a path runs once).
    pub fn take(&mut self, client: ClientId, id: u64) -> Option<&GroupPath> {
        let index = self
            .held
            .iter()
            .rposition(|(from, sample)| *from == client && sample.payload().id == id)?;
        let (_, sample) = self.held.remove(index);
        self.taken = Some(sample);
        self.taken.as_ref().map(|sample| sample.payload())
    }
}
