//! Connecting: [`ClientBuilder`], [`Client`], and the server's description.

use core::fmt;
use core::time::Duration;
use std::cell::{Cell, RefCell};
use std::time::Instant;

use iceoryx2::node::{Node, NodeBuilder};
use iceoryx2::port::listener::Listener;
use iceoryx2::prelude::{NodeName, ServiceName, SignalHandlingMode};
use iceoryx2::service::Service;
use iceoryx2::service::builder::publish_subscribe::PublishSubscribeOpenError;
use motion_ipc::{
    AxisInfo, ClientId, CommandReply, CommandRequest, MotionFrame, SCHEMA_VERSION, ServerInfo,
    ServerStats, ServiceNames,
};

use crate::jog::JogTable;
use crate::received::{LatestCache, Received};
use crate::{Axis, ClientError, ConnectError};

/// A [`MotionFrame`] still in shared memory.
pub type Frame<S> = Received<S, MotionFrame>;
/// A [`ServerInfo`] still in shared memory.
pub type Info<S> = Received<S, ServerInfo>;
/// A [`ServerStats`] still in shared memory.
pub type Stats<S> = Received<S, ServerStats>;

pub(crate) type CommandPort<S> =
    iceoryx2::port::client::Client<S, CommandRequest, (), CommandReply, ()>;

/// How long [`Client::connect`] retries by default before saying no server runs.
pub const DEFAULT_CONNECT_TIMEOUT: Duration = Duration::from_secs(2);
/// How long a command waits for its reply by default.
pub const DEFAULT_REPLY_TIMEOUT: Duration = Duration::from_secs(1);

/// Options for connecting to a motiond instance.
#[derive(Debug, Clone)]
pub struct ClientBuilder {
    server: String,
    node_name: String,
    connect_timeout: Duration,
    reply_timeout: Duration,
    signal_handling: SignalHandlingMode,
}

impl ClientBuilder {
    /// Options for the instance called `server` (`[server] name` in its config).
    pub fn new(server: &str) -> Self {
        Self {
            server: server.to_owned(),
            node_name: "motion-client".to_owned(),
            connect_timeout: DEFAULT_CONNECT_TIMEOUT,
            reply_timeout: DEFAULT_REPLY_TIMEOUT,
            signal_handling: SignalHandlingMode::HandleTerminationRequests,
        }
    }

    /// The iceoryx2 node name of this client (shown by iceoryx2 tools); "motion-client".
    #[must_use]
    pub fn node_name(mut self, name: &str) -> Self {
        name.clone_into(&mut self.node_name);
        self
    }

    /// How long to retry while the server's services do not exist yet (default 2 s).
    #[must_use]
    pub fn connect_timeout(mut self, timeout: Duration) -> Self {
        self.connect_timeout = timeout;
        self
    }

    /// How long a command waits for its reply (default 1 s).
    #[must_use]
    pub fn reply_timeout(mut self, timeout: Duration) -> Self {
        self.reply_timeout = timeout;
        self
    }

    /// iceoryx2's signal handling. The default, `HandleTerminationRequests`, catches SIGINT
    /// and SIGTERM so that every wait of the client ends with [`ClientError::Interrupted`]
    /// (and a jog guard stops its axis). Choose `Disabled` if your program handles signals.
    #[must_use]
    pub fn signal_handling(mut self, mode: SignalHandlingMode) -> Self {
        self.signal_handling = mode;
        self
    }

    /// Connects over the service type `S` (`ipc::Service` for a real server).
    pub fn connect<S: Service>(self) -> Result<Client<S>, ConnectError> {
        Client::connect_with(self)
    }
}

/// A connection to one motiond instance: frames, server description, commands.
///
/// All methods take `&self`; a client is meant to be used from one thread (iceoryx2 ports
/// of the `ipc` service are not `Send`). See the crate docs for an example.
pub struct Client<S: Service> {
    pub(crate) server: String,
    pub(crate) node: Node<S>,
    pub(crate) id: ClientId,
    pub(crate) frames: LatestCache<S, MotionFrame>,
    pub(crate) tick: Listener<S>,
    pub(crate) commands: CommandPort<S>,
    pub(crate) info: LatestCache<S, ServerInfo>,
    pub(crate) stats: RefCell<Option<LatestCache<S, ServerStats>>>,
    pub(crate) names: ServiceNames,
    pub(crate) sequence: Cell<u64>,
    pub(crate) reply_timeout: Duration,
    /// Tick of the last accepted goal per axis, so that waits ignore older frames.
    pub(crate) goal_ticks: RefCell<Vec<u64>>,
    pub(crate) jogs: RefCell<JogTable>,
}

impl<S: Service> fmt::Debug for Client<S> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Client")
            .field("server", &self.server)
            .field("id", &self.id)
            .finish_non_exhaustive()
    }
}

