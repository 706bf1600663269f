//! Putting the server together: links, drivers, threads, the main thread's housekeeping
//! (liveness checks, logs, status line) and the shutdown.

use core::time::Duration;
use std::io::{IsTerminal, Write};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering};

use motion_drivers::{DeviceFault, Seconds};
use motion_engine::Engine;
use motion_ipc::{ClientId, DeviceState, ServerPidFile, read_text};
use motion_link::{Link, LinkConfig};
use rtrb::RingBuffer;

use crate::error::ServerError;
use crate::io::{self, IoThread, LinkPort};
use crate::rt::{IoRt, monotonic_now};
use crate::stats::format_ns;
use crate::systemd::{Supervisor, TickHealth};
use crate::tick::{self, Report, StatusLine, TickSetup};
use crate::{node_records, services};
use motion_blackbox::{BlackboxFile, Journal, RecorderSetup, directory};
use motion_config::boards::{sim_can_link, sim_link};
use motion_config::{IoMode, ServerConfig, Transport};

/// How the server was asked to run.
#[derive(Debug, Clone, Copy, Default)]
pub struct RunOptions {
    /// Fail instead of warning when real-time set-up is incomplete.
    pub require_rt: bool,
}

/// Opens every link of `config` (sim links with their models).
fn open_links(config: &ServerConfig) -> Result<Vec<Box<dyn Link>>, ServerError> {
    let mut links: Vec<Box<dyn Link>> = Vec::with_capacity(config.links.len());
    for (index, spec) in config.links.iter().enumerate() {
        let link: Box<dyn Link> = match &spec.transport {
            Transport::Sim { .. } => Box::new(sim_link(config, index)),
            Transport::Serial { path, baud } => LinkConfig::Serial(
                motion_link::serial::SerialConfig::new(path.to_string_lossy(), *baud),
            )
            .create()
            .map_err(|source| link_error(&spec.name, source))?,
            Transport::Spidev {
                path,
                speed_hz,
                mode,
            } => LinkConfig::Spidev(motion_link::spidev::SpidevConfig::new(
                path.to_string_lossy(),
                *mode,
                *speed_hz,
            ))
            .create()
            .map_err(|source| link_error(&spec.name, source))?,
            Transport::SpiSocket { path } => LinkConfig::SpiSocket(
                motion_link::spi_socket::SpiSocketConfig::new(path.to_string_lossy()),
            )
            .create()
            .map_err(|source| link_error(&spec.name, source))?,
            Transport::SocketCan { interface, bitrate } => LinkConfig::SocketCan(
                motion_link::socketcan::SocketCanConfig::new(interface.as_str(), *bitrate),
            )
            .create()
            .map_err(|source| link_error(&spec.name, source))?,
            Transport::SimCan { .. } => Box::new(sim_can_link(config, index)),
        };
        links.push(link);
    }
    Ok(links)
}

fn link_error(link: &str, source: motion_link::LinkError) -> ServerError {
    ServerError::Link {
        link: link.to_owned(),
        source,
    }
}

