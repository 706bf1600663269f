//! A test rig: the engine, real `SimLink`s to simulated boards, and a fake clock.
//!
//! [`Rig::tick`] does what motiond's loop does each tick — read every link, feed the engine,
//! step, write what the drivers want to send — with time advanced by the test, never slept.
//! Link faults (a `SimFaults` unplug) surface as `Disconnected` errors; the rig reports
//! them to the engine and tries to reopen the link every [`REOPEN_EVERY`], as motiond's
//! I/O threads do.
//!
//! By default the rig's I/O side is perfect and reports nothing: messages are written in
//! the tick that made them and every tick reads. [`Rig::stamp_io`] makes it report write
//! stamps and horizons as motiond's I/O threads do, and lets it lag: messages reach the
//! wire a fixed delay after they were queued, and the I/O side may run only now and then
//! (a starved thread).

use core::time::Duration;
use std::collections::VecDeque;
use std::sync::{Arc, Mutex, MutexGuard};

use motion_drivers::{Driver, LinkKind};
use motion_engine::{CommandPort, Engine, EngineConfig};
use motion_ipc::{
    AxisFlags, AxisState, ClientId, CommandKind, CommandReply, CommandRequest, DeviceState,
    MotionFrame,
};
use motion_link::sim::{CanDevice, SpiDevice, StreamDevice};
use motion_link::{Link, LinkErrorKind};

/// How often the rig retries opening a disconnected link.
pub const REOPEN_EVERY: Duration = Duration::from_millis(100);

fn scope(hook: Option<fn(bool)>, entering: bool) {
    if let Some(hook) = hook {
        hook(entering);
    }
}

/// A device model shared between the simulated wire and the test, so the test can look at
/// (and poke) the model's true state while the link owns it.
#[derive(Debug)]
pub struct Shared<T>(pub Arc<Mutex<T>>);

impl<T> Shared<T> {
    /// Wraps `model`; returns the wire side and the test's handle.
    pub fn new(model: T) -> (Box<Self>, Arc<Mutex<T>>) {
        let inner = Arc::new(Mutex::new(model));
        (Box::new(Self(Arc::clone(&inner))), inner)
    }

    fn lock(&self) -> MutexGuard<'_, T> {
        self.0.lock().expect("model lock")
    }
}

impl<T: StreamDevice> StreamDevice for Shared<T> {
    fn receive(&mut self, now: Duration, bytes: &[u8]) {
        self.lock().receive(now, bytes);
    }
    fn transmit(&mut self, now: Duration, out: &mut [u8]) -> usize {
        self.lock().transmit(now, out)
    }
    fn next_event(&self, now: Duration) -> Option<Duration> {
        self.lock().next_event(now)
    }
    fn baud(&self) -> Option<u32> {
        self.lock().baud()
    }
}

impl<T: CanDevice> CanDevice for Shared<T> {
    fn receive(&mut self, now: Duration, frame: &motion_drivers::CanRecord) {
        self.lock().receive(now, frame);
    }
    fn transmit(&mut self, now: Duration) -> Option<(Duration, motion_drivers::CanRecord)> {
        self.lock().transmit(now)
    }
    fn next_event(&self, now: Duration) -> Option<Duration> {
        self.lock().next_event(now)
    }
}

impl<T: SpiDevice> SpiDevice for Shared<T> {
    fn transfer(&mut self, now: Duration, mosi: &[u8], miso: &mut [u8]) -> bool {
        self.lock().transfer(now, mosi, miso)
    }
    fn advance(&mut self, now: Duration) {
        self.lock().advance(now);
    }
}

/// Commands in, replies out.
#[derive(Debug, Default)]
pub struct Queue {
    pub requests: VecDeque<CommandRequest>,
    pub replies: Vec<CommandReply>,
}

impl CommandPort for Queue {
    fn next_request(&mut self) -> Option<CommandRequest> {
        self.requests.pop_front()
    }
    fn reply(&mut self, reply: CommandReply) {
        self.replies.push(reply);
    }
}

/// Every message written to one link, with the time it was written.
pub type WireLog = Vec<(Duration, Vec<u8>)>;

struct RigLink {
    link: Box<dyn Link>,
    down: bool,
    next_reopen: Duration,
    log: WireLog,
    /// Stamped I/O: messages queued and not written yet, with the time they were queued.
    unwritten: VecDeque<(Duration, Vec<u8>)>,
}

/// How a stamped I/O side lags (see [`Rig::stamp_io`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct IoLag {
    /// A message reaches the wire this long after it was queued.
    pub write_delay: Duration,
    /// The I/O side runs (writes what is due, reads what arrived) only this often; zero:
    /// every tick.
    pub runs_every: Duration,
    /// Report write stamps and horizons to the engine (motiond does); `false` shows what
    /// the same lag does to an engine that is not told.
    pub report: bool,
}

