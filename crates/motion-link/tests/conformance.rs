//! One conformance suite, run against every `Link` implementation this machine can host:
//! `serial` over a pseudo-terminal pair (the test plays the device on the master side),
//! `spi-socket` (the test listens on a temporary Unix socket) and `sim` (stream and SPI,
//! with echo / loopback devices).
//!
//! Each peer echoes: a stream device sends back every byte, an SPI device ties MISO to
//! MOSI. `spidev` needs hardware and is not run here.

use std::io::{Read, Write};
use std::os::fd::{AsFd, OwnedFd};
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use motion_link::serial::{SerialConfig, SerialLink};
use motion_link::sim::{SimFaults, SimLink, SpiDevice, StreamDevice};
use motion_link::spi_socket::{SpiSocketConfig, SpiSocketLink};
use motion_link::{Link, LinkErrorKind, LinkKind};

/// How many times a test waits for bytes before it gives up (each wait is 1 ms of real or
/// simulated time), so nothing here can hang.
const PATIENCE: usize = 3000;

/// What the suite needs from each implementation.
trait Harness {
    fn link(&mut self) -> &mut dyn Link;
    /// The time to pass to the link.
    fn now(&self) -> Duration;
    /// Lets 1 ms pass (sleep, or advance the simulated clock).
    fn wait(&mut self);
    /// Takes the device away as abruptly as the transport allows.
    fn unplug(&mut self);
    /// Brings the device back at the same path.
    fn replug(&mut self);
    /// Whether `read_wait` really waits (the real transports; a simulated wire has no
    /// clock and never does).
    fn blocks(&self) -> bool {
        true
    }
}

fn read_exactly(h: &mut dyn Harness, n: usize, chunk: usize) -> Vec<u8> {
    let mut got = Vec::new();
    let mut buf = vec![0u8; chunk.max(1)];
    for _ in 0..PATIENCE {
        let now = h.now();
        let k = h.link().read(now, &mut buf).expect("read");
        got.extend_from_slice(&buf[..k]);
        if got.len() >= n {
            break;
        }
        if k == 0 {
            h.wait();
        }
    }
    assert_eq!(got.len(), n, "expected {n} bytes, got {got:?}");
    got
}

fn write_all(h: &mut dyn Harness, bytes: &[u8]) {
    let mut done = 0;
    for _ in 0..PATIENCE {
        let now = h.now();
        done += h.link().write(now, &bytes[done..]).expect("write");
        if done == bytes.len() {
            return;
        }
        h.wait();
    }
    panic!("only {done} of {} bytes accepted", bytes.len());
}

/// Writes `bytes` in pieces of `chunk` (one SPI transaction each) and reads them back.
fn round_trip(h: &mut dyn Harness, bytes: &[u8], chunk: usize) {
    for piece in bytes.chunks(chunk) {
        write_all(h, piece);
    }
    let got = read_exactly(h, bytes.len(), chunk);
    assert_eq!(got, bytes, "chunk size {chunk}");
}

fn expect_disconnected(h: &mut dyn Harness) {
    let mut buf = [0u8; 16];
    for _ in 0..PATIENCE {
        let now = h.now();
        let read = h.link().read(now, &mut buf);
        match read {
            Err(e) if e.kind() == LinkErrorKind::Disconnected => {
                assert!(e.to_string().contains(h.link().name()), "{e}");
                return;
            }
            Err(e) => panic!("unexpected error kind {:?}: {e}", e.kind()),
            Ok(_) => {
                // A stream write also discovers the hang-up.
                let now = h.now();
                if let Err(e) = h.link().write(now, &[0x55]) {
                    assert_eq!(e.kind(), LinkErrorKind::Disconnected, "{e}");
                    return;
                }
                h.wait();
            }
        }
    }
    panic!("{} never reported the unplug", h.link().name());
}

