//! The tick thread: absolute deadlines, the engine step written into a loaned sample, the
//! link queues, statistics, overruns and the shutdown sequence.

use core::time::Duration;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering};

use iceoryx2::port::update_connections::UpdateConnections;
use motion_boards::AnyDriver;
use motion_drivers::{Driver, Verdict};
use motion_engine::Engine;
use motion_ipc::{
    ClientId, DeviceState, FaultCode, LinkIo, MachineParams, MotionFrame, ServerInfo, ServerStats,
    write_text,
};
use rtrb::{Consumer, Producer};

use crate::command_port::IpcCommands;
use crate::error::StartError;
use crate::estop_watch::EstopWatch;
use crate::io::{LinkEvent, LinkPort, NEVER, PACKET_LEN, Packet};
use crate::phases::{Phase, PhaseClock, PhaseMeans};
use crate::rt::{self, IoRt, RtStatus, monotonic_now, sleep_until};
use crate::services::{ClientDirectory, Services, SlotUse};
use crate::stats::Latency;
use motion_blackbox::Journal;
use motion_blackbox::record::Trigger;
use motion_config::ServerSettings;

/// How long a shutdown waits for the boards to acknowledge their stop goals.
pub const SHUTDOWN_TIMEOUT: Duration = Duration::from_secs(2);

