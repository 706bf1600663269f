//! The baseline peer: the running program re-executed with [`PEER_FLAG`], a plain process that
//! does with iceoryx2 what motiond does, minus everything motiond adds (engine, links,
//! drivers): its own services with motiond's settings, an absolute-deadline tick at the
//! same rate, requests answered at the start of each tick, a frame-sized sample published
//! and the tick event notified. `busy-rr` mode answers requests as fast as it can instead;
//! `streaming` also drains a `setpoints` service at the start of each tick and counts the
//! setpoints that came in time for it.
//!
//! Protocol with the bench: the peer prints `ready` once its services exist, runs until
//! its stdin closes, then prints `wakeup <summary>`, `work <summary>` and `setpoints
//! <in time> <late>` and exits.
//!
//! Its command line: `PROGRAM --motion-bench-peer MODE NAME HZ [--rt-priority N] [--cpu N]`.
//! Any program that runs the bench calls [`run_if_requested`] before parsing its own
//! arguments, so the cargo bench and motionctl both serve as their own peer.

use std::ffi::OsString;
use std::io::{BufRead, BufReader, Read};
use std::process::{Child, ChildStdin, ChildStdout, Command, ExitCode, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use iceoryx2::prelude::*;
use motion_ipc::{CommandReply, Reason, ServiceNames};

use crate::args::PeerMode;
use crate::dist::{Dist, Summary};
use crate::peer_services::{PeerServices, answer, create, publish, say};
use crate::rt::{self, now_ns, sleep_until_ns};

/// The first argument that makes a program the baseline peer.
pub const PEER_FLAG: &str = "--motion-bench-peer";

/// When this process was started as a baseline peer (its first argument is [`PEER_FLAG`])
/// or as the bare poller ([`crate::poller::POLLER_FLAG`]), serves as one and returns its
/// exit status; `None` otherwise. Call it first in `main`.
pub fn run_if_requested() -> Option<ExitCode> {
    let args: Vec<OsString> = std::env::args_os().skip(1).collect();
    if args.first().and_then(|a| a.to_str()) == Some(crate::poller::POLLER_FLAG) {
        return Some(crate::poller::run(args.get(1..).unwrap_or(&[])));
    }
    if args.first().and_then(|a| a.to_str()) != Some(PEER_FLAG) {
        return None;
    }
    let words: Vec<String> = args
        .iter()
        .skip(1)
        .map(|a| a.to_string_lossy().into_owned())
        .collect();
    set_log_level_from_env_or(LogLevel::Error);
    Some(ExitCode::from(match PeerArgs::parse(&words) {
        Ok(peer) => run(peer.mode, &peer.name, peer.hz, peer.rt_priority, peer.cpu),
        Err(error) => {
            eprintln!("latency bench peer: {error}");
            2
        }
    }))
}

/// The peer's command line after [`PEER_FLAG`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PeerArgs {
    /// What it does.
    pub mode: PeerMode,
    /// Its instance name.
    pub name: String,
    /// Its tick rate.
    pub hz: u32,
    /// SCHED_FIFO priority of its tick thread.
    pub rt_priority: Option<u8>,
    /// Core of its tick thread.
    pub cpu: Option<usize>,
}

impl PeerArgs {
    /// The words after [`PEER_FLAG`].
    pub fn to_words(&self) -> Vec<String> {
        let mut words = vec![
            self.mode.word().to_owned(),
            self.name.clone(),
            self.hz.to_string(),
        ];
        if let Some(priority) = self.rt_priority {
            words.extend(["--rt-priority".to_owned(), priority.to_string()]);
        }
        if let Some(cpu) = self.cpu {
            words.extend(["--cpu".to_owned(), cpu.to_string()]);
        }
        words
    }

    /// Parses [`PeerArgs::to_words`].
    pub fn parse(words: &[String]) -> Result<Self, String> {
        let usage = || {
            format!(
                "usage: {PEER_FLAG} ticking|busy-rr|streaming NAME HZ [--rt-priority N] [--cpu N]"
            )
        };
        let [mode, name, hz, rest @ ..] = words else {
            return Err(usage());
        };
        let mode = PeerMode::from_word(mode).ok_or_else(usage)?;
        let hz: u32 = hz.parse().map_err(|_| usage())?;
        if name.is_empty() || hz == 0 {
            return Err(usage());
        }
        let mut peer = Self {
            mode,
            name: name.clone(),
            hz,
            rt_priority: None,
            cpu: None,
        };
        let mut rest = rest.iter();
        while let Some(flag) = rest.next() {
            let value = rest.next().ok_or_else(usage)?;
            match flag.as_str() {
                "--rt-priority" => {
                    peer.rt_priority = Some(value.parse().map_err(|_| usage())?);
                }
                "--cpu" => peer.cpu = Some(value.parse().map_err(|_| usage())?),
                _ => return Err(usage()),
            }
        }
        Ok(peer)
    }
}