fn service_name(name: &str, server: &str) -> Result<ServiceName, ConnectError> {
    ServiceName::new(name).map_err(|error| ConnectError::BadName {
        name: server.to_owned(),
        detail: format!("{error:?}"),
    })
}

/// Retries `open` until it succeeds or `deadline` passes.
fn retry<T, E>(deadline: Instant, mut open: impl FnMut() -> Result<T, E>) -> Result<T, E> {
    loop {
        match open() {
            Ok(value) => return Ok(value),
            Err(error) if Instant::now() >= deadline => return Err(error),
            Err(_) => std::thread::sleep(Duration::from_millis(10)),
        }
    }
}

impl<S: Service> Client<S> {
    /// Connects to the instance `server` with default options over `S`.
    ///
    /// Waits up to [`DEFAULT_CONNECT_TIMEOUT`] for the server's services and its
    /// [`ServerInfo`]; fails with [`ConnectError::NoServer`] when none runs.
    pub fn connect(server: &str) -> Result<Self, ConnectError> {
        ClientBuilder::new(server).connect()
    }

    fn connect_with(options: ClientBuilder) -> Result<Self, ConnectError> {
        let started = Instant::now();
        let deadline = started + options.connect_timeout;
        let server = options.server.clone();
        let names = ServiceNames::new(&server);
        let node_name =
            NodeName::new(&options.node_name).map_err(|error| ConnectError::BadName {
                name: options.node_name.clone(),
                detail: format!("{error:?}"),
            })?;
        let node = NodeBuilder::new()
            .name(&node_name)
            .signal_handling_mode(options.signal_handling)
            .create::<S>()
            .map_err(|error| ConnectError::ipc("create a node", error))?;
        if options.signal_handling == SignalHandlingMode::HandleTerminationRequests {
            // iceoryx2 installs its SIGINT/SIGTERM capture on the first look at the
            // signal state; look now, so that a Ctrl-C between here and the first wait is
            // caught (and the axis stopped) instead of killing the process mid-command.
            let _ = node.wait(Duration::ZERO);
        }

        let frame_name = service_name(&names.frame(), &server)?;
        let frame_service = retry(deadline, || {
            node.service_builder(&frame_name)
                .publish_subscribe::<MotionFrame>()
                .open()
        })
        .map_err(|error| match error {
            PublishSubscribeOpenError::DoesNotExist
            | PublishSubscribeOpenError::IsMarkedForDestruction
            | PublishSubscribeOpenError::HangsInCreation => ConnectError::NoServer {
                name: server.clone(),
                service: names.frame(),
                waited: options.connect_timeout,
            },
            PublishSubscribeOpenError::IncompatibleTypes => ConnectError::SchemaMismatch {
                name: server.clone(),
                server: 0,
                client: SCHEMA_VERSION,
            },
            PublishSubscribeOpenError::ExceedsMaxNumberOfNodes => ConnectError::Ipc {
                what: "join the frame service",
                detail: "the server's client limit is reached ([server] max_clients)".to_owned(),
            },
            other => ConnectError::ipc("open the frame service", other),
        })?;
        let frames = frame_service
            .subscriber_builder()
            .create()
            .map_err(|error| ConnectError::ipc("subscribe to the frame service", error))?;

        let tick_name = service_name(&names.tick(), &server)?;
        let tick = retry(deadline, || node.service_builder(&tick_name).event().open())
            .map_err(|error| ConnectError::ipc("open the tick event service", error))?
            .listener_builder()
            .create()
            .map_err(|error| ConnectError::ipc("listen to the tick event", error))?;

        let command_name = service_name(&names.command(), &server)?;
        let commands = retry(deadline, || {
            node.service_builder(&command_name)
                .request_response::<CommandRequest, CommandReply>()
                .open()
        })
        .map_err(|error| ConnectError::ipc("open the command service", error))?
        .client_builder()
        .create()
        .map_err(|error| ConnectError::ipc("create a command client", error))?;

        let info_name = service_name(&names.info(), &server)?;
        let info_subscriber = retry(deadline, || {
            node.service_builder(&info_name)
                .publish_subscribe::<ServerInfo>()
                .open()
        })
        .map_err(|error| ConnectError::ipc("open the info service", error))?
        .subscriber_builder()
        .create()
        .map_err(|error| ConnectError::ipc("subscribe to the info service", error))?;
        let info = LatestCache::new(info_subscriber);
        // The server delivers its history sample when it next updates its connections.
        let info_timeout = options.connect_timeout.max(Duration::from_millis(500));
        let info_deadline = started + info_timeout;
        let description = loop {
            let received = info.refresh().map_err(|error| ConnectError::Ipc {
                what: "receive the server description",
                detail: error.to_string(),
            })?;
            if let Some(description) = received {
                break description;
            }
            if Instant::now() >= info_deadline {
                return Err(ConnectError::NoInfo {
                    name: server,
                    service: names.info(),
                    waited: info_timeout,
                });
            }
            std::thread::sleep(Duration::from_millis(5));
        };
        if description.schema_version != SCHEMA_VERSION {
            return Err(ConnectError::SchemaMismatch {
                name: server,
                server: description.schema_version,
                client: SCHEMA_VERSION,
            });
        }
        let axis_count = description.axes().len();
        drop(description);

        let id = ClientId::from_u128(node.id().value());
        let client = Self {
            server,
            node,
            id,
            frames: LatestCache::new(frames),
            tick,
            commands,
            info,
            stats: RefCell::new(None),
            names,
            sequence: Cell::new(0),
            reply_timeout: options.reply_timeout,
            goal_ticks: RefCell::new(vec![0; axis_count]),
            jogs: RefCell::new(JogTable::default()),
        };
        client.open_stats();
        Ok(client)
    }