/// What the tick thread tells the main thread.
#[derive(Debug)]
pub enum Report {
    /// The services exist and the loop runs.
    Started {
        /// Real-time set-up achieved.
        rt: RtStatus,
        /// The server's own node id (not a client).
        node_id: u128,
    },
    /// The thread could not start.
    Failed(StartError),
    /// A device's state or firmware changed.
    Device {
        /// Device index (config order).
        index: usize,
        /// Its readiness.
        state: DeviceState,
        /// Firmware string, zero padded.
        firmware: [u8; 32],
    },
    /// A driver reached a verdict on its board (not answering, reset), with its evidence.
    Verdict {
        /// Device index (config order).
        index: usize,
        /// The verdict.
        verdict: Verdict,
    },
    /// An axis faulted.
    Fault {
        /// Axis index (config order).
        axis: usize,
        /// The fault.
        code: FaultCode,
        /// Its measured figure.
        value: f64,
        /// The tolerance it broke.
        limit: f64,
    },
    /// A service's port slots are all taken (reported once until some free up).
    SlotsFull(SlotUse),
    /// The e-stop was latched by the e-stop event or SIGUSR1 (not by a command).
    EstopBy(&'static str),
    /// Once a second.
    Stats(StatusLine),
    /// The tick's phases (`tick-profile` builds only, every `phases::REPORT_EVERY` ticks).
    Phases(PhaseMeans),
    /// The loop ended (shutdown complete or timed out).
    Stopped {
        /// Whether every board acknowledged before the timeout.
        at_rest: bool,
    },
}

/// The figures of the status line (small and `Copy`: no allocation to report them).
#[derive(Debug, Clone, Copy)]
pub struct StatusLine {
    /// The tick.
    pub tick: u64,
    /// Wake-up latency since start.
    pub wakeup: motion_ipc::LatencySummary,
    /// Tick work time since start.
    pub work: motion_ipc::LatencySummary,
    /// Ticks that missed their deadline.
    pub overruns: u64,
    /// Live client nodes.
    pub clients: u32,
    /// Bit i: link i is up.
    pub links_up: u32,
}

impl StatusLine {
    fn of(stats: &ServerStats) -> Self {
        let mut links_up = 0;
        for (index, link) in stats.links().iter().enumerate().take(32) {
            if link.up == 1 {
                links_up |= 1 << index;
            }
        }
        Self {
            tick: stats.tick,
            wakeup: stats.wakeup,
            work: stats.work,
            overruns: stats.overruns,
            clients: stats.clients,
            links_up,
        }
    }
}

/// Everything the tick thread owns.
#[derive(Debug)]
pub struct TickSetup {
    /// The engine, with its drivers (the registry's enum: static dispatch).
    pub engine: Engine<AnyDriver>,
    /// The tick's end of every link's I/O thread, in link order.
    pub ports: Vec<LinkPort>,
    /// Link names, in link order (for the stats).
    pub link_names: Vec<String>,
    /// `[server]` settings.
    pub settings: ServerSettings,
    /// CLOCK_MONOTONIC at start: the engine's time is measured from here.
    pub epoch: Duration,
    /// Set by the main thread: begin the shutdown stop.
    pub shutdown: Arc<AtomicBool>,
    /// Clients the main thread found dead.
    pub dead_clients: Consumer<ClientId>,
    /// Live clients, as the main thread counts them.
    pub clients_alive: Arc<AtomicU32>,
    /// Dead iceoryx2 nodes' records the main thread removed (for the stats).
    pub nodes_cleaned: Arc<AtomicU64>,
    /// What the tick thread tells the main thread.
    pub reports: Producer<Report>,
    /// `--require-rt`: fail unless the real-time set-up is complete.
    pub require_rt: bool,
    /// What the I/O threads' real-time set-up achieved.
    pub io_rt: IoRt,
    /// The machine parameters in effect (published once on `params`).
    pub params: Box<MachineParams>,
    /// Set by SIGUSR1: latch the e-stop.
    pub estop_signal: Arc<AtomicBool>,
    /// Stamped at the end of every tick (the systemd watchdog is fed from it).
    pub health: Arc<crate::systemd::TickHealth>,
    /// The black box's journal (disabled with `blackbox_seconds = 0`).
    pub journal: Journal,
    /// The axes whose references outlive the server (crate::references), if any.
    pub references: Option<crate::references::Watch>,
}

/// Runs the tick loop until shutdown. Never returns early without a `Failed` or `Stopped`
/// report.
pub fn run(mut setup: TickSetup) {
    let services = match Services::create(&setup.settings.name, setup.settings.max_clients as usize)
    {
        Ok(services) => services,
        Err(error) => {
            report_at_start(&mut setup, Report::Failed(error.into()));
            return;
        }
    };
    let (rt_status, _dma_guard) = match rt::set_up(
        &setup.settings,
        setup.require_rt,
        std::mem::take(&mut setup.io_rt),
    ) {
        Ok(done) => done,
        Err(error) => {
            report_at_start(&mut setup, Report::Failed(error));
            return;
        }
    };
    let rt_flags = rt_status.flags();
    let node_id = services.node.id().value();
    setup.health.beat(monotonic_now());
    report_at_start(
        &mut setup,
        Report::Started {
            rt: rt_status,
            node_id,
        },
    );
    Loop::new(setup, services, rt_flags).run();
}

/// Hands a start-up report to the main thread. Its queue is empty at start, so this never
/// fails; if it did, the report goes to the log instead (the loop has no stats yet).
fn report_at_start(setup: &mut TickSetup, report: Report) {
    if let Err(rtrb::PushError::Full(report)) = setup.reports.push(report) {
        tracing::error!("report queue full at start: {report:?}");
    }
}

struct Loop {
    setup: TickSetup,
    services: Services,
    wakeup: Latency,
    work: Latency,
    stats: Box<ServerStats>,
    spare_frame: Box<MotionFrame>,
    device_seen: Vec<(DeviceState, [u8; 32])>,
    /// Each driver's verdict count last reported (`DeviceStatus::verdicts`).
    verdicts_seen: Vec<u32>,
    /// Per axis: the fault code in the last frame (to report new faults once).
    faults_seen: Vec<u16>,
    directory: ClientDirectory,
    consecutive_overruns: u64,
    overrun_fault_latched: bool,
    /// Whether the last frame had the e-stop latched (a new latch triggers the black box).
    estop_seen: bool,
    /// Says when the `estop` listener has something (`None`: ask it every tick).
    estop_watch: Option<EstopWatch>,
    /// Ticks since the listener was last asked.
    ticks_since_estop_look: u32,
}

/// The most ticks between two looks at the `estop` listener even when its watch saw
/// nothing (64 ms at 1 kHz): the bound on an e-stop event's delay should the watch thread
/// ever fail.
const ESTOP_LOOK_EVERY: u32 = 64;

impl Loop {
    /// Hands `report` to the main thread; a full queue drops it and counts it.
    fn report(&mut self, report: Report) {
        if self.setup.reports.push(report).is_err() {
            self.stats.events_dropped += 1;
        }
    }

