//! An e-stop that always gets through, and a stop of every axis that needs nothing but the
//! command service. Neither connects a [`Client`](crate::Client): no frame subscription, no
//! server description.

use core::fmt;
use core::time::Duration;
use std::time::Instant;

use iceoryx2::node::{Node, NodeView as _};
use iceoryx2::port::notifier::NotifierCreateError;
use iceoryx2::prelude::{CallbackProgression, Config, NodeName, NodeState, SignalHandlingMode};
use iceoryx2::service::Service;
use motion_ipc::{
    ClientId, CommandKind, CommandReply, CommandRequest, FrameFlags, MotionFrame, PidFileError,
    Reason, ServerPidFile, ServiceNames,
};
use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;

use crate::error::with_causes;
use crate::ports::{self, CommandPorts, Opening, service_name};
use crate::{Accepted, ClientError, ConnectError, EstopError};

/// How an e-stop was delivered by [`estop`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EstopPath {
    /// A request on the command service, accepted by the server in `tick`.
    Command {
        /// The tick in which the e-stop latched.
        tick: u64,
    },
    /// A notification on the `estop` event service, taken by `listeners` listeners (the
    /// server latches on any notification; there is no reply to wait for).
    Event {
        /// How many listeners were notified.
        listeners: usize,
    },
    /// SIGUSR1 to the server's process, as its pid file names it.
    Signal {
        /// The process signalled.
        pid: i32,
    },
}

impl EstopPath {
    /// "command", "event" or "signal".
    pub const fn name(&self) -> &'static str {
        match self {
            Self::Command { .. } => "command",
            Self::Event { .. } => "event",
            Self::Signal { .. } => "signal",
        }
    }
}

impl fmt::Display for EstopPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Command { tick } => write!(f, "the command service (latched in tick {tick})"),
            Self::Event { listeners } => write!(
                f,
                "the estop event service ({listeners} listener{} notified)",
                if *listeners == 1 { "" } else { "s" }
            ),
            Self::Signal { pid } => write!(f, "SIGUSR1 to the server process (pid {pid})"),
        }
    }
}

fn node<S: Service>(name: &str) -> Result<Node<S>, ConnectError> {
    let node_name = NodeName::new(name).map_err(|error| ConnectError::InvalidName {
        name: name.to_owned(),
        kind: "node",
        source: error.into(),
    })?;
    crate::ports::create_node::<S>(&node_name, SignalHandlingMode::Disabled)
        .map_err(|error| ConnectError::ipc("create a node", error))
}

/// Sends `kind` for every axis on a fresh command port and waits for the reply until
/// `deadline`.
fn command_all<S: Service>(
    node: &Node<S>,
    server: &str,
    opening: &Opening<'_>,
    kind: CommandKind,
    deadline: Instant,
) -> Result<CommandReply, ClientError> {
    let names = ServiceNames::new(server);
    let CommandPorts { port, .. } = ports::open_commands(node, opening, &names.command())?;
    let request = CommandRequest::new(
        ClientId::from_u128(node.id().value()),
        1,
        CommandRequest::ALL_AXES,
        kind,
    );
    let pending = port
        .send_copy(request)
        .map_err(|error| ClientError::ipc("send a command", error))?;
    if pending.number_of_server_connections() == 0 {
        return Err(ClientError::NoServer { kind: kind.name() });
    }
    let started = Instant::now();
    loop {
        if let Some(response) = pending
            .receive()
            .map_err(|error| ClientError::ipc("receive a command reply", error))?
        {
            if response.payload().sequence == request.sequence {
                return Ok(*response.payload());
            }
            continue;
        }
        if Instant::now() >= deadline {
            return Err(ClientError::NoReply {
                kind: kind.name(),
                waited: started.elapsed(),
            });
        }
        std::thread::sleep(Duration::from_micros(100));
    }
}

/// Stops every axis of the instance `server` through the command service alone (no frame
/// subscription, no description): opens a command port, sends `Stop` for all axes and
/// waits for the reply. `timeout` bounds the whole call (a missing service is retried for
/// it).
pub fn stop_all<S: Service>(server: &str, timeout: Duration) -> Result<Accepted, ClientError> {
    let deadline = Instant::now() + timeout;
    let node = node::<S>("motion-stop")?;
    let opening = Opening::new(server, timeout);
    let reply = command_all(&node, server, &opening, CommandKind::Stop, deadline)?;
    match reply.result() {
        Ok(()) => Ok(Accepted {
            sequence: reply.sequence,
            tick: reply.tick_applied,
        }),
        Err(reason) => Err(ClientError::refused(
            reply.kind,
            "all axes".to_owned(),
            reason,
            reply.tick_applied,
            None,
        )),
    }
}

/// An e-stop [`estop`] delivered and saw latched.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Estop {
    /// How it was delivered.
    pub path: EstopPath,
    /// The tick of the first frame seen with the e-stop latched; `None` when no frame
    /// could be read (every frame subscriber slot taken) and the command service's reply,
    /// from the one server port of the instance, is the only word of it.
    pub seen_in_frame: Option<u64>,
}

