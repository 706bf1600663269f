//! What every campaign shares: an isolated iceoryx2 root (so its shared-memory files can be
//! counted exactly, whatever else runs on the machine), the motiond binary, instance names
//! and config files, distributions, and a thread that reads every frame of a server and
//! keeps each tick's latency (deadline → frame sent, the server's own stamps).

use core::time::Duration;
use std::cell::Cell;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use anyhow::{Context, bail};
use iceoryx2::prelude::*;
use motion_ipc::{MotionFrame, ServerStats, ServiceNames};
use motion_testkit::Server;
use nix::sys::signal::Signal;

/// The campaigns' environment.
#[derive(Debug)]
pub struct Harness {
    /// The working directory (every file of the run, the iceoryx2 root among them).
    pub dir: PathBuf,
    /// The motiond under test.
    pub motiond: PathBuf,
    /// `config/sim.toml` of the source tree.
    pub sim_config: PathBuf,
    /// The short version (CI).
    pub quick: bool,
    /// Seed of every random choice.
    pub seed: u64,
    /// The source tree (scripts/fuzz).
    pub source: PathBuf,
    /// Campaign 8: seconds per fuzz target.
    pub fuzz_seconds: u64,
    iox_root: PathBuf,
    shm_prefix: String,
    names: Cell<u32>,
}

impl Harness {
    /// Makes `dir` with a `config/iceoryx2.toml` that points iceoryx2 at `dir/iox2` with
    /// its own shared-memory prefix, and makes `dir` the working directory: every process
    /// started from here (motiond, the client processes) and this one use that root.
    pub fn new(
        dir: &Path,
        motiond: &Path,
        sim_config: &Path,
        quick: bool,
        seed: u64,
    ) -> anyhow::Result<Self> {
        let motiond = std::fs::canonicalize(motiond)
            .with_context(|| format!("motiond binary {}", motiond.display()))?;
        let sim_config = std::fs::canonicalize(sim_config)
            .with_context(|| format!("{}", sim_config.display()))?;
        std::fs::create_dir_all(dir.join("config"))
            .with_context(|| format!("create {}", dir.display()))?;
        let dir = std::fs::canonicalize(dir)?;
        let iox_root = dir.join("iox2");
        let shm_prefix = format!("rel{}_", std::process::id());
        std::fs::write(
            dir.join("config/iceoryx2.toml"),
            format!(
                "# written by the reliability campaigns: an iceoryx2 root of their own\n\
                 [global]\nroot-path = \"{}/\"\nprefix = \"{shm_prefix}\"\n",
                iox_root.display()
            ),
        )?;
        std::env::set_current_dir(&dir)?;
        Ok(Self {
            dir,
            motiond,
            sim_config,
            quick,
            seed,
            source: PathBuf::from("."),
            fuzz_seconds: 0,
            iox_root,
            shm_prefix,
            names: Cell::new(0),
        })
    }

    /// A fresh instance name for `campaign`.
    pub fn name(&self, campaign: &str) -> String {
        let n = self.names.get() + 1;
        self.names.set(n);
        format!("rel{}-{campaign}-{n}", std::process::id())
    }

    /// Writes `text` to `dir/<file>`.
    pub fn write(&self, file: &str, text: &str) -> anyhow::Result<PathBuf> {
        let path = self.dir.join(file);
        std::fs::write(&path, text).with_context(|| format!("write {}", path.display()))?;
        Ok(path)
    }

    /// A path in the working directory.
    pub fn path(&self, file: &str) -> PathBuf {
        self.dir.join(file)
    }

    /// Starts motiond on `config`.
    pub fn server(&self, config: &Path) -> anyhow::Result<Server> {
        Ok(Server::spawn(&self.motiond, config)?)
    }

