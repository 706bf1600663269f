//! The iceoryx2 services of one instance (shared-memory contract in `crates/motion-ipc`):
//! creating them, taking them over after a crashed server, watching their port slots, and
//! telling the tick which node sent a request.

use crate::Ipc;
use crate::error::ServiceError;
use crate::paths::PathInbox;
use crate::setpoints::SetpointInbox;
use iceoryx2::node::NodeView;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::server::Server;
use iceoryx2::prelude::*;
use iceoryx2::service::port_factory::event::PortFactory as EventFactory;
use iceoryx2::service::port_factory::publish_subscribe::PortFactory as PubSubFactory;
use iceoryx2::service::port_factory::request_response::PortFactory as RequestResponseFactory;
use motion_ipc::{
    ClientId, CommandReply, CommandRequest, MachineParams, MotionFrame, ServerInfo, ServerStats,
    ServiceNames,
};

/// The command service's port factory.
pub type CommandFactory = RequestResponseFactory<Ipc, CommandRequest, (), CommandReply, ()>;

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
    /// `params`, history 1.
    pub params: Publisher<Ipc, MachineParams, ()>,
    /// `estop` event: any notification latches the e-stop.
    pub estop: Listener<Ipc>,
    /// `paths`: the groups' paths clients send, held for their `Run`.
    pub paths: PathInbox,
    /// `setpoints`: the groups' streamed setpoints.
    pub setpoints: SetpointInbox,
    /// The services themselves, for their port counts.
    pub factories: Factories,
    /// `max_clients` the services were made with.
    pub max_clients: usize,
}

/// The services' port factories (dynamic configs: which ports are connected).
#[derive(Debug)]
pub struct Factories {
    frame: PubSubFactory<Ipc, MotionFrame, ()>,
    info: PubSubFactory<Ipc, ServerInfo, ()>,
    stats: PubSubFactory<Ipc, ServerStats, ()>,
    params: PubSubFactory<Ipc, MachineParams, ()>,
    tick: EventFactory<Ipc>,
    estop: EventFactory<Ipc>,
    /// The command service.
    pub command: CommandFactory,
}

/// Frames a subscriber can fall behind before the oldest is dropped (safe overflow).
pub const FRAME_BUFFER: usize = 32;

/// Requests a client may have outstanding at once.
pub const MAX_REQUESTS_PER_CLIENT: usize = 8;

/// Notifier slots of the e-stop event per `max_clients`: its own pool, separate from the
/// command service's clients, so that exhausting one does not lock out the other.
pub const ESTOP_NOTIFIERS_PER_CLIENT: usize = 2;

/// One service whose port slots can run out, for the "all slots taken" report.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SlotUse {
    /// Bit of `ServerStats::full_services`.
    pub bit: u32,
    /// Service leaf name (`frame`) and what its slots are (`subscriber`).
    pub service: &'static str,
    /// What the slots are.
    pub slot: &'static str,
    /// Ports connected now.
    pub used: usize,
    /// Ports the service admits.
    pub limit: usize,
}

impl Factories {
    /// Port use of every service that clients connect to (`inboxes`: the publishers of
    /// `paths` and of `setpoints`, which their inboxes own).
    pub fn slot_use(&self, max_clients: usize, inboxes: [usize; 2]) -> [SlotUse; 9] {
        let sub = |bit, service, used| SlotUse {
            bit,
            service,
            slot: "subscriber",
            used,
            limit: max_clients,
        };
        [
            sub(
                ServerStats::FULL_FRAME,
                "frame",
                self.frame.dynamic_config().number_of_subscribers(),
            ),
            SlotUse {
                bit: ServerStats::FULL_TICK,
                service: "tick",
                slot: "listener",
                used: self.tick.dynamic_config().number_of_listeners(),
                limit: max_clients,
            },
            SlotUse {
                bit: ServerStats::FULL_COMMAND,
                service: "command",
                slot: "client",
                used: self.command.dynamic_config().number_of_clients(),
                limit: max_clients,
            },
            sub(
                ServerStats::FULL_INFO,
                "info",
                self.info.dynamic_config().number_of_subscribers(),
            ),
            sub(
                ServerStats::FULL_STATS,
                "stats",
                self.stats.dynamic_config().number_of_subscribers(),
            ),
            sub(
                ServerStats::FULL_PARAMS,
                "params",
                self.params.dynamic_config().number_of_subscribers(),
            ),
            SlotUse {
                bit: ServerStats::FULL_ESTOP,
                service: "estop",
                slot: "notifier",
                used: self.estop.dynamic_config().number_of_notifiers(),
                limit: max_clients * ESTOP_NOTIFIERS_PER_CLIENT,
            },
            SlotUse {
                bit: ServerStats::FULL_PATHS,
                service: "paths",
                slot: "publisher",
                used: inboxes[0],
                limit: max_clients,
            },
            SlotUse {
                bit: ServerStats::FULL_SETPOINTS,
                service: "setpoints",
                slot: "publisher",
                used: inboxes[1],
                limit: max_clients,
            },
        ]
    }
}