/// Runs the server until SIGINT/SIGTERM. A second signal exits at once.
pub fn run(config: ServerConfig, options: RunOptions) -> Result<(), ServerError> {
    let shutdown = Arc::new(AtomicBool::new(false));
    for signal in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        // Order matters: the conditional exit sees the flag set by an earlier signal.
        signal_hook::flag::register_conditional_shutdown(signal, 130, Arc::clone(&shutdown))
            .map_err(ServerError::SignalHandlers)?;
        signal_hook::flag::register(signal, Arc::clone(&shutdown))
            .map_err(ServerError::SignalHandlers)?;
    }
    // The e-stop of last resort: a process that can signal us (same user, or root) latches
    // the e-stop even when every service slot is taken.
    let estop_signal = Arc::new(AtomicBool::new(false));
    signal_hook::flag::register(signal_hook::consts::SIGUSR1, Arc::clone(&estop_signal))
        .map_err(ServerError::SignalHandlers)?;
    // SIGUSR2: save the black box now.
    let save_blackbox = Arc::new(AtomicBool::new(false));
    signal_hook::flag::register(signal_hook::consts::SIGUSR2, Arc::clone(&save_blackbox))
        .map_err(ServerError::SignalHandlers)?;
    for warning in &config.warnings {
        tracing::warn!("{}", warning.warning_line(&config.path));
    }

    let dead = services::clean_dead_nodes();
    if !dead.is_empty() {
        tracing::info!(
            "removed the shared-memory leftovers of {} dead iceoryx2 node(s)",
            dead.len()
        );
    }

    let params = crate::params::machine_params(&config);
    let mut drivers = motion_config::boards::build(&config)?;
    // Before the drivers' first step: the references a previous run saved (the state
    // directory checked first: the server does not start with one that is not its own).
    let (references, mut keeper) = crate::references::start(&config, &mut drivers)?.unzip();
    // The black box's directory, checked (and made) before any link opens: one that is not
    // the server's own is refused now, not at the first fault.
    if config.server.blackbox_seconds > 0 {
        let dir = &config.server.blackbox_dir;
        motion_config::private_dir::PrivateDir::open(dir, directory::KEY, directory::DIR_MODE)?;
        tracing::info!("black box: {}", dir.display());
    }
    let engine = Engine::new(config.engine_config(), drivers).map_err(ServerError::Engine)?;
    let links = open_links(&config)?;

    let epoch = monotonic_now();
    let period = engine.config().period();
    let io_stop = Arc::new(AtomicBool::new(false));
    let mut ports: Vec<LinkPort> = Vec::with_capacity(links.len());
    let mut io_threads: Vec<IoThread> = Vec::with_capacity(links.len());
    let io_options = io::IoThreadOptions {
        epoch,
        idle: io::IDLE_WAIT,
        rt_priority: config.server.io_rt_priority,
        cpu: config.server.io_cpu,
    };
    let mut io_rt = IoRt::default();
    let (mut fifo_refused, mut pin_refused) = (false, false);
    for (spec, link) in config.links.iter().zip(links) {
        if let IoMode::Tick { budget } = spec.io {
            // The tick runs this link itself (crate::io::inline): no thread.
            let port =
                io::inline::start(link, epoch, budget, spec.spi_bit_rate()).map_err(|source| {
                    ServerError::IoThread {
                        link: spec.name.clone(),
                        source,
                    }
                })?;
            ports.push(port);
            continue;
        }
        let (port, mut thread) = io::spawn(&spec.name, link, io_options, Arc::clone(&io_stop))
            .map_err(|source| ServerError::IoThread {
                link: spec.name.clone(),
                source,
            })?;
        // Every thread asks the same of the same process's limits: a refusal is reported
        // once (the first thread's), and what one thread was refused counts as not had.
        let outcome = thread.take_rt().unwrap_or_default();
        let first = io_rt.problems.is_empty();
        match outcome.fifo {
            Some(Ok(priority)) => io_rt.fifo = Some(priority),
            Some(Err(error)) => {
                fifo_refused = true;
                if first {
                    io_rt.problems.push(error);
                }
            }
            None => {}
        }
        match outcome.pinned {
            Some(Ok(cpu)) => io_rt.pinned = Some(cpu),
            Some(Err(error)) => {
                pin_refused = true;
                if first {
                    io_rt.problems.push(error);
                }
            }
            None => {}
        }
        ports.push(port);
        io_threads.push(thread);
    }
    if fifo_refused {
        io_rt.fifo = None;
    }
    if pin_refused {
        io_rt.pinned = None;
    }

    let health = Arc::new(TickHealth::default());
    let mut supervisor = Supervisor::from_env(period);
    if supervisor.is_some() {
        tracing::info!(
            "systemd: notifying readiness on $NOTIFY_SOCKET{}",
            crate::systemd::watchdog_from_env().map_or(String::new(), |interval| format!(
                ", feeding the watchdog ({} ms) while ticks complete",
                interval.as_millis()
            ))
        );
    }
    let (dead_tx, dead_rx) = RingBuffer::<ClientId>::new(256);
    let (report_tx, mut report_rx) = RingBuffer::<Report>::new(64);
    let clients_alive = Arc::new(AtomicU32::new(0));
    let nodes_cleaned = Arc::new(AtomicU64::new(dead.len() as u64));
    let (journal, recorder) = start_recorder(&config, save_blackbox)?;
    let setup = TickSetup {
        engine,
        ports,
        link_names: config.links.iter().map(|l| l.name.clone()).collect(),
        settings: config.server.clone(),
        epoch,
        shutdown: Arc::clone(&shutdown),
        dead_clients: dead_rx,
        clients_alive: Arc::clone(&clients_alive),
        nodes_cleaned: Arc::clone(&nodes_cleaned),
        reports: report_tx,
        require_rt: options.require_rt,
        io_rt,
        params,
        estop_signal,
        health: Arc::clone(&health),
        journal,
        references,
    };
    let tick_thread = std::thread::Builder::new()
        .name("tick".into())
        .spawn(move || tick::run(setup))
        .map_err(ServerError::TickThread)?;

    let systemd = Systemd {
        supervisor: supervisor.as_mut(),
        health: &health,
        shutdown: &shutdown,
    };
    let liveness = Liveness {
        clients_alive: &clients_alive,
        nodes_cleaned: &nodes_cleaned,
    };
    let result = housekeeping(
        &config,
        &mut report_rx,
        dead_tx,
        liveness,
        systemd,
        keeper.as_mut(),
    );
    io_stop.store(true, Ordering::Relaxed);
    if tick_thread.join().is_err() {
        tracing::error!("the tick thread panicked");
    }
    if let Some(keeper) = keeper.as_mut() {
        // What the last frames said.
        keeper.drain();
    }
    if let Some((stop, thread)) = recorder {
        stop.store(true, Ordering::Release);
        if thread.join().is_err() {
            tracing::error!("the black box recorder panicked");
        }
    }
    for thread in io_threads {
        thread.join();
    }
    result
}

