//! The bridge process: one loop that takes the server's samples from shared memory and
//! publishes them on zenoh, and takes remote commands from zenoh, judges them
//! ([`Policy`]) and forwards them to the server's command service, passing each reply back.
//!
//! The bridge forwards only what arrives: it never renews a jog on a remote's behalf, so a
//! remote whose network drops stops sending renewals and the server's deadman stops its
//! axis within `command_timeout_ms`. When a remote's session ends (its zenoh liveliness
//! token goes: the process ended, or zenoh gave up on its link), the bridge sends a stop
//! for every axis still running that remote's jog and releases its claims; on its own exit
//! it stops every remote jog.

mod commands;
mod error;
mod intake;
mod jobs;
mod net;
mod refusals;
mod server;
mod sessions;

use core::time::Duration;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::Instant;

use iceoryx2::node::Node;
use iceoryx2::prelude::SignalHandlingMode;
use motion_ipc::{
    ClientId, CommandReply, MachineParams, MotionFrame, ServerInfo, ServerStats, ServiceNames,
};
use zenoh::Wait as _;
use zenoh::query::Query;

pub use error::BridgeError;
pub use net::zenoh_config;

use self::commands::InFlight;
use self::intake::Intake;
use self::jobs::Queue;
use self::net::Net;
use self::server::{Ipc, ServerPorts};
use crate::config::BridgeConfig;
use crate::policy::Policy;
use motion_wire::keys::{Keys, Origin, Refusal};
use motion_wire::wire::{self, Payload};

/// How long the loop sleeps at most between looks at the server.
const POLL: Duration = Duration::from_millis(5);
/// Frames may stay away this long before the bridge takes the server for gone.
const SILENCE: Duration = Duration::from_secs(1);
/// How often a missing server is looked for.
const REOPEN: Duration = Duration::from_millis(250);
/// Remote queries waiting in the loop's channel; more are answered `busy` on zenoh's
/// thread (a flood never grows the bridge's memory). E-stops do not wait there.
const MAX_WAITING_QUERIES: usize = 1024;
/// Events the loop handles between two looks at the server (its samples, replies and
/// request slots): a flood of queries never keeps it from them.
const EVENTS_PER_TURN: usize = 64;
/// How long the bridge's own stops wait for the server when it exits.
const SHUTDOWN_WAIT: Duration = Duration::from_millis(500);

/// A read of the newest state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Read {
    Info,
    Stats,
    Params,
    Frame,
}

/// What wakes the loop.
pub(crate) enum Event {
    /// The server published a frame.
    Tick,
    /// A remote's command, and when zenoh handed it over.
    Command(Query, Instant),
    /// A remote opens a session, and when zenoh handed the query over.
    Open(Query, Instant),
    /// A remote reads the newest description, statistics, parameters or frame.
    Read(Read, Query),
    /// A remote client's liveliness token appeared or went.
    Remote { key: String, alive: bool },
    /// An e-stop waits on its own path (`intake.rs`).
    Estop,
    /// A transport to a remote peer (its zenoh id) opened or closed.
    Transport { zid: String, alive: bool },
}

/// The newest sample of a service, as received and as bytes for the network.
struct Cached<T> {
    value: Box<T>,
    origin: u128,
    bytes: Vec<u8>,
}

impl<T: Payload + Copy> Cached<T> {
    fn new(value: &T, origin: u128) -> Self {
        Self {
            value: Box::new(*value),
            origin,
            bytes: wire::encode(value),
        }
    }
}

/// Counters for the log.
#[derive(Debug, Default, Clone, Copy)]
struct Counters {
    forwarded: u64,
    refused: u64,
    frames: u64,
}

/// A running bridge of one motiond instance; see the crate docs.
pub struct Bridge {
    config: BridgeConfig,
    keys: Keys,
    names: ServiceNames,
    node: Node<Ipc>,
    bridge_id: ClientId,
    server: Option<ServerPorts>,
    next_open: Instant,
    last_frame_at: Instant,
    net: Net,
    events: Receiver<Event>,
    intake: Arc<Intake>,
    /// The zenoh ids of the remotes connected to the bridge itself.
    transports: std::collections::HashSet<String>,
    tick_pending: Arc<AtomicBool>,
    ticker_stop: Arc<AtomicBool>,
    ticker: Option<std::thread::JoinHandle<()>>,
    policy: Policy,
    started: Instant,
    info: Option<Cached<ServerInfo>>,
    stats: Option<Cached<ServerStats>>,
    params: Option<Cached<MachineParams>>,
    frame: Option<(Box<MotionFrame>, u128)>,
    next_frame_tick: u64,
    next_json: Instant,
    queue: Queue,
    in_flight: Vec<InFlight>,
    counters: Counters,
}