    fn new(mut setup: TickSetup, services: Services, rt_flags: u32) -> Self {
        // The I/O threads report writes and horizons (crate::io); frame stamps are
        // CLOCK_MONOTONIC.
        setup.engine.stamp_links();
        setup.engine.set_clock_origin(setup.epoch);
        // Every link is handed to its I/O thread closed; the thread reports `Up` once it
        // opened it (an `Up` already queued is taken at the first tick). Until then the
        // link's boards are starting, not down.
        setup.journal.start(setup.epoch, setup.ports.len());
        for (device, reference) in setup.references.iter().flat_map(|watch| watch.restored()) {
            setup.journal.restored_reference(*device, reference);
        }
        setup.journal.prepare_snapshots(&setup.engine);
        for link in 0..setup.ports.len() {
            setup.journal.link_opening(link);
            setup.engine.link_opening(link);
        }
        let mut stats = Box::new(ServerStats::EMPTY);
        stats.rt_flags = rt_flags;
        stats.link_count = setup.ports.len().min(stats.links.len()) as u32;
        for (name, out) in setup.link_names.iter().zip(stats.links.iter_mut()) {
            write_text(&mut out.name, name);
        }
        let devices = setup.engine.config().devices.len();
        let axes = setup.engine.config().axes.len();
        let directory = ClientDirectory::new(services.max_clients);
        let estop_watch = EstopWatch::start(&services.estop)
            .inspect_err(|error| {
                tracing::warn!(
                    "the estop event is looked for every tick: its watch thread did not start \
                     ({error})"
                );
            })
            .ok();
        Self {
            setup,
            services,
            wakeup: Latency::new(),
            work: Latency::new(),
            stats,
            spare_frame: Box::new(MotionFrame::EMPTY),
            device_seen: vec![(DeviceState::Offline, [0; 32]); devices],
            verdicts_seen: vec![0; devices],
            faults_seen: vec![0; axes],
            directory,
            consecutive_overruns: 0,
            overrun_fault_latched: false,
            estop_seen: false,
            estop_watch,
            ticks_since_estop_look: 0,
        }
    }

