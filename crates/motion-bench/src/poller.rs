//! The bare poller: the baseline of the I/O phase's CPU row. A process that performs the
//! same transactions on the same four links as an idle motiond, at the same rates
//! ([`crate::poller_boards`]: the drivers' idle polls and the start-up their answers need),
//! reads every reply back, and publishes a frame-sized sample every tick as the plain peer
//! does ([`crate::peer`]) — nothing else: no engine, no drivers, no decoding beyond what its
//! schedule needs. What motiond costs above it is motiond's own; what it costs above the
//! plain peer is the links'.
//!
//! One thread, the running program re-executed with [`POLLER_FLAG`] (served from
//! [`crate::peer::run_if_requested`], so the cargo bench and motionctl both serve it):
//! poll(2) on the links' descriptors until the next tick's absolute deadline, reading what
//! arrives; at each tick, each board takes what its link delivered and writes what is due,
//! then the frame is published.
//!
//! Protocol with the bench: `ready` once every board's start-up is done; the line
//! [`COMMANDS`] on its stdin starts board commands (each board's message of the command →
//! wire phase, stamped just before its write: the poller's own write latency is that
//! stamp → the first byte at the board); when its stdin closes, `sent <i> <count>` (idle polls
//! after the start-up) and `decided <i> <stamps…>` per board, and it exits.
//!
//! Command line: `PROGRAM --motion-bench-poller NAME HZ QSB PACK QUAD SPIM
//! [--rt-priority N] [--cpu N]` (the four link paths in the I/O phase's order).

use core::time::Duration;
use std::ffi::OsString;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, ExitCode, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use iceoryx2::prelude::{LogLevel, set_log_level_from_env_or};
use motion_link::Link;
use motion_link::serial::{SerialConfig, SerialLink};
use motion_link::spi_socket::{SpiSocketConfig, SpiSocketLink};
use nix::poll::{PollFd, PollFlags};
use nix::sys::time::TimeSpec;

use crate::io_links::Links;
use crate::peer_services::{answer, create, publish, say};
use crate::poller_boards::{Idle, PACK_BAUD};
use crate::pty::BAUD;
use crate::rt::{self, XorShift, now_ns};
use crate::sweep::ServerRt;
use crate::wire_board::WireBoard;

/// The first argument that makes a program the bare poller.
pub const POLLER_FLAG: &str = "--motion-bench-poller";

/// The line on the poller's stdin that starts the board commands.
pub const COMMANDS: &str = "commands";

/// How long the boards' start-up may take.
const STARTUP_LIMIT: Duration = Duration::from_secs(10);

/// The poller's command line after [`POLLER_FLAG`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PollerArgs {
    /// Its instance name (its frame service).
    pub name: String,
    /// Its tick rate.
    pub hz: u32,
    /// The four links.
    pub links: Links,
    /// SCHED_FIFO priority and core of its thread.
    pub rt: ServerRt,
}

impl PollerArgs {
    /// The words after [`POLLER_FLAG`].
    pub fn to_words(&self) -> Vec<OsString> {
        let mut words: Vec<OsString> = vec![self.name.clone().into(), self.hz.to_string().into()];
        for path in [
            &self.links.qsb,
            &self.links.pack,
            &self.links.quad,
            &self.links.spim,
        ] {
            words.push(path.clone().into_os_string());
        }
        if let Some(priority) = self.rt.priority {
            words.extend(["--rt-priority".into(), priority.to_string().into()]);
        }
        if let Some(cpu) = self.rt.cpu {
            words.extend(["--cpu".into(), cpu.to_string().into()]);
        }
        words
    }

