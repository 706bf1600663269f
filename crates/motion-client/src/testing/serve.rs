//! The fake server's thread: its services and its tick loop.

use core::time::Duration;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, mpsc};
use std::time::Instant;

use iceoryx2::node::Node;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::update_connections::UpdateConnections;
use iceoryx2::prelude::{
    NodeBuilder, NodeName, PayloadHeader as _, ServiceName, SignalHandlingMode, ZeroCopySend,
};
use iceoryx2::service::Service;
use motion_ipc::{
    ClientId, CommandReply, CommandRequest, GroupPath, MachineParams, MotionFrame, ServerInfo,
    ServerStats, ServiceNames, Setpoint,
};

use super::Shared;
use super::config::FakeConfig;
use super::model::{Judged, Model, StoredPath};

fn fail(what: &str) -> impl Fn(&dyn core::fmt::Debug) -> String + '_ {
    move |error| format!("fake server: {what}: {error:?}")
}

pub(super) fn serve<S: Service>(
    config: &FakeConfig,
    stop: &AtomicBool,
    shared: &Shared,
    ready: &mpsc::Sender<Result<(), String>>,
) -> Result<(), String> {
    let result = serve_inner::<S>(config, stop, shared, ready);
    if let Err(error) = &result {
        let _ = ready.send(Err(error.clone()));
    }
    result
}

/// The e-stop latched through a path; recorded for the test.
fn note_estop(shared: &Shared, source: &'static str) {
    if let Ok(mut log) = shared.estops.lock() {
        log.push(source);
    }
}

/// Removes a SIGUSR1 registration when the thread ends.
struct SignalRegistration(Option<signal_hook::SigId>);

impl Drop for SignalRegistration {
    fn drop(&mut self) {
        if let Some(id) = self.0.take() {
            signal_hook::low_level::unregister(id);
        }
    }
}

/// A publisher of a rarely published payload whose newest sample a late subscriber gets
/// (history 1), as the real server's info, stats and params services.
fn latest_publisher<S: Service, T: core::fmt::Debug + ZeroCopySend + 'static>(
    node: &Node<S>,
    name: &ServiceName,
    what: &str,
    max: usize,
    max_nodes: usize,
) -> Result<Publisher<S, T, ()>, String> {
    node.service_builder(name)
        .publish_subscribe::<T>()
        .history_size(1)
        .subscriber_max_buffer_size(1)
        .max_subscribers(max)
        .max_publishers(2)
        .max_nodes(max_nodes)
        .open_or_create()
        .map_err(|e| format!("fake server: {what} service: {e:?}"))?
        .publisher_builder()
        .create()
        .map_err(|e| format!("fake server: {what} publisher: {e:?}"))
}

