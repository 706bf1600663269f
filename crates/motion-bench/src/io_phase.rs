//! The I/O phase: a motiond of the bench's own with four idle external links — two ptys (a
//! QSB-M at 230400 baud, a SIXpack at 19200) and two SPI sockets (a QuadQuad2Drv, an
//! SPI_motor stepper), every board simulated by a thread of this bench — measured for
//!
//! 1. its CPU use, % of one core in 500 ms windows (the sum over its threads of
//!    `/proc/<pid>/task/*/schedstat`, the kernel's own count of time on a CPU), beside a
//!    plain iceoryx2 peer ticking at the same rate (publishing a frame, answering requests);
//!    with `--io-before PATH` the same motiond phase runs a second binary (an older build)
//!    for a before/after on the same machine;
//! 2. how long a reply's bytes wait in the tty before motiond's I/O thread reads them: a
//!    thread of the bench watches the QSB pty's input queue (FIONREAD on a descriptor of
//!    its own) and times each stretch from "bytes queued" to "queue empty again"; the
//!    baseline is the same watch on a pty of the same kind whose only reader is a plain
//!    thread blocked in poll(2) then read(2), the least any I/O thread can do;
//! 3. the bare poller's CPU on a fresh set of the same boards, in the same windows, and its
//!    own write latency per board ([`crate::io_poller`]): the baseline that tells the
//!    links' own cost from motiond's.
//!
//! Idle: no axis moves, but the drivers keep their boards polled (the QSB streams its
//! counter every 1.95 ms, the packs are queried in turn, the SPI boards polled each poll
//! period): that traffic is what an idle motiond costs.