    /// Parses [`PollerArgs::to_words`].
    ///
    /// # Errors
    /// The usage, in words.
    pub fn parse(words: &[OsString]) -> Result<Self, String> {
        let usage = || {
            format!("usage: {POLLER_FLAG} NAME HZ QSB PACK QUAD SPIM [--rt-priority N] [--cpu N]")
        };
        let [name, hz, qsb, pack, quad, spim, rest @ ..] = words else {
            return Err(usage());
        };
        let name = name.to_str().filter(|n| !n.is_empty()).ok_or_else(usage)?;
        let hz: u32 = hz
            .to_str()
            .and_then(|h| h.parse().ok())
            .filter(|&h| h > 0)
            .ok_or_else(usage)?;
        let mut args = Self {
            name: name.to_owned(),
            hz,
            links: Links {
                qsb: PathBuf::from(qsb),
                pack: PathBuf::from(pack),
                quad: PathBuf::from(quad),
                spim: PathBuf::from(spim),
            },
            rt: ServerRt::default(),
        };
        let mut rest = rest.iter();
        while let Some(flag) = rest.next() {
            let value = rest.next().and_then(|v| v.to_str()).ok_or_else(usage)?;
            match flag.to_str() {
                Some("--rt-priority") => {
                    args.rt.priority = Some(value.parse().map_err(|_| usage())?);
                }
                Some("--cpu") => args.rt.cpu = Some(value.parse().map_err(|_| usage())?),
                _ => return Err(usage()),
            }
        }
        Ok(args)
    }
}

/// The poller process's `main` on the words after [`POLLER_FLAG`]: its exit status.
pub fn run(words: &[OsString]) -> ExitCode {
    set_log_level_from_env_or(LogLevel::Error);
    let outcome = PollerArgs::parse(words).and_then(|args| serve(&args));
    match outcome {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("latency bench bare poller: {error}");
            ExitCode::FAILURE
        }
    }
}

/// Opens the four links as motiond does (serial at the boards' line rates, SPI sockets).
fn open(links: &Links) -> Result<Vec<Box<dyn Link>>, String> {
    let path = |p: &Path| p.to_string_lossy().into_owned();
    let serial = |p: &Path, baud| {
        SerialLink::open(SerialConfig::new(path(p), baud))
            .map(|link| Box::new(link) as Box<dyn Link>)
            .map_err(|e| e.to_string())
    };
    let spi = |p: &Path| {
        SpiSocketLink::connect(SpiSocketConfig::new(path(p)))
            .map(|link| Box::new(link) as Box<dyn Link>)
            .map_err(|e| e.to_string())
    };
    Ok(vec![
        serial(&links.qsb, BAUD)?,
        serial(&links.pack, PACK_BAUD)?,
        spi(&links.quad)?,
        spi(&links.spim)?,
    ])
}

/// Waits until a link has bytes or `until_ns` passes; the indices of the readable links.
fn wait(links: &[Box<dyn Link>], until_ns: u64) -> [bool; 4] {
    let mut readable = [false; 4];
    let mut fds = Vec::with_capacity(4);
    let mut index_of = Vec::with_capacity(4);
    for (index, link) in links.iter().enumerate() {
        if let Some(fd) = link.poll_fd() {
            fds.push(PollFd::new(fd, PollFlags::POLLIN));
            index_of.push(index);
        }
    }
    let left = until_ns.saturating_sub(now_ns());
    let timeout = TimeSpec::from_duration(Duration::from_nanos(left));
    if nix::poll::ppoll(&mut fds, Some(timeout), None).unwrap_or(0) > 0 {
        for (fd, &index) in fds.iter().zip(&index_of) {
            let ready = fd
                .revents()
                .is_some_and(|r| r.intersects(PollFlags::POLLIN | PollFlags::POLLHUP));
            if let Some(slot) = readable.get_mut(index) {
                *slot = ready;
            }
        }
    }
    readable
}

