//! motiond's services as a plain process serves them, with motiond's settings: created
//! ([`create`]), every waiting request answered ([`answer`]), a frame-sized sample
//! published and the tick event notified ([`publish`]), and the lines a child process
//! says to the bench ([`say`]). The baseline peer ([`crate::peer`]) and the bare poller
//! ([`crate::poller`]) both serve with them.

use std::io::Write;

use iceoryx2::prelude::*;
use motion_ipc::{CommandReply, CommandRequest, MotionFrame, Reason, ServiceNames, Setpoint};

use crate::ipc::Ipc;
use crate::rt::now_ns;

/// Clients the peer's services admit (as motiond's default).
const MAX_CLIENTS: usize = 32;

/// motiond's services as the plain peer serves them.
pub(crate) struct PeerServices {
    _node: Node<Ipc>,
    frame: iceoryx2::port::publisher::Publisher<Ipc, MotionFrame, ()>,
    tick: iceoryx2::port::notifier::Notifier<Ipc>,
    /// The command service's server.
    pub(crate) command: iceoryx2::port::server::Server<Ipc, CommandRequest, (), CommandReply, ()>,
    /// The setpoints service's subscriber, when the peer streams.
    pub(crate) setpoints: Option<iceoryx2::port::subscriber::Subscriber<Ipc, Setpoint, ()>>,
}

/// Setpoints waiting before a tick takes them (motiond's `SETPOINTS_BUFFER`).
const SETPOINTS_BUFFER: usize = 16;

/// motiond's service settings (crates/motiond/src/services.rs, setpoints.rs).
pub(crate) fn create(name: &str, setpoints: bool) -> Result<PeerServices, String> {
    let names = ServiceNames::new(name);
    let node = crate::ipc::node("peer")?;
    let service = |n: String| ServiceName::new(&n).map_err(|e| format!("{n:?}: {e:?}"));
    let max_nodes = MAX_CLIENTS + 2;
    let frame = node
        .service_builder(&service(names.frame())?)
        .publish_subscribe::<MotionFrame>()
        .history_size(1)
        .subscriber_max_buffer_size(32) // motiond's FRAME_BUFFER
        .max_subscribers(MAX_CLIENTS)
        .max_publishers(1)
        .max_nodes(max_nodes)
        .enable_safe_overflow(true)
        .create()
        .map_err(|e| format!("{}: {e:?}", names.frame()))?
        .publisher_builder()
        .create()
        .map_err(|e| format!("frame publisher: {e:?}"))?;
    let tick = node
        .service_builder(&service(names.tick())?)
        .event()
        .max_notifiers(1)
        .max_listeners(MAX_CLIENTS)
        .max_nodes(max_nodes)
        .create()
        .map_err(|e| format!("{}: {e:?}", names.tick()))?
        .notifier_builder()
        .create()
        .map_err(|e| format!("tick notifier: {e:?}"))?;
    let command = node
        .service_builder(&service(names.command())?)
        .request_response::<CommandRequest, CommandReply>()
        .max_servers(1)
        .max_clients(MAX_CLIENTS)
        .max_nodes(max_nodes)
        .max_active_requests_per_client(8)
        .max_response_buffer_size(8)
        .enable_safe_overflow_for_responses(true)
        .create()
        .map_err(|e| format!("{}: {e:?}", names.command()))?
        .server_builder()
        .create()
        .map_err(|e| format!("command server: {e:?}"))?;
    let setpoints = if setpoints {
        Some(
            node.service_builder(&service(names.setpoints())?)
                .publish_subscribe::<Setpoint>()
                .history_size(0)
                .subscriber_max_buffer_size(SETPOINTS_BUFFER)
                .subscriber_max_borrowed_samples(2)
                .max_subscribers(1)
                .max_publishers(MAX_CLIENTS)
                .max_nodes(max_nodes)
                .enable_safe_overflow(true)
                .create()
                .map_err(|e| format!("{}: {e:?}", names.setpoints()))?
                .subscriber_builder()
                .create()
                .map_err(|e| format!("setpoints subscriber: {e:?}"))?,
        )
    } else {
        None
    };
    Ok(PeerServices {
        _node: node,
        frame,
        tick,
        command,
        setpoints,
    })
}

/// Writes `line` to the bench (stdout), flushed.
pub(crate) fn say(line: &str) -> Result<(), String> {
    let mut out = std::io::stdout().lock();
    writeln!(out, "{line}")
        .and_then(|()| out.flush())
        .map_err(|e| format!("stdout: {e}"))
}

/// Answers every waiting request (refused: the peer has no axis).
pub(crate) fn answer(services: &PeerServices, tick: u64) {
    while let Ok(Some(active)) = services.command.receive() {
        let reply = CommandReply::to(active.payload(), Reason::UnknownAxis, tick);
        let _ = active.send_copy(reply);
    }
}

/// Publishes tick `tick`'s frame-sized sample (deadline `deadline_ns`) and notifies the
/// tick event: the instant it was published, if it was.
pub(crate) fn publish(services: &PeerServices, tick: u64, deadline_ns: u64) -> Option<u64> {
    let published = services.frame.loan_uninit().ok().map(|sample| {
        let mut sample = sample.write_payload(MotionFrame::EMPTY);
        let frame = sample.payload_mut();
        frame.tick = tick;
        frame.time_ns = deadline_ns;
        frame.publish_ns = now_ns();
        let publish_ns = frame.publish_ns;
        let _ = sample.send();
        publish_ns
    });
    let _ = services.tick.notify();
    published
}