/// Bytes of the queue from the tick's journal to the recorder thread (drained every
/// 50 ms: a tick of `config/sim.toml` journals about 1.8 KiB, a path at most 600 KiB).
const JOURNAL_QUEUE_BYTES: usize = 8 << 20;

/// The ring's bytes per tick of `blackbox_seconds`: a tick of `config/sim.toml` journals
/// about 1 KiB; a run whose ticks average more keeps fewer seconds.
const RING_BYTES_PER_TICK: usize = 2048;

/// The black box's recorder thread and the tick's journal into it; with
/// `blackbox_seconds = 0`, a journal that records nothing and no thread.
#[allow(clippy::type_complexity)]
fn start_recorder(
    config: &ServerConfig,
    save_now: Arc<AtomicBool>,
) -> Result<
    (
        Journal,
        Option<(Arc<AtomicBool>, std::thread::JoinHandle<()>)>,
    ),
    ServerError,
> {
    let server = &config.server;
    if server.blackbox_seconds == 0 {
        return Ok((Journal::disabled(), None));
    }
    let (producer, consumer) = rtrb::RingBuffer::new(JOURNAL_QUEUE_BYTES);
    let stop = Arc::new(AtomicBool::new(false));
    let setup = RecorderSetup {
        queue: consumer,
        keep_ticks: server.blackbox_seconds as usize * server.tick_hz as usize,
        ring_bytes: server.blackbox_seconds as usize
            * server.tick_hz as usize
            * RING_BYTES_PER_TICK,
        file: BlackboxFile {
            server_name: server.name.clone(),
            tick_hz: server.tick_hz,
            config_path: config.path.clone(),
            // Read again for the file (a replay builds the same machine from it); a file
            // gone meanwhile leaves it empty and the replay then needs --config.
            config_text: std::fs::read_to_string(&config.path).unwrap_or_default(),
            link_names: config.links.iter().map(|l| l.name.clone()).collect(),
        },
        dir: server.blackbox_dir.clone(),
        on_exit: server.blackbox_on_exit,
        keep_files: server.blackbox_keep as usize,
        pointer: ServerPidFile::blackbox_pointer(&server.name),
        save_now,
        stop: Arc::clone(&stop),
    };
    let thread = std::thread::Builder::new()
        .name("blackbox".into())
        .spawn(move || motion_blackbox::recorder::run(setup))
        .map_err(ServerError::RecorderThread)?;
    // A snapshot every quarter of the ring: a saved ring holds at least three quarters of
    // its ticks after its first snapshot, replayable from there.
    let snapshot_every = (server.blackbox_seconds as u64 * u64::from(server.tick_hz) / 4).max(1);
    Ok((Journal::new(producer, snapshot_every), Some((stop, thread))))
}