fn serve(args: &PollerArgs) -> Result<(), String> {
    let services = create(&args.name, false)?;
    let mut links = open(&args.links)?;
    let stop = Arc::new(AtomicBool::new(false));
    let commanding = Arc::new(AtomicBool::new(false));
    {
        let stop = Arc::clone(&stop);
        let commanding = Arc::clone(&commanding);
        std::thread::spawn(move || {
            for line in std::io::stdin().lines() {
                match line.as_deref().map(str::trim) {
                    Ok(COMMANDS) => commanding.store(true, Ordering::Relaxed),
                    Ok(_) => {}
                    Err(_) => break,
                }
            }
            stop.store(true, Ordering::Relaxed);
        });
    }
    let _ = rt::set_up_thread(args.rt.priority, args.rt.cpu);
    let period = 1_000_000_000 / u64::from(args.hz);
    let epoch = now_ns();
    let mut deadline = epoch + period;
    let mut tick = 0u64;
    let mut idle = Idle::new();
    let mut ready = false;
    let mut buf = [0u8; 4096];
    let mut sent = [0u64; 4];
    let mut commands = Commands::new();
    while !stop.load(Ordering::Relaxed) {
        let readable = wait(&links, deadline);
        for (index, link) in links.iter_mut().enumerate() {
            if !readable.get(index).copied().unwrap_or(false) {
                continue;
            }
            loop {
                let len = link
                    .read(Duration::from_nanos(now_ns() - epoch), &mut buf)
                    .map_err(|e| e.to_string())?;
                if len == 0 {
                    break;
                }
                idle.take(index, buf.get(..len).unwrap_or(&[]));
            }
        }
        if now_ns() < deadline {
            continue;
        }
        tick += 1;
        answer(&services, tick);
        let now = Duration::from_nanos(deadline - epoch);
        if commanding.load(Ordering::Relaxed) {
            commands.tick(now, &mut idle, &mut links)?;
        }
        let started = ready;
        idle.tick(now, &mut links, |index, _| {
            if started && let Some(count) = sent.get_mut(index) {
                *count += 1;
            }
        })
        .map_err(|e| e.to_string())?;
        let _ = publish(&services, tick, deadline);
        if !ready && idle.started() {
            ready = true;
            say("ready")?;
        }
        if !ready && Duration::from_nanos(now_ns() - epoch) > STARTUP_LIMIT {
            return Err(format!(
                "the boards' start-up did not finish within {} s",
                STARTUP_LIMIT.as_secs()
            ));
        }
        deadline += period;
        let done = now_ns();
        while deadline <= done {
            deadline += period;
            tick += 1;
        }
    }
    for (index, count) in sent.iter().enumerate() {
        say(&format!("sent {index} {count}"))?;
    }
    for (index, stamps) in commands.decided.iter().enumerate() {
        let words: Vec<String> = stamps.iter().map(u64::to_string).collect();
        say(&format!("decided {index} {}", words.join(" ")))?;
    }
    Ok(())
}

/// Board commands, once the bench asks for them: each board gets its command message of
/// the command → wire phase ([`WireBoard::fallback_message`], alternating signs) in the
/// first tick its line is free after 1 ms + a random part of the board's pace, as the wire
/// phase's client paces motiond's; each stamped (CLOCK_MONOTONIC) just before its write.
struct Commands {
    next_ns: [u64; 4],
    positive: [bool; 4],
    random: XorShift,
    /// Per board: the stamps of the commands written.
    decided: [Vec<u64>; 4],
}

impl Commands {
    fn new() -> Self {
        Self {
            next_ns: [0; 4],
            positive: [true; 4],
            random: XorShift::new(u64::from(std::process::id()) ^ now_ns()),
            decided: core::array::from_fn(|_| Vec::with_capacity(8192)),
        }
    }

    fn tick(
        &mut self,
        now: Duration,
        idle: &mut Idle,
        links: &mut [Box<dyn Link>],
    ) -> Result<(), String> {
        for (index, (board, link)) in WireBoard::ALL.into_iter().zip(links.iter_mut()).enumerate() {
            let (Some(next), Some(positive), Some(decided)) = (
                self.next_ns.get_mut(index),
                self.positive.get_mut(index),
                self.decided.get_mut(index),
            ) else {
                continue;
            };
            if now_ns() < *next {
                continue;
            }
            let message = board.on_the_wire(&board.fallback_message(*positive));
            let stamp = now_ns();
            if idle
                .command(index, now, link.as_mut(), &message)
                .map_err(|e| e.to_string())?
            {
                decided.push(stamp);
                *positive = !*positive;
                *next = stamp + 1_000_000 + self.random.below(board.pace_ns());
            }
        }
        Ok(())
    }
}

/// A running bare poller.
#[derive(Debug)]
pub struct Poller {
    child: Child,
    stdin: Option<ChildStdin>,
    stdout: BufReader<ChildStdout>,
}

/// What the poller reports when it stops.
#[derive(Debug, Clone, Default)]
pub struct PollerFigures {
    /// Per board: idle polls written after the start-up (board commands not counted).
    pub sent: [u64; 4],
    /// Per board: the instants (CLOCK_MONOTONIC, ns) at which its board commands were
    /// decided, in order ([`Poller::start_commands`]).
    pub decided: [Vec<u64>; 4],
}