impl core::fmt::Debug for Bridge {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Bridge")
            .field("server", &self.config.server)
            .field("connected", &self.server.is_some())
            .field("counters", &self.counters)
            .finish_non_exhaustive()
    }
}

impl Bridge {
    /// Opens the zenoh session (listening as configured) and starts watching the server;
    /// the server need not run yet.
    pub fn start(config: BridgeConfig) -> Result<Self, BridgeError> {
        let keys = Keys::new(&config.server)?;
        let names = ServiceNames::new(&config.server);
        let node = server::node(
            "motion-bridge",
            SignalHandlingMode::HandleTerminationRequests,
        )?;
        let (sender, events) = std::sync::mpsc::channel();
        let now = Instant::now();
        let intake = Arc::new(
            Intake::new(keys.clone(), config.remotes.clone(), sender.clone(), now)
                .map_err(BridgeError::Thread)?,
        );
        let zenoh = zenoh_config(
            config.zenoh_config.as_deref(),
            "peer",
            &config.listen,
            &config.connect,
        )?;
        net::check_exposure(&config, &zenoh)?;
        let net = Net::open(zenoh, &keys, &sender, &intake)?;
        let tick_pending = Arc::new(AtomicBool::new(false));
        let ticker_stop = Arc::new(AtomicBool::new(false));
        let ticker = server::spawn_ticker(
            &names,
            sender,
            Arc::clone(&tick_pending),
            Arc::clone(&ticker_stop),
        )
        .map_err(BridgeError::Thread)?;
        let bridge_id = ClientId::from_u128(node.id().value());
        let policy = Policy::new(config.remotes.clone(), config.max_delay);
        tracing::info!(
            server = %config.server,
            listen = ?config.listen,
            connect = ?config.connect,
            zid = %net.session.zid(),
            remotes = config.remotes.len(),
            "bridge up"
        );
        Ok(Self {
            config,
            keys,
            names,
            node,
            bridge_id,
            server: None,
            next_open: now,
            last_frame_at: now,
            net,
            events,
            intake,
            transports: std::collections::HashSet::new(),
            tick_pending,
            ticker_stop,
            ticker: Some(ticker),
            policy,
            started: now,
            info: None,
            stats: None,
            params: None,
            frame: None,
            next_frame_tick: 0,
            next_json: now,
            queue: Queue::default(),
            in_flight: Vec::new(),
            counters: Counters::default(),
        })
    }

    /// The zenoh id of the bridge's session.
    pub fn zid(&self) -> String {
        self.net.session.zid().to_string()
    }

    /// Runs until SIGINT or SIGTERM (or `stop` is set), then stops every remote jog.
    pub fn run(&mut self, stop: &AtomicBool) {
        while !stop.load(Ordering::Relaxed) && self.node.wait(Duration::ZERO).is_ok() {
            match self.events.recv_timeout(POLL) {
                Ok(event) => self.handle(event),
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => break,
            }
            for _ in 0..EVENTS_PER_TURN {
                if self.intake.estop_waiting() {
                    self.take_estops();
                }
                let Ok(event) = self.events.try_recv() else {
                    break;
                };
                self.handle(event);
            }
            self.service();
        }
        self.shutdown();
    }

    fn handle(&mut self, event: Event) {
        match event {
            Event::Tick => self.tick_pending.store(false, Ordering::Release),
            Event::Command(query, received) => {
                self.intake.took_one();
                self.on_command(query, received);
            }
            Event::Open(query, received) => {
                self.intake.took_one();
                self.on_open(query, received);
            }
            Event::Read(read, query) => {
                self.intake.took_one();
                self.on_read(read, &query);
            }
            Event::Remote { key, alive } => self.on_remote(&key, alive),
            Event::Estop => self.take_estops(),
            Event::Transport { zid, alive } => self.on_transport(zid, alive),
        }
    }

    /// Everything that does not wait for an event: the server's samples, publishing,
    /// sending queued commands and passing replies back.
    fn service(&mut self) {
        self.take_estops();
        let now = Instant::now();
        if self.server.is_none() && now >= self.next_open {
            self.next_open = now + REOPEN;
            match ServerPorts::open(&self.node, &self.names) {
                Ok(ports) => {
                    tracing::info!(server = %self.config.server, "motiond found");
                    self.server = Some(ports);
                    self.last_frame_at = now;
                }
                Err(why) => tracing::debug!(%why, "motiond not there yet"),
            }
        }
        self.take_samples(now);
        self.publish_json(now);
        self.pump();
        self.collect_replies(now);
        self.intake.flush_log(false);
    }