/// The main thread's side of the systemd conversation (crate::systemd).
struct Systemd<'a> {
    /// `None` when not started by systemd with `Type=notify`.
    supervisor: Option<&'a mut Supervisor>,
    health: &'a TickHealth,
    shutdown: &'a AtomicBool,
}

impl Systemd<'_> {
    fn devices(&mut self, config: &ServerConfig, states: &[DeviceState], started: bool) {
        let Some(supervisor) = self.supervisor.as_deref_mut() else {
            return;
        };
        let waiting: Vec<&str> = config
            .devices
            .iter()
            .zip(states)
            .filter(|(_, state)| **state != DeviceState::Online)
            .map(|(device, _)| device.name.as_str())
            .collect();
        if started {
            supervisor.started(&waiting, states.len());
        } else {
            supervisor.devices(&waiting, states.len());
        }
    }

    /// Shutdown began (a signal, or the tick loop ended).
    fn stopping(&mut self) {
        if let Some(supervisor) = self.supervisor.as_deref_mut() {
            supervisor.stopping();
        }
    }

    fn poll(&mut self) {
        if self.shutdown.load(Ordering::Relaxed) {
            self.stopping();
        }
        let Some(supervisor) = self.supervisor.as_deref_mut() else {
            return;
        };
        if let Some(stuck) = supervisor.poll(monotonic_now(), self.health) {
            tracing::error!(
                "the tick thread has not completed a tick for {} ms: no longer feeding the systemd watchdog",
                stuck.as_millis()
            );
        }
    }
}

/// What the main thread's liveness checks share with the tick (for the stats).
struct Liveness<'a> {
    /// Live client nodes at the last check.
    clients_alive: &'a AtomicU32,
    /// Dead nodes' records removed since start.
    nodes_cleaned: &'a AtomicU64,
}

/// Removes the server's pid file when dropped, if it still names this process.
struct PidFileGuard(ServerPidFile);

impl Drop for PidFileGuard {
    fn drop(&mut self) {
        self.0.remove_if_this_process();
    }
}

