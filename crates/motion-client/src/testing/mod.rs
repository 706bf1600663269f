//! A fake motiond for tests (feature `testing`): the same services with the same types
//! (frame, tick, command, info, stats, params, estop), under the server's node name, a
//! thread ticking at a fixed rate, and a small kinematic model of each axis.
//!
//! It judges every request with the server's own rulebook ([`motion_ipc::rules`]: schema,
//! kind, finite values, identity from the transport, targets, claims, e-stop, shutdown,
//! capabilities, device readiness, faults, limits and rates), group and stream requests in
//! the engine's order, and `crates/motion-engine/tests/rulebook_parity.rs` runs one table of
//! axis and signal requests and one of group and stream requests through the engine and
//! this fake and demands the same answers; client and CLI behaviour can so be
//! tested without the real server. Positions move at the commanded speed without
//! acceleration; nothing here models a board. Every request it receives is logged for
//! assertions; tests change device states, inputs and faults with [`FakeServer`]'s
//! methods, and restart it under the same name with [`FakeServer::restart`].

mod config;
mod model;
mod serve;

use core::time::Duration;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, mpsc};
use std::thread::JoinHandle;

use iceoryx2::service::Service;
use motion_ipc::{CommandRequest, DeviceState, FaultCode, GroupAbort};

pub use config::{FakeAxis, FakeConfig, FakeDevice, FakeGroup, FakeParam, FakeSignal};

/// A name no other test of this process or of a concurrent run uses.
pub fn unique_name(prefix: &str) -> String {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let count = COUNTER.fetch_add(1, Ordering::Relaxed);
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |since| since.subsec_nanos());
    format!("{prefix}-{}-{count}-{nanos}", std::process::id())
}

/// A change a test makes to the running fake, applied at its next tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FakeControl {
    /// Forces device `device` into `state` (until the next restart).
    DeviceState {
        /// Device index.
        device: usize,
        /// The state it reports from now on.
        state: DeviceState,
    },
    /// Sets the raw value an input reports (electrical level 0/1, or ADC counts).
    Input {
        /// Signal index.
        signal: usize,
        /// The raw value.
        raw: f64,
    },
    /// A capture or trigger signal's event: its sequence counts one, in this tick, with
    /// `raw` as its new raw value (a capture's count) when given.
    Event {
        /// Signal index.
        signal: usize,
        /// The new raw value, if any.
        raw: Option<f64>,
    },
    /// The board of axis `axis` no longer reports the fault it raised: as on the server, a
    /// fault a board raised ends when its cause is gone (the axis stays stopped); a fault the
    /// server raised (following error, overspeed, limits) waits for a reset either way.
    FaultGone {
        /// Axis index.
        axis: usize,
    },
    /// Begins the server's shutdown (as SIGTERM does): every axis stops and new motion is
    /// refused with `ShuttingDown`.
    ShutDown,
    /// Faults axis `axis` with `code`, its figure `value` and tolerance `limit`.
    Fault {
        /// Axis index.
        axis: usize,
        /// The fault.
        code: FaultCode,
        /// The measured figure.
        value: f64,
        /// The tolerance it broke.
        limit: f64,
    },
    /// Aborts group `group`'s running motion with `abort`, naming axis `axis` (an index
    /// into the config's axes) with its figure and tolerance, as the server's path or goal
    /// supervision would.
    AbortGroup {
        /// Group index.
        group: usize,
        /// Why.
        abort: GroupAbort,
        /// The axis that aborted it.
        axis: Option<usize>,
        /// The figure.
        value: f64,
        /// The tolerance it broke.
        limit: f64,
    },
}

/// What the test and the serving thread share.
#[derive(Debug, Default)]
pub(crate) struct Shared {
    /// Every request with the incarnation (0, then one more per restart) that took it.
    pub(crate) requests: Mutex<Vec<(u64, CommandRequest)>>,
    /// The current incarnation.
    pub(crate) generation: AtomicU64,
    pub(crate) controls: Mutex<Vec<FakeControl>>,
    pub(crate) estops: Mutex<Vec<&'static str>>,
    pub(crate) estop_latched: AtomicBool,
}

/// A running fake server; stops when dropped.
#[derive(Debug)]
pub struct FakeServer {
    config: FakeConfig,
    shared: Arc<Shared>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<Result<(), String>>>,
    start: fn(&FakeConfig, &Arc<Shared>, &Arc<AtomicBool>) -> ServeResult,
}

type ServeResult = Result<JoinHandle<Result<(), String>>, String>;

fn spawn<S: Service>(
    config: &FakeConfig,
    shared: &Arc<Shared>,
    stop: &Arc<AtomicBool>,
) -> ServeResult {
    let (ready_tx, ready_rx) = mpsc::channel();
    let thread = {
        let config = config.clone();
        let shared = Arc::clone(shared);
        let stop = Arc::clone(stop);
        std::thread::spawn(move || serve::serve::<S>(&config, &stop, &shared, &ready_tx))
    };
    match ready_rx.recv_timeout(Duration::from_secs(10)) {
        Ok(Ok(())) => Ok(thread),
        Ok(Err(error)) => Err(error),
        Err(_) => Err(thread
            .join()
            .map_err(|_| "fake server panicked".to_owned())
            .and_then(|result| result.map(|()| "fake server never became ready".to_owned()))
            .unwrap_or_else(|error| error)),
    }
}