    fn take_samples(&mut self, now: Instant) {
        let Some(ports) = self.server.as_ref() else {
            return;
        };
        let mut failure = None;
        let mut infos = Vec::new();
        let mut stats = None;
        let mut params = None;
        if let Err(error) = server::drain(&ports.info, |value, origin| {
            infos.push(Cached::new(value, origin));
        }) {
            failure = Some(error);
        }
        if let Err(error) = server::drain(&ports.stats, |value, origin| {
            stats = Some(Cached::new(value, origin));
        }) {
            failure = Some(error);
        }
        if let Some(subscriber) = ports.params.as_ref()
            && let Err(error) = server::drain(subscriber, |value, origin| {
                params = Some(Cached::new(value, origin));
            })
        {
            failure = Some(error);
        }
        for info in infos {
            self.on_info(info);
        }
        if let Some(stats) = stats {
            if let Err(error) = self
                .net
                .stats
                .put(stats.bytes.clone())
                .attachment(Origin(stats.origin).encode())
                .wait()
            {
                tracing::warn!(%error, "cannot publish stats");
            }
            self.stats = Some(stats);
        }
        if params.is_some() {
            self.params = params;
        }
        if let Err(error) = self.take_frames(now) {
            failure = Some(error);
        }
        if failure.is_some() || now.duration_since(self.last_frame_at) > SILENCE {
            tracing::warn!(
                server = %self.config.server,
                why = failure.map_or_else(|| "no frame for a second".to_owned(), |error| error.to_string()),
                "motiond gone; looking for it again"
            );
            self.drop_server();
        }
    }

    fn on_info(&mut self, info: Cached<ServerInfo>) {
        if let Some(old) = &self.info
            && old.origin != info.origin
        {
            tracing::info!("motiond restarted: remote claims and jogs ended with it");
            self.policy.server_restarted();
            self.next_frame_tick = 0;
        }
        if let Err(error) = self
            .net
            .info
            .put(info.bytes.clone())
            .attachment(Origin(info.origin).encode())
            .wait()
        {
            tracing::warn!(%error, "cannot publish the server description");
        }
        self.info = Some(info);
    }

    /// Frames since the last look: every `tick_hz / frame_rate`-th published.
    fn take_frames(&mut self, now: Instant) -> Result<(), BridgeError> {
        let Some(ports) = self.server.as_ref() else {
            return Ok(());
        };
        let tick_hz = self.info.as_ref().map_or(1000, |info| info.value.tick_hz);
        let decimation =
            ((f64::from(tick_hz.max(1)) / self.config.frame_rate).round() as u64).max(1);
        let mut newest: Option<(MotionFrame, u128)> = None;
        let mut next_tick = self.next_frame_tick;
        let publisher = &self.net.frame;
        let mut published = 0;
        let mut restarted = false;
        server::drain(&ports.frame, |frame, origin| {
            if let Some((last, _)) = &newest
                && frame.tick < last.tick
            {
                restarted = true;
                next_tick = 0;
            }
            if frame.tick >= next_tick {
                next_tick = frame.tick + decimation;
                published += 1;
                if let Err(error) = publisher
                    .put(wire::encode(frame))
                    .attachment(Origin(origin).encode())
                    .wait()
                {
                    tracing::warn!(%error, "cannot publish a frame");
                }
            }
            newest = Some((*frame, origin));
        })?;
        if let Some((frame, origin)) = newest {
            if self
                .frame
                .as_ref()
                .is_some_and(|(last, _)| frame.tick < last.tick)
            {
                restarted = true;
                // The first frames of the new server: publish from the next one due.
                next_tick = frame.tick + 1;
            }
            self.last_frame_at = now;
            self.policy.reconcile(&frame, self.bridge_id);
            match self.frame.as_mut() {
                Some((boxed, node)) => {
                    **boxed = frame;
                    *node = origin;
                }
                None => self.frame = Some((Box::new(frame), origin)),
            }
        }
        if restarted {
            self.policy.server_restarted();
        }
        self.next_frame_tick = next_tick;
        self.counters.frames += published;
        Ok(())
    }

    fn publish_json(&mut self, now: Instant) {
        if now < self.next_json {
            return;
        }
        let period = Duration::from_secs_f64(1.0 / self.config.json_rate);
        self.next_json = (self.next_json + period).max(now);
        let (Some(info), Some((frame, _))) = (&self.info, &self.frame) else {
            return;
        };
        let policy = &self.policy;
        let state = motion_wire::json::state(&info.value, frame, |target, index| {
            policy
                .holder(target, index)
                .map(|remote| remote.identity.as_str())
        });
        match serde_json::to_vec(&state) {
            Ok(bytes) => {
                if let Err(error) = self.net.json.put(bytes).wait() {
                    tracing::warn!(%error, "cannot publish the JSON state");
                }
            }
            Err(error) => tracing::warn!(%error, "cannot write the JSON state"),
        }
    }