impl fmt::Display for Estop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.seen_in_frame {
            Some(tick) => write!(f, "{} — latched in the frame of tick {tick}", self.path),
            None => write!(
                f,
                "{} — no frame subscriber slot free to see it in a frame",
                self.path
            ),
        }
    }
}

/// Latches the e-stop of the instance `server` by the first path that works, needing no
/// frame subscription and no connected [`Client`](crate::Client), and reports success only
/// when the server said so:
///
/// 1. a request on the command service (a fresh client port), waiting for the reply up to
///    half of `timeout`; the reply comes from the instance's one server port;
/// 2. when the command service has no free client port, does not answer, or refuses: a
///    notification on the `estop` event service (own ports, so it works when the command
///    service's client slots are exhausted);
/// 3. when that fails too: SIGUSR1 to the server's process as its pid file names it
///    ([`ServerPidFile`]: a file only the server's user can have written, naming a live
///    process of that user with the recorded start time, whose iceoryx2 node is the
///    server's) — never a process found by its node name, which any process may choose.
///    Not sent to a process that does not catch SIGUSR1 (its `/proc/<pid>/status` says
///    so): the signal's default action would end that server instead of latching its
///    e-stop.
///
/// After an event or a signal, a frame of the server (the frame service's one publisher)
/// must show the e-stop latched before `timeout` ends; otherwise the call fails, saying
/// what was sent. After an accepted command the frame is looked for too, and the reply
/// alone is taken when no frame subscriber slot is free.
pub fn estop<S: Service>(server: &str, timeout: Duration) -> Result<Estop, EstopError> {
    let started = Instant::now();
    let deadline = started + timeout.max(Duration::from_millis(200));
    let names = ServiceNames::new(server);
    let mut server_found = false;
    let node = node::<S>("motion-estop");
    let (command, event) = match &node {
        Ok(node) => {
            // 1. The command service.
            let reply_by = started + (timeout / 2).max(Duration::from_millis(20));
            let opening = Opening::once(server);
            let command = match command_all(node, server, &opening, CommandKind::EStop, reply_by) {
                Ok(reply) => match reply.result() {
                    Ok(()) => {
                        let path = EstopPath::Command {
                            tick: reply.tick_applied,
                        };
                        return match see_latched(node, server, reply.tick_applied, deadline) {
                            Ok(tick) => Ok(Estop {
                                path,
                                seen_in_frame: Some(tick),
                            }),
                            Err(Unseen::NoSlot(_)) => Ok(Estop {
                                path,
                                seen_in_frame: None,
                            }),
                            Err(Unseen::NotLatched(why)) => {
                                Err(EstopError::unconfirmed(server, path, why))
                            }
                        };
                    }
                    Err(reason) => {
                        server_found = true;
                        refused(reason)
                    }
                },
                Err(error) => {
                    server_found |= !matches!(
                        error,
                        ClientError::NoServer { .. }
                            | ClientError::Connect(ConnectError::NoServer { .. })
                    );
                    with_causes(&error)
                }
            };
            // 2. The estop event service.
            let event = match notify_estop(node, &names) {
                Ok(listeners) => {
                    return confirm(node, server, EstopPath::Event { listeners }, deadline);
                }
                Err((found, why)) => {
                    server_found |= found;
                    why
                }
            };
            (command, event)
        }
        Err(error) => (with_causes(error), with_causes(error)),
    };
    // 3. SIGUSR1 to the server's process.
    match signal_server::<S>(server, &names) {
        Ok(pid) => match &node {
            Ok(node) => confirm(node, server, EstopPath::Signal { pid }, deadline),
            Err(error) => Err(EstopError::unconfirmed(
                server,
                EstopPath::Signal { pid },
                format!("no frame can be read: {}", with_causes(error)),
            )),
        },
        Err((found, signal)) => Err(EstopError {
            server: server.to_owned(),
            command,
            event,
            signal,
            server_found: server_found || found,
            unconfirmed: None,
        }),
    }
}

/// After an event or a signal: only a frame showing the latch counts.
fn confirm<S: Service>(
    node: &Node<S>,
    server: &str,
    path: EstopPath,
    deadline: Instant,
) -> Result<Estop, EstopError> {
    match see_latched(node, server, 0, deadline) {
        Ok(tick) => Ok(Estop {
            path,
            seen_in_frame: Some(tick),
        }),
        Err(Unseen::NoSlot(why) | Unseen::NotLatched(why)) => {
            Err(EstopError::unconfirmed(server, path, why))
        }
    }
}

/// Why no frame showed the latch.
enum Unseen {
    /// No frame could be read at all (no subscriber slot, no frame service).
    NoSlot(String),
    /// Frames came, none latched, until the deadline.
    NotLatched(String),
}