    fn open_stats(&self) {
        if self.stats.borrow().is_some() {
            return;
        }
        let Ok(name) = ServiceName::new(&self.names.stats()) else {
            return;
        };
        let subscriber = self
            .node
            .service_builder(&name)
            .publish_subscribe::<ServerStats>()
            .open()
            .ok()
            .and_then(|service| service.subscriber_builder().create().ok());
        if let Some(subscriber) = subscriber {
            *self.stats.borrow_mut() = Some(LatestCache::new(subscriber));
        }
    }

    /// The instance name this client talks to.
    pub fn server_name(&self) -> &str {
        &self.server
    }

    /// This client's id as the server sees it (its iceoryx2 node id).
    pub fn id(&self) -> ClientId {
        self.id
    }

    /// The iceoryx2 node of this client (to build your own ports or wait sets).
    pub fn node(&self) -> &Node<S> {
        &self.node
    }

    /// The server's description: axes (names, units, limits, capabilities), devices, tick
    /// rate, deadman. Refreshed from the info service on every call (devices coming online
    /// or reporting firmware change it; the axis list never changes while a server runs).
    pub fn info(&self) -> Result<Info<S>, ClientError> {
        self.info
            .refresh()?
            .ok_or_else(|| ClientError::ipc("read the server description", "none received"))
    }

    /// The newest [`ServerStats`] (published about once a second); `None` until the first.
    pub fn stats(&self) -> Result<Option<Stats<S>>, ClientError> {
        self.open_stats();
        match self.stats.borrow().as_ref() {
            Some(cache) => cache.refresh(),
            None => Ok(None),
        }
    }

    /// The handle of the axis called `name`.
    pub fn axis(&self, name: &str) -> Result<Axis<'_, S>, ClientError> {
        let info = self.info.current();
        let index = info
            .as_ref()
            .and_then(|info| info.axis_index(name))
            .ok_or_else(|| ClientError::UnknownAxis(name.to_owned()))?;
        Ok(Axis::new(self, index))
    }

    /// Handles of every axis, in config order.
    pub fn axes(&self) -> Vec<Axis<'_, S>> {
        let count = self.goal_ticks.borrow().len();
        (0..count).map(|index| Axis::new(self, index)).collect()
    }

    /// The static description of axis `index` (a copy: 128 bytes).
    pub(crate) fn axis_info(&self, index: usize) -> AxisInfo {
        self.info
            .current()
            .and_then(|info| info.axes().get(index).copied())
            .unwrap_or(AxisInfo::EMPTY)
    }

    /// The name of axis `index`, for messages.
    pub(crate) fn axis_label(&self, axis: u32) -> String {
        if axis == CommandRequest::ALL_AXES {
            return "all axes".to_owned();
        }
        let info = self.axis_info(axis as usize);
        match info.name() {
            "" => format!("axis #{axis}"),
            name => format!("axis {name}"),
        }
    }

    /// `Err(Interrupted)` once SIGINT or SIGTERM arrived (with iceoryx2 signal handling on).
    pub fn check_interrupted(&self) -> Result<(), ClientError> {
        match self.node.wait(Duration::ZERO) {
            Ok(()) => Ok(()),
            Err(_) => Err(ClientError::Interrupted),
        }
    }

    /// The tick event listener, to attach to your own iceoryx2 `WaitSet`
    /// (`waitset.attach_notification(client.tick_listener())`). After a wake-up, read with
    /// [`Client::latest`] or [`Client::try_next_frame`].
    pub fn tick_listener(&self) -> &Listener<S> {
        &self.tick
    }

    /// Blocks until the next tick notification or `timeout` (no busy waiting).
    pub(crate) fn wait_tick(&self, timeout: Duration) -> Result<(), ClientError> {
        match self.tick.timed_wait(|_| {}, timeout) {
            Ok(_) => self.check_interrupted(),
            Err(iceoryx2::port::listener::ListenerWaitError::InterruptSignal) => {
                self.check_interrupted()
            }
            Err(error) => Err(ClientError::ipc("wait for the tick event", error)),
        }
    }
}