/// A running peer process.
#[derive(Debug)]
pub struct Peer {
    child: Child,
    stdin: Option<ChildStdin>,
    stdout: BufReader<ChildStdout>,
    /// Its services.
    pub names: ServiceNames,
}

/// The peer's own tick figures, reported when it stops.
#[derive(Debug, Clone, Copy, Default)]
pub struct PeerFigures {
    /// Wake-up latency of its tick.
    pub wakeup: Summary,
    /// Its per-tick work (answer requests, loan, write 8 KiB, send, notify).
    pub work: Summary,
    /// `streaming`: setpoints taken in the tick they were for (or earlier).
    pub setpoints_in_time: u64,
    /// `streaming`: setpoints taken after the tick they were for.
    pub setpoints_late: u64,
    /// `streaming`: frame `k` published → the setpoint for `k + 1` taken from the service
    /// (the peer's own stamp, as motiond's `GroupState::last_received_ns`), ns.
    pub received: Summary,
}

impl Peer {
    /// Starts `mode` at `hz` under a fresh instance name and waits until it serves.
    pub fn start(
        mode: PeerMode,
        hz: u32,
        rt_priority: Option<u8>,
        cpu: Option<usize>,
    ) -> Result<Self, String> {
        let exe = std::env::current_exe().map_err(|e| format!("own executable: {e}"))?;
        let name = format!("bench-peer-{}-{}", std::process::id(), now_ns() % 1_000_000);
        let words = PeerArgs {
            mode,
            name: name.clone(),
            hz,
            rt_priority,
            cpu,
        }
        .to_words();
        let mut child = Command::new(exe)
            .arg(PEER_FLAG)
            .args(words)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .map_err(|e| format!("start the baseline peer: {e}"))?;
        let stdin = child.stdin.take();
        let stdout = child
            .stdout
            .take()
            .ok_or_else(|| "baseline peer: no stdout".to_owned())?;
        let mut peer = Self {
            child,
            stdin,
            stdout: BufReader::new(stdout),
            names: ServiceNames::new(&name),
        };
        let mut line = String::new();
        let _ = peer.stdout.read_line(&mut line);
        if line.trim() != "ready" {
            let _ = peer.child.kill();
            let _ = peer.child.wait();
            return Err(format!(
                "the baseline peer did not start (said {:?})",
                line.trim()
            ));
        }
        Ok(peer)
    }

    /// The peer's process id.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// Stops the peer and collects its figures.
    pub fn stop(mut self) -> Result<PeerFigures, String> {
        drop(self.stdin.take());
        let mut text = String::new();
        let _ = self.stdout.read_to_string(&mut text);
        let status = self
            .child
            .wait()
            .map_err(|e| format!("baseline peer: {e}"))?;
        if !status.success() {
            return Err(format!("the baseline peer failed: {status}"));
        }
        let mut figures = PeerFigures::default();
        for line in text.lines() {
            if let Some(rest) = line.strip_prefix("wakeup ") {
                figures.wakeup = Summary::from_line(rest).unwrap_or_default();
            } else if let Some(rest) = line.strip_prefix("work ") {
                figures.work = Summary::from_line(rest).unwrap_or_default();
            } else if let Some(rest) = line.strip_prefix("received ") {
                figures.received = Summary::from_line(rest).unwrap_or_default();
            } else if let Some(rest) = line.strip_prefix("setpoints ") {
                let mut counts = rest.split_whitespace().map(|w| w.parse().unwrap_or(0));
                figures.setpoints_in_time = counts.next().unwrap_or(0);
                figures.setpoints_late = counts.next().unwrap_or(0);
            }
        }
        Ok(figures)
    }
}

impl Drop for Peer {
    fn drop(&mut self) {
        if self.stdin.is_some() {
            drop(self.stdin.take());
            let _ = self.child.wait();
        }
    }
}

