//! Connecting: [`ClientBuilder`], [`Client`], and the server's description.

use core::fmt;
use core::ops::Deref;
use core::time::Duration;
use std::cell::{Cell, RefCell};
use std::rc::Rc;
use std::time::Instant;

use iceoryx2::node::Node;
use iceoryx2::port::listener::Listener;
use iceoryx2::prelude::{NodeName, SignalHandlingMode};
use iceoryx2::service::Service;
use motion_ipc::{
    AxisInfo, ClientId, CommandRequest, MachineParams, MotionFrame, SCHEMA_VERSION, ServerInfo,
    ServerStats, ServiceNames, SignalInfo, Target,
};

use crate::group::RunMark;
use crate::jog::JogTable;
use crate::ports::{self, CommandPorts, FramePorts, Opening, PathPorts, SetpointPorts};
use crate::received::{LatestCache, Received};
use crate::session::{Seen, Session};
use crate::{Axis, ClientError, ConnectError, Restart, Unanswered};

/// How long a connecting client waits for the server description once its info subscriber
/// exists (at least; the connect timeout when longer).
const INFO_WAIT: Duration = Duration::from_millis(500);
/// A [`MotionFrame`] still in shared memory.
pub type Frame<S> = Received<S, MotionFrame>;
/// A [`ServerInfo`] still in shared memory.
pub type Info<S> = Received<S, ServerInfo>;
/// A [`ServerStats`] still in shared memory.
pub type Stats<S> = Received<S, ServerStats>;
/// The [`MachineParams`] still in shared memory.
pub type Params<S> = Received<S, MachineParams>;

/// How long [`Client::connect`] retries by default before saying no server runs.
pub const DEFAULT_CONNECT_TIMEOUT: Duration = Duration::from_secs(2);
/// How long a command waits for its reply by default.
pub const DEFAULT_REPLY_TIMEOUT: Duration = Duration::from_secs(1);