/// Waits for a frame of tick `from_tick` or later with the e-stop latched; its tick.
fn see_latched<S: Service>(
    node: &Node<S>,
    server: &str,
    from_tick: u64,
    deadline: Instant,
) -> Result<u64, Unseen> {
    let names = ServiceNames::new(server);
    let opening = Opening::once(server);
    let (subscriber, _) = ports::open_subscriber::<S, MotionFrame>(node, &opening, &names.frame())
        .map_err(|error| {
            Unseen::NoSlot(format!("no frame can be read: {}", with_causes(&error)))
        })?;
    let mut newest = None;
    loop {
        while let Some(sample) = subscriber.receive().map_err(|error| {
            let error = ClientError::ipc("receive a frame", error);
            Unseen::NoSlot(format!("frames cannot be read: {}", with_causes(&error)))
        })? {
            let frame = sample.payload();
            newest = Some(frame.tick);
            if frame.tick >= from_tick && frame.flags().contains(FrameFlags::ESTOP_LATCHED) {
                return Ok(frame.tick);
            }
        }
        if Instant::now() >= deadline {
            return Err(Unseen::NotLatched(match newest {
                Some(tick) => format!(
                    "the server's frames (the newest of tick {tick}) do not show the e-stop latched"
                ),
                None => "the server published no frame".to_owned(),
            }));
        }
        std::thread::sleep(Duration::from_millis(1));
    }
}

fn refused(reason: Reason) -> String {
    format!("refused: {reason}")
}

/// Notifies the estop event; the number of listeners notified, or (service seen, why not).
fn notify_estop<S: Service>(node: &Node<S>, names: &ServiceNames) -> Result<usize, (bool, String)> {
    let service = names.estop();
    let name = service_name(&service, "").map_err(|error| (false, with_causes(&error)))?;
    let factory = node
        .service_builder(&name)
        .event()
        .open()
        .map_err(|error| {
            let error = ConnectError::ipc("open an event service", error);
            (
                false,
                format!("cannot open {service}: {}", with_causes(&error)),
            )
        })?;
    let notifier = factory
        .notifier_builder()
        .create()
        .map_err(|error| match error {
            NotifierCreateError::ExceedsMaxSupportedNotifiers => (
                true,
                ConnectError::PortsExhausted {
                    service: service.clone(),
                    port: "notifier slot",
                }
                .to_string(),
            ),
            other => (
                true,
                with_causes(&ConnectError::ipc("create a notifier", other)),
            ),
        })?;
    match notifier.notify() {
        Ok(0) => Err((true, format!("nobody listens on {service}"))),
        Ok(listeners) => Ok(listeners),
        Err(error) => Err((
            true,
            with_causes(&ClientError::ipc("notify the estop event", error)),
        )),
    }
}

/// Whether process `pid` catches SIGUSR1, from the `SigCgt` mask of `/proc/<pid>/status`;
/// `None` when that cannot be read.
fn catches_sigusr1(pid: u32) -> Option<bool> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let mask = status
        .lines()
        .find_map(|line| line.strip_prefix("SigCgt:"))
        .and_then(|hex| u64::from_str_radix(hex.trim(), 16).ok())?;
    Some(mask & (1 << (Signal::SIGUSR1 as u64 - 1)) != 0)
}

/// Sends SIGUSR1 to the process the server's pid file names, once the file is trusted and
/// the node it names is alive, is the server's and runs in that process; its pid, or (a
/// server was seen, why not).
fn signal_server<S: Service>(server: &str, names: &ServiceNames) -> Result<i32, (bool, String)> {
    let file = ServerPidFile::of(server);
    let process = file.read_verified().map_err(|error| {
        (
            !matches!(error, PidFileError::Missing { .. }),
            error.to_string(),
        )
    })?;
    let wanted = names.server_node();
    let mut node_found = None;
    let listed = Node::<S>::list(Config::global_config(), |state| {
        if let NodeState::Alive(view) = &state
            && view.id().value() == process.node
        {
            node_found = Some(
                view.details()
                    .as_ref()
                    .map(|details| (details.name().as_str() == wanted, details.process_id())),
            );
            return CallbackProgression::Stop;
        }
        CallbackProgression::Continue
    });
    if let Err(error) = listed {
        return Err((
            true,
            with_causes(&ClientError::ipc("list the nodes", error)),
        ));
    }
    let pid = process.pid;
    match node_found {
        None => {
            return Err((
                true,
                format!(
                    "the node {} that {} names is not alive (the server is stopping?): not sent",
                    process.node,
                    file.path().display()
                ),
            ));
        }
        Some(Some((true, node_pid))) if node_pid.value() as u32 == pid => {}
        Some(_) => {
            return Err((
                true,
                format!(
                    "the node {} that {} names is not the server's `{wanted}` in process {pid}: not sent",
                    process.node,
                    file.path().display()
                ),
            ));
        }
    }
    if catches_sigusr1(pid) == Some(false) {
        // SIGUSR1's default action would end the server instead of latching its e-stop.
        return Err((
            true,
            format!(
                "the server process (pid {pid}) does not handle SIGUSR1 (an older motiond?): not sent"
            ),
        ));
    }
    let pid = i32::try_from(pid).map_err(|_| (true, format!("pid {pid} out of range")))?;
    kill(Pid::from_raw(pid), Signal::SIGUSR1)
        .map(|()| pid)
        .map_err(|error| (true, format!("kill({pid}, SIGUSR1): {error}")))
}
