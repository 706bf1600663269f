//! The bridge's side of the shared memory: the server's services, opened (and reopened
//! after a server restart) as an ordinary client would, and a thread that turns the `tick`
//! event into wake-ups of the bridge's loop.

use core::time::Duration;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::Sender;
use std::time::Instant;

use iceoryx2::node::{Node, NodeBuilder};
use iceoryx2::pending_response::PendingResponse;
use iceoryx2::port::client::Client as ClientPort;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::{
    NodeName, PayloadHeader as _, PortFactory as _, ServiceName, SignalHandlingMode, ZeroCopySend,
    ipc,
};
use motion_ipc::{
    CommandReply, CommandRequest, MachineParams, MotionFrame, ServerInfo, ServerStats, ServiceNames,
};

use super::{BridgeError, Event};

/// The service type of a real server.
pub(crate) type Ipc = ipc::Service;

/// A command sent to the server, waiting for its reply.
pub(crate) type Pending = PendingResponse<Ipc, CommandRequest, (), CommandReply, ()>;

/// The server's services as the bridge uses them.
pub(crate) struct ServerPorts {
    pub(crate) frame: Subscriber<Ipc, MotionFrame, ()>,
    pub(crate) info: Subscriber<Ipc, ServerInfo, ()>,
    pub(crate) stats: Subscriber<Ipc, ServerStats, ()>,
    /// `None` from a server without the params service.
    pub(crate) params: Option<Subscriber<Ipc, MachineParams, ()>>,
    pub(crate) command: ClientPort<Ipc, CommandRequest, (), CommandReply, ()>,
    /// Requests the server takes from one client at a time.
    pub(crate) max_in_flight: usize,
}

impl core::fmt::Debug for ServerPorts {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("ServerPorts")
            .field("max_in_flight", &self.max_in_flight)
            .finish_non_exhaustive()
    }
}

fn service_name(name: &str) -> Result<ServiceName, BridgeError> {
    ServiceName::new(name)
        .map_err(|error| BridgeError::ipc(format!("name a service `{name}`"), error))
}

fn subscriber<T: core::fmt::Debug + ZeroCopySend + 'static>(
    node: &Node<Ipc>,
    name: &str,
) -> Result<Subscriber<Ipc, T, ()>, BridgeError> {
    node.service_builder(&service_name(name)?)
        .publish_subscribe::<T>()
        .open()
        .map_err(|error| BridgeError::ipc(format!("open {name}"), error))?
        .subscriber_builder()
        .create()
        .map_err(|error| BridgeError::ipc(format!("subscribe to {name}"), error))
}

impl ServerPorts {
    /// Opens every service of the instance; the first failure says which.
    pub(crate) fn open(node: &Node<Ipc>, names: &ServiceNames) -> Result<Self, BridgeError> {
        let command_name = names.command();
        let factory = node
            .service_builder(&service_name(&command_name)?)
            .request_response::<CommandRequest, CommandReply>()
            .open()
            .map_err(|error| BridgeError::ipc(format!("open {command_name}"), error))?;
        let max_in_flight = factory
            .static_config()
            .max_active_requests_per_client()
            .max(1);
        let command = factory.client_builder().create().map_err(|error| {
            BridgeError::ipc(format!("create a client of {command_name}"), error)
        })?;
        Ok(Self {
            frame: subscriber(node, &names.frame())?,
            info: subscriber(node, &names.info())?,
            stats: subscriber(node, &names.stats())?,
            params: subscriber(node, &names.params()).ok(),
            command,
            max_in_flight,
        })
    }

    /// Sends `request`; `None` when no server takes requests on the service.
    pub(crate) fn send(&self, request: CommandRequest) -> Result<Option<Pending>, BridgeError> {
        let pending = self
            .command
            .send_copy(request)
            .map_err(|error| BridgeError::ipc("send to the command service", error))?;
        Ok((pending.number_of_server_connections() > 0).then_some(pending))
    }
}

/// The reply to `pending` if it arrived, with the node that sent it.
pub(crate) fn take_reply(pending: &Pending) -> Result<Option<(CommandReply, u128)>, BridgeError> {
    loop {
        match pending.receive() {
            Ok(Some(response)) => {
                if response.payload().sequence == pending.payload().sequence {
                    return Ok(Some((
                        *response.payload(),
                        response.header().node_id().value(),
                    )));
                }
            }
            Ok(None) => return Ok(None),
            Err(error) => return Err(BridgeError::ipc("receive a reply", error)),
        }
    }
}

/// Every waiting sample of `subscriber`, in order, with its publisher's node.
pub(crate) fn drain<T: core::fmt::Debug + ZeroCopySend + Copy + 'static>(
    subscriber: &Subscriber<Ipc, T, ()>,
    mut each: impl FnMut(&T, u128),
) -> Result<usize, BridgeError> {
    let mut count = 0;
    loop {
        match subscriber.receive() {
            Ok(Some(sample)) => {
                count += 1;
                each(sample.payload(), sample.header().node_id().value());
            }
            Ok(None) => return Ok(count),
            Err(error) => return Err(BridgeError::ipc("receive a sample", error)),
        }
    }
}

/// The bridge's iceoryx2 node.
pub(crate) fn node(name: &str, signals: SignalHandlingMode) -> Result<Node<Ipc>, BridgeError> {
    let name = NodeName::new(name)
        .map_err(|error| BridgeError::ipc(format!("name a node `{name}`"), error))?;
    NodeBuilder::new()
        .name(&name)
        .signal_handling_mode(signals)
        .create::<Ipc>()
        .map_err(|error| BridgeError::ipc("create a node", error))
}

/// Starts the thread that waits on the server's `tick` event and sends [`Event::Tick`] (one
/// at a time: `pending` is set until the loop takes it). Ends when `stop` is set.
pub(crate) fn spawn_ticker(
    names: &ServiceNames,
    events: Sender<Event>,
    pending: Arc<AtomicBool>,
    stop: Arc<AtomicBool>,
) -> std::io::Result<std::thread::JoinHandle<()>> {
    let tick_name = names.tick();
    std::thread::Builder::new()
        .name("bridge-tick".to_owned())
        .spawn(move || {
            let Ok(node) = node("motion-bridge-tick", SignalHandlingMode::Disabled) else {
                return;
            };
            let mut listener: Option<Listener<Ipc>> = None;
            let mut next_open = Instant::now();
            while !stop.load(Ordering::Relaxed) {
                let Some(port) = listener.as_ref() else {
                    if Instant::now() >= next_open {
                        listener = open_listener(&node, &tick_name);
                        next_open = Instant::now() + Duration::from_millis(250);
                    } else {
                        std::thread::sleep(Duration::from_millis(20));
                    }
                    continue;
                };
                match port.timed_wait(|_| {}, Duration::from_millis(100)) {
                    Ok(0) => {
                        // Silent for 100 ms: the server may be gone, or its services
                        // recreated under us; listen anew.
                        listener = None;
                    }
                    Ok(_) => {
                        if !pending.swap(true, Ordering::AcqRel)
                            && events.send(Event::Tick).is_err()
                        {
                            return;
                        }
                    }
                    Err(_) => listener = None,
                }
            }
        })
}

fn open_listener(node: &Node<Ipc>, name: &str) -> Option<Listener<Ipc>> {
    node.service_builder(&ServiceName::new(name).ok()?)
        .event()
        .open()
        .ok()?
        .listener_builder()
        .create()
        .ok()
}
