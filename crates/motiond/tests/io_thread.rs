//! The I/O thread sleeps on its link's descriptor and the tick's eventfd: bytes that arrive,
//! output the tick queued, a hang-up and a simulated link's next event each wake it, with
//! no poll period behind them. Every thread here is spawned with an idle limit of an hour,
//! so anything that only a timer would have noticed never arrives within the test's
//! patience (correctness, not timing: the patience is generous).

use core::time::Duration;
use std::os::fd::{AsFd, OwnedFd};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

use motion_link::Link;
use motion_link::serial::{SerialConfig, SerialLink};
use motion_link::sim::{SimLink, StreamDevice};
use motiond::io::{self, IoThread, LinkEvent, LinkPort, Packet};
use nix::poll::{PollFd, PollFlags, PollTimeout, poll};

/// Far longer than any test waits: only a wake-up on readiness can deliver in time.
const NEVER: Duration = Duration::from_secs(3600);
/// How long a test waits for something that should come at once.
const PATIENCE: Duration = Duration::from_secs(10);

fn start(link: Box<dyn Link>) -> (LinkPort, IoThread, Arc<AtomicBool>) {
    start_named("test", link, None, None)
}

/// An I/O thread `io-<name>` asked for `rt_priority` and `cpu`, once it has opened its
/// link (bytes written to a pty before that are the tty's to discard).
fn start_named(
    name: &str,
    link: Box<dyn Link>,
    rt_priority: Option<u8>,
    cpu: Option<usize>,
) -> (LinkPort, IoThread, Arc<AtomicBool>) {
    let (mut port, thread, stop) = spawn_closed(name, link, rt_priority, cpu);
    assert_eq!(
        events(&mut port, 1),
        [LinkEvent::Up],
        "the thread opens its link"
    );
    (port, thread, stop)
}

/// An I/O thread, without waiting for anything.
fn spawn_closed(
    name: &str,
    link: Box<dyn Link>,
    rt_priority: Option<u8>,
    cpu: Option<usize>,
) -> (LinkPort, IoThread, Arc<AtomicBool>) {
    let stop = Arc::new(AtomicBool::new(false));
    let options = io::IoThreadOptions {
        epoch: motiond::rt::monotonic_now(),
        idle: NEVER,
        rt_priority,
        cpu,
    };
    let (port, thread) = io::spawn(name, link, options, Arc::clone(&stop)).expect("spawn");
    (port, thread, stop)
}

/// Stops the thread and checks it finishes (woken, not after its idle limit).
fn finish(thread: IoThread, stop: &AtomicBool) {
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    let (done_tx, done_rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        thread.join();
        let _ = done_tx.send(());
    });
    done_rx
        .recv_timeout(PATIENCE)
        .expect("the I/O thread did not stop when told to");
}

/// Everything the thread received until `want` bytes arrived or patience ran out.
fn receive(port: &mut LinkPort, want: usize) -> Vec<u8> {
    let started = Instant::now();
    let mut got = Vec::new();
    while got.len() < want && started.elapsed() < PATIENCE {
        match port.rx.pop() {
            Ok(packet) => got.extend_from_slice(packet.bytes()),
            Err(_) => std::thread::sleep(Duration::from_millis(1)),
        }
    }
    got
}

fn pty_link() -> (OwnedFd, SerialLink) {
    let pty = nix::pty::openpty(None, None).expect("openpty");
    let path = nix::unistd::ttyname(pty.slave.as_fd()).expect("ttyname");
    let mut config = SerialConfig::new(path.to_string_lossy(), 230_400);
    config.exclusive = false;
    let link = SerialLink::open(config).expect("open the pty's slave");
    // The link opened its own descriptor of the slave; the master stays with the test.
    drop(pty.slave);
    (pty.master, link)
}

fn read_master(master: &OwnedFd, want: usize) -> Vec<u8> {
    let started = Instant::now();
    let mut got = Vec::new();
    while got.len() < want && started.elapsed() < PATIENCE {
        let mut fds = [PollFd::new(master.as_fd(), PollFlags::POLLIN)];
        if poll(&mut fds, PollTimeout::from(100u16)).unwrap_or(0) == 0 {
            continue;
        }
        let mut buf = [0u8; 64];
        match nix::unistd::read(master, &mut buf) {
            Ok(n) => got.extend_from_slice(&buf[..n]),
            Err(_) => break,
        }
    }
    got
}