/// Options for connecting to a motiond instance.
#[derive(Debug, Clone)]
pub struct ClientBuilder {
    pub(crate) server: String,
    node_name: String,
    pub(crate) connect_timeout: Duration,
    pub(crate) reply_timeout: Duration,
    signal_handling: SignalHandlingMode,
    /// Connect through a bridge instead of shared memory (when it has an endpoint).
    #[cfg(feature = "zenoh")]
    pub(crate) remote: crate::link::RemoteOptions,
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
            #[cfg(feature = "zenoh")]
            remote: crate::link::RemoteOptions::default(),
        }
    }

    /// Connects through the `motion-bridge` at the zenoh `endpoint` (`tcp/HOST:7447`,
    /// `tls/HOST:7447`) instead of shared memory (feature `zenoh`; see the `remote`
    /// module docs for what differs).
    #[cfg(feature = "zenoh")]
    #[must_use]
    pub fn remote(mut self, endpoint: &str) -> Self {
        self.remote.endpoint = Some(endpoint.to_owned());
        self
    }

    /// The identity a remote client sends commands as (the bridge's allow-list is per
    /// identity); default [`DEFAULT_IDENTITY`](crate::remote::DEFAULT_IDENTITY). Only with
    /// [`ClientBuilder::remote`].
    #[cfg(feature = "zenoh")]
    #[must_use]
    pub fn identity(mut self, identity: &str) -> Self {
        identity.clone_into(&mut self.remote.identity);
        self
    }

    /// zenoh's own config file (JSON5) for a remote client: TLS certificates, user and
    /// password. Only with [`ClientBuilder::remote`].
    #[cfg(feature = "zenoh")]
    #[must_use]
    pub fn zenoh_config(mut self, path: impl Into<std::path::PathBuf>) -> Self {
        self.remote.zenoh_config = Some(path.into());
        self
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
/// Connecting opens only the info service. The frame subscription (and the tick event) is
/// opened by the first call that needs frames, the command port by the first command, the
/// params and stats services by their first read: a client that only commands works while
/// every frame subscriber slot of the server is taken.
///
/// All methods take `&self`; a client is meant to be used from one thread (iceoryx2 ports
/// of the `ipc` service are not `Send`). See the crate docs for an example.
pub struct Client<S: Service> {
    pub(crate) server: String,
    pub(crate) node: Node<S>,
    pub(crate) id: ClientId,
    pub(crate) names: ServiceNames,
    pub(crate) connect_timeout: Duration,
    pub(crate) reply_timeout: Duration,
    pub(crate) info: LatestCache<S, ServerInfo>,
    pub(crate) frames: RefCell<Option<Rc<FramePorts<S>>>>,
    pub(crate) commands: RefCell<Option<Rc<CommandPorts<S>>>>,
    pub(crate) stats: RefCell<Option<LatestCache<S, ServerStats>>>,
    pub(crate) params: RefCell<Option<Rc<LatestCache<S, MachineParams>>>>,
    pub(crate) session: Session,
    pub(crate) sequence: Cell<u64>,
    /// Tick and restart count of the last accepted goal per axis, so that waits ignore
    /// older frames and end when the server restarted.
    pub(crate) goal_ticks: RefCell<Vec<(u64, u64)>>,
    pub(crate) jogs: RefCell<JogTable>,
    /// The publisher on the `paths` service, created by the first path sent.
    pub(crate) paths: RefCell<Option<Rc<PathPorts<S>>>>,
    /// The publisher on the `setpoints` service, taken with the command port (or by the
    /// first stream when no slot was free then).
    pub(crate) setpoints: RefCell<Option<Rc<SetpointPorts<S>>>>,
    /// The id of the last path this client sent (ids count up from 1).
    pub(crate) path_ids: Cell<u64>,
    /// Per group (config order): the last path this client ran on it, so that waits know
    /// which motion is theirs.
    pub(crate) group_runs: RefCell<Vec<Option<RunMark>>>,
    /// The bridge this client talks through, when remote.
    #[cfg(feature = "zenoh")]
    pub(crate) remote: Option<crate::link::Link>,
}

/// Refuses a server whose contract is not this client's (`version` is the schema version
/// its description carries).
pub(crate) fn check_schema(server: &str, version: u32) -> Result<(), ConnectError> {
    if version == SCHEMA_VERSION {
        return Ok(());
    }
    Err(ConnectError::SchemaMismatch {
        name: server.to_owned(),
        server: version,
        client: SCHEMA_VERSION,
    })
}

impl<S: Service> fmt::Debug for Client<S> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Client")
            .field("server", &self.server)
            .field("id", &self.id)
            .finish_non_exhaustive()
    }
}

/// The tick event listener of a client's frame subscription; see [`Client::tick_listener`].
pub struct TickListener<S: Service>(Rc<Listener<S>>);

impl<S: Service> fmt::Debug for TickListener<S> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("TickListener").finish_non_exhaustive()
    }
}

impl<S: Service> Deref for TickListener<S> {
    type Target = Listener<S>;
    fn deref(&self) -> &Listener<S> {
        &self.0
    }
}

impl<S: Service> Client<S> {
    /// Connects to the instance `server` with default options over `S`.
    ///
    /// Waits up to [`DEFAULT_CONNECT_TIMEOUT`] for the server's info service and its
    /// [`ServerInfo`]; fails with [`ConnectError::NoServer`] when none runs.
    pub fn connect(server: &str) -> Result<Self, ConnectError> {
        ClientBuilder::new(server).connect()
    }

    /// This client's iceoryx2 node (identity, signal handling).
    pub(crate) fn make_node(options: &ClientBuilder) -> Result<Node<S>, ConnectError> {
        let node_name =
            NodeName::new(&options.node_name).map_err(|error| ConnectError::InvalidName {
                name: options.node_name.clone(),
                kind: "node",
                source: error.into(),
            })?;
        let node = ports::create_node::<S>(&node_name, options.signal_handling)
            .map_err(|error| ConnectError::ipc("create a node", error))?;
        if options.signal_handling == SignalHandlingMode::HandleTerminationRequests {
            // iceoryx2 installs its SIGINT/SIGTERM capture on the first look at the
            // signal state; look now, so that a Ctrl-C between here and the first wait is
            // caught (and the axis stopped) instead of killing the process mid-command.
            let _ = node.wait(Duration::ZERO);
        }
        Ok(node)
    }