#[allow(clippy::too_many_lines)]
fn serve_inner<S: Service>(
    config: &FakeConfig,
    stop: &AtomicBool,
    shared: &Shared,
    ready: &mpsc::Sender<Result<(), String>>,
) -> Result<(), String> {
    let names = ServiceNames::new(&config.name);
    let service = |name: String| ServiceName::new(&name).map_err(|e| fail("service name")(&e));
    // The real server's node name, so that clients find this process by it.
    let node_name = NodeName::new(&names.server_node()).map_err(|e| fail("node name")(&e))?;
    let node = NodeBuilder::new()
        .name(&node_name)
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<S>()
        .map_err(|e| fail("node")(&e))?;
    let max = config.max_clients.max(1);
    let max_nodes = max + 4;
    let tick = node
        .service_builder(&service(names.tick())?)
        .event()
        .max_notifiers(2)
        .max_listeners(max)
        .max_nodes(max_nodes)
        .open_or_create()
        .map_err(|e| fail("tick service")(&e))?
        .notifier_builder()
        .create()
        .map_err(|e| fail("tick notifier")(&e))?;
    let commands = node
        .service_builder(&service(names.command())?)
        .request_response::<CommandRequest, CommandReply>()
        .max_servers(2)
        .max_clients(max)
        .max_nodes(max_nodes)
        .open_or_create()
        .map_err(|e| fail("command service")(&e))?
        .server_builder()
        .create()
        .map_err(|e| fail("command server")(&e))?;
    let estop = node
        .service_builder(&service(names.estop())?)
        .event()
        .max_notifiers(max)
        .max_listeners(2)
        .max_nodes(max_nodes)
        .open_or_create()
        .map_err(|e| fail("estop service")(&e))?
        .listener_builder()
        .create()
        .map_err(|e| fail("estop listener")(&e))?;
    let info_publisher =
        latest_publisher::<S, ServerInfo>(&node, &service(names.info())?, "info", max, max_nodes)?;
    let stats_publisher = latest_publisher::<S, ServerStats>(
        &node,
        &service(names.stats())?,
        "stats",
        max,
        max_nodes,
    )?;
    let params_publisher = latest_publisher::<S, MachineParams>(
        &node,
        &service(names.params())?,
        "params",
        max,
        max_nodes,
    )?;
    // Paths for groups: every client may publish (lazily: a sample is about 400 KB).
    let paths = node
        .service_builder(&service(names.paths())?)
        .publish_subscribe::<GroupPath>()
        .history_size(0)
        .subscriber_max_buffer_size(4)
        .max_subscribers(2)
        .max_publishers(max)
        .max_nodes(max_nodes)
        .open_or_create()
        .map_err(|e| fail("paths service")(&e))?
        .subscriber_builder()
        .create()
        .map_err(|e| fail("paths subscriber")(&e))?;
    // Setpoints streamed to groups: from any client, judged by the sender's node.
    let setpoints = node
        .service_builder(&service(names.setpoints())?)
        .publish_subscribe::<Setpoint>()
        .history_size(0)
        .subscriber_max_buffer_size(16)
        .max_subscribers(1)
        .max_publishers(max)
        .max_nodes(max_nodes)
        .enable_safe_overflow(true)
        .open_or_create()
        .map_err(|e| fail("setpoints service")(&e))?
        .subscriber_builder()
        .create()
        .map_err(|e| fail("setpoints subscriber")(&e))?;
    // The frame service comes last, as in the real server.
    let frames = node
        .service_builder(&service(names.frame())?)
        .publish_subscribe::<MotionFrame>()
        .history_size(1)
        .subscriber_max_buffer_size(32)
        .max_subscribers(max)
        .max_publishers(2)
        .max_nodes(max_nodes)
        .enable_safe_overflow(true)
        .open_or_create()
        .map_err(|e| fail("frame service")(&e))?
        .publisher_builder()
        .create()
        .map_err(|e| fail("frame publisher")(&e))?;

    // The pid file, as motiond writes it once its services exist.
    let pid_file = PidFileGuard(motion_ipc::ServerPidFile::of(&config.name));
    // iceoryx2's root directory: an ipc node makes it, a fake on the in-process service
    // (the first of a fresh machine's tests, say) may find it missing.
    if let Some(dir) = pid_file.0.path().parent() {
        std::fs::create_dir_all(dir).map_err(|e| fail("iceoryx2 root directory")(&e))?;
    }
    pid_file
        .0
        .write_for_this_process(node.id().value())
        .map_err(|e| fail("pid file")(&e))?;

    let sigusr1 = Arc::new(AtomicBool::new(false));
    let _registration = SignalRegistration(if config.latch_on_sigusr1 {
        Some(
            signal_hook::flag::register(signal_hook::consts::SIGUSR1, Arc::clone(&sigusr1))
                .map_err(|e| fail("SIGUSR1 handler")(&e))?,
        )
    } else {
        None
    });

    let start_ns = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(1, |since| {
            u64::try_from(since.as_nanos()).unwrap_or(u64::MAX)
        });
    let mut model = Model::new(config);
    if config.info_delay_ticks == 0 {
        info_publisher
            .send_copy(model.info(config, start_ns))
            .map_err(|e| fail("info send")(&e))?;
    }
    params_publisher
        .send_copy(Model::params(config))
        .map_err(|e| fail("params send")(&e))?;
    let mut published_states = model.device_states();
    let generation = shared.generation.load(Ordering::Relaxed);
    let _ = ready.send(Ok(()));

    let period = Duration::from_secs(1) / config.tick_hz.max(1);
    let start = Instant::now();
    let mut next = start;
    while !stop.load(Ordering::Relaxed) {
        let now = Instant::now();
        if next > now {
            std::thread::sleep(next - now);
        }
        if let Ok(mut controls) = shared.controls.lock() {
            for control in controls.drain(..) {
                model.control(control);
            }
        }
        if estop.try_wait(|_| {}).map_err(|e| fail("estop wait")(&e))? > 0 {
            model.latch_estop();
            note_estop(shared, "event");
        }
        if sigusr1.swap(false, Ordering::Relaxed) {
            model.latch_estop();
            note_estop(shared, "signal");
        }
        // Like the real server: the tick's setpoints before its commands.
        while let Some(setpoint) = setpoints
            .receive()
            .map_err(|e| fail("receive a setpoint")(&e))?
        {
            let from = ClientId::from_u128(setpoint.header().node_id().value());
            model.handle_setpoint(from, &setpoint);
        }
        while let Some(active) = commands.receive().map_err(|e| fail("receive")(&e))? {
            let request = *active.payload();
            let sender = ClientId::from_u128(active.header().node_id().value());
            if let Ok(mut log) = shared.requests.lock() {
                log.push((generation, request));
            }
            // A client publishes a path just before it sends the `Run` naming it.
            while let Some(path) = paths.receive().map_err(|e| fail("receive a path")(&e))? {
                let from = ClientId::from_u128(path.header().node_id().value());
                model.store_path(StoredPath::new(from, &path));
            }
            let judged = model.apply(&request, sender);
            if judged.reason == motion_ipc::Reason::Accepted
                && request.kind() == Ok(motion_ipc::CommandKind::EStop)
            {
                note_estop(shared, "command");
            }
            active
                .send_copy(reply(&request, &judged, model.tick))
                .map_err(|e| fail("reply")(&e))?;
        }
        shared.estop_latched.store(model.estop, Ordering::Relaxed);
        model.step(period.as_secs_f64(), config.command_timeout_ms);
        let mut frame = MotionFrame::EMPTY;
        // Like the real server: the tick's deadline, then the time just before sending.
        model.write_frame(&mut frame, period * model.tick_u32(), start.elapsed());
        frames
            .send_copy(frame)
            .map_err(|e| fail("frame send")(&e))?;
        tick.notify().map_err(|e| fail("notify")(&e))?;
        let states = model.device_states();
        if states != published_states
            || (config.info_delay_ticks > 0 && model.tick == config.info_delay_ticks)
        {
            info_publisher
                .send_copy(model.info(config, start_ns))
                .map_err(|e| fail("info send")(&e))?;
            published_states = states;
        }
        // Late subscribers get the history sample when the publisher updates connections.
        info_publisher
            .update_connections()
            .map_err(|e| fail("info connections")(&e))?;
        params_publisher
            .update_connections()
            .map_err(|e| fail("params connections")(&e))?;
        if model.tick.is_multiple_of(u64::from(config.tick_hz.max(1))) {
            let mut stats = ServerStats::EMPTY;
            stats.tick = model.tick;
            stats.commands = model.commands;
            stats.rejected = model.rejected;
            stats_publisher
                .send_copy(stats)
                .map_err(|e| fail("stats send")(&e))?;
        }
        model.tick += 1;
        next += period;
    }
    Ok(())
}

/// The reply to `request`, with the detail fields of `judged`.
fn reply(request: &CommandRequest, judged: &Judged, tick: u64) -> CommandReply {
    let mut reply = CommandReply::to(request, judged.reason, tick);
    reply.at_point = judged.at_point;
    reply.at_axis = judged.at_axis;
    reply.holder = judged.holder;
    reply.value = judged.value;
    reply.limit = judged.limit;
    reply
}

/// Removes the fake's pid file when it stops.
struct PidFileGuard(motion_ipc::ServerPidFile);

impl Drop for PidFileGuard {
    fn drop(&mut self) {
        self.0.remove_if_this_process();
    }
}