impl Poller {
    /// Starts the poller at `hz` on `links` (boards already served there) and waits until
    /// every board's start-up is done.
    ///
    /// # Errors
    /// The program could not be started, or said something else than `ready`.
    pub fn start(hz: u32, rt: ServerRt, links: &Links) -> Result<Self, String> {
        let exe = std::env::current_exe().map_err(|e| format!("own executable: {e}"))?;
        let args = PollerArgs {
            name: format!(
                "bench-poller-{}-{}",
                std::process::id(),
                now_ns() % 1_000_000
            ),
            hz,
            links: links.clone(),
            rt,
        };
        let mut child = Command::new(exe)
            .arg(POLLER_FLAG)
            .args(args.to_words())
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .map_err(|e| format!("start the bare poller: {e}"))?;
        let stdin = child.stdin.take();
        let stdout = child
            .stdout
            .take()
            .ok_or_else(|| "bare poller: no stdout".to_owned())?;
        let mut poller = Self {
            child,
            stdin,
            stdout: BufReader::new(stdout),
        };
        let mut line = String::new();
        let _ = poller.stdout.read_line(&mut line);
        if line.trim() != "ready" {
            let _ = poller.child.kill();
            let _ = poller.child.wait();
            return Err(format!(
                "the bare poller did not start (said {:?})",
                line.trim()
            ));
        }
        Ok(poller)
    }

    /// Its process id.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// From now on the poller also sends each board its command message.
    ///
    /// # Errors
    /// Its stdin is closed.
    pub fn start_commands(&mut self) -> Result<(), String> {
        let stdin = self
            .stdin
            .as_mut()
            .ok_or_else(|| "bare poller: stdin closed".to_owned())?;
        writeln!(stdin, "{COMMANDS}")
            .and_then(|()| stdin.flush())
            .map_err(|e| format!("bare poller: {e}"))
    }

    /// Stops it and collects its figures.
    ///
    /// # Errors
    /// It failed.
    pub fn stop(mut self) -> Result<PollerFigures, String> {
        drop(self.stdin.take());
        let mut text = String::new();
        let _ = self.stdout.read_to_string(&mut text);
        let status = self.child.wait().map_err(|e| format!("bare poller: {e}"))?;
        if !status.success() {
            return Err(format!("the bare poller failed: {status}"));
        }
        let mut figures = PollerFigures::default();
        for line in text.lines() {
            let mut words = line.splitn(3, ' ');
            let (Some(kind), Some(index), Some(rest)) = (words.next(), words.next(), words.next())
            else {
                continue;
            };
            let Some(index) = index.parse::<usize>().ok().filter(|&i| i < 4) else {
                continue;
            };
            match kind {
                "sent" => figures.sent[index] = rest.trim().parse().unwrap_or(0),
                "decided" => {
                    figures.decided[index] = rest
                        .split_whitespace()
                        .filter_map(|w| w.parse().ok())
                        .collect();
                }
                _ => {}
            }
        }
        Ok(figures)
    }
}

impl Drop for Poller {
    fn drop(&mut self) {
        if self.stdin.is_some() {
            drop(self.stdin.take());
            let _ = self.child.wait();
        }
    }
}

#[cfg(test)]
mod tests {
    use std::ffi::OsString;

    use super::PollerArgs;
    use crate::io_links::Links;
    use crate::sweep::ServerRt;

    #[test]
    fn the_command_line_round_trips_and_refuses_garbage() {
        let args = PollerArgs {
            name: "bench-poller-1".to_owned(),
            hz: 1000,
            links: Links {
                qsb: "/tmp/q.tty".into(),
                pack: "/tmp/p.tty".into(),
                quad: "/tmp/q.sock".into(),
                spim: "/tmp/s.sock".into(),
            },
            rt: ServerRt {
                priority: Some(80),
                cpu: Some(1),
            },
        };
        assert_eq!(PollerArgs::parse(&args.to_words()), Ok(args.clone()));
        let words = |list: &[&str]| list.iter().map(OsString::from).collect::<Vec<_>>();
        for bad in [
            words(&["n", "1000", "a", "b", "c"]),
            words(&["n", "0", "a", "b", "c", "d"]),
            words(&["", "1000", "a", "b", "c", "d"]),
            words(&["n", "1000", "a", "b", "c", "d", "--cpu"]),
            words(&["n", "1000", "a", "b", "c", "d", "--nice", "3"]),
        ] {
            assert!(PollerArgs::parse(&bad).is_err(), "{bad:?}");
        }
    }
}