#[test]
fn a_reply_written_to_a_pty_is_delivered_on_the_descriptor_becoming_readable() {
    let (master, link) = pty_link();
    let (mut port, thread, stop) = start(Box::new(link));
    // Let the thread fall asleep with nothing queued and nothing to read.
    std::thread::sleep(Duration::from_millis(50));
    nix::unistd::write(&master, b"r 14 00001113 !\r\n").expect("write on the master");
    let got = receive(&mut port, 17);
    assert_eq!(got, b"r 14 00001113 !\r\n");
    finish(thread, &stop);
}

#[test]
fn output_the_tick_queued_is_written_when_it_wakes_the_thread() {
    let (master, link) = pty_link();
    let (mut port, thread, stop) = start(Box::new(link));
    std::thread::sleep(Duration::from_millis(50));
    port.tx.push(Packet::new(b"R14\r\n")).expect("room");
    port.waker.wake();
    assert_eq!(read_master(&master, 5), b"R14\r\n");
    // And again, after the thread slept once more: every wake-up counts.
    std::thread::sleep(Duration::from_millis(20));
    port.tx.push(Packet::new(b"R0E\r\n")).expect("room");
    port.waker.wake();
    assert_eq!(read_master(&master, 5), b"R0E\r\n");
    finish(thread, &stop);
}

#[test]
fn a_hang_up_wakes_the_thread_and_takes_the_link_down() {
    let (master, link) = pty_link();
    let (mut port, thread, stop) = start(Box::new(link));
    std::thread::sleep(Duration::from_millis(50));
    drop(master);
    assert_eq!(events(&mut port, 1), [LinkEvent::Down]);
    finish(thread, &stop);
}

/// The link events until `want` arrived or patience ran out.
fn events(port: &mut LinkPort, want: usize) -> Vec<LinkEvent> {
    let started = Instant::now();
    let mut got = Vec::new();
    while got.len() < want && started.elapsed() < PATIENCE {
        match port.events.pop() {
            Ok(event) => got.push(event),
            Err(_) => std::thread::sleep(Duration::from_millis(1)),
        }
    }
    got
}