    fn connect_with(options: ClientBuilder) -> Result<Self, ConnectError> {
        #[cfg(feature = "zenoh")]
        if let Some(endpoint) = options.remote.endpoint.clone() {
            return Self::connect_remote(&options, &endpoint);
        }
        let started = Instant::now();
        let server = options.server.clone();
        let names = ServiceNames::new(&server);
        let node = Self::make_node(&options)?;

        let opening = Opening::new(&server, options.connect_timeout);
        let (subscriber, _) =
            ports::open_subscriber::<S, ServerInfo>(&node, &opening, &names.info())?;
        let info = LatestCache::new(subscriber);
        // The server delivers its history sample when it next updates its connections: it
        // gets half a second from the moment the subscriber exists, however much of the
        // connect timeout waiting for a free slot took (a client that got the last slot
        // late was told that the server was still starting up).
        let info_timeout = options.connect_timeout.max(INFO_WAIT);
        let info_deadline = (started + info_timeout).max(Instant::now() + INFO_WAIT);
        let description = loop {
            let received = info
                .refresh()
                .map_err(|error| ConnectError::Description(Box::new(error)))?;
            if let Some(description) = received {
                break description;
            }
            if Instant::now() >= info_deadline {
                return Err(ConnectError::NoInfo {
                    name: server,
                    service: names.info(),
                    waited: started.elapsed(),
                });
            }
            std::thread::sleep(Duration::from_millis(5));
        };
        check_schema(&server, description.schema_version)?;
        let axis_count = description.axes().len();
        let session = Session::new(
            &server,
            description.origin_node(),
            description.server_pid,
            description.start_time_ns,
        );
        drop(description);
        Ok(Self::assemble(
            &options, server, node, names, info, session, axis_count,
        ))
    }

    /// The client made of what connecting found, over either transport (a remote client
    /// then sets its `remote` link): no port is open yet beyond the description's.
    pub(crate) fn assemble(
        options: &ClientBuilder,
        server: String,
        node: Node<S>,
        names: ServiceNames,
        info: LatestCache<S, ServerInfo>,
        session: Session,
        axis_count: usize,
    ) -> Self {
        let id = ClientId::from_u128(node.id().value());
        Self {
            server,
            node,
            id,
            names,
            connect_timeout: options.connect_timeout,
            reply_timeout: options.reply_timeout,
            info,
            frames: RefCell::new(None),
            commands: RefCell::new(None),
            stats: RefCell::new(None),
            params: RefCell::new(None),
            session,
            sequence: Cell::new(0),
            goal_ticks: RefCell::new(vec![(0, 0); axis_count]),
            jogs: RefCell::new(JogTable::default()),
            paths: RefCell::new(None),
            setpoints: RefCell::new(None),
            path_ids: Cell::new(0),
            group_runs: RefCell::new(Vec::new()),
            #[cfg(feature = "zenoh")]
            remote: None,
        }
    }

    /// Whether this client talks to its server through a bridge (feature `zenoh`).
    pub fn is_remote(&self) -> bool {
        #[cfg(feature = "zenoh")]
        if self.remote.is_some() {
            return true;
        }
        false
    }

    /// The frame subscription, opened on first use.
    pub(crate) fn frame_ports(&self) -> Result<Rc<FramePorts<S>>, ClientError> {
        if let Some(ports) = self.frames.borrow().as_ref() {
            return Ok(Rc::clone(ports));
        }
        #[cfg(feature = "zenoh")]
        if let Some(link) = &self.remote {
            let feed = link.feed::<MotionFrame>(&link.keys().frame(), true)?;
            let ports = Rc::new(FramePorts {
                cache: LatestCache::remote(feed),
                tick: None,
                service_id: None,
            });
            *self.frames.borrow_mut() = Some(Rc::clone(&ports));
            return Ok(ports);
        }
        let opening = Opening::new(&self.server, self.connect_timeout);
        let ports = Rc::new(ports::open_frames(
            &self.node,
            &opening,
            &self.names.frame(),
            &self.names.tick(),
        )?);
        *self.frames.borrow_mut() = Some(Rc::clone(&ports));
        Ok(ports)
    }

