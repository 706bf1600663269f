//! The one shape of the services clients publish into and only the server takes from
//! (`paths`, `setpoints`): [`Inbox`] hands out each sample with the node that sent it —
//! read from the service's dynamic config (written by iceoryx2 when the publisher
//! connected), never from the payload — and counts the samples whose publisher had left
//! before the tick looked. What each service then does with a node's samples (the paths'
//! room, the setpoints' budget per tick) is its own module's rule.

use core::fmt::Debug;

use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2::sample::Sample;
use iceoryx2::service::port_factory::PortFactory as _;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory;
use motion_ipc::ClientId;

use crate::Ipc;
use crate::error::ServiceError;

/// The server's end of an inbox service: its subscriber, its port factory (whose dynamic
/// config names each publisher's node) and the nodes of the publishers seen so far.
#[derive(Debug)]
pub struct Inbox<T: Debug + ZeroCopySend + 'static> {
    subscriber: Subscriber<Ipc, T, ()>,
    factory: PortFactory<Ipc, T, ()>,
    /// Publisher id → its node, as the dynamic config said (ids are never reused;
    /// capacity reserved at start-up: cleared when full, never grown).
    nodes: Vec<(u128, ClientId)>,
    /// Samples whose publisher had left before the tick looked (dropped: nobody may
    /// claim them).
    pub orphans: u64,
}

impl<T: Debug + ZeroCopySend + 'static> Inbox<T> {
    /// Creates (or opens) `name` for payload `T`: no history, `buffer` samples a publisher
    /// may have queued, `borrowed` samples the server may hold, `max_clients` publishers
    /// and the server's one subscriber.
    pub fn create(
        node: &Node<Ipc>,
        name: &str,
        max_clients: usize,
        buffer: usize,
        borrowed: usize,
    ) -> Result<Self, ServiceError> {
        let service_name = ServiceName::new(name).map_err(|e| ServiceError::Name {
            what: "service",
            source: e.into(),
            name: name.to_owned(),
        })?;
        let factory = node
            .service_builder(&service_name)
            .publish_subscribe::<T>()
            .history_size(0)
            .subscriber_max_buffer_size(buffer)
            .subscriber_max_borrowed_samples(borrowed)
            .max_subscribers(1)
            .max_publishers(max_clients)
            .max_nodes(max_clients + 2)
            .enable_safe_overflow(true)
            .open_or_create()
            .map_err(|e| ServiceError::service(name, e))?;
        let subscriber = factory
            .subscriber_builder()
            .create()
            .map_err(|e| ServiceError::service(name, e))?;
        Ok(Self {
            subscriber,
            factory,
            nodes: Vec::with_capacity(max_clients + 2),
            orphans: 0,
        })
    }

    /// The next sample that arrived, with its sender's node; `None` when none is waiting.
    /// A sample whose publisher left before we looked is dropped and counted.
    pub fn take(&mut self) -> Option<(ClientId, Sample<Ipc, T, ()>)> {
        loop {
            let sample = self.subscriber.receive().ok().flatten()?;
            let publisher = sample.header().publisher_id().value();
            match self.node_of(publisher) {
                Some(node) => return Some((node, sample)),
                None => self.orphans += 1,
            }
        }
    }

    /// Publishers connected now (for the "all slots taken" report).
    pub fn publishers(&self) -> usize {
        self.factory.dynamic_config().number_of_publishers()
    }

    /// The node of `publisher`, from the cache or the service's dynamic config.
    fn node_of(&mut self, publisher: u128) -> Option<ClientId> {
        if let Some((_, node)) = self.nodes.iter().find(|(id, _)| *id == publisher) {
            return Some(*node);
        }
        let mut node = None;
        self.factory.dynamic_config().list_publishers(|details| {
            if details.publisher_id.value() == publisher {
                node = Some(ClientId::from_u128(details.node_id.value()));
                return CallbackProgression::Stop;
            }
            CallbackProgression::Continue
        });
        let node = node?;
        if self.nodes.len() == self.nodes.capacity() {
            self.nodes.clear();
        }
        self.nodes.push((publisher, node));
        Some(node)
    }
}
