//! Plain iceoryx2 access to one instance's services (motiond's or the baseline peer's):
//! everything is opened, never created, exactly as an outside client would.

use core::time::Duration;
use std::time::Instant;

use iceoryx2::port::client::Client;
use iceoryx2::port::listener::Listener;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use motion_ipc::{CommandReply, CommandRequest, MotionFrame, ServerStats, ServiceNames};

/// Inter-process shared memory, as motiond uses.
pub type Ipc = ipc::Service;
/// Frame subscriber.
pub type Frames = Subscriber<Ipc, MotionFrame, ()>;
/// Command client.
pub type Commands = Client<Ipc, CommandRequest, (), CommandReply, ()>;

/// How long opening a service is retried (a just-started server may still be creating it).
pub const OPEN_TIMEOUT: Duration = Duration::from_secs(5);

/// A node of this bench. Signal handling is off, so Ctrl-C ends the bench at once.
pub fn node(label: &str) -> Result<Node<Ipc>, String> {
    let name = format!("motiond-bench-{label}");
    let name = NodeName::new(&name).map_err(|e| format!("node name {name:?}: {e:?}"))?;
    NodeBuilder::new()
        .name(&name)
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<Ipc>()
        .map_err(|e| format!("iceoryx2 node: {e:?}"))
}

fn service_name(name: &str) -> Result<ServiceName, String> {
    ServiceName::new(name).map_err(|e| format!("service name {name:?}: {e:?}"))
}

fn retry<T, E: core::fmt::Debug>(
    what: &str,
    timeout: Duration,
    mut open: impl FnMut() -> Result<T, E>,
) -> Result<T, String> {
    let deadline = Instant::now() + timeout;
    loop {
        match open() {
            Ok(value) => return Ok(value),
            Err(error) if Instant::now() >= deadline => {
                return Err(format!("open {what}: {error:?}"));
            }
            Err(_) => std::thread::sleep(Duration::from_millis(20)),
        }
    }
}

/// Subscribes to `motiond/<name>/frame`.
pub fn open_frames(
    node: &Node<Ipc>,
    names: &ServiceNames,
    timeout: Duration,
) -> Result<Frames, String> {
    let name = service_name(&names.frame())?;
    retry(&names.frame(), timeout, || {
        node.service_builder(&name)
            .publish_subscribe::<MotionFrame>()
            .open()
    })?
    .subscriber_builder()
    .create()
    .map_err(|e| format!("subscribe to {}: {e:?}", names.frame()))
}

/// Listens to `motiond/<name>/tick`.
pub fn open_tick(node: &Node<Ipc>, names: &ServiceNames) -> Result<Listener<Ipc>, String> {
    let name = service_name(&names.tick())?;
    retry(&names.tick(), OPEN_TIMEOUT, || {
        node.service_builder(&name).event().open()
    })?
    .listener_builder()
    .create()
    .map_err(|e| format!("listen to {}: {e:?}", names.tick()))
}

/// A client of `motiond/<name>/command`.
pub fn open_commands(node: &Node<Ipc>, names: &ServiceNames) -> Result<Commands, String> {
    let name = service_name(&names.command())?;
    retry(&names.command(), OPEN_TIMEOUT, || {
        node.service_builder(&name)
            .request_response::<CommandRequest, CommandReply>()
            .open()
    })?
    .client_builder()
    .create()
    .map_err(|e| format!("command client of {}: {e:?}", names.command()))
}

/// Subscribes to `motiond/<name>/stats`.
pub fn open_stats(
    node: &Node<Ipc>,
    names: &ServiceNames,
    timeout: Duration,
) -> Result<Subscriber<Ipc, ServerStats, ()>, String> {
    let name = service_name(&names.stats())?;
    retry(&names.stats(), timeout, || {
        node.service_builder(&name)
            .publish_subscribe::<ServerStats>()
            .open()
    })?
    .subscriber_builder()
    .create()
    .map_err(|e| format!("subscribe to {}: {e:?}", names.stats()))
}

/// The newest sample waiting in `subscriber`, if any (older ones are dropped).
pub fn latest<T: Copy + core::fmt::Debug + ZeroCopySend>(
    subscriber: &Subscriber<Ipc, T, ()>,
) -> Result<Option<T>, String> {
    let mut newest = None;
    loop {
        match subscriber.receive() {
            Ok(Some(sample)) => newest = Some(*sample.payload()),
            Ok(None) => return Ok(newest),
            Err(e) => return Err(format!("receive: {e:?}")),
        }
    }
}

/// Waits up to `timeout` for the next stats sample newer than `after_tick`.
pub fn wait_stats(
    subscriber: &Subscriber<Ipc, ServerStats, ()>,
    after_tick: u64,
    timeout: Duration,
) -> Result<Option<ServerStats>, String> {
    let deadline = Instant::now() + timeout;
    let mut newest = None;
    loop {
        if let Some(stats) = latest(subscriber)? {
            newest = Some(stats);
        }
        match newest {
            Some(stats) if stats.tick > after_tick => return Ok(Some(stats)),
            _ if Instant::now() >= deadline => return Ok(newest),
            _ => std::thread::sleep(Duration::from_millis(20)),
        }
    }
}

/// The tick period and axis count from two consecutive frames (the deadline step).
pub fn frame_timing(frames: &Frames, timeout: Duration) -> Result<(u64, u32), String> {
    let deadline = Instant::now() + timeout;
    let mut previous: Option<(u64, u64)> = None;
    loop {
        match frames.receive() {
            Ok(Some(sample)) => {
                let frame = sample.payload();
                if let Some((tick, time_ns)) = previous
                    && frame.tick == tick + 1
                    && frame.time_ns > time_ns
                {
                    return Ok((frame.time_ns - time_ns, frame.axis_count));
                }
                previous = Some((frame.tick, frame.time_ns));
            }
            Ok(None) => {
                if Instant::now() >= deadline {
                    return Err(format!(
                        "no two consecutive frames within {timeout:?}: is the server ticking?"
                    ));
                }
                std::thread::sleep(Duration::from_micros(200));
            }
            Err(e) => return Err(format!("receive a frame: {e:?}")),
        }
    }
}