impl FakeServer {
    /// Creates the services over `S` and starts ticking; returns once clients can connect.
    pub fn start<S: Service>(config: FakeConfig) -> Result<Self, String> {
        let shared = Arc::new(Shared::default());
        let stop = Arc::new(AtomicBool::new(false));
        let thread = spawn::<S>(&config, &shared, &stop)?;
        Ok(Self {
            config,
            shared,
            stop,
            thread: Some(thread),
            start: spawn::<S>,
        })
    }

    /// The instance name.
    pub fn name(&self) -> &str {
        &self.config.name
    }

    /// What it serves.
    pub fn config(&self) -> &FakeConfig {
        &self.config
    }

    /// Every request received so far (by this server and the ones it restarted as), in
    /// order.
    pub fn requests(&self) -> Vec<CommandRequest> {
        self.shared
            .requests
            .lock()
            .map(|log| log.iter().map(|(_, request)| *request).collect())
            .unwrap_or_default()
    }

    /// The requests the current incarnation took (since the last [`FakeServer::restart`]).
    pub fn requests_since_restart(&self) -> Vec<CommandRequest> {
        let generation = self.shared.generation.load(Ordering::Relaxed);
        self.shared
            .requests
            .lock()
            .map(|log| {
                log.iter()
                    .filter(|(taken_by, _)| *taken_by == generation)
                    .map(|(_, request)| *request)
                    .collect()
            })
            .unwrap_or_default()
    }

    /// Whether the e-stop is latched now.
    pub fn estop_latched(&self) -> bool {
        self.shared.estop_latched.load(Ordering::Relaxed)
    }

    /// How each e-stop came in, in order: "command", "event" or "signal" (SIGUSR1).
    pub fn estop_sources(&self) -> Vec<&'static str> {
        self.shared
            .estops
            .lock()
            .map(|log| log.clone())
            .unwrap_or_default()
    }

    /// Queues a change for the next tick.
    pub fn control(&self, control: FakeControl) {
        if let Ok(mut queue) = self.shared.controls.lock() {
            queue.push(control);
        }
    }

    /// Forces device `device` into `state`.
    pub fn set_device_state(&self, device: usize, state: DeviceState) {
        self.control(FakeControl::DeviceState { device, state });
    }

    /// Sets the raw value input `signal` reports.
    pub fn set_input(&self, signal: usize, raw: f64) {
        self.control(FakeControl::Input { signal, raw });
    }

    /// A capture of `raw` counts on capture signal `signal` (its sequence counts one).
    pub fn capture(&self, signal: usize, raw: f64) {
        self.control(FakeControl::Event {
            signal,
            raw: Some(raw),
        });
    }

    /// Aborts group `group`'s running motion with `abort`, naming axis `axis` with its
    /// figure `value` and tolerance `limit`.
    pub fn abort_group(
        &self,
        group: usize,
        abort: GroupAbort,
        axis: Option<usize>,
        value: f64,
        limit: f64,
    ) {
        self.control(FakeControl::AbortGroup {
            group,
            abort,
            axis,
            value,
            limit,
        });
    }

    /// Faults axis `axis`.
    pub fn fault_axis(&self, axis: usize, code: FaultCode, value: f64, limit: f64) {
        self.control(FakeControl::Fault {
            axis,
            code,
            value,
            limit,
        });
    }

    /// Stops serving (its node, and with it every port, goes away) and starts again under
    /// the same name: a new server process as clients see it (a new node, a new start time,
    /// tick 0, every axis stopped, no claims). Requests keep being logged in the same log.
    pub fn restart(&mut self) -> Result<(), String> {
        self.stop_thread()?;
        self.stop = Arc::new(AtomicBool::new(false));
        self.shared.estop_latched.store(false, Ordering::Relaxed);
        self.shared.generation.fetch_add(1, Ordering::Relaxed);
        let thread = (self.start)(&self.config, &self.shared, &self.stop)?;
        self.thread = Some(thread);
        Ok(())
    }

    /// Stops the server and reports an error its thread hit.
    pub fn shutdown(mut self) -> Result<(), String> {
        self.stop_thread()
    }

    fn stop_thread(&mut self) -> Result<(), String> {
        self.stop.store(true, Ordering::Relaxed);
        match self.thread.take() {
            Some(thread) => thread
                .join()
                .map_err(|_| "fake server panicked".to_owned())?,
            None => Ok(()),
        }
    }
}

impl Drop for FakeServer {
    fn drop(&mut self) {
        let _ = self.stop_thread();
    }
}