/// The engine wired to simulated links.
pub struct Rig {
    pub engine: Engine,
    links: Vec<RigLink>,
    pub frame: Box<MotionFrame>,
    pub port: Queue,
    pub now: Duration,
    pub period: Duration,
    pub client: ClientId,
    sequence: u64,
    /// Record every written message per link (off by default: costs memory).
    pub log_wire: bool,
    /// Called with `true` before and `false` after each stretch of engine work in a tick
    /// (feeding received bytes, stepping, polling transmits), so that a test can count
    /// what the engine alone does (e.g. allocations) apart from the simulated links.
    pub engine_scope: Option<fn(bool)>,
    /// Stamped I/O and its lag.
    io: Option<IoLag>,
    /// When the stamped I/O side last ran.
    io_ran_at: Option<Duration>,
}

impl Rig {
    /// `links` in config order (one `SimLink` or other `Link` per `config.links` entry),
    /// `drivers` in `config.devices` order.
    pub fn new(
        config: EngineConfig,
        drivers: Vec<Box<dyn Driver>>,
        links: Vec<Box<dyn Link>>,
    ) -> Self {
        assert_eq!(
            config.links.len(),
            links.len(),
            "one link per configured link"
        );
        let period = config.period();
        let engine = Engine::new(config, drivers).expect("valid engine config");
        Self {
            engine,
            links: links
                .into_iter()
                .map(|link| RigLink {
                    link,
                    down: false,
                    next_reopen: Duration::ZERO,
                    log: Vec::new(),
                    unwritten: VecDeque::new(),
                })
                .collect(),
            frame: Box::new(MotionFrame::EMPTY),
            port: Queue::default(),
            now: Duration::ZERO,
            period,
            client: ClientId::from_u128(0x00C1_1E27),
            sequence: 0,
            log_wire: false,
            engine_scope: None,
            io: None,
            io_ran_at: None,
        }
    }

    /// From now on the I/O side lags as `lag` says and (if `lag.report`) reports every
    /// write and its horizon to the engine, as motiond's I/O threads do.
    pub fn stamp_io(&mut self, lag: IoLag) {
        if lag.report {
            self.engine.stamp_links();
        }
        self.io = Some(lag);
    }

    /// Stamped I/O: whether the I/O side runs in this tick.
    fn io_runs(&mut self, now: Duration) -> bool {
        let Some(lag) = self.io else {
            return true;
        };
        let runs = self
            .io_ran_at
            .is_none_or(|at| now.saturating_sub(at) >= lag.runs_every);
        if runs {
            self.io_ran_at = Some(now);
        }
        runs
    }

    /// Stamped I/O: writes the messages of link `index` that are due, reporting each.
    fn write_due(&mut self, index: usize, now: Duration) {
        let Some(lag) = self.io else {
            return;
        };
        let Some(rig_link) = self.links.get_mut(index) else {
            return;
        };
        while let Some((queued_at, _)) = rig_link.unwritten.front()
            && now.saturating_sub(*queued_at) >= lag.write_delay
        {
            let Some((_, bytes)) = rig_link.unwritten.pop_front() else {
                break;
            };
            if rig_link.down {
                continue;
            }
            match rig_link.link.write(now, &bytes) {
                Ok(written) => {
                    assert_eq!(written, bytes.len(), "the sim link took a partial message");
                    if self.log_wire {
                        rig_link.log.push((now, bytes));
                    }
                    if lag.report {
                        self.engine.link_written(index, now);
                    }
                }
                Err(error) => {
                    if error.kind() == LinkErrorKind::Disconnected {
                        rig_link.down = true;
                        rig_link.unwritten.clear();
                        rig_link.next_reopen = now + REOPEN_EVERY;
                        self.engine.link_down(index, now);
                        return;
                    }
                    if self.engine.link_kind(index) == Some(LinkKind::Spi) {
                        let floating = [0xFFu8; 4096];
                        self.engine
                            .handle_link_rx(index, now, now, &floating[..bytes.len()]);
                    }
                    if lag.report {
                        self.engine.link_written(index, now);
                    }
                }
            }
        }
    }