    fn run(mut self) {
        let period = self.setup.engine.config().period();
        let epoch = self.setup.epoch;
        let mut deadline = monotonic_now() + period;
        let mut last_stats = Duration::ZERO;
        let mut last_liveness = Duration::ZERO;
        let mut shutting_since: Option<Duration> = None;
        let mut buf = [0u8; PACKET_LEN];
        let mut phases = PhaseClock::default();
        self.publish_info();
        self.publish_params();
        loop {
            sleep_until(deadline);
            let wake = monotonic_now();
            self.wakeup
                .record(duration_ns(wake.saturating_sub(deadline)));
            let now = deadline.saturating_sub(epoch);
            phases.begin(wake);
            self.setup.journal.tick(now);
            if self.setup.journal.snapshot_due() {
                self.setup.journal.snapshot(&self.setup.engine);
            }

            self.take_link_input(now);
            phases.lap(Phase::Input);
            while let Ok(client) = self.setup.dead_clients.pop() {
                self.setup.journal.client_dead(client);
                self.setup.engine.client_dead(client);
            }
            self.take_estops();
            if now.saturating_sub(last_liveness) >= self.setup.settings.liveness_check {
                last_liveness = now;
                self.end_claims_of_departed_clients();
            }
            if shutting_since.is_none() && self.setup.shutdown.load(Ordering::Relaxed) {
                self.setup.journal.shutdown();
                self.setup.engine.begin_shutdown();
                shutting_since = Some(now);
            }
            phases.lap(Phase::Clients);
            self.step_and_publish(now, deadline);
            phases.lap(Phase::Step);
            self.queue_link_output(now, &mut buf);
            phases.lap(Phase::Output);

            self.report_faults();
            if now.saturating_sub(last_stats) >= Duration::from_secs(1) {
                last_stats = now;
                self.check_slots();
                self.publish_stats(deadline);
            }
            self.report_devices();
            if let Some(since) = shutting_since {
                let at_rest = self.setup.engine.all_at_rest();
                if at_rest || now.saturating_sub(since) >= SHUTDOWN_TIMEOUT {
                    self.report(Report::Stopped { at_rest });
                    return;
                }
            }
            phases.lap(Phase::Reports);
            if let Some(means) = phases.end_tick() {
                self.report(Report::Phases(means));
            }
            let done = monotonic_now();
            self.work.record(duration_ns(done.saturating_sub(wake)));
            self.setup.health.beat(done);
            deadline += period;
            if done > deadline {
                // Missed at least one deadline: skip the missed ticks (no burst of
                // catch-up ticks) and count the overrun.
                let mut skipped = 0;
                while deadline <= done {
                    deadline += period;
                    skipped += 1;
                }
                self.setup.journal.skip(skipped);
                self.setup.engine.skip_ticks(skipped);
                self.stats.overruns += 1;
                self.consecutive_overruns += 1;
                self.stats.max_consecutive_overruns = self
                    .stats
                    .max_consecutive_overruns
                    .max(self.consecutive_overruns);
                let limit = u64::from(self.setup.settings.max_consecutive_overruns);
                if limit > 0 && self.consecutive_overruns >= limit && !self.overrun_fault_latched {
                    self.setup.journal.overrun_fault();
                    self.setup.engine.stop_all_with_fault(FaultCode::Overrun);
                    self.overrun_fault_latched = true;
                }
            } else {
                self.consecutive_overruns = 0;
                self.overrun_fault_latched = false;
            }
        }
    }

    /// Per link: down/up events, write reports (those from before a `Down` belong to no
    /// message the engine still tracks), received bytes, and the horizon read before them.
    fn take_link_input(&mut self, now: Duration) {
        let engine = &mut self.setup.engine;
        let journal = &mut self.setup.journal;
        for (index, port) in self.setup.ports.iter_mut().enumerate() {
            if let Some(inline) = port.inline.as_mut() {
                // A link the tick runs itself: what came back since the last tick's
                // transfers (crate::io::inline).
                inline.look();
            }
            let heard = port.heard();
            while let Ok(event) = port.events.pop() {
                match event {
                    LinkEvent::Down => {
                        port.generation = port.generation.wrapping_add(1);
                        journal.link_down(index);
                        engine.link_down(index, now);
                    }
                    LinkEvent::Up => {
                        journal.link_up(index);
                        engine.link_up(index, now);
                    }
                }
            }
            while let Ok(written) = port.written.pop() {
                if written.generation == port.generation {
                    journal.link_written(index, written.at);
                    engine.link_written(index, written.at);
                }
            }
            while let Ok(packet) = port.rx.pop() {
                journal.link_rx(index, packet.at(), packet.bytes());
                engine.handle_link_rx(index, now, packet.at(), packet.bytes());
            }
            journal.link_heard(index, heard);
            engine.link_heard(index, heard);
        }
    }