/// The suite.
fn conformance(h: &mut dyn Harness) {
    let name = h.link().name().to_owned();
    // Idle: a read returns 0 at once.
    let now = h.now();
    assert_eq!(
        h.link().read(now, &mut [0u8; 8]).expect("idle read"),
        0,
        "{name}"
    );

    // read_wait: idle, it gives up after its timeout with nothing; a byte on its way ends
    // the wait (real transports; a simulated wire never waits).
    let now = h.now();
    assert_eq!(
        h.link()
            .read_wait(now, &mut [0u8; 8], Duration::from_millis(5))
            .expect("idle read_wait"),
        0
    );
    if h.blocks() {
        write_all(h, b"wake");
        let now = h.now();
        let mut buf = [0u8; 8];
        let n = h
            .link()
            .read_wait(now, &mut buf, Duration::from_secs(5))
            .expect("read_wait");
        assert!(n >= 1, "{name}: read_wait returned without the echo");
        let rest = read_exactly(h, 4 - n, 8);
        assert_eq!([&buf[..n], &rest[..]].concat(), b"wake");
    }

    // Round trip of every byte value, then every chunk size from 1 to 64.
    let all: Vec<u8> = (0..=255u8).collect();
    round_trip(h, &all, 256);
    let message: Vec<u8> = (0..200u32).map(|i| (i * 7 + 3) as u8).collect();
    for chunk in 1..=64 {
        round_trip(h, &message, chunk);
    }
    let now = h.now();
    assert_eq!(h.link().read(now, &mut [0u8; 8]).expect("idle again"), 0);

    // Multi-part writes: one transaction on SPI, consecutive bytes on a stream.
    let now = h.now();
    let n = h
        .link()
        .write_parts(now, &[b"ab", b"", b"cde"])
        .expect("write_parts");
    assert_eq!(n, 5);
    assert_eq!(read_exactly(h, 5, 16), b"abcde");
    let stats = h.link().stats();
    assert!(stats.bytes_out >= 256 + 64 * 200 + 5, "{stats:?}");
    assert!(stats.bytes_out <= 256 + 64 * 200 + 5 + 4, "{stats:?}");
    assert_eq!(stats.bytes_in, stats.bytes_out, "{stats:?}");
    if h.link().kind() == LinkKind::Spi {
        assert!(stats.transactions > 64, "{stats:?}");
    } else {
        assert_eq!(stats.transactions, 0);
    }
    let now = h.now();
    h.link().flush(now).expect("flush");

    // Unplug: Disconnected, and it stays so without a reopen.
    h.unplug();
    expect_disconnected(h);
    let now = h.now();
    let again = h.link().read(now, &mut [0u8; 4]).unwrap_err();
    assert_eq!(again.kind(), LinkErrorKind::Disconnected, "{again}");
    let errors = h.link().stats().errors;
    assert!(errors >= 2);

    // Replug and reopen: traffic flows again.
    h.replug();
    let now = h.now();
    h.link().reopen(now).expect("reopen");
    assert_eq!(h.link().stats().reconnects, 1);
    round_trip(h, b"back again", 4);
}

// ---------------------------------------------------------------- sim

/// Echoes every byte it receives, at the instant it receives it.
#[derive(Default)]
struct Echo {
    pending: Vec<u8>,
}

impl StreamDevice for Echo {
    fn receive(&mut self, _now: Duration, bytes: &[u8]) {
        self.pending.extend_from_slice(bytes);
    }
    fn transmit(&mut self, _now: Duration, out: &mut [u8]) -> usize {
        let n = out.len().min(self.pending.len());
        out[..n].copy_from_slice(&self.pending[..n]);
        self.pending.drain(..n);
        n
    }
    fn next_event(&self, now: Duration) -> Option<Duration> {
        (!self.pending.is_empty()).then_some(now)
    }
}

/// MISO tied to MOSI.
struct Loopback;

impl SpiDevice for Loopback {
    fn transfer(&mut self, _now: Duration, mosi: &[u8], miso: &mut [u8]) -> bool {
        miso.copy_from_slice(mosi);
        true
    }
    fn advance(&mut self, _now: Duration) {}
}

struct SimHarness {
    link: SimLink,
    faults: SimFaults,
    now: Duration,
}

impl SimHarness {
    fn new(link: SimLink) -> Self {
        Self {
            faults: link.faults(),
            link,
            now: Duration::from_secs(1),
        }
    }
}

impl Harness for SimHarness {
    fn link(&mut self) -> &mut dyn Link {
        &mut self.link
    }
    fn now(&self) -> Duration {
        self.now
    }
    fn wait(&mut self) {
        self.now += Duration::from_millis(1);
    }
    fn unplug(&mut self) {
        self.faults.unplug();
    }
    fn replug(&mut self) {
        self.faults.replug();
    }
    fn blocks(&self) -> bool {
        false
    }
}