/// The peer process's `main`: returns the exit status.
pub fn run(mode: PeerMode, name: &str, hz: u32, rt_priority: Option<u8>, cpu: Option<usize>) -> u8 {
    match serve(mode, name, hz, rt_priority, cpu) {
        Ok(()) => 0,
        Err(error) => {
            eprintln!("latency bench peer: {error}");
            1
        }
    }
}

fn serve(
    mode: PeerMode,
    name: &str,
    hz: u32,
    rt_priority: Option<u8>,
    cpu: Option<usize>,
) -> Result<(), String> {
    if name.is_empty() || hz == 0 {
        return Err("the peer needs a name and a tick rate above 0".to_owned());
    }
    let services = create(name, mode == PeerMode::Streaming)?;
    let stop = Arc::new(AtomicBool::new(false));
    let watcher = Arc::clone(&stop);
    std::thread::spawn(move || {
        let mut sink = Vec::new();
        let _ = std::io::stdin().read_to_end(&mut sink);
        watcher.store(true, Ordering::Relaxed);
    });
    let mut wakeup = Dist::new();
    let mut work = Dist::new();
    let mut setpoints = (0, 0);
    let mut received = Dist::new();
    match mode {
        PeerMode::Ticking | PeerMode::Streaming => {
            let _ = rt::set_up_thread(rt_priority, cpu);
            say("ready")?;
            let mut figures = TickFigures {
                wakeup: &mut wakeup,
                work: &mut work,
                setpoints: &mut setpoints,
                received: &mut received,
            };
            tick_loop(&services, hz, &stop, &mut figures)?;
        }
        PeerMode::BusyRr => {
            say("ready")?;
            busy_loop(&services, &stop)?;
        }
    }
    say(&format!("wakeup {}", wakeup.summary().to_line()))?;
    say(&format!("work {}", work.summary().to_line()))?;
    say(&format!("received {}", received.summary().to_line()))?;
    say(&format!("setpoints {} {}", setpoints.0, setpoints.1))
}

struct TickFigures<'a> {
    wakeup: &'a mut Dist,
    work: &'a mut Dist,
    /// Setpoints taken in (or before) their tick, and after it.
    setpoints: &'a mut (u64, u64),
    /// Frame `k` published → the setpoint for `k + 1` taken.
    received: &'a mut Dist,
}

/// Publish stamps of the peer's last frames, by tick modulo this.
const PUBLISHED: usize = 64;

fn tick_loop(
    services: &PeerServices,
    hz: u32,
    stop: &AtomicBool,
    figures: &mut TickFigures<'_>,
) -> Result<(), String> {
    let period = 1_000_000_000 / u64::from(hz);
    let mut deadline = now_ns() + period;
    let mut tick = 0u64;
    let mut published = [(u64::MAX, 0u64); PUBLISHED];
    while !stop.load(Ordering::Relaxed) {
        sleep_until_ns(deadline);
        let wake = now_ns();
        figures.wakeup.record(wake.saturating_sub(deadline));
        tick += 1;
        answer(services, tick);
        if let Some(setpoints) = &services.setpoints {
            while let Ok(Some(sample)) = setpoints.receive() {
                let taken = now_ns();
                let answered = sample.payload().for_tick.wrapping_sub(1);
                let (at, publish_ns) = published[answered as usize % PUBLISHED];
                if at == answered {
                    figures.received.record(taken.saturating_sub(publish_ns));
                }
                if sample.payload().for_tick >= tick {
                    figures.setpoints.0 += 1;
                } else {
                    figures.setpoints.1 += 1;
                }
            }
        }
        if let Some(publish_ns) = publish(services, tick, deadline) {
            published[tick as usize % PUBLISHED] = (tick, publish_ns);
        }
        let done = now_ns();
        figures.work.record(done.saturating_sub(wake));
        deadline += period;
        while deadline <= done {
            deadline += period;
            tick += 1;
        }
    }
    Ok(())
}

fn busy_loop(services: &PeerServices, stop: &AtomicBool) -> Result<(), String> {
    let mut spins = 0u32;
    while !(spins.is_multiple_of(4096) && stop.load(Ordering::Relaxed)) {
        spins = spins.wrapping_add(1);
        match services.command.receive() {
            Ok(Some(active)) => {
                let reply = CommandReply::to(active.payload(), Reason::UnknownAxis, 0);
                let _ = active.send_copy(reply);
            }
            Ok(None) => std::hint::spin_loop(),
            Err(e) => return Err(format!("receive a request: {e:?}")),
        }
    }
    Ok(())
}