/// A link is handed to its thread closed: the thread opens it and says `Up`; a tty that is
/// not there yet is no `Down` (the link never opened), and is opened once it appears.
#[test]
fn a_link_that_is_not_there_yet_is_opened_when_it_appears_and_never_reported_down() {
    let dir = std::env::temp_dir().join(format!("motiond-io-late-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("late.tty");
    let _ = std::fs::remove_file(&path);
    let mut config = SerialConfig::new(path.to_string_lossy(), 230_400);
    config.exclusive = false;
    let link = SerialLink::new(config).expect("a valid config, closed");
    let (mut port, thread, stop) = spawn_closed("late", Box::new(link), None, None);
    // Several reopen attempts fail meanwhile (100, 200, 400 ms backoff).
    std::thread::sleep(Duration::from_millis(400));
    assert_eq!(
        port.events.pop().ok(),
        None,
        "no event before the tty exists"
    );
    assert!(!port.counters.up.load(std::sync::atomic::Ordering::Relaxed));
    let pty = nix::pty::openpty(None, None).expect("openpty");
    let slave = nix::unistd::ttyname(pty.slave.as_fd()).expect("ttyname");
    std::os::unix::fs::symlink(&slave, &path).expect("symlink the pty");
    assert_eq!(events(&mut port, 1), [LinkEvent::Up]);
    assert_eq!(
        port.counters
            .reconnects
            .load(std::sync::atomic::Ordering::Relaxed),
        0,
        "a first opening is no reconnection"
    );
    nix::unistd::write(&pty.master, b"r 14 00001113 !\r\n").expect("write on the master");
    assert_eq!(receive(&mut port, 17), b"r 14 00001113 !\r\n");
    finish(thread, &stop);
    let _ = std::fs::remove_file(&path);
}

/// Answers every byte after a fixed delay (a device's scheduled reply, which only the
/// link's `next_event` announces).
#[derive(Default)]
struct LateEcho {
    due: Vec<(Duration, u8)>,
}

impl StreamDevice for LateEcho {
    fn receive(&mut self, now: Duration, bytes: &[u8]) {
        for &byte in bytes {
            self.due.push((now + Duration::from_millis(20), byte));
        }
    }
    fn transmit(&mut self, now: Duration, out: &mut [u8]) -> usize {
        let ready = self.due.iter().take_while(|(at, _)| *at <= now).count();
        let n = ready.min(out.len());
        for (slot, (_, byte)) in out.iter_mut().zip(self.due.drain(..n)) {
            *slot = byte;
        }
        n
    }
    fn next_event(&self, _now: Duration) -> Option<Duration> {
        self.due.first().map(|(at, _)| *at)
    }
}

#[test]
fn a_simulated_link_is_looked_at_again_at_its_next_event() {
    let link = SimLink::stream("late echo", 230_400, Box::new(LateEcho::default()));
    let (mut port, thread, stop) = start(Box::new(link));
    port.tx.push(Packet::new(b"ping")).expect("room");
    port.waker.wake();
    // Nothing but the link's next event (the device's delayed answer) wakes the thread.
    assert_eq!(receive(&mut port, 4), b"ping");
    finish(thread, &stop);
}

/// The scheduling policy (field 41 of `/proc/self/task/TID/stat`, 1 = SCHED_FIFO) and the
/// real-time priority (field 40) of this process's thread named `comm`.
fn policy_of_thread(comm: &str) -> Option<(u32, u32)> {
    let stat = std::fs::read_to_string(task_of_thread(comm)?.join("stat")).ok()?;
    // Fields after the parenthesised name start at field 3.
    let rest = &stat[stat.rfind(')')? + 2..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let priority = fields.get(40 - 3)?.parse().ok()?;
    let policy = fields.get(41 - 3)?.parse().ok()?;
    Some((policy, priority))
}

/// `/proc/self/task/TID` of this process's thread named `comm`.
fn task_of_thread(comm: &str) -> Option<std::path::PathBuf> {
    std::fs::read_dir("/proc/self/task")
        .ok()?
        .flatten()
        .map(|task| task.path())
        .find(|path| {
            std::fs::read_to_string(path.join("comm")).is_ok_and(|name| name.trim_end() == comm)
        })
}

/// `[server] io_rt_priority`: the thread takes SCHED_FIFO at that priority before its first
/// pass and says whether it got it; refused (no CAP_SYS_NICE, no RLIMIT_RTPRIO), it says
/// why, naming the priority, and serves its link at the normal policy.
#[test]
fn an_io_thread_takes_the_real_time_priority_it_is_given_or_says_why_not() {
    let (master, link) = pty_link();
    let (mut port, mut thread, stop) = start_named("rtprio", Box::new(link), Some(7), None);
    let outcome = thread.take_rt().expect("the set-up's outcome");
    assert!(outcome.pinned.is_none(), "no core was asked for");
    match outcome.fifo {
        Some(Ok(priority)) => {
            assert_eq!(priority, 7);
            assert_eq!(policy_of_thread("io-rtprio"), Some((1, 7)));
        }
        Some(Err(error)) => {
            let text = error.to_string();
            assert!(text.contains("SCHED_FIFO priority 7"), "{text}");
            assert_eq!(policy_of_thread("io-rtprio").map(|(p, _)| p), Some(0));
        }
        None => panic!("a priority was asked for: the thread must answer"),
    }
    assert!(thread.take_rt().is_none(), "the answer is taken once");
    nix::unistd::write(&master, b"r 14 00001113 !\r\n").expect("write on the master");
    assert_eq!(receive(&mut port, 17), b"r 14 00001113 !\r\n");
    finish(thread, &stop);
}

#[test]
fn an_io_thread_without_a_priority_stays_at_the_normal_policy() {
    let (_master, link) = pty_link();
    let (_port, mut thread, stop) = start_named("plain", Box::new(link), None, None);
    let outcome = thread.take_rt().expect("the set-up's outcome");
    assert!(outcome.fifo.is_none() && outcome.pinned.is_none());
    assert_eq!(policy_of_thread("io-plain").map(|(p, _)| p), Some(0));
    finish(thread, &stop);
}

/// The cores this process's thread named `comm` may run on (`Cpus_allowed_list` of its
/// status).
fn cores_of_thread(comm: &str) -> Option<String> {
    let status = std::fs::read_to_string(task_of_thread(comm)?.join("status")).ok()?;
    status
        .lines()
        .find_map(|l| l.strip_prefix("Cpus_allowed_list:"))
        .map(|l| l.trim().to_owned())
}

/// `[server] io_cpu`: the thread pins itself to that core before its first pass and says
/// so; a core that does not exist is refused, said, and the link still served.
#[test]
fn an_io_thread_pins_itself_to_the_core_it_is_given_or_says_why_not() {
    let last = core_affinity::get_core_ids()
        .and_then(|cores| cores.iter().map(|c| c.id).max())
        .expect("the process's cores");
    for (comm, cpu, exists) in [("pinned", last, true), ("nopin", 4096, false)] {
        let (master, link) = pty_link();
        let (mut port, mut thread, stop) = start_named(comm, Box::new(link), None, Some(cpu));
        let outcome = thread.take_rt().expect("the set-up's outcome");
        assert!(outcome.fifo.is_none());
        let thread_comm = format!("io-{comm}");
        match outcome.pinned {
            Some(Ok(got)) => {
                assert!(exists);
                assert_eq!(got, cpu);
                assert_eq!(cores_of_thread(&thread_comm), Some(cpu.to_string()));
            }
            Some(Err(error)) => {
                assert!(!exists, "{error}");
                assert!(error.to_string().contains("cpu 4096"), "{error}");
            }
            None => panic!("a core was asked for: the thread must answer"),
        }
        nix::unistd::write(&master, b"r 14 00001113 !\r\n").expect("write on the master");
        assert_eq!(receive(&mut port, 17), b"r 14 00001113 !\r\n");
        finish(thread, &stop);
    }
}

/// Waits until the thread's horizon passes `at` (port time); the instant it saw it, in the
/// test's time, or `None` after `patience`.
fn heard_past(port: &LinkPort, at: Duration, patience: Duration) -> Option<Instant> {
    let started = Instant::now();
    while started.elapsed() < patience {
        if port.heard() > at {
            return Some(Instant::now());
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    None
}

#[test]
fn the_tick_s_wish_to_look_by_an_instant_is_kept_with_no_bytes_and_no_timer() {
    // Port time counts from about here (the thread's epoch is taken a little later, so
    // these instants are, if anything, later in its time).
    let epoch = motiond::rt::monotonic_now();
    let now = || motiond::rt::monotonic_now().saturating_sub(epoch);
    let (_master, link) = pty_link();
    let (port, thread, stop) = start(Box::new(link));
    // A silent link and an idle limit of an hour: only the wish makes the thread look.
    let a = now() + Duration::from_millis(150);
    port.queued_and_look_by(false, Some(a));
    assert!(
        heard_past(&port, a, PATIENCE).is_some(),
        "never looked after a"
    );
    // A wish, then a later one while the thread sleeps towards the first (the deadline
    // moved on): the thread needs no wake-up for it, but still looks after it.
    let b = now() + Duration::from_millis(100);
    port.queued_and_look_by(false, Some(b));
    std::thread::sleep(Duration::from_millis(20));
    let c = now() + Duration::from_millis(300);
    port.queued_and_look_by(false, Some(c));
    assert!(
        heard_past(&port, c, PATIENCE).is_some(),
        "never looked after c"
    );
    // A far wish, then an earlier one: the thread is woken to sleep less.
    let far = now() + Duration::from_secs(30);
    port.queued_and_look_by(false, Some(far));
    std::thread::sleep(Duration::from_millis(20));
    let asked = Instant::now();
    let near = now() + Duration::from_millis(100);
    port.queued_and_look_by(false, Some(near));
    let seen = heard_past(&port, near, PATIENCE).expect("never looked after the near wish");
    assert!(
        seen.duration_since(asked) < Duration::from_secs(20),
        "the thread slept towards the far wish"
    );
    finish(thread, &stop);
}