    /// Forgets the server's ports; what waited for it is answered `no-server`.
    fn drop_server(&mut self) {
        self.refuse_all(Refusal::NoServer, "motiond went away before it answered");
        self.server = None;
        self.next_open = Instant::now() + REOPEN;
    }

    fn latest_tick(&self) -> u64 {
        self.frame.as_ref().map_or(0, |(frame, _)| frame.tick)
    }

    fn server_node(&self) -> u128 {
        self.info.as_ref().map_or(0, |info| info.origin)
    }

    fn on_read(&self, read: Read, query: &Query) {
        let cached = match read {
            Read::Info => self.info.as_ref().map(|c| (c.bytes.clone(), c.origin)),
            Read::Stats => self.stats.as_ref().map(|c| (c.bytes.clone(), c.origin)),
            Read::Params => self.params.as_ref().map(|c| (c.bytes.clone(), c.origin)),
            Read::Frame => self
                .frame
                .as_ref()
                .map(|(frame, origin)| (wire::encode(&**frame), *origin)),
        };
        match cached {
            Some((bytes, origin)) => {
                if let Err(error) = query
                    .reply(query.key_expr().clone(), bytes)
                    .attachment(Origin(origin).encode())
                    .wait()
                {
                    tracing::debug!(%error, "cannot answer a read");
                }
            }
            None => refuse(
                Some(query),
                Refusal::NoServer,
                &format!(
                    "motiond `{}` has published no {} to this bridge (not running?)",
                    self.config.server,
                    match read {
                        Read::Info => "description",
                        Read::Stats => "statistics",
                        Read::Params => "machine parameters",
                        Read::Frame => "frame",
                    }
                ),
            ),
        }
    }

    /// A transport to the remote `zid` opened or closed: the sessions opened through it end
    /// with it (a copy of their liveliness keys does not keep them).
    fn on_transport(&mut self, zid: String, alive: bool) {
        if alive {
            self.transports.insert(zid);
            return;
        }
        self.transports.remove(&zid);
        let requests = self.policy.transport_gone(&zid);
        if !requests.is_empty() {
            tracing::info!(
                %zid,
                stops_and_releases = requests.len(),
                "a remote's transport closed: its sessions end"
            );
        }
        for request in requests {
            self.queue.push_own(request);
        }
    }

    fn on_remote(&mut self, key: &str, alive: bool) {
        let Some((identity, session)) = self.keys.remote_of(key) else {
            return;
        };
        if alive {
            tracing::info!(%identity, %session, "remote client connected");
            self.policy.session_live(&identity, session);
            return;
        }
        let requests = self.policy.session_gone(&identity, session);
        tracing::info!(
            %identity,
            %session,
            stops_and_releases = requests.len(),
            "remote client gone"
        );
        for request in requests {
            self.queue.push_own(request);
        }
    }

    /// Stops every remote jog and waits a little for the server to take the stops.
    fn shutdown(&mut self) {
        let stops = self.policy.shutdown();
        if !stops.is_empty() {
            tracing::info!(axes = stops.len(), "stopping remote jogs before exiting");
        }
        for request in stops {
            self.queue.push_own(request);
        }
        let until = Instant::now() + SHUTDOWN_WAIT;
        while (!self.queue.is_empty() || !self.in_flight.is_empty()) && Instant::now() < until {
            self.pump();
            self.collect_replies(Instant::now());
            std::thread::sleep(Duration::from_millis(1));
        }
        self.intake.flush_log(true);
        tracing::info!(
            forwarded = self.counters.forwarded,
            refused = self.counters.refused,
            frames = self.counters.frames,
            "bridge down"
        );
    }
}

impl Drop for Bridge {
    fn drop(&mut self) {
        self.ticker_stop.store(true, Ordering::Relaxed);
        if let Some(ticker) = self.ticker.take() {
            let _ = ticker.join();
        }
    }
}

fn answer(query: &Query, reply: &CommandReply, origin: u128) {
    if let Err(error) = query
        .reply(query.key_expr().clone(), wire::encode(reply))
        .attachment(Origin(origin).encode())
        .wait()
    {
        tracing::debug!(%error, "cannot pass a reply back");
    }
}

pub(crate) fn refuse(query: Option<&Query>, refusal: Refusal, text: &str) {
    if let Some(query) = query
        && let Err(error) = query.reply_err(refusal.reply_text(text)).wait()
    {
        tracing::debug!(%error, "cannot send a refusal");
    }
}