#[test]
fn sim_stream_link_conforms() {
    let link = SimLink::stream("echo", 115_200, Box::new(Echo::default()));
    conformance(&mut SimHarness::new(link));
}

#[test]
fn sim_spi_link_conforms() {
    let link = SimLink::spi("loopback", 500_000, Box::new(Loopback));
    conformance(&mut SimHarness::new(link));
}

// ---------------------------------------------------------------- serial over a pty

/// Plays the device on the master side of a pseudo-terminal, echoing.
struct PtyPeer {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl PtyPeer {
    /// Opens a pty pair, points `link_path` at its slave and echoes on the master.
    fn start(link_path: &Path) -> Self {
        let pty = nix::pty::openpty(None, None).expect("openpty");
        let slave_path = nix::unistd::ttyname(pty.slave.as_fd()).expect("ttyname");
        let _ = std::fs::remove_file(link_path);
        std::os::unix::fs::symlink(&slave_path, link_path).expect("symlink");
        // Keep the slave open until the link has it, so the master never sees EIO early.
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let thread = std::thread::spawn(move || echo_master(pty.master, pty.slave, &flag));
        Self {
            stop,
            thread: Some(thread),
        }
    }

    fn stop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            t.join().expect("echo thread");
        }
    }
}

impl Drop for PtyPeer {
    fn drop(&mut self) {
        self.stop();
    }
}

fn echo_master(master: OwnedFd, slave: OwnedFd, stop: &AtomicBool) {
    use nix::poll::{PollFd, PollFlags, poll};
    let mut buf = [0u8; 512];
    let mut slave = Some(slave);
    let started = Instant::now();
    while !stop.load(Ordering::SeqCst) {
        if started.elapsed() > Duration::from_millis(200) {
            slave = None;
        }
        let mut fds = [PollFd::new(master.as_fd(), PollFlags::POLLIN)];
        match poll(&mut fds, 5u16) {
            Ok(1) => {}
            _ => continue,
        }
        match nix::unistd::read(&master, &mut buf) {
            Ok(n) if n > 0 => {
                let mut done = 0;
                while done < n {
                    match nix::unistd::write(&master, &buf[done..n]) {
                        Ok(k) => done += k,
                        Err(_) => break,
                    }
                }
            }
            // EIO: nobody has the slave open right now.
            _ => std::thread::sleep(Duration::from_millis(2)),
        }
    }
    drop(slave);
    // Dropping the master hangs the slave up.
}

struct PtyHarness {
    link: SerialLink,
    peer: PtyPeer,
    path: PathBuf,
    start: Instant,
}

impl Harness for PtyHarness {
    fn link(&mut self) -> &mut dyn Link {
        &mut self.link
    }
    fn now(&self) -> Duration {
        self.start.elapsed()
    }
    fn wait(&mut self) {
        std::thread::sleep(Duration::from_millis(1));
    }
    fn unplug(&mut self) {
        self.peer.stop();
    }
    fn replug(&mut self) {
        self.peer = PtyPeer::start(&self.path);
    }
}

fn temp_path(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("motion-link-{}-{name}", std::process::id()));
    let _ = std::fs::remove_file(&dir);
    dir
}

#[test]
fn serial_link_over_a_pty_conforms() {
    let path = temp_path("tty");
    let peer = PtyPeer::start(&path);
    let config = SerialConfig::new(path.to_string_lossy(), 230_400);
    let link = SerialLink::open(config).expect("open pty slave");
    let mut h = PtyHarness {
        link,
        peer,
        path: path.clone(),
        start: Instant::now(),
    };
    conformance(&mut h);
    drop(h);
    let _ = std::fs::remove_file(path);
}

// ---------------------------------------------------------------- spi-socket

