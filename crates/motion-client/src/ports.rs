//! Opening the server's services, each only when first needed, with clear errors when the
//! server is absent or its port slots are taken.

use core::fmt;
use core::time::Duration;
use std::time::Instant;

use iceoryx2::identifiers::UniqueServiceId;
use iceoryx2::node::Node;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::listener::ListenerCreateError;
use iceoryx2::port::publisher::{Publisher, PublisherCreateError};
use iceoryx2::port::subscriber::{Subscriber, SubscriberCreateError};
use iceoryx2::prelude::{PortFactory as _, ServiceName, ZeroCopySend};
use iceoryx2::service::Service;
use iceoryx2::service::builder::event::EventOpenError;
use iceoryx2::service::builder::publish_subscribe::PublishSubscribeOpenError;
use iceoryx2::service::builder::request_response::RequestResponseOpenError;
use iceoryx2::service::port_factory::client::ClientCreateError;
use motion_ipc::{CommandReply, CommandRequest, GroupPath, MotionFrame, SCHEMA_VERSION, Setpoint};

use crate::ConnectError;
use crate::received::LatestCache;

pub(crate) type CommandClient<S> =
    iceoryx2::port::client::Client<S, CommandRequest, (), CommandReply, ()>;

/// The frame subscription: the frames and the tick event that announces each.
pub(crate) struct FramePorts<S: Service> {
    pub(crate) cache: LatestCache<S, MotionFrame>,
    /// The tick event; `None` over a bridge (frames are waited for on the network).
    pub(crate) tick: Option<std::rc::Rc<Listener<S>>>,
    /// The frame service's id; `None` over a bridge.
    pub(crate) service_id: Option<UniqueServiceId>,
}

impl<S: Service> fmt::Debug for FramePorts<S> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("FramePorts").finish_non_exhaustive()
    }
}

/// A client port on the command service.
pub(crate) struct CommandPorts<S: Service> {
    pub(crate) port: CommandClient<S>,
    pub(crate) service_id: UniqueServiceId,
}

impl<S: Service> fmt::Debug for CommandPorts<S> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("CommandPorts").finish_non_exhaustive()
    }
}

/// A publisher on the `paths` service (a group's paths; each sample is about 400 KB, so
/// only a client that sends paths has one).
pub(crate) struct PathPorts<S: Service> {
    pub(crate) publisher: Publisher<S, GroupPath, ()>,
    pub(crate) service_id: UniqueServiceId,
}

impl<S: Service> fmt::Debug for PathPorts<S> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("PathPorts").finish_non_exhaustive()
    }
}

/// A publisher on the `setpoints` service (a group's streamed setpoints, 288 bytes each;
/// taken with a client's command port).
pub(crate) struct SetpointPorts<S: Service> {
    pub(crate) publisher: Publisher<S, Setpoint, ()>,
    pub(crate) service_id: UniqueServiceId,
}

impl<S: Service> fmt::Debug for SetpointPorts<S> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SetpointPorts").finish_non_exhaustive()
    }
}

/// What every open needs to know.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Opening<'a> {
    /// The instance name.
    pub(crate) server: &'a str,
    /// Retry a missing service until then.
    pub(crate) deadline: Instant,
    /// How long that is from the start, for messages.
    pub(crate) waited: Duration,
}

impl<'a> Opening<'a> {
    /// Retries for `waited` from now.
    pub(crate) fn new(server: &'a str, waited: Duration) -> Self {
        Self {
            server,
            deadline: Instant::now() + waited,
            waited,
        }
    }

    /// One attempt only.
    pub(crate) fn once(server: &'a str) -> Self {
        Self::new(server, Duration::ZERO)
    }

    fn no_server(&self, service: &str) -> ConnectError {
        ConnectError::NoServer {
            name: self.server.to_owned(),
            service: service.to_owned(),
            waited: self.waited,
        }
    }
}

pub(crate) fn service_name(name: &str, server: &str) -> Result<ServiceName, ConnectError> {
    ServiceName::new(name).map_err(|error| ConnectError::InvalidName {
        name: server.to_owned(),
        kind: "service",
        source: error.into(),
    })
}