use core::time::Duration;
use std::collections::BTreeMap;
use std::os::fd::{AsFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::sync::mpsc::channel;
use std::time::Instant;

use motion_base::Model;
use motion_link::sim::StreamDevice;
use nix::poll::{PollFd, PollFlags, PollTimeout, poll};

use crate::args::PeerMode;
use crate::cpu::{measure_cpu, threads_line};
use crate::dist::Dist;
use crate::io_links::{DEVICES, Links, config_text};
use crate::io_poller::PollerRun;
use crate::peer::Peer;
use crate::poller_boards::{PACK_BAUD, SPIM_ADDRESS};
use crate::pty::{PtyBoard, Wire, queued};
use crate::report::{Row, Unit, write_dist};
use crate::rt::now_ns;
use crate::sim_boards::{serial_board, spi_board};
use crate::spi_board::SpiBoard;
use crate::sweep::{Server, ServerRt, last_line};
use crate::wire::WireRun;

/// What one motiond run measured.
#[derive(Debug)]
pub struct CpuRun {
    /// The binary.
    pub binary: PathBuf,
    /// % of one core per window, in hundredths of a percent.
    pub cpu: Dist,
    /// Mean % of one core per thread name over the whole window.
    pub threads: BTreeMap<String, f64>,
    /// How long until every device was online.
    pub online_after: Duration,
}

/// What the phase measured.
#[derive(Debug)]
pub struct IoRun {
    /// This build's motiond.
    pub ours: CpuRun,
    /// The `--io-before` binary, if given.
    pub before: Option<Result<CpuRun, String>>,
    /// The plain peer's CPU, same windows.
    pub peer: Dist,
    /// The bare poller's CPU, same windows, and its own write latency.
    pub poller: Result<PollerRun, String>,
    /// Bytes queued at the QSB pty → queue empty again (motiond's I/O thread read them), ns.
    pub reply: Dist,
    /// The same on a pty read by a plain poll(2) + read(2) thread, ns.
    pub reply_baseline: Dist,
    /// The real-time keys motiond and the plain peer ran with.
    pub rt: ServerRt,
}

/// The four simulated boards.
struct Boards {
    qsb: PtyBoard,
    pack: PtyBoard,
    quad: SpiBoard,
    spim: SpiBoard,
}

impl Boards {
    fn start(links: &Links) -> Result<Self, String> {
        // Nobody listens for their command lines here.
        let (qsb_lines, _) = channel();
        let (pack_lines, _) = channel();
        Ok(Self {
            qsb: PtyBoard::start(&links.qsb, b"\x00", qsb_lines)?,
            pack: PtyBoard::start_with(
                &links.pack,
                serial_board(Model::TMCPACK)?,
                Wire::uart(PACK_BAUD),
                b"\x00",
                pack_lines,
            )?,
            quad: SpiBoard::start(&links.quad, spi_board(Model::QQ2DRV, None, None)?)?,
            spim: SpiBoard::start(
                &links.spim,
                spi_board(Model::SPIMOTOR, Some(SPIM_ADDRESS), Some("stepper"))?,
            )?,
        })
    }

    fn stop(&mut self) {
        self.qsb.stop();
        self.pack.stop();
        self.quad.stop();
        self.spim.stop();
    }
}

/// Waits until the log says every device is online.
fn wait_online(server: &mut Server, log: &Path) -> Result<Duration, String> {
    let started = Instant::now();
    loop {
        if let Some(status) = server.child.try_wait().map_err(|e| e.to_string())? {
            return Err(format!("motiond exited ({status}): {}", last_line(log)));
        }
        let text = std::fs::read_to_string(log).unwrap_or_default();
        if DEVICES
            .iter()
            .all(|device| text.contains(&format!("device `{device}` online")))
        {
            return Ok(started.elapsed());
        }
        if started.elapsed() > Duration::from_secs(20) {
            return Err(format!(
                "not every device online after 20 s: {}",
                last_line(log)
            ));
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Times each stretch from "bytes queued in the tty" to "queue empty again" for `duration`
/// (a busy watch: one core, so that the stretch ends are seen within a microsecond).
fn watch_queue(tty: &OwnedFd, duration: Duration) -> Dist {
    let mut dist = Dist::new();
    let end = now_ns() + u64::try_from(duration.as_nanos()).unwrap_or(u64::MAX);
    let mut since: Option<u64> = None;
    loop {
        let now = now_ns();
        if now >= end {
            break;
        }
        let waiting = queued(tty) > 0;
        match (waiting, since) {
            (true, None) => since = Some(now),
            (false, Some(start)) => {
                dist.record(now - start);
                since = None;
            }
            _ => std::hint::spin_loop(),
        }
    }
    dist
}

/// One motiond run of `binary`: start, online, CPU for `duration`, then (when `reply` is
/// given) the reply watch for that long.
fn motiond_run(
    binary: &Path,
    tick_hz: u32,
    rt: ServerRt,
    duration: Duration,
    dir: &Path,
    tag: &str,
    reply: Option<(Duration, &mut Dist)>,
) -> Result<CpuRun, String> {
    let pid = std::process::id();
    let links = Links {
        qsb: dir.join(format!("io-qsb-{tag}-{pid}.tty")),
        pack: dir.join(format!("io-pack-{tag}-{pid}.tty")),
        quad: dir.join(format!("io-quad-{tag}-{pid}.sock")),
        spim: dir.join(format!("io-spim-{tag}-{pid}.sock")),
    };
    let mut boards = Boards::start(&links)?;
    let name = format!("bench-io-{tag}-{pid}");
    let config = dir.join(format!("io-{tag}.toml"));
    let log = dir.join(format!("io-{tag}.log"));
    std::fs::write(&config, config_text(&name, tick_hz, rt, &links))
        .map_err(|e| format!("{}: {e}", config.display()))?;
    let mut server = Server::start(binary, &config, &log)?;
    let outcome = (|| {
        let online_after = wait_online(&mut server, &log)?;
        // Start-up traffic (configuration, start-up stops) settles first.
        std::thread::sleep(Duration::from_secs(1));
        let (cpu, threads) = measure_cpu(server.child.id(), duration);
        if let Some((span, dist)) = reply {
            let tty = boards.qsb.slave()?;
            *dist = watch_queue(&tty, span);
        }
        Ok(CpuRun {
            binary: binary.to_path_buf(),
            cpu,
            threads,
            online_after,
        })
    })();
    server.stop();
    boards.stop();
    outcome
}

/// A board that streams one 20-byte line every 1.95 ms whatever it is told (the QSB's
/// counter stream without the QSB), for the baseline's pty.
#[derive(Debug, Default)]
struct Streamer {
    next: Duration,
}

impl StreamDevice for Streamer {
    fn receive(&mut self, _now: Duration, _bytes: &[u8]) {}
    fn transmit(&mut self, now: Duration, out: &mut [u8]) -> usize {
        const LINE: &[u8] = b"s0E00001234000ABCD!\n";
        if now < self.next || out.len() < LINE.len() {
            return 0;
        }
        self.next = now + Duration::from_micros(1953);
        out[..LINE.len()].copy_from_slice(LINE);
        LINE.len()
    }
    fn next_event(&self, _now: Duration) -> Option<Duration> {
        Some(self.next)
    }
}

/// The baseline of the reply watch: a streaming pty read by a plain poll + read thread (at the
/// priority motiond's I/O threads take with `rt`).
fn reply_baseline(dir: &Path, duration: Duration, rt: ServerRt) -> Result<Dist, String> {
    let link = dir.join(format!("io-baseline-{}.tty", std::process::id()));
    let (lines, _) = channel();
    let mut board = PtyBoard::start_with(
        &link,
        Box::new(Streamer::default()),
        Wire::QSB,
        b"\x00",
        lines,
    )?;
    let reader_fd = board.slave()?;
    let watch_fd = board.slave()?;
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let reader = {
        let stop = std::sync::Arc::clone(&stop);
        std::thread::Builder::new()
            .name("plain-reader".to_owned())
            .spawn(move || {
                // The priority motiond's I/O threads take below its tick's.
                let priority = rt.priority.map(|p| p.saturating_sub(1).max(1));
                let _ = crate::rt::set_up_thread(priority, None);
                let mut buf = [0u8; 256];
                while !stop.load(std::sync::atomic::Ordering::Relaxed) {
                    let mut fds = [PollFd::new(reader_fd.as_fd(), PollFlags::POLLIN)];
                    if poll(&mut fds, PollTimeout::from(100u16)).unwrap_or(0) > 0 {
                        let _ = nix::unistd::read(&reader_fd, &mut buf);
                    }
                }
            })
            .map_err(|e| format!("spawn the plain reader: {e}"))?
    };
    let dist = watch_queue(&watch_fd, duration);
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    let _ = reader.join();
    board.stop();
    Ok(dist)
}

/// Runs the phase: this build's motiond (CPU for `duration`, then the reply watch for half
/// of it), the `before` binary's (CPU), the reply baseline, the plain peer's CPU.
/// The bench's motiond and the plain peer both run with `rt` (the bench's `--rt-priority`,
/// `--cpu`).
pub fn run(
    motiond: &Path,
    before: Option<&Path>,
    tick_hz: u32,
    rt: ServerRt,
    duration: Duration,
    dir: &Path,
) -> Result<IoRun, String> {
    let span = (duration / 2).max(Duration::from_secs(1));
    let mut reply = Dist::new();
    let ours = motiond_run(
        motiond,
        tick_hz,
        rt,
        duration,
        dir,
        "ours",
        Some((span, &mut reply)),
    )?;
    let before =
        before.map(|binary| motiond_run(binary, tick_hz, rt, duration, dir, "before", None));
    let reply_baseline = reply_baseline(dir, span, rt)?;
    let peer = Peer::start(PeerMode::Ticking, tick_hz, rt.priority, rt.cpu)?;
    let (peer_cpu, _) = measure_cpu(peer.pid(), duration);
    peer.stop()?;
    let poller = crate::io_poller::run(tick_hz, rt, duration, span, dir);
    Ok(IoRun {
        ours,
        before,
        peer: peer_cpu,
        poller,
        rt,
        reply,
        reply_baseline,
    })
}

/// The phase's rows (and its distribution files in `out`); notes for what failed. The
/// bare poller's rows set the command → wire rows of `wire` (that phase's run, if it ran)
/// beside its own write latency.
pub fn rows(
    run: &IoRun,
    hz: u32,
    wire: Option<&WireRun>,
    out: Option<&Path>,
    notes: &mut Vec<String>,
) -> Vec<Row> {
    let cpu_label = format!(
        "plain iceoryx2 peer ticking at {hz} Hz (answers requests, publishes a frame-sized \
         sample, notifies the tick event): its CPU in the same windows"
    );
    let mut rows = vec![Row {
        figure: "motiond CPU, four idle external links (QSB and SIXpack on ptys, QuadQuad2Drv \
                 and SPI_motor on SPI sockets), % of one core per 500 ms window"
            .to_owned(),
        unit: Unit::CentiPercent,
        ours: run.ours.cpu.summary(),
        baseline: Some(run.peer.summary()),
        baseline_label: cpu_label.clone(),
        note: format!(
            "{} ({}; online after {:.1} s); per thread over the whole phase: {}",
            run.ours.binary.display(),
            run.rt.describe(),
            run.ours.online_after.as_secs_f64(),
            threads_line(&run.ours.threads)
        ),
    }];
    match &run.before {
        Some(Ok(before)) => rows.push(Row {
            figure: "the same, --io-before binary (an older build)".to_owned(),
            unit: Unit::CentiPercent,
            ours: before.cpu.summary(),
            baseline: Some(run.peer.summary()),
            baseline_label: cpu_label,
            note: format!(
                "{} (online after {:.1} s); per thread: {}",
                before.binary.display(),
                before.online_after.as_secs_f64(),
                threads_line(&before.threads)
            ),
        }),
        Some(Err(e)) => notes.push(format!("--io-before: not measured: {e}")),
        None => {}
    }
    match &run.poller {
        Ok(poller) => rows.extend(crate::io_poller::rows(
            poller,
            &run.ours.cpu,
            &run.peer,
            wire,
            notes,
        )),
        Err(e) => notes.push(format!("the bare poller: not measured this run: {e}")),
    }
    rows.push(Row {
        figure: "reply bytes waiting in the tty until the I/O thread has read them (QSB pty: \
                 its stream lines and answers)"
            .to_owned(),
        unit: Unit::Ns,
        ours: run.reply.summary(),
        baseline: Some(run.reply_baseline.summary()),
        baseline_label: "a pty of the same kind (a line every 1.95 ms, paced at 230400 baud) \
                         read by a plain thread blocked in poll(2), then read(2)"
            .to_owned(),
        note: "a thread of the bench watches the tty's input queue (FIONREAD, busy: it takes \
               one core) and times each stretch from bytes queued to queue empty; the bytes \
               then wait in the receive ring for the next tick, by design"
            .to_owned(),
    });
    for (slug, title, dist) in [
        (
            "io-cpu-motiond",
            "motiond CPU per 500 ms window, 1/100 %",
            &run.ours.cpu,
        ),
        (
            "io-cpu-peer",
            "plain peer CPU per 500 ms window, 1/100 %",
            &run.peer,
        ),
        (
            "io-reply-motiond",
            "bytes queued → read, motiond",
            &run.reply,
        ),
        (
            "io-reply-baseline",
            "bytes queued → read, plain poll + read",
            &run.reply_baseline,
        ),
    ] {
        if let Some(error) = write_dist(out, slug, title, dist) {
            notes.push(format!("could not write {error}"));
        }
    }
    if let Ok(poller) = &run.poller
        && let Some(error) = write_dist(
            out,
            "io-cpu-poller",
            "bare poller CPU per 500 ms window, 1/100 %",
            &poller.cpu,
        )
    {
        notes.push(format!("could not write {error}"));
    }
    rows
}