    /// E-stops that did not come as commands: the `estop` event, SIGUSR1.
    fn take_estops(&mut self) {
        let mut notified = false;
        // The listener is asked when its watch saw a notification (crate::estop_watch), and
        // every ESTOP_LOOK_EVERY ticks whatever the watch says (a safety function must not
        // rest on one helper thread alone), or every tick when the watch could not be
        // started.
        self.ticks_since_estop_look = self.ticks_since_estop_look.saturating_add(1);
        let announced = self.estop_watch.as_ref().is_none_or(EstopWatch::pending);
        if announced || self.ticks_since_estop_look >= ESTOP_LOOK_EVERY {
            self.ticks_since_estop_look = 0;
            let watch = self.estop_watch.as_ref().filter(|_| announced);
            if let Some(watch) = watch {
                watch.clear();
            }
            if self.services.estop.try_wait(|_| notified = true).is_err() {
                self.stats.events_dropped += 1;
            }
            // Only a watch that announced waits to be told it was taken.
            if let Some(watch) = watch {
                watch.resume();
            }
        }
        let signalled = self.setup.estop_signal.swap(false, Ordering::Relaxed);
        if notified || signalled {
            self.setup.journal.estop(if notified { 1 } else { 2 });
            self.setup.engine.estop();
            let by = if notified {
                "the estop event"
            } else {
                "SIGUSR1"
            };
            self.report(Report::EstopBy(by));
        }
    }

    /// Claims end when their owner has no client port on the command service any more
    /// (it exited, normally or not, or dropped its client).
    fn end_claims_of_departed_clients(&mut self) {
        self.directory.refresh(&self.services.factories.command);
        loop {
            let departed = self
                .setup
                .engine
                .claim_holders()
                .find(|holder| !self.directory.is_connected(*holder));
            let Some(holder) = departed else { break };
            self.setup.journal.release_claims(holder);
            self.setup.engine.release_claims_of(holder);
        }
    }

    /// Logs (through the main thread) every service whose slots are all taken, once until
    /// some free up, and counts it in the stats.
    fn check_slots(&mut self) {
        let mut full = 0;
        for slots in self.services.slot_use() {
            if slots.used >= slots.limit {
                full |= slots.bit;
                if self.stats.full_services & slots.bit == 0 {
                    self.stats.full_events += 1;
                    self.report(Report::SlotsFull(slots));
                }
            }
        }
        self.stats.full_services = full;
    }

    /// Reports axes that faulted since the last frame.
    fn report_faults(&mut self) {
        for index in 0..self.faults_seen.len() {
            let fault = self.setup.engine.axis_fault(index);
            let code = fault.map_or(0, |(code, _, _)| code as u16);
            if self.faults_seen.get(index) != Some(&code) {
                if let Some(seen) = self.faults_seen.get_mut(index) {
                    *seen = code;
                }
                if let Some((code, value, limit)) = fault {
                    self.setup.journal.trigger(Trigger::Fault, index);
                    self.report(Report::Fault {
                        axis: index,
                        code,
                        value,
                        limit,
                    });
                }
            }
        }
    }

    fn step_and_publish(&mut self, now: Duration, deadline: Duration) {
        self.services.paths.receive();
        self.services
            .setpoints
            .deliver(&mut self.setup.engine, &mut self.setup.journal);
        self.setup.journal.step();
        let mut commands = IpcCommands {
            server: &self.services.command,
            factory: &self.services.factories.command,
            directory: &mut self.directory,
            current: None,
            sender: ClientId::NONE,
            replies_lost: 0,
            paths: &mut self.services.paths,
            journal: &mut self.setup.journal,
        };
        match self.services.frame.loan_uninit() {
            Ok(sample) => {
                let mut sample = sample.write_payload(MotionFrame::EMPTY);
                let frame = sample.payload_mut();
                self.setup.engine.step(now, &mut commands, frame);
                commands.paths.note_claimants(frame);
                commands
                    .journal
                    .frame_and_estop(frame, &mut self.estop_seen);
                if let Some(watch) = self.setup.references.as_mut() {
                    watch.observe(frame);
                }
                frame.time_ns = duration_ns(deadline);
                frame.publish_ns = duration_ns(monotonic_now());
                if sample.send().is_err() {
                    self.stats.frames_lost += 1;
                }
            }
            Err(_) => {
                // No sample to loan (every one held by slow subscribers): the tick goes on.
                self.setup
                    .engine
                    .step(now, &mut commands, &mut self.spare_frame);
                commands.paths.note_claimants(&self.spare_frame);
                commands
                    .journal
                    .frame_and_estop(&self.spare_frame, &mut self.estop_seen);
                if let Some(watch) = self.setup.references.as_mut() {
                    watch.observe(&self.spare_frame);
                }
                self.stats.frames_lost += 1;
            }
        }
        self.stats.replies_lost += commands.replies_lost;
        if self.services.tick.notify().is_err() {
            self.stats.publish_failures += 1;
        }
        // Late subscribers of the rarely published info and stats get their history sample
        // only when the publisher looks at its connections; this is cheap when nothing
        // changed.
        for updated in [
            self.services.info.update_connections(),
            self.services.stats.update_connections(),
            self.services.params.update_connections(),
        ] {
            if updated.is_err() {
                self.stats.events_dropped += 1;
            }
        }
    }

