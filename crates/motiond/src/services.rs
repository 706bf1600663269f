//! The iceoryx2 services of one instance (DESIGN.md "Shared-memory contract").

use iceoryx2::node::NodeView;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::server::Server;
use iceoryx2::prelude::*;
use motion_ipc::{
    CommandReply, CommandRequest, MotionFrame, ServerInfo, ServerStats, ServiceNames,
};

/// The service type motiond runs on: inter-process shared memory, single-threaded ports
/// (every port lives on the tick thread).
pub type Ipc = ipc::Service;

/// Every port the tick thread uses.
#[derive(Debug)]
pub struct Services {
    /// The node (owns the shared memory; dropping it releases everything).
    pub node: Node<Ipc>,
    /// `frame`, history 1.
    pub frame: Publisher<Ipc, MotionFrame, ()>,
    /// `tick` event.
    pub tick: Notifier<Ipc>,
    /// `command` request-response server.
    pub command: Server<Ipc, CommandRequest, (), CommandReply, ()>,
    /// `info`, history 1.
    pub info: Publisher<Ipc, ServerInfo, ()>,
    /// `stats`, history 1.
    pub stats: Publisher<Ipc, ServerStats, ()>,
}

/// Frames a subscriber can fall behind before the oldest is dropped (safe overflow).
pub const FRAME_BUFFER: usize = 32;

/// Requests a client may have outstanding at once.
pub const MAX_REQUESTS_PER_CLIENT: usize = 8;

impl Services {
    /// Creates the instance's services. Fails when another live motiond already serves
    /// `name` (the frame service exists and is not stale).
    pub fn create(name: &str, max_clients: usize) -> Result<Self, String> {
        let names = ServiceNames::new(name);
        let node_name = format!("motiond-{name}");
        let node = NodeBuilder::new()
            .name(
                &node_name
                    .as_str()
                    .try_into()
                    .map_err(|e| format!("node name {node_name:?}: {e:?}"))?,
            )
            .create::<Ipc>()
            .map_err(|e| format!("iceoryx2 node: {e:?}"))?;
        let service_name = |n: String| -> Result<ServiceName, String> {
            n.as_str()
                .try_into()
                .map_err(|e| format!("service name {n:?}: {e:?}"))
        };
        let max_nodes = max_clients + 2;
        let frame_name = service_name(names.frame())?;
        if node
            .service_builder(&frame_name)
            .publish_subscribe::<MotionFrame>()
            .open()
            .is_ok()
        {
            return Err(format!(
                "service {} exists: another motiond is serving instance `{name}`; stop it or pick another [server] name",
                names.frame()
            ));
        }
        let tick = node
            .service_builder(&service_name(names.tick())?)
            .event()
            .max_notifiers(1)
            .max_listeners(max_clients)
            .max_nodes(max_nodes)
            .open_or_create()
            .map_err(|e| format!("service {}: {e:?}", names.tick()))?
            .notifier_builder()
            .create()
            .map_err(|e| format!("tick notifier: {e:?}"))?;
        let command = node
            .service_builder(&service_name(names.command())?)
            .request_response::<CommandRequest, CommandReply>()
            .max_servers(1)
            .max_clients(max_clients)
            .max_nodes(max_nodes)
            .max_active_requests_per_client(MAX_REQUESTS_PER_CLIENT)
            .max_response_buffer_size(MAX_REQUESTS_PER_CLIENT)
            .enable_safe_overflow_for_responses(true)
            .open_or_create()
            .map_err(|e| format!("service {}: {e:?}", names.command()))?
            .server_builder()
            .create()
            .map_err(|e| format!("command server: {e:?}"))?;
        let info = state_publisher::<ServerInfo>(&node, &service_name(names.info())?, max_clients)?;
        let stats =
            state_publisher::<ServerStats>(&node, &service_name(names.stats())?, max_clients)?;
        // The frame service comes last: a client that sees it can open every other one.
        let frame = node
            .service_builder(&frame_name)
            .publish_subscribe::<MotionFrame>()
            .history_size(1)
            // A client that is late by up to FRAME_BUFFER ticks loses nothing (8 KiB each).
            .subscriber_max_buffer_size(FRAME_BUFFER)
            .max_subscribers(max_clients)
            .max_publishers(1)
            .max_nodes(max_nodes)
            .enable_safe_overflow(true)
            .create()
            .map_err(|e| {
                format!(
                    "service {}: {e:?} — is another motiond serving instance `{name}`? Stop it or pick another [server] name",
                    names.frame()
                )
            })?
            .publisher_builder()
            .create()
            .map_err(|e| format!("frame publisher: {e:?}"))?;
        Ok(Self {
            node,
            frame,
            tick,
            command,
            info,
            stats,
        })
    }
}

/// A publisher of a rarely changing state (info, stats): history 1, so a late subscriber
/// gets the current value at once.
fn state_publisher<T: core::fmt::Debug + ZeroCopySend + 'static>(
    node: &Node<Ipc>,
    name: &ServiceName,
    max_clients: usize,
) -> Result<Publisher<Ipc, T, ()>, String> {
    node.service_builder(name)
        .publish_subscribe::<T>()
        .history_size(1)
        .subscriber_max_buffer_size(1)
        .max_subscribers(max_clients)
        .max_publishers(1)
        .max_nodes(max_clients + 2)
        .open_or_create()
        .map_err(|e| format!("service {name}: {e:?}"))?
        .publisher_builder()
        .create()
        .map_err(|e| format!("{name} publisher: {e:?}"))
}

/// Removes the shared-memory leftovers of dead processes (a crashed motiond or client) and
/// returns the ids of the dead nodes found.
pub fn clean_dead_nodes() -> Vec<u128> {
    let mut dead = Vec::new();
    let _ = Node::<Ipc>::list(Config::global_config(), |state| {
        if let NodeState::Dead(view) = state {
            dead.push(view.id().value());
            let _ = view.try_remove_stale_resources();
        }
        CallbackProgression::Continue
    });
    dead
}

/// Live nodes other than `except`.
pub fn count_live_nodes(except: u128) -> u32 {
    let mut count = 0;
    let _ = Node::<Ipc>::list(Config::global_config(), |state| {
        if let NodeState::Alive(view) = &state
            && view.id().value() != except
        {
            count += 1;
        }
        CallbackProgression::Continue
    });
    count
}