    /// The frame subscription if it is open (never opens it).
    pub(crate) fn frame_ports_if_open(&self) -> Option<Rc<FramePorts<S>>> {
        self.frames.borrow().as_ref().map(Rc::clone)
    }

    /// The command port, opened on first use.
    pub(crate) fn command_ports(&self) -> Result<Rc<CommandPorts<S>>, ClientError> {
        if let Some(ports) = self.commands.borrow().as_ref() {
            return Ok(Rc::clone(ports));
        }
        let opening = Opening::new(&self.server, self.connect_timeout);
        let ports = Rc::new(ports::open_commands(
            &self.node,
            &opening,
            &self.names.command(),
        )?);
        *self.commands.borrow_mut() = Some(Rc::clone(&ports));
        self.reserve_setpoint_port();
        Ok(ports)
    }

    /// When the frame service was recreated (a server that could not reuse it), the frame
    /// subscription is reopened on the new one; true when that happened.
    pub(crate) fn reopen_frames_if_recreated(&self) -> Result<bool, ClientError> {
        if self.is_remote() {
            return Ok(false);
        }
        let Some(ports) = self.frame_ports_if_open() else {
            return Ok(false);
        };
        let now = ports::pubsub_id_now::<S, MotionFrame>(&self.node, &self.names.frame());
        if now.is_none_or(|id| Some(id) == ports.service_id) {
            return Ok(false);
        }
        *self.frames.borrow_mut() = None;
        drop(ports);
        self.frame_ports()?;
        Ok(true)
    }

    /// Like [`Client::reopen_frames_if_recreated`] for the command port.
    pub(crate) fn reopen_commands_if_recreated(&self) -> Result<bool, ClientError> {
        if self.is_remote() {
            return Ok(false);
        }
        let Some(ports) = self.commands.borrow().as_ref().map(Rc::clone) else {
            return Ok(false);
        };
        let now = ports::command_id_now::<S>(&self.node, &self.names.command());
        if now.is_none_or(|id| id == ports.service_id) {
            return Ok(false);
        }
        *self.commands.borrow_mut() = None;
        drop(ports);
        self.command_ports()?;
        Ok(true)
    }

    fn open_stats(&self) {
        if self.stats.borrow().is_some() {
            return;
        }
        #[cfg(feature = "zenoh")]
        if let Some(link) = &self.remote {
            *self.stats.borrow_mut() = link.stats_cache(self.reply_timeout);
            return;
        }
        let opening = Opening::once(&self.server);
        if let Ok((subscriber, _)) =
            ports::open_subscriber::<S, ServerStats>(&self.node, &opening, &self.names.stats())
        {
            *self.stats.borrow_mut() = Some(LatestCache::new(subscriber));
        }
    }

    /// The instance name this client talks to.
    pub fn server_name(&self) -> &str {
        &self.server
    }

    /// This client's id as the server sees it (its iceoryx2 node id). Every request carries
    /// it in [`CommandRequest::client`]; the server takes identity from the transport and
    /// refuses a request whose non-zero `client` is not the sending node, so zero would do
    /// as well (a client in another language may send zero).
    pub fn id(&self) -> ClientId {
        self.id
    }

    /// The iceoryx2 node of this client (to build your own ports or wait sets).
    pub fn node(&self) -> &Node<S> {
        &self.node
    }

    /// The service names of the server.
    pub fn service_names(&self) -> &ServiceNames {
        &self.names
    }

    /// Takes every waiting description and keeps the newest; notes a restart.
    pub(crate) fn refresh_info(&self) -> Result<Option<Info<S>>, ClientError> {
        while let Some(info) = self.info.take_next()? {
            let seen =
                self.session
                    .observe_info(info.origin_node(), info.server_pid, info.start_time_ns);
            match seen {
                Seen::Retired => self.info.forget(),
                Seen::Restarted => self.on_restart(),
                Seen::Current => {}
            }
        }
        Ok(self.info.current())
    }