    /// Per link: the drivers' messages into the transmit ring (stamped with `now`), the
    /// I/O thread woken if anything was queued, and asked to look at the link again by the
    /// drivers' next deadline; a link the tick runs itself (`io = "tick"`) gets them
    /// written now instead.
    fn queue_link_output(&mut self, now: Duration, buf: &mut [u8; PACKET_LEN]) {
        for (index, port) in self.setup.ports.iter_mut().enumerate() {
            let mut queued = false;
            // Two slots: a message may need a change of the line rate before it.
            while port.tx.slots() > 1 {
                let Some(len) = self.setup.engine.poll_link_transmit(index, now, buf) else {
                    self.setup.journal.link_tx_none(index);
                    break;
                };
                self.setup.journal.link_tx(index, &buf[..len]);
                if let Some(baud) = self.setup.engine.take_link_rate(index) {
                    self.setup.journal.link_rate(index, baud);
                    if port.tx.push(Packet::rate_change(baud, now)).is_err() {
                        port.counters.dropped.fetch_add(1, Ordering::Relaxed);
                    }
                }
                // `slots() > 0` was checked: the push cannot fail, but a failure would
                // still be counted rather than lost silently.
                if port.tx.push(Packet::stamped(&buf[..len], now)).is_err() {
                    port.counters.dropped.fetch_add(1, Ordering::Relaxed);
                }
                queued = true;
            }
            match port.inline.as_mut() {
                // No thread to wake: the tick writes them now, within its budget.
                Some(inline) => inline.transfer(),
                None => {
                    port.queued_and_look_by(queued, self.setup.engine.link_poll_timeout(index));
                }
            }
        }
    }