    /// One tick at `self.now`, then time advances by one period.
    pub fn tick(&mut self) {
        let now = self.now;
        let mut buf = [0u8; 4096];
        let io_runs = self.io_runs(now);
        if io_runs {
            for index in 0..self.links.len() {
                self.write_due(index, now);
            }
        }
        for (index, rig_link) in self.links.iter_mut().enumerate() {
            if !io_runs {
                continue;
            }
            if rig_link.down {
                if now >= rig_link.next_reopen {
                    if rig_link.link.reopen(now).is_ok() {
                        rig_link.down = false;
                        self.engine.link_up(index, now);
                    } else {
                        rig_link.next_reopen = now + REOPEN_EVERY;
                    }
                }
                continue;
            }
            loop {
                match rig_link.link.read(now, &mut buf) {
                    Ok(0) => break,
                    Ok(len) => {
                        scope(self.engine_scope, true);
                        self.engine.handle_link_rx(index, now, now, &buf[..len]);
                        scope(self.engine_scope, false);
                    }
                    Err(error) => {
                        if error.kind() == LinkErrorKind::Disconnected {
                            rig_link.down = true;
                            rig_link.unwritten.clear();
                            rig_link.next_reopen = now + REOPEN_EVERY;
                            self.engine.link_down(index, now);
                        }
                        break;
                    }
                }
            }
            if let Some(lag) = self.io
                && lag.report
                && !rig_link.down
            {
                // Everything that arrived is read; nothing queued before the oldest
                // unwritten message is still waiting.
                let heard = rig_link
                    .unwritten
                    .front()
                    .map_or(now, |(queued_at, _)| (*queued_at).min(now));
                self.engine.link_heard(index, heard);
            }
        }
        scope(self.engine_scope, true);
        self.engine.step(now, &mut self.port, &mut self.frame);
        scope(self.engine_scope, false);
        for (index, rig_link) in self.links.iter_mut().enumerate() {
            loop {
                scope(self.engine_scope, true);
                let next = self.engine.poll_link_transmit(index, now, &mut buf);
                scope(self.engine_scope, false);
                let Some(len) = next else {
                    break;
                };
                if rig_link.down {
                    continue;
                }
                if self.io.is_some() {
                    rig_link.unwritten.push_back((now, buf[..len].to_vec()));
                    continue;
                }
                match rig_link.link.write(now, &buf[..len]) {
                    Ok(written) => {
                        assert_eq!(written, len, "the sim link took a partial message");
                        if self.log_wire {
                            rig_link.log.push((now, buf[..len].to_vec()));
                        }
                    }
                    Err(error) => {
                        if error.kind() == LinkErrorKind::Disconnected {
                            rig_link.down = true;
                            rig_link.next_reopen = now + REOPEN_EVERY;
                            self.engine.link_down(index, now);
                        } else if self.engine.link_kind(index) == Some(LinkKind::Spi) {
                            // As motiond's I/O thread: a failed transaction reads as a
                            // floating bus, so MISO routing stays aligned.
                            let floating = [0xFFu8; 4096];
                            self.engine
                                .handle_link_rx(index, now, now, &floating[..len]);
                        }
                    }
                }
            }
        }
        if io_runs && self.io.is_some_and(|lag| lag.write_delay.is_zero()) {
            // A prompt I/O side writes in the tick that queued.
            for index in 0..self.links.len() {
                self.write_due(index, now);
            }
        }
        self.now += self.period;
    }

    /// `count` ticks.
    pub fn run(&mut self, count: usize) {
        for _ in 0..count {
            self.tick();
        }
    }

    /// Ticks until `done(frame)` holds or `limit` of simulated time passes; returns whether
    /// it held.
    pub fn run_until(
        &mut self,
        limit: Duration,
        mut done: impl FnMut(&MotionFrame) -> bool,
    ) -> bool {
        let end = self.now + limit;
        while self.now < end {
            self.tick();
            if done(&self.frame) {
                return true;
            }
        }
        false
    }

    /// Sends one command in the next tick and returns the engine's reply.
    pub fn command(&mut self, axis: u32, kind: CommandKind, values: [f64; 3]) -> CommandReply {
        self.sequence += 1;
        let request =
            CommandRequest::new(self.client, self.sequence, axis, kind).with_values(values);
        self.port.requests.push_back(request);
        self.tick();
        let reply = self.port.replies.pop().expect("every request is answered");
        assert_eq!(reply.sequence, self.sequence);
        reply
    }

    /// Axis `index` in the last frame.
    pub fn axis(&self, index: usize) -> AxisState {
        self.frame.axes[index]
    }

    /// Messages written to link `index` (when `log_wire` is on).
    pub fn wire_log(&self, index: usize) -> &WireLog {
        &self.links[index].log
    }

    /// Whether link `index` is currently considered down by the rig.
    pub fn link_is_down(&self, index: usize) -> bool {
        self.links[index].down
    }
}

/// Whether axis `axis` of the last frame has `flag` set.
pub fn flag(rig: &Rig, axis: usize, flag: AxisFlags) -> bool {
    rig.axis(axis).flags & flag.0 != 0
}

/// Whether axis `axis` of the last frame is neither stale nor faulted and its board is
/// online (configured, its start-up stop acknowledged): it takes goals.
pub fn fresh(rig: &Rig, axis: usize) -> bool {
    !flag(rig, axis, AxisFlags::STALE)
        && !flag(rig, axis, AxisFlags::FAULT)
        && rig.axis(axis).device_state() == Ok(DeviceState::Online)
}

/// Whether the first `axes` axes of `frame` are neither stale nor faulted, on online boards.
pub fn all_fresh(frame: &MotionFrame, axes: usize) -> bool {
    (0..axes).all(|i| {
        frame.axes[i].flags & (AxisFlags::STALE.0 | AxisFlags::FAULT.0) == 0
            && frame.axes[i].device_state() == Ok(DeviceState::Online)
    })
}

/// Sends a command and asserts the engine accepted it.
pub fn accepted(rig: &mut Rig, axis: u32, kind: CommandKind, values: [f64; 3]) {
    let reply = rig.command(axis, kind, values);
    assert_eq!(reply.result(), Ok(()), "{kind:?} {values:?}");
}