/// The main thread's work while the tick runs: reports, logs, the status line, client
/// liveness, systemd's readiness and watchdog. Returns when the tick thread stops.
fn housekeeping(
    config: &ServerConfig,
    reports: &mut rtrb::Consumer<Report>,
    mut dead_clients: rtrb::Producer<ClientId>,
    liveness: Liveness<'_>,
    mut systemd: Systemd<'_>,
    mut references: Option<&mut crate::references::Keeper>,
) -> Result<(), ServerError> {
    let status_line = std::io::stderr().is_terminal();
    let mut server_node = 0u128;
    let mut next_liveness = monotonic_now();
    let mut firmware: Vec<String> = vec![String::new(); config.devices.len()];
    let mut summary_printed = false;
    let mut device_states = vec![DeviceState::Offline; config.devices.len()];
    let started = monotonic_now();
    // Where `motionctl estop` finds the one process to signal when every service slot is
    // taken; removed again however this function returns.
    let pid_file = PidFileGuard(ServerPidFile::of(&config.server.name));
    let mut pid_file_error = None;
    let mut sweeper = node_records::Sweeper::default();
    loop {
        systemd.poll();
        while let Ok(report) = reports.pop() {
            match report {
                Report::Failed(error) => return Err(error.into()),
                Report::Started { rt, node_id } => {
                    server_node = node_id;
                    match pid_file.0.write_for_this_process(node_id) {
                        Ok(_) => tracing::debug!("pid file {}", pid_file.0.path().display()),
                        Err(error) => {
                            // A client's e-stop of last resort could not tell this process
                            // from an impostor: do not run without it.
                            tracing::error!("{error}; stopping every axis and exiting");
                            pid_file_error = Some(error);
                            systemd.shutdown.store(true, Ordering::Relaxed);
                        }
                    }
                    for problem in &rt.problems {
                        tracing::warn!("real-time: {problem}; continuing without it");
                    }
                    tracing::info!("real-time: {}", rt.summary());
                    systemd.devices(config, &device_states, true);
                }
                Report::Device {
                    index,
                    state,
                    firmware: text,
                } => {
                    let name = config.devices.get(index).map_or("?", |d| d.name.as_str());
                    let text = read_text(&text).to_owned();
                    match state {
                        DeviceState::Online => {
                            tracing::info!("device `{name}` online, firmware {text:?}");
                        }
                        DeviceState::Starting => {
                            tracing::info!(
                                "device `{name}` starting (probing, configuring, start-up stop)"
                            );
                        }
                        DeviceState::Faulted => tracing::warn!("device `{name}` faulted"),
                        DeviceState::Offline => tracing::warn!("device `{name}` is not answering"),
                    }
                    if let Some(slot) = firmware.get_mut(index) {
                        *slot = match state {
                            DeviceState::Offline => "(not answering)".into(),
                            _ => text,
                        };
                    }
                    if let Some(slot) = device_states.get_mut(index) {
                        *slot = state;
                    }
                    systemd.devices(config, &device_states, false);
                }
                Report::Verdict { index, verdict } => {
                    let name = config.devices.get(index).map_or("?", |d| d.name.as_str());
                    let what = match verdict.fault {
                        DeviceFault::Reset => "was reset",
                        DeviceFault::NotResponding => "is not answering",
                        _ => "faulted",
                    };
                    tracing::warn!(
                        "device `{name}` {what} (at {}): {}",
                        Seconds(verdict.at),
                        verdict.evidence.as_str()
                    );
                }
                Report::Fault {
                    axis,
                    code,
                    value,
                    limit,
                } => {
                    let (name, unit) = config
                        .axes
                        .get(axis)
                        .map_or(("?", ""), |a| (a.name.as_str(), a.unit.as_str()));
                    tracing::warn!(
                        "fault {}: {}",
                        code.name(),
                        code.explain(name, value, limit, unit)
                    );
                }
                Report::SlotsFull(slots) => {
                    tracing::warn!(
                        "service motiond/{}/{}: all {} {} slots are taken; new clients are refused there until one leaves (raise [server] max_clients)",
                        config.server.name,
                        slots.service,
                        slots.limit,
                        slots.slot
                    );
                }
                Report::EstopBy(by) => tracing::warn!("e-stop latched by {by}"),
                Report::Phases(means) => tracing::info!("{}", means.line()),
                Report::Stats(stats) => {
                    if !summary_printed
                        && monotonic_now().saturating_sub(started) >= Duration::from_secs(1)
                    {
                        print_summary(config, &firmware);
                        summary_printed = true;
                    }
                    if status_line {
                        let mut err = std::io::stderr().lock();
                        let _ = write!(err, "\r\x1b[2K{}", status(&stats, config));
                        let _ = err.flush();
                    }
                }
                Report::Stopped { at_rest } => {
                    systemd.stopping();
                    if status_line {
                        eprintln!();
                    }
                    if at_rest {
                        tracing::info!("every axis stopped; shared memory released");
                    } else {
                        tracing::warn!(
                            "shutdown: not every board acknowledged its stop within {:?}",
                            tick::SHUTDOWN_TIMEOUT
                        );
                    }
                    if let Some(error) = pid_file_error {
                        return Err(error.into());
                    }
                    return Ok(());
                }
            }
        }
        if let Some(keeper) = references.as_deref_mut() {
            keeper.drain();
        }
        let now = monotonic_now();
        if now >= next_liveness && server_node != 0 {
            next_liveness = now + config.server.liveness_check;
            // Dead nodes' records removed (off the tick thread, bounded per pass); live
            // clients counted; dead ones' claims ended.
            let sweep = sweeper.sweep(
                server_node,
                node_records::RESIDUE_AGE,
                node_records::SWEEP_BUDGET,
            );
            let (dead, live) = (sweep.dead, sweep.live);
            liveness
                .nodes_cleaned
                .fetch_add(u64::from(sweep.cleaned), Ordering::Relaxed);
            for id in dead {
                if id != server_node && dead_clients.push(ClientId::from_u128(id)).is_err() {
                    tracing::warn!("dead-client queue full; retrying at the next check");
                }
            }
            liveness.clients_alive.store(live, Ordering::Relaxed);
        }
        std::thread::sleep(Duration::from_millis(10).min(config.server.liveness_check));
    }
}