    fn publish_stats(&mut self, deadline: Duration) {
        let engine = &self.setup.engine;
        let stats = &mut self.stats;
        stats.tick = engine.tick();
        stats.time_ns = duration_ns(deadline);
        stats.wakeup = self.wakeup.summary();
        stats.work = self.work.summary();
        let counters = engine.counters();
        stats.commands = counters.commands;
        stats.rejected = counters.rejected;
        stats.faults = counters.faults;
        stats.clients = self.setup.clients_alive.load(Ordering::Relaxed);
        stats.nodes_cleaned = self.setup.nodes_cleaned.load(Ordering::Relaxed);
        stats.blackbox_lost = self.setup.journal.lost_since_start();
        let paths = &self.services.paths;
        stats.paths_dropped = paths.dropped + paths.inbox.orphans;
        let setpoints = &self.services.setpoints;
        stats.setpoints_dropped = setpoints.over_budget + setpoints.inbox.orphans;
        let config = engine.config();
        for (index, (port, out)) in self
            .setup
            .ports
            .iter()
            .zip(stats.links.iter_mut())
            .enumerate()
        {
            let (mut replies, mut bad) = (0u64, 0u64);
            for device in (0..config.devices.len()).filter(|&d| config.devices[d].link == index) {
                if let Some(driver) = engine.driver(device) {
                    let status = driver.status();
                    replies += status.replies;
                    bad += u64::from(status.timeouts) + u64::from(status.bad_replies);
                }
            }
            let c = &port.counters;
            out.bytes_in = c.bytes_in.load(Ordering::Relaxed);
            out.bytes_out = c.bytes_out.load(Ordering::Relaxed);
            out.errors = c.errors.load(Ordering::Relaxed) + c.dropped.load(Ordering::Relaxed) + bad;
            out.reconnects = c.reconnects.load(Ordering::Relaxed);
            out.up = u32::from(c.up.load(Ordering::Relaxed));
            out.deferred = u32::try_from(c.deferred.load(Ordering::Relaxed)).unwrap_or(u32::MAX);
            out.frames = replies;
        }
        let epoch = self.setup.epoch;
        let absolute = |ns: u64| {
            if ns == NEVER {
                0
            } else {
                duration_ns(epoch + Duration::from_nanos(ns))
            }
        };
        for (port, out) in self.setup.ports.iter().zip(stats.link_io.iter_mut()) {
            let c = &port.counters;
            *out = LinkIo {
                last_write_ns: absolute(c.last_write_ns.load(Ordering::Relaxed)),
                last_read_ns: absolute(c.last_read_ns.load(Ordering::Relaxed)),
                transactions: c.transactions.load(Ordering::Relaxed),
                reads: c.reads.load(Ordering::Relaxed),
            };
        }
        let sent = match self.services.stats.loan_uninit() {
            Ok(sample) => sample.write_payload(**stats).send().is_ok(),
            Err(_) => false,
        };
        if !sent {
            // Shows in the next figures that do get through.
            stats.publish_failures += 1;
        }
        let line = StatusLine::of(stats);
        self.report(Report::Stats(line));
    }

    fn report_devices(&mut self) {
        let mut changed = false;
        for index in 0..self.device_seen.len() {
            let Some(driver) = self.setup.engine.driver(index) else {
                continue;
            };
            let status = driver.status();
            if let Some(seen) = self.verdicts_seen.get_mut(index)
                && *seen != status.verdicts
            {
                *seen = status.verdicts;
                if let Some(verdict) = status.verdict {
                    self.report(Report::Verdict { index, verdict });
                }
            }
            let state = self
                .setup
                .engine
                .device_state(index)
                .unwrap_or(DeviceState::Offline);
            let mut firmware = [0u8; 32];
            write_text(&mut firmware, status.firmware());
            if self.device_seen.get(index) != Some(&(state, firmware)) {
                if let Some(seen) = self.device_seen.get_mut(index) {
                    *seen = (state, firmware);
                }
                changed = true;
                self.report(Report::Device {
                    index,
                    state,
                    firmware,
                });
            }
        }
        if changed {
            self.publish_info();
        }
    }

    fn publish_params(&mut self) {
        let sent = match self.services.params.loan_uninit() {
            Ok(sample) => sample.write_payload(*self.setup.params).send().is_ok(),
            Err(_) => false,
        };
        if !sent {
            self.stats.publish_failures += 1;
        }
    }

    fn publish_info(&mut self) {
        let sent = match self.services.info.loan_uninit() {
            Ok(sample) => {
                let mut sample = sample.write_payload(ServerInfo::EMPTY);
                let info = sample.payload_mut();
                self.setup.engine.fill_info(info);
                info.max_clients = self.setup.settings.max_clients;
                info.server_pid = std::process::id();
                info.start_time_ns = duration_ns(self.setup.epoch);
                sample.send().is_ok()
            }
            Err(_) => false,
        };
        if !sent {
            self.stats.publish_failures += 1;
        }
    }
}

fn duration_ns(duration: Duration) -> u64 {
    u64::try_from(duration.as_nanos()).unwrap_or(u64::MAX)
}