/// Retries `open` until it succeeds or `deadline` passes.
pub(crate) fn retry<T, E>(
    deadline: Instant,
    mut open: impl FnMut() -> Result<T, E>,
) -> Result<T, E> {
    loop {
        match open() {
            Ok(value) => return Ok(value),
            Err(error) if Instant::now() >= deadline => return Err(error),
            Err(_) => std::thread::sleep(Duration::from_millis(10)),
        }
    }
}

fn exhausted(service: &str, port: &'static str) -> ConnectError {
    ConnectError::PortsExhausted {
        service: service.to_owned(),
        port,
    }
}

fn pubsub_open_error(
    error: PublishSubscribeOpenError,
    opening: &Opening<'_>,
    service: &str,
) -> ConnectError {
    match error {
        PublishSubscribeOpenError::DoesNotExist
        | PublishSubscribeOpenError::IsMarkedForDestruction
        | PublishSubscribeOpenError::HangsInCreation => opening.no_server(service),
        PublishSubscribeOpenError::IncompatibleTypes => ConnectError::SchemaMismatch {
            name: opening.server.to_owned(),
            server: 0,
            client: SCHEMA_VERSION,
        },
        PublishSubscribeOpenError::ExceedsMaxNumberOfNodes => exhausted(service, "node slot"),
        other => ConnectError::ipc("open a publish-subscribe service", other),
    }
}

/// A subscriber on the publish-subscribe service `service` and the service's unique id.
pub(crate) fn open_subscriber<S: Service, T: fmt::Debug + ZeroCopySend + 'static>(
    node: &Node<S>,
    opening: &Opening<'_>,
    service: &str,
) -> Result<(Subscriber<S, T, ()>, UniqueServiceId), ConnectError> {
    let name = service_name(service, opening.server)?;
    let factory = retry(opening.deadline, || {
        node.service_builder(&name).publish_subscribe::<T>().open()
    })
    .map_err(|error| pubsub_open_error(error, opening, service))?;
    let subscriber = factory
        .subscriber_builder()
        .create()
        .map_err(|error| match error {
            SubscriberCreateError::ExceedsMaxSupportedSubscribers => {
                exhausted(service, "subscriber slot")
            }
            other => ConnectError::ipc("create a subscriber", other),
        })?;
    Ok((subscriber, factory.unique_service_id()))
}

fn event_open_error(error: EventOpenError, opening: &Opening<'_>, service: &str) -> ConnectError {
    match error {
        EventOpenError::DoesNotExist
        | EventOpenError::IsMarkedForDestruction
        | EventOpenError::HangsInCreation => opening.no_server(service),
        EventOpenError::ExceedsMaxNumberOfNodes => exhausted(service, "node slot"),
        other => ConnectError::ipc("open an event service", other),
    }
}

/// Subscribes to the frames and listens to the tick event.
pub(crate) fn open_frames<S: Service>(
    node: &Node<S>,
    opening: &Opening<'_>,
    frame_service: &str,
    tick_service: &str,
) -> Result<FramePorts<S>, ConnectError> {
    let (subscriber, service_id) = open_subscriber::<S, MotionFrame>(node, opening, frame_service)?;
    let tick_name = service_name(tick_service, opening.server)?;
    let tick = retry(opening.deadline, || {
        node.service_builder(&tick_name).event().open()
    })
    .map_err(|error| event_open_error(error, opening, tick_service))?
    .listener_builder()
    .create()
    .map_err(|error| match error {
        ListenerCreateError::ExceedsMaxSupportedListeners => {
            exhausted(tick_service, "listener slot")
        }
        other => ConnectError::ipc("listen to the tick event", other),
    })?;
    Ok(FramePorts {
        cache: LatestCache::new(subscriber),
        tick: Some(std::rc::Rc::new(tick)),
        service_id: Some(service_id),
    })
}