    /// config/sim.toml under the instance name `name`, with extra `[server]` keys.
    pub fn sim_toml(&self, name: &str, server_keys: &str) -> anyhow::Result<String> {
        let text = std::fs::read_to_string(&self.sim_config)?;
        let Some(at) = text.find("name = \"demo\"") else {
            bail!("{}: no `name = \"demo\"`", self.sim_config.display());
        };
        let mut out = text.clone();
        out.replace_range(
            at..at + "name = \"demo\"".len(),
            &format!("name = \"{name}\"\n{server_keys}"),
        );
        Ok(out)
    }

    /// Every file of the isolated iceoryx2 root: node and service records under the root,
    /// shared-memory segments with the run's prefix in /dev/shm — except iceoryx2's one
    /// global management segment (`…node.<version>.global_mgmt`), made once per root and
    /// kept by design.
    pub fn iox_files(&self) -> usize {
        self.iox_listing().len()
    }

    /// Node records in the isolated root (one directory per node, live or dead).
    pub fn iox_nodes(&self) -> usize {
        std::fs::read_dir(self.iox_root.join("nodes"))
            .map(|entries| {
                entries
                    .filter_map(Result::ok)
                    .filter(|e| e.path().is_dir())
                    .count()
            })
            .unwrap_or(0)
    }

    /// Removes the run's iceoryx2 root: its shared-memory segments in /dev/shm (the global
    /// management segment among them: the prefix is this run's alone) and its directory.
    pub fn remove_iox_root(&self) {
        if let Ok(entries) = std::fs::read_dir("/dev/shm") {
            for entry in entries.filter_map(Result::ok) {
                if entry
                    .file_name()
                    .to_string_lossy()
                    .starts_with(&self.shm_prefix)
                {
                    let _ = std::fs::remove_file(entry.path());
                }
            }
        }
        let _ = std::fs::remove_dir_all(&self.iox_root);
    }

    /// The files [`Harness::iox_files`] counts, listed (for a report of leftovers).
    pub fn iox_listing(&self) -> Vec<String> {
        let mut names = Vec::new();
        if let Ok(entries) = std::fs::read_dir("/dev/shm") {
            for entry in entries.filter_map(Result::ok) {
                let name = entry.file_name().to_string_lossy().into_owned();
                if name.starts_with(&self.shm_prefix) && !name.ends_with(".global_mgmt") {
                    names.push(format!("/dev/shm/{name}"));
                }
            }
        }
        list_files(&self.iox_root, &mut names);
        names.sort();
        names
    }

    /// Checks "server alive" in `row`: the server still runs, and exits with 0 on the
    /// SIGTERM this sends it.
    pub fn check_alive_and_stop(&self, row: &mut crate::report::Row, server: &mut Server) {
        let alive = server.is_running();
        let code = server.signal_and_wait(Signal::SIGTERM, Duration::from_secs(10));
        row.check(
            "server alive",
            alive && code == Some(0),
            format!("alive {alive}, exit {code:?}"),
        );
    }

    /// After the server exited with `code` and every client was dropped: waits 200 ms for
    /// the last files to go, then checks "clean exit, 0 stale files" in `row`.
    pub fn check_clean_exit(&self, row: &mut crate::report::Row, code: Option<i32>) {
        std::thread::sleep(Duration::from_millis(200));
        let files = self.iox_files();
        row.check(
            "clean exit, 0 stale files",
            code == Some(0) && files == 0,
            format!(
                "exit {code:?}, {files} iceoryx2 files left: {:?}",
                self.iox_listing()
            ),
        );
    }
}

fn list_files(dir: &Path, out: &mut Vec<String>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.filter_map(Result::ok) {
        let path = entry.path();
        if path.is_dir() {
            list_files(&path, out);
        } else {
            out.push(path.display().to_string());
        }
    }
}

/// A distribution of values (ns, ticks, …), kept whole: quantiles are exact.
#[derive(Debug, Clone, Default)]
pub struct Samples(Vec<f64>);

impl Samples {
    /// Adds a value.
    pub fn push(&mut self, value: f64) {
        self.0.push(value);
    }