fn service_name(name: String) -> Result<ServiceName, ServiceError> {
    ServiceName::new(&name).map_err(|e| ServiceError::Name {
        what: "service",
        source: e.into(),
        name,
    })
}

impl Services {
    /// Port use of every service that clients connect to.
    pub fn slot_use(&self) -> [SlotUse; 9] {
        let inboxes = [
            self.paths.inbox.publishers(),
            self.setpoints.inbox.publishers(),
        ];
        self.factories.slot_use(self.max_clients, inboxes)
    }

    /// Creates the instance's services, or takes them over from a server that crashed while
    /// clients kept them open. Fails when another live motiond serves `name` (its node is
    /// alive), naming its process.
    pub fn create(name: &str, max_clients: usize) -> Result<Self, ServiceError> {
        let names = ServiceNames::new(name);
        let node_name = names.server_node();
        let iceoryx_name = NodeName::new(&node_name).map_err(|e| ServiceError::Name {
            what: "node",
            name: node_name.clone(),
            source: e.into(),
        })?;
        // iceoryx2 can refuse a node for a moment while another process removes a dead
        // process's node records: a few tries.
        let mut attempt = 0;
        let node = loop {
            match NodeBuilder::new().name(&iceoryx_name).create::<Ipc>() {
                Ok(node) => break node,
                Err(e) if attempt >= 4 => return Err(ServiceError::Node(e)),
                Err(_) => {
                    attempt += 1;
                    std::thread::sleep(core::time::Duration::from_millis(20));
                }
            }
        };
        if let Some(pid) = live_server(&node_name, node.id().value()) {
            return Err(ServiceError::AnotherServer {
                pid,
                instance: name.to_owned(),
            });
        }
        // A crashed server's leftovers (its ports in services that clients kept open) go
        // first, so that its publisher and server slots are free for us.
        clean_dead_nodes();
        let max_nodes = max_clients + 2;
        let tick = event_service(
            &node,
            &service_name(names.tick())?,
            1,
            max_clients,
            max_nodes,
        )?;
        let tick_notifier = tick
            .notifier_builder()
            .create()
            .map_err(|e| ServiceError::service(&names.tick(), e))?;
        let estop = event_service(
            &node,
            &service_name(names.estop())?,
            max_clients * ESTOP_NOTIFIERS_PER_CLIENT,
            1,
            max_nodes * ESTOP_NOTIFIERS_PER_CLIENT,
        )?;
        let estop_listener = estop
            .listener_builder()
            .create()
            .map_err(|e| ServiceError::service(&names.estop(), e))?;
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
            .map_err(|e| ServiceError::service(&names.command(), e))?;
        let command_server = command
            .server_builder()
            .create()
            .map_err(|e| ServiceError::service(&names.command(), e))?;
        let (info, info_factory) =
            state_publisher::<ServerInfo>(&node, &service_name(names.info())?, max_clients)?;
        let (stats, stats_factory) =
            state_publisher::<ServerStats>(&node, &service_name(names.stats())?, max_clients)?;
        let (params, params_factory) =
            state_publisher::<MachineParams>(&node, &service_name(names.params())?, max_clients)?;
        let paths = crate::paths::create(&node, &names.paths(), max_clients)?;
        let setpoints = crate::setpoints::create(&node, &names.setpoints(), max_clients)?;
        // The frame service comes last: a client that sees it can open every other one.
        let frame = node
            .service_builder(&service_name(names.frame())?)
            .publish_subscribe::<MotionFrame>()
            .history_size(1)
            // A client that is late by up to FRAME_BUFFER ticks loses nothing.
            .subscriber_max_buffer_size(FRAME_BUFFER)
            .max_subscribers(max_clients)
            .max_publishers(1)
            .max_nodes(max_nodes)
            .enable_safe_overflow(true)
            .open_or_create()
            .map_err(|e| ServiceError::service(&names.frame(), e))?;
        let frame_publisher = frame
            .publisher_builder()
            .create()
            .map_err(|e| ServiceError::service(&names.frame(), e))?;
        Ok(Self {
            node,
            frame: frame_publisher,
            tick: tick_notifier,
            command: command_server,
            info,
            stats,
            params,
            estop: estop_listener,
            paths,
            setpoints,
            factories: Factories {
                frame,
                info: info_factory,
                stats: stats_factory,
                params: params_factory,
                tick,
                estop,
                command,
            },
            max_clients,
        })
    }
}

