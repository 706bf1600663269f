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
use motion_ipc::{ClientId, CommandKind, CommandReply, CommandRequest, Reason, ServiceNames};
use nix::sys::signal::{Signal, kill};
use nix::unistd::Pid;

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
    /// SIGUSR1 to the server's process, found by its iceoryx2 node name.
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

fn node<S: Service>(name: &str) -> Result<Node<S>, String> {
    let name = NodeName::new(name).map_err(|error| format!("{error:?}"))?;
    crate::ports::create_node::<S>(&name, SignalHandlingMode::Disabled)
        .map_err(|error| format!("cannot create an iceoryx2 node: {error:?}"))
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
    let node = node::<S>("motion-stop").map_err(|detail| ClientError::Ipc {
        what: "create a node",
        detail,
    })?;
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

/// Latches the e-stop of the instance `server` by the first path that works, needing no
/// frame subscription and no connected [`Client`](crate::Client):
///
/// 1. a request on the command service (a fresh client port), waiting for the reply up to
///    half of `timeout`;
/// 2. when the command service has no free client port, does not answer, or refuses: a
///    notification on the `estop` event service (own ports, so it works when the command
///    service's client slots are exhausted);
/// 3. when that fails too: SIGUSR1 to the server process, found by its iceoryx2 node name
///    ([`ServiceNames::server_node`]) without opening any service. Not sent to a process
///    that does not catch SIGUSR1 (its `/proc/<pid>/status` says so): the signal's default
///    action would end that server instead of latching its e-stop.
///
/// Returns the path that delivered it, or every path's failure.
pub fn estop<S: Service>(server: &str, timeout: Duration) -> Result<EstopPath, EstopError> {
    let started = Instant::now();
    let names = ServiceNames::new(server);
    let mut server_found = false;
    let (command, event) = match node::<S>("motion-estop") {
        Ok(node) => {
            // 1. The command service.
            let deadline = started + (timeout / 2).max(Duration::from_millis(20));
            let opening = Opening::once(server);
            let command = match command_all(&node, server, &opening, CommandKind::EStop, deadline) {
                Ok(reply) => match reply.result() {
                    Ok(()) => {
                        return Ok(EstopPath::Command {
                            tick: reply.tick_applied,
                        });
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
                    error.to_string()
                }
            };
            // 2. The estop event service.
            let event = match notify_estop(&node, &names) {
                Ok(listeners) => return Ok(EstopPath::Event { listeners }),
                Err((found, why)) => {
                    server_found |= found;
                    why
                }
            };
            (command, event)
        }
        Err(detail) => (detail.clone(), detail),
    };
    // 3. SIGUSR1 to the server's process.
    match signal_server::<S>(&names) {
        Ok(pid) => Ok(EstopPath::Signal { pid }),
        Err((found, signal)) => Err(EstopError {
            server: server.to_owned(),
            command,
            event,
            signal,
            server_found: server_found || found,
        }),
    }
}

fn refused(reason: Reason) -> String {
    format!("refused: {reason}")
}

/// Notifies the estop event; the number of listeners notified, or (service seen, why not).
fn notify_estop<S: Service>(node: &Node<S>, names: &ServiceNames) -> Result<usize, (bool, String)> {
    let service = names.estop();
    let name = service_name(&service, "").map_err(|error| (false, error.to_string()))?;
    let factory = node
        .service_builder(&name)
        .event()
        .open()
        .map_err(|error| (false, format!("cannot open {service}: {error:?}")))?;
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
            other => (true, format!("cannot create a notifier: {other:?}")),
        })?;
    match notifier.notify() {
        Ok(0) => Err((true, format!("nobody listens on {service}"))),
        Ok(listeners) => Ok(listeners),
        Err(error) => Err((true, format!("notify failed: {error:?}"))),
    }
}

/// Whether process `pid` catches SIGUSR1, from the `SigCgt` mask of `/proc/<pid>/status`;
/// `None` when that cannot be read.
fn catches_sigusr1(pid: i32) -> Option<bool> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let mask = status
        .lines()
        .find_map(|line| line.strip_prefix("SigCgt:"))
        .and_then(|hex| u64::from_str_radix(hex.trim(), 16).ok())?;
    Some(mask & (1 << (Signal::SIGUSR1 as u64 - 1)) != 0)
}

/// Sends SIGUSR1 to every live process whose iceoryx2 node is the server's; its pid, or
/// (a server node was seen, why not).
fn signal_server<S: Service>(names: &ServiceNames) -> Result<i32, (bool, String)> {
    let wanted = names.server_node();
    let mut pids = Vec::new();
    let listed = Node::<S>::list(Config::global_config(), |state| {
        if let NodeState::Alive(view) = &state
            && let Some(details) = view.details()
            && details.name().as_str() == wanted
        {
            pids.push(details.process_id().value());
        }
        CallbackProgression::Continue
    });
    if let Err(error) = listed {
        return Err((false, format!("cannot list iceoryx2 nodes: {error:?}")));
    }
    if pids.is_empty() {
        return Err((false, format!("no live process has the node `{wanted}`")));
    }
    let mut last = Err((true, String::new()));
    for pid in pids {
        if catches_sigusr1(pid) == Some(false) {
            // SIGUSR1's default action would end the server instead of latching its e-stop.
            last = Err((
                true,
                format!(
                    "the server process (pid {pid}) does not handle SIGUSR1 (an older motiond?): not sent"
                ),
            ));
            continue;
        }
        last = match kill(Pid::from_raw(pid), Signal::SIGUSR1) {
            Ok(()) => return Ok(pid),
            Err(error) => Err((true, format!("kill({pid}, SIGUSR1): {error}"))),
        };
    }
    last
}