    /// How many values.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether there is none.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The `q` quantile (nearest rank), NaN when empty.
    pub fn quantile(&self, q: f64) -> f64 {
        if self.0.is_empty() {
            return f64::NAN;
        }
        let mut sorted = self.0.clone();
        sorted.sort_by(f64::total_cmp);
        let rank = (q * sorted.len() as f64).ceil() as usize;
        sorted[rank.clamp(1, sorted.len()) - 1]
    }

    /// The largest value, NaN when empty.
    pub fn max(&self) -> f64 {
        self.0.iter().copied().fold(f64::NAN, f64::max)
    }

    /// `p50 a / p99 b / max c` with `unit` after each value scaled by `scale`.
    pub fn p50_p99_max(&self, scale: f64, unit: &str) -> String {
        format!(
            "p50 {:.1} / p99 {:.1} / max {:.1} {unit}",
            self.quantile(0.5) * scale,
            self.quantile(0.99) * scale,
            self.max() * scale
        )
    }
}

/// Reads every frame of an instance on a thread of its own and keeps, per tick, the
/// server's latency from the tick's deadline to the frame's send (`publish_ns − time_ns`:
/// wake-up plus work; frames carry no separate wake-up stamp) and any `extra` figures.
#[derive(Debug)]
pub struct TickMeter {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    shared: Arc<Mutex<MeterData>>,
}

/// What a [`TickMeter`] collected since the last [`TickMeter::take`].
#[derive(Debug, Default)]
pub struct MeterData {
    /// Deadline → frame sent, ns, one per tick seen.
    pub latency: Samples,
    /// Ticks missing between frames seen (skipped by the server, or dropped for us).
    pub gaps: u64,
    /// Frames seen.
    pub frames: u64,
    /// Per axis: `tick − last_refresh_tick` of each frame seen.
    pub refresh_age: Vec<Samples>,
    /// The newest frame.
    pub last: Option<Box<MotionFrame>>,
}

impl TickMeter {
    /// Starts reading `name`'s frames (waits up to 10 s for the service).
    pub fn start(name: &str) -> anyhow::Result<Self> {
        let stop = Arc::new(AtomicBool::new(false));
        let shared = Arc::new(Mutex::new(MeterData::default()));
        let (ready_tx, ready_rx) = std::sync::mpsc::channel();
        let thread = {
            let (stop, shared, name) = (Arc::clone(&stop), Arc::clone(&shared), name.to_owned());
            std::thread::Builder::new()
                .name("tick-meter".to_owned())
                .spawn(move || {
                    let node = match NodeBuilder::new().create::<ipc::Service>() {
                        Ok(node) => node,
                        Err(e) => {
                            let _ = ready_tx.send(Err(format!("{e:?}")));
                            return;
                        }
                    };
                    let subscriber = match motion_testkit::client::try_open_frames(
                        &node,
                        &name,
                        Duration::from_secs(10),
                    ) {
                        Ok(s) => s,
                        Err(e) => {
                            let _ = ready_tx.send(Err(e.to_string()));
                            return;
                        }
                    };
                    let _ = ready_tx.send(Ok(()));
                    meter_loop(&subscriber, &stop, &shared);
                })?
        };
        match ready_rx.recv_timeout(Duration::from_secs(15)) {
            Ok(Ok(())) => {}
            Ok(Err(e)) => bail!("tick meter: {e}"),
            Err(_) => bail!("tick meter: no frame service within 15 s"),
        }
        Ok(Self {
            stop,
            thread: Some(thread),
            shared,
        })
    }

    /// Takes what was collected so far (the next window starts empty).
    pub fn take(&self) -> MeterData {
        self.shared
            .lock()
            .map(|mut data| {
                let last = data.last.clone();
                let taken = core::mem::take(&mut *data);
                data.last = last;
                taken
            })
            .unwrap_or_default()
    }
}