/// The event service `name` with room for these many notifiers, listeners and nodes.
fn event_service(
    node: &Node<Ipc>,
    name: &ServiceName,
    max_notifiers: usize,
    max_listeners: usize,
    max_nodes: usize,
) -> Result<EventFactory<Ipc>, ServiceError> {
    node.service_builder(name)
        .event()
        .max_notifiers(max_notifiers)
        .max_listeners(max_listeners)
        .max_nodes(max_nodes)
        .open_or_create()
        .map_err(|e| ServiceError::service(name.as_str(), e))
}

/// A publisher of a rarely changing state (info, stats, params): history 1, so a late
/// subscriber gets the current value at once.
#[allow(clippy::type_complexity)]
fn state_publisher<T: core::fmt::Debug + ZeroCopySend + 'static>(
    node: &Node<Ipc>,
    name: &ServiceName,
    max_clients: usize,
) -> Result<(Publisher<Ipc, T, ()>, PubSubFactory<Ipc, T, ()>), ServiceError> {
    let service = node
        .service_builder(name)
        .publish_subscribe::<T>()
        .history_size(1)
        .subscriber_max_buffer_size(1)
        .max_subscribers(max_clients)
        .max_publishers(1)
        .max_nodes(max_clients + 2)
        .open_or_create()
        .map_err(|e| ServiceError::service(name.as_str(), e))?;
    let publisher = service
        .publisher_builder()
        .create()
        .map_err(|e| ServiceError::service(name.as_str(), e))?;
    Ok((publisher, service))
}

/// The process id of a live node called `node_name` other than `except`.
fn live_server(node_name: &str, except: u128) -> Option<u32> {
    let mut found = None;
    let _ = Node::<Ipc>::list(Config::global_config(), |state| {
        if let NodeState::Alive(view) = &state
            && view.id().value() != except
            && view
                .details()
                .as_ref()
                .is_some_and(|details| details.name().as_str() == node_name)
        {
            found = Some(view.id().pid::<Ipc>().map_or(0, |pid| pid.value() as u32));
            return CallbackProgression::Stop;
        }
        CallbackProgression::Continue
    });
    found
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

/// Which node each client port of the command service belongs to, as the service's
/// dynamic config says (written by iceoryx2 when the port connected — not by the payload).
/// Fixed capacity, filled on demand: no allocation after construction.
#[derive(Debug)]
pub struct ClientDirectory {
    /// (client port id, node id).
    entries: Vec<(u128, u128)>,
    /// Nodes with a client port on the command service, at the last [`Self::refresh`].
    connected: Vec<u128>,
    capacity: usize,
}

impl ClientDirectory {
    /// Room for `max_clients` ports.
    pub fn new(max_clients: usize) -> Self {
        let capacity = max_clients.max(1);
        Self {
            entries: Vec::with_capacity(capacity),
            connected: Vec::with_capacity(capacity),
            capacity,
        }
    }

    /// The node of client port `port`; `ClientId::NONE` when the service does not know it.
    pub fn node_of(&mut self, command: &CommandFactory, port: u128) -> ClientId {
        if let Some((_, node)) = self.entries.iter().find(|(p, _)| *p == port) {
            return ClientId::from_u128(*node);
        }
        let mut found = None;
        command.dynamic_config().list_clients(|details| {
            if details.client_id.value() == port {
                found = Some(details.node_id.value());
                return CallbackProgression::Stop;
            }
            CallbackProgression::Continue
        });
        let Some(node) = found else {
            return ClientId::NONE;
        };
        if self.entries.len() == self.capacity {
            self.entries.remove(0);
        }
        self.entries.push((port, node));
        ClientId::from_u128(node)
    }

    /// Re-reads which client ports are connected; forgets the ports that left.
    pub fn refresh(&mut self, command: &CommandFactory) {
        self.connected.clear();
        let mut ports_seen = 0usize;
        let (connected, capacity) = (&mut self.connected, self.capacity);
        let entries = &mut self.entries;
        let mut live_ports = [0u128; 64];
        command.dynamic_config().list_clients(|details| {
            let node = details.node_id.value();
            if !connected.contains(&node) && connected.len() < capacity {
                connected.push(node);
            }
            if ports_seen < live_ports.len() {
                live_ports[ports_seen] = details.client_id.value();
            }
            ports_seen += 1;
            CallbackProgression::Continue
        });
        if ports_seen <= live_ports.len() {
            entries.retain(|(port, _)| live_ports[..ports_seen].contains(port));
        }
    }

    /// Whether `node` had a client port on the command service at the last refresh.
    pub fn is_connected(&self, node: ClientId) -> bool {
        self.connected.contains(&node.as_u128())
    }
}