    /// The server's description: axes (names, units, limits, capabilities, supervision),
    /// devices, signals, tick rate, deadman. Refreshed from the info service on every call
    /// (devices coming online or reporting firmware change it; the axis and signal lists
    /// never change while a server runs).
    pub fn info(&self) -> Result<Info<S>, ClientError> {
        self.refresh_info()?
            .ok_or_else(|| ClientError::NotPublished {
                what: "server description",
                service: self.names.info(),
                why: Unanswered::NotFromThisServer,
            })
    }

    /// The newest [`ServerStats`] (published about once a second); `None` until the first.
    pub fn stats(&self) -> Result<Option<Stats<S>>, ClientError> {
        self.open_stats();
        match self.stats.borrow().as_ref() {
            Some(cache) => cache.refresh(),
            None => Ok(None),
        }
    }

    /// The machine parameters in effect (every device's and axis's key as the config spells
    /// it, its effective value with unit, and whether the config set it or it is the
    /// default). The params service is subscribed to on the first call only; waits up to the
    /// reply timeout for the server's sample.
    pub fn machine_params(&self) -> Result<Params<S>, ClientError> {
        #[cfg(feature = "zenoh")]
        if let Some(link) = &self.remote {
            return link.machine_params(&self.params, self.reply_timeout);
        }
        let cache = match self.params.borrow().as_ref() {
            Some(cache) => Some(Rc::clone(cache)),
            None => None,
        };
        let cache = match cache {
            Some(cache) => cache,
            None => {
                let opening = Opening::once(&self.server);
                let service = self.names.params();
                let (subscriber, _) =
                    ports::open_subscriber::<S, MachineParams>(&self.node, &opening, &service)
                        .map_err(|error| match error {
                            ConnectError::NoServer { .. } => ClientError::NotPublished {
                                what: "machine parameters",
                                service: service.clone(),
                                why: Unanswered::NoService { schema: 2 },
                            },
                            other => other.into(),
                        })?;
                let cache = Rc::new(LatestCache::new(subscriber));
                *self.params.borrow_mut() = Some(Rc::clone(&cache));
                cache
            }
        };
        let deadline = Instant::now() + self.reply_timeout;
        loop {
            if let Some(params) = cache.refresh()? {
                return Ok(params);
            }
            if Instant::now() >= deadline {
                return Err(ClientError::NotPublished {
                    what: "machine parameters",
                    service: self.names.params(),
                    why: Unanswered::Timeout(self.reply_timeout),
                });
            }
            std::thread::sleep(Duration::from_millis(5));
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

    /// The static description of axis `index` (a copy).
    pub(crate) fn axis_info(&self, index: usize) -> AxisInfo {
        self.info
            .current()
            .and_then(|info| info.axes().get(index).copied())
            .unwrap_or(AxisInfo::EMPTY)
    }

    /// The static description of signal `index` (a copy).
    pub(crate) fn signal_info(&self, index: usize) -> SignalInfo {
        self.info
            .current()
            .and_then(|info| info.signals().get(index).copied())
            .unwrap_or(SignalInfo::EMPTY)
    }

    /// The name of device `index`.
    pub(crate) fn device_name(&self, index: usize) -> String {
        self.info
            .current()
            .and_then(|info| info.devices().get(index).map(|d| d.name().to_owned()))
            .unwrap_or_else(|| format!("#{index}"))
    }

    /// What a request is about, for messages: "axis x", "signal lamp", "all axes".
    pub(crate) fn target_label(&self, target: Target, index: u32) -> String {
        if target == Target::Axis && index == CommandRequest::ALL_AXES {
            return "all axes".to_owned();
        }
        let name = match target {
            Target::Axis => self.axis_info(index as usize).name().to_owned(),
            Target::Signal => self.signal_info(index as usize).name().to_owned(),
            Target::Group => self
                .info
                .current()
                .and_then(|info| {
                    info.groups()
                        .get(index as usize)
                        .map(|g| g.name().to_owned())
                })
                .unwrap_or_default(),
            Target::Device => self
                .info
                .current()
                .and_then(|info| {
                    info.devices()
                        .get(index as usize)
                        .map(|d| d.name().to_owned())
                })
                .unwrap_or_default(),
        };
        let what = match target {
            Target::Axis => "axis",
            Target::Signal => "signal",
            Target::Group => "group",
            Target::Device => "device",
        };
        match name.as_str() {
            "" => format!("{what} #{index}"),
            name => format!("{what} {name}"),
        }
    }

    /// The server restart this client saw and nobody acknowledged yet, if any.
    pub fn restart(&self) -> Option<Restart> {
        self.session.unacknowledged()
    }

    /// Looks for a server restart now (reads the newest description; cheap). `Err` with
    /// [`ClientError::ServerRestarted`] while a restart is not acknowledged.
    pub fn check_server(&self) -> Result<(), ClientError> {
        self.refresh_info()?;
        match self.session.unacknowledged() {
            Some(restart) => Err(ClientError::ServerRestarted(restart)),
            None => Ok(()),
        }
    }

    /// Accepts that the server restarted: goals may be sent to the new server again (jog
    /// and claim guards of the old server stay ended). Returns the restart, if one was
    /// pending.
    pub fn acknowledge_restart(&self) -> Option<Restart> {
        self.session.acknowledge()
    }

    /// Forgets what belonged to the old server after a restart was noticed.
    pub(crate) fn on_restart(&self) {
        if let Some(ports) = self.frame_ports_if_open() {
            ports.cache.forget();
        }
        // Read the new server's description (its pid) if it is already there.
        while let Ok(Some(info)) = self.info.take_next() {
            if self
                .session
                .observe_info(info.origin_node(), info.server_pid, info.start_time_ns)
                == Seen::Retired
            {
                self.info.forget();
            }
        }
    }

    /// `Err(Interrupted)` once SIGINT or SIGTERM arrived (with iceoryx2 signal handling on).
    pub fn check_interrupted(&self) -> Result<(), ClientError> {
        match self.node.wait(Duration::ZERO) {
            Ok(()) => Ok(()),
            Err(_) => Err(ClientError::Interrupted),
        }
    }

    /// The tick event listener (opens the frame subscription if needed), to attach to your
    /// own iceoryx2 `WaitSet` (`waitset.attach_notification(&*client.tick_listener()?)`).
    /// After a wake-up, read with [`Client::latest`] or [`Client::try_next_frame`].
    ///
    /// A remote client (feature `zenoh`) has no tick event: `Err(Network)`; use
    /// [`Client::next_frame`] or [`Client::for_each_frame`].
    pub fn tick_listener(&self) -> Result<TickListener<S>, ClientError> {
        match &self.frame_ports()?.tick {
            Some(listener) => Ok(TickListener(Rc::clone(listener))),
            None => Err(ClientError::Network {
                what: "listen to the tick event",
                why: Unanswered::NotOnThisConnection(
                    "a client connected through a bridge has no tick event to attach to a \
                     WaitSet: use next_frame or for_each_frame",
                ),
            }),
        }
    }

    /// Blocks until the next tick notification or `timeout` (no busy waiting); over a
    /// bridge, until the next frame arrives.
    pub(crate) fn wait_tick(&self, timeout: Duration) -> Result<(), ClientError> {
        let ports = self.frame_ports()?;
        let Some(tick) = ports.tick.as_ref() else {
            #[cfg(feature = "zenoh")]
            if let Some(feed) = ports.cache.feed() {
                feed.wait(timeout)?;
            }
            return self.check_interrupted();
        };
        match tick.timed_wait(|_| {}, timeout) {
            Ok(_) => self.check_interrupted(),
            Err(iceoryx2::port::listener::ListenerWaitError::InterruptSignal) => {
                self.check_interrupted()
            }
            Err(error) => Err(ClientError::ipc("wait for the tick event", error)),
        }
    }
}