/// Listens on a Unix socket and answers every transaction with its own MOSI bytes.
struct SocketPeer {
    stop: Arc<AtomicBool>,
    hang_up: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl SocketPeer {
    fn start(path: &Path) -> Self {
        let listener = UnixListener::bind(path).expect("bind");
        listener.set_nonblocking(true).expect("nonblocking");
        let stop = Arc::new(AtomicBool::new(false));
        let hang_up = Arc::new(AtomicBool::new(false));
        let (s, k) = (stop.clone(), hang_up.clone());
        let thread = std::thread::spawn(move || {
            while !s.load(Ordering::SeqCst) {
                match listener.accept() {
                    Ok((conn, _)) => serve_loopback(conn, &s, &k),
                    Err(_) => std::thread::sleep(Duration::from_millis(1)),
                }
            }
        });
        Self {
            stop,
            hang_up,
            thread: Some(thread),
        }
    }
}

impl Drop for SocketPeer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            t.join().expect("socket thread");
        }
    }
}

fn serve_loopback(mut conn: UnixStream, stop: &AtomicBool, hang_up: &AtomicBool) {
    conn.set_nonblocking(false).expect("blocking");
    conn.set_read_timeout(Some(Duration::from_millis(5)))
        .expect("timeout");
    let mut pending: Vec<u8> = Vec::new();
    let mut buf = [0u8; 4096];
    loop {
        if stop.load(Ordering::SeqCst) || hang_up.swap(false, Ordering::SeqCst) {
            return;
        }
        match conn.read(&mut buf) {
            Ok(0) => return,
            Ok(n) => pending.extend_from_slice(&buf[..n]),
            Err(_) => continue,
        }
        while pending.len() >= 2 {
            let len = usize::from(u16::from_le_bytes([pending[0], pending[1]]));
            if pending.len() < 2 + len {
                break;
            }
            let mosi: Vec<u8> = pending.drain(..2 + len).skip(2).collect();
            if conn.write_all(&mosi).is_err() {
                return;
            }
        }
    }
}

struct SocketHarness {
    link: SpiSocketLink,
    peer: SocketPeer,
    start: Instant,
}

impl Harness for SocketHarness {
    fn link(&mut self) -> &mut dyn Link {
        &mut self.link
    }
    fn now(&self) -> Duration {
        self.start.elapsed()
    }
    fn wait(&mut self) {
        std::thread::sleep(Duration::from_millis(1));
    }
    fn unplug(&mut self) {
        self.peer.hang_up.store(true, Ordering::SeqCst);
    }
    fn replug(&mut self) {}
}

#[test]
fn spi_socket_link_conforms() {
    let path = temp_path("spi.sock");
    let peer = SocketPeer::start(&path);
    let link =
        SpiSocketLink::connect(SpiSocketConfig::new(path.to_string_lossy())).expect("connect");
    let mut h = SocketHarness {
        link,
        peer,
        start: Instant::now(),
    };
    conformance(&mut h);
    drop(h);
    let _ = std::fs::remove_file(path);
}

#[test]
fn spi_socket_peer_closing_mid_answer_is_disconnected() {
    let path = temp_path("short.sock");
    let listener = UnixListener::bind(&path).expect("bind");
    let server = std::thread::spawn(move || {
        let (mut conn, _) = listener.accept().expect("accept");
        let mut req = [0u8; 6];
        conn.read_exact(&mut req).expect("request");
        assert_eq!(req, [4, 0, 1, 2, 3, 4], "u16 LE length, then MOSI");
        conn.write_all(&[9, 9]).expect("short answer");
        // Dropping the connection: the answer stays two bytes short.
    });
    let mut link =
        SpiSocketLink::connect(SpiSocketConfig::new(path.to_string_lossy())).expect("connect");
    assert_eq!(link.write(Duration::ZERO, &[1, 2, 3, 4]).expect("write"), 4);
    server.join().expect("server");
    let mut got = Vec::new();
    let mut buf = [0u8; 8];
    let mut outcome = None;
    for _ in 0..PATIENCE {
        match link.read(Duration::ZERO, &mut buf) {
            Ok(n) => got.extend_from_slice(&buf[..n]),
            Err(e) => {
                outcome = Some(e);
                break;
            }
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    let err = outcome.expect("the short answer was never reported");
    assert_eq!(got, [9, 9]);
    assert_eq!(err.kind(), LinkErrorKind::Disconnected, "{err}");
    assert!(err.to_string().contains("before answering"), "{err}");
    let _ = std::fs::remove_file(path);
}