impl Drop for TickMeter {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

fn meter_loop(
    subscriber: &motion_testkit::client::FrameSubscriber,
    stop: &AtomicBool,
    shared: &Mutex<MeterData>,
) {
    let mut last_tick: Option<u64> = None;
    while !stop.load(Ordering::Relaxed) {
        let mut batch: Vec<MotionFrame> = Vec::new();
        while let Ok(Some(sample)) = subscriber.receive() {
            batch.push(*sample);
        }
        if !batch.is_empty()
            && let Ok(mut data) = shared.lock()
        {
            for frame in &batch {
                // (A restarted server counts from 0 again: no gap.)
                if let Some(previous) = last_tick
                    && frame.tick > previous + 1
                {
                    data.gaps += frame.tick - previous - 1;
                }
                last_tick = Some(frame.tick);
                data.frames += 1;
                data.latency
                    .push(frame.publish_ns.saturating_sub(frame.time_ns) as f64);
                let axes = frame.axes();
                if data.refresh_age.len() < axes.len() {
                    data.refresh_age.resize(axes.len(), Samples::default());
                }
                for (index, axis) in axes.iter().enumerate() {
                    data.refresh_age[index]
                        .push(frame.tick.saturating_sub(axis.last_refresh_tick) as f64);
                }
            }
            if let Some(frame) = batch.last() {
                data.last = Some(Box::new(*frame));
            }
        }
        std::thread::sleep(Duration::from_millis(2));
    }
}

/// The newest [`ServerStats`] of `name` (waits up to `timeout`).
pub fn server_stats(
    node: &Node<ipc::Service>,
    name: &str,
    timeout: Duration,
) -> anyhow::Result<ServerStats> {
    let service: ServiceName = ServiceNames::new(name)
        .stats()
        .as_str()
        .try_into()
        .map_err(|e| anyhow::anyhow!("{e:?}"))?;
    let subscriber = node
        .service_builder(&service)
        .publish_subscribe::<ServerStats>()
        .open()
        .map_err(|e| anyhow::anyhow!("stats service: {e:?}"))?
        .subscriber_builder()
        .create()
        .map_err(|e| anyhow::anyhow!("stats subscriber: {e:?}"))?;
    let end = std::time::Instant::now() + timeout;
    loop {
        let mut latest = None;
        while let Ok(Some(sample)) = subscriber.receive() {
            latest = Some(*sample);
        }
        if let Some(stats) = latest {
            return Ok(stats);
        }
        if std::time::Instant::now() > end {
            bail!("no stats from `{name}` within {timeout:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Resident memory (KiB), threads and open fds of a process.
#[derive(Debug, Clone, Copy, Default)]
pub struct ProcessUse {
    /// VmRSS, KiB.
    pub rss_kib: u64,
    /// Threads.
    pub threads: u64,
    /// Open file descriptors.
    pub fds: u64,
}

/// Reads /proc/<pid>.
pub fn process_use(pid: u32) -> Option<ProcessUse> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let field = |key: &str| {
        status
            .lines()
            .find(|l| l.starts_with(key))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|v| v.parse::<u64>().ok())
    };
    let fds = std::fs::read_dir(format!("/proc/{pid}/fd")).ok()?.count() as u64;
    Some(ProcessUse {
        rss_kib: field("VmRSS:")?,
        threads: field("Threads:")?,
        fds,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_are_nearest_rank() {
        let mut s = Samples::default();
        assert!(s.quantile(0.5).is_nan());
        for v in 1..=1000 {
            s.push(f64::from(v));
        }
        assert_eq!(s.quantile(0.5), 500.0);
        assert_eq!(s.quantile(0.99), 990.0);
        assert_eq!(s.quantile(0.9999), 1000.0);
        assert_eq!(s.quantile(0.0), 1.0);
        assert_eq!(s.max(), 1000.0);
        assert_eq!(s.p50_p99_max(0.001, "k"), "p50 0.5 / p99 1.0 / max 1.0 k");
    }

    #[test]
    fn process_use_reads_this_process() {
        let me = process_use(std::process::id()).expect("/proc");
        assert!(me.rss_kib > 0 && me.threads >= 1 && me.fds >= 3, "{me:?}");
    }
}