fn status(stats: &StatusLine, config: &ServerConfig) -> String {
    let links: Vec<String> = config
        .links
        .iter()
        .enumerate()
        .map(|(i, l)| {
            format!(
                "{}:{}",
                l.name,
                if stats.links_up & (1 << i) != 0 {
                    "up"
                } else {
                    "DOWN"
                }
            )
        })
        .collect();
    format!(
        "tick {} | wake p50 {} p99 {} max {} | work p99 {} | overruns {} | clients {} | {}",
        stats.tick,
        format_ns(stats.wakeup.p50_ns),
        format_ns(stats.wakeup.p99_ns),
        format_ns(stats.wakeup.max_ns),
        format_ns(stats.work.p99_ns),
        stats.overruns,
        stats.clients,
        links.join(" ")
    )
}

fn print_summary(config: &ServerConfig, firmware: &[String]) {
    let server = &config.server;
    let mut lines = vec![format!(
        "motiond `{}`: {} Hz tick, deadman {} ms, {} links, {} devices, {} axes; services motiond/{}/{{frame,tick,command,info,stats,params,estop}}",
        server.name,
        server.tick_hz,
        server.command_timeout.as_millis(),
        config.links.len(),
        config.devices.len(),
        config.axes.len(),
        server.name
    )];
    for (index, link) in config.links.iter().enumerate() {
        lines.push(format!("  link {} ({:?})", link.name, link.transport));
        for (d, device) in config
            .devices
            .iter()
            .enumerate()
            .filter(|(_, d)| d.link == index)
        {
            let fw = firmware.get(d).map_or("", String::as_str);
            let fw = if fw.is_empty() {
                "(waiting for the board)"
            } else {
                fw
            };
            lines.push(format!(
                "    device {} {} @ {} firmware {fw}",
                device.name, device.model, device.address
            ));
            for axis in config.axes.iter().filter(|a| a.device == d) {
                lines.push(format!(
                    "      axis {} ch {} [{}, {}] {} max {} {}/s",
                    axis.name,
                    axis.channel,
                    axis.min,
                    axis.max,
                    axis.unit,
                    axis.max_velocity,
                    axis.unit
                ));
            }
        }
    }
    eprintln!("\r\x1b[2K{}", lines.join("\n"));
}