/// A client port on the command service.
pub(crate) fn open_commands<S: Service>(
    node: &Node<S>,
    opening: &Opening<'_>,
    service: &str,
) -> Result<CommandPorts<S>, ConnectError> {
    let name = service_name(service, opening.server)?;
    let factory = retry(opening.deadline, || {
        node.service_builder(&name)
            .request_response::<CommandRequest, CommandReply>()
            .open()
    })
    .map_err(|error| match error {
        RequestResponseOpenError::DoesNotExist
        | RequestResponseOpenError::IsMarkedForDestruction
        | RequestResponseOpenError::HangsInCreation => opening.no_server(service),
        RequestResponseOpenError::IncompatibleRequestOrResponseType => {
            ConnectError::SchemaMismatch {
                name: opening.server.to_owned(),
                server: 0,
                client: SCHEMA_VERSION,
            }
        }
        RequestResponseOpenError::ExceedsMaxNumberOfNodes => exhausted(service, "node slot"),
        other => ConnectError::ipc("open the command service", other),
    })?;
    let port = factory
        .client_builder()
        .create()
        .map_err(|error| match error {
            ClientCreateError::ExceedsMaxSupportedClients => exhausted(service, "client slot"),
            other => ConnectError::ipc("create a command client", other),
        })?;
    Ok(CommandPorts {
        port,
        service_id: factory.unique_service_id(),
    })
}

/// A publisher on the `paths` service `service` (created by the server), lending one
/// sample at a time.
pub(crate) fn open_paths<S: Service>(
    node: &Node<S>,
    opening: &Opening<'_>,
    service: &str,
) -> Result<PathPorts<S>, ConnectError> {
    let name = service_name(service, opening.server)?;
    let factory = retry(opening.deadline, || {
        node.service_builder(&name)
            .publish_subscribe::<GroupPath>()
            .open()
    })
    .map_err(|error| pubsub_open_error(error, opening, service))?;
    let publisher = factory
        .publisher_builder()
        .max_loaned_samples(1)
        .create()
        .map_err(|error| match error {
            PublisherCreateError::ExceedsMaxSupportedPublishers => {
                exhausted(service, "publisher slot")
            }
            other => ConnectError::ipc("create a path publisher", other),
        })?;
    Ok(PathPorts {
        publisher,
        service_id: factory.unique_service_id(),
    })
}

/// A publisher on the `setpoints` service `service` (created by the server).
pub(crate) fn open_setpoints<S: Service>(
    node: &Node<S>,
    opening: &Opening<'_>,
    service: &str,
) -> Result<SetpointPorts<S>, ConnectError> {
    let name = service_name(service, opening.server)?;
    let factory = retry(opening.deadline, || {
        node.service_builder(&name)
            .publish_subscribe::<Setpoint>()
            .open()
    })
    .map_err(|error| pubsub_open_error(error, opening, service))?;
    let publisher = factory
        .publisher_builder()
        .create()
        .map_err(|error| match error {
            PublisherCreateError::ExceedsMaxSupportedPublishers => {
                exhausted(service, "publisher slot")
            }
            other => ConnectError::ipc("create a setpoint publisher", other),
        })?;
    Ok(SetpointPorts {
        publisher,
        service_id: factory.unique_service_id(),
    })
}

/// The unique id the publish-subscribe service `service` has now (`None` when it does not
/// exist): differs from the one a port was made on when the service was recreated.
pub(crate) fn pubsub_id_now<S: Service, T: fmt::Debug + ZeroCopySend + 'static>(
    node: &Node<S>,
    service: &str,
) -> Option<UniqueServiceId> {
    let name = ServiceName::new(service).ok()?;
    node.service_builder(&name)
        .publish_subscribe::<T>()
        .open()
        .ok()
        .map(|factory| factory.unique_service_id())
}

/// Like [`pubsub_id_now`] for the command service.
pub(crate) fn command_id_now<S: Service>(node: &Node<S>, service: &str) -> Option<UniqueServiceId> {
    let name = ServiceName::new(service).ok()?;
    node.service_builder(&name)
        .request_response::<CommandRequest, CommandReply>()
        .open()
        .ok()
        .map(|factory| factory.unique_service_id())
}

/// Creates a node, trying again a few times: iceoryx2 can refuse a node for a moment
/// (`InternalError`) while another process removes a dead process's node records.
pub(crate) fn create_node<S: Service>(
    name: &iceoryx2::prelude::NodeName,
    signals: iceoryx2::prelude::SignalHandlingMode,
) -> Result<Node<S>, iceoryx2::node::NodeCreationFailure> {
    let mut attempt = 0;
    loop {
        match iceoryx2::prelude::NodeBuilder::new()
            .name(name)
            .signal_handling_mode(signals)
            .create::<S>()
        {
            Ok(node) => return Ok(node),
            Err(error) if attempt >= 4 => return Err(error),
            Err(_) => {
                attempt += 1;
                std::thread::sleep(Duration::from_millis(20));
            }
        }
    }
}
