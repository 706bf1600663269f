//! A simulated serial board served on a pseudo-terminal by a thread of the calling process,
//! so that motiond (a child process) opens a real tty through serialport while the caller
//! watches the model's true state — and can "unplug" it by closing the master side, or put
//! noise on the line ([`LineNoise`]).

use core::time::Duration;
use std::collections::VecDeque;
use std::os::fd::{AsFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Instant;

use motion_link::sim::StreamDevice;
use motion_sim::rng::SimRng;
use nix::poll::{PollFd, PollFlags, PollTimeout, poll};

use crate::KitError;

/// Bytes with the model time they crossed the line.
pub type ByteLog = Arc<Mutex<Vec<(Duration, u8)>>>;

/// Bit errors on the board → host direction: each data bit of each byte the board sends is
/// inverted with probability `ber` (independent errors, a binary symmetric channel).
#[derive(Debug)]
pub struct LineNoise {
    ber_bits: AtomicU64,
    flipped: AtomicU64,
    bytes: AtomicU64,
    seed: u64,
}

impl LineNoise {
    /// A quiet line (ber 0) whose errors, once switched on, follow `seed`.
    pub fn new(seed: u64) -> Arc<Self> {
        Arc::new(Self {
            ber_bits: AtomicU64::new(0f64.to_bits()),
            flipped: AtomicU64::new(0),
            bytes: AtomicU64::new(0),
            seed,
        })
    }

    /// Sets the bit-error rate (0 ..= 1).
    pub fn set_ber(&self, ber: f64) {
        self.ber_bits
            .store(ber.clamp(0.0, 1.0).to_bits(), Ordering::Relaxed);
    }

    /// The bit-error rate now.
    pub fn ber(&self) -> f64 {
        f64::from_bits(self.ber_bits.load(Ordering::Relaxed))
    }

    /// Bits inverted so far.
    pub fn flipped(&self) -> u64 {
        self.flipped.load(Ordering::Relaxed)
    }

    /// Bytes the board sent through the noise so far.
    pub fn bytes(&self) -> u64 {
        self.bytes.load(Ordering::Relaxed)
    }
}

/// Draws the errors of a [`LineNoise`] (geometric gaps between errors, so a tiny rate
/// costs nothing per bit).
struct Channel {
    noise: Arc<LineNoise>,
    rng: SimRng,
    ber: f64,
    /// Data bits until the next error.
    gap: u64,
}

impl Channel {
    fn new(noise: Arc<LineNoise>) -> Self {
        let rng = SimRng::new(noise.seed);
        Self {
            noise,
            rng,
            ber: 0.0,
            gap: u64::MAX,
        }
    }

    fn draw_gap(&mut self) {
        self.gap = if self.ber <= 0.0 {
            u64::MAX
        } else if self.ber >= 1.0 {
            0
        } else {
            let u = self.rng.next_f64().max(f64::MIN_POSITIVE);
            (u.ln() / (1.0 - self.ber).ln())
                .floor()
                .min(u64::MAX as f64) as u64
        };
    }

    fn pass(&mut self, byte: u8) -> u8 {
        let ber = self.noise.ber();
        if ber != self.ber {
            self.ber = ber;
            self.draw_gap();
        }
        self.noise.bytes.fetch_add(1, Ordering::Relaxed);
        let mut out = byte;
        let mut bit = 0u64;
        while bit < 8 {
            if self.gap >= 8 - bit {
                self.gap -= 8 - bit;
                break;
            }
            bit += self.gap;
            out ^= 1 << bit;
            self.noise.flipped.fetch_add(1, Ordering::Relaxed);
            bit += 1;
            self.draw_gap();
        }
        out
    }
}

/// What a [`PtyBoard`] does besides serving its model.
#[derive(Debug, Clone, Default)]
pub struct PtyOptions {
    /// Noise on the board → host direction.
    pub noise: Option<Arc<LineNoise>>,
    /// Log every byte the board sent (before the noise) in [`PtyBoard::sent`].
    pub log_sent: bool,
    /// The line runs at the rate the server set on its end of the pty (read from the
    /// master side, [`motion_link::serial::tty_speed`]) instead of the `baud` given, and
    /// what crosses between it and a board listening at another rate
    /// ([`StreamDevice::baud`]: a Trinamic pack after `$40`) is garbled
    /// ([`motion_link::sim::garble`]), as on a real line.
    pub follow_rate: bool,
}

/// A board model on a pty, reachable at `link` (a symlink to the pty's slave).
#[derive(Debug)]
pub struct PtyBoard {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    /// The symlink the server's config names.
    pub link: PathBuf,
    /// Every byte the server sent, with the model time it reached the board.
    pub received: ByteLog,
    /// Every byte the board sent (with [`PtyOptions::log_sent`]), as it left the board.
    pub sent: ByteLog,
}

impl PtyBoard {
    /// Serves `device` on a new pty and points `link` at it (replacing an old symlink).
    /// Bytes the board sends reach the tty at `baud` (10 bits a byte), as on a real line:
    /// a byte is written when its last bit would have arrived. Panics when the pty cannot
    /// be made.
    pub fn start<D: StreamDevice + Send + 'static>(
        link: &Path,
        device: Arc<Mutex<D>>,
        epoch: Instant,
        baud: u32,
    ) -> Self {
        Self::try_start(link, device, epoch, baud, PtyOptions::default())
            .unwrap_or_else(|e| panic!("serve a board on a pty: {e}"))
    }

    /// [`PtyBoard::start`] with options, and the reason when it fails.
    pub fn try_start<D: StreamDevice + Send + 'static>(
        link: &Path,
        device: Arc<Mutex<D>>,
        epoch: Instant,
        baud: u32,
        options: PtyOptions,
    ) -> Result<Self, KitError> {
        let pty = nix::pty::openpty(None, None).map_err(KitError::sys("openpty"))?;
        // Child processes (the server under test) must not inherit the master: an
        // inherited copy would keep the "adapter" plugged in after `unplug`.
        for fd in [&pty.master, &pty.slave] {
            nix::fcntl::fcntl(
                fd,
                nix::fcntl::FcntlArg::F_SETFD(nix::fcntl::FdFlag::FD_CLOEXEC),
            )
            .map_err(KitError::sys("FD_CLOEXEC on the pty"))?;
        }
        let slave_path =
            nix::unistd::ttyname(pty.slave.as_fd()).map_err(KitError::sys("ttyname"))?;
        // Raw from the start (no echo, no line discipline), as a UART is.
        let mut termios =
            nix::sys::termios::tcgetattr(&pty.slave).map_err(KitError::sys("tcgetattr"))?;
        nix::sys::termios::cfmakeraw(&mut termios);
        nix::sys::termios::tcsetattr(&pty.slave, nix::sys::termios::SetArg::TCSANOW, &termios)
            .map_err(KitError::sys("tcsetattr"))?;
        let _ = std::fs::remove_file(link);
        std::os::unix::fs::symlink(&slave_path, link).map_err(KitError::io(format!(
            "symlink {} to the pty",
            link.display()
        )))?;
        let stop = Arc::new(AtomicBool::new(false));
        let received: ByteLog = Arc::default();
        let sent: ByteLog = Arc::default();
        let thread = {
            let stop = Arc::clone(&stop);
            let logs = Logs {
                received: Arc::clone(&received),
                sent: options.log_sent.then(|| Arc::clone(&sent)),
            };
            let channel = options.noise.map(Channel::new);
            let master = pty.master;
            // Keep our own slave fd open so the master never reads EIO while the server is
            // between opens.
            let slave = pty.slave;
            std::thread::Builder::new()
                .name("pty-board".to_owned())
                .spawn(move || {
                    // A board answers on its own clock, never starved (module board_priority).
                    let _ = crate::board_priority::raise();
                    let line = Line {
                        baud,
                        follow_rate: options.follow_rate,
                    };
                    serve(&master, &device, &stop, epoch, line, &logs, channel);
                    drop(slave);
                })
                .map_err(KitError::io("spawn the pty thread"))?
        };
        Ok(Self {
            stop,
            thread: Some(thread),
            link: link.to_owned(),
            received,
            sent,
        })
    }

    /// Takes the bytes received so far out of the log.
    pub fn take_received(&self) -> Vec<(Duration, u8)> {
        take(&self.received)
    }

    /// Takes the bytes sent so far out of the log.
    pub fn take_sent(&self) -> Vec<(Duration, u8)> {
        take(&self.sent)
    }

    /// Closes the master side and removes the link: the server's tty reports a hang-up and
    /// the path is gone, as with an unplugged USB adapter (and the pty number cannot be
    /// reused under the old path by another test's pty). Only the first call does anything:
    /// a board plugged in on the same path afterwards keeps its link.
    pub fn unplug(&mut self) {
        if self.thread.is_none() {
            return;
        }
        let _ = std::fs::remove_file(&self.link);
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

fn take(log: &ByteLog) -> Vec<(Duration, u8)> {
    log.lock()
        .map(|mut bytes| core::mem::take(&mut *bytes))
        .unwrap_or_default()
}

impl Drop for PtyBoard {
    fn drop(&mut self) {
        self.unplug();
    }
}

struct Logs {
    received: ByteLog,
    sent: Option<ByteLog>,
}

/// The rate of the line a [`PtyBoard`] serves.
#[derive(Clone, Copy)]
struct Line {
    baud: u32,
    /// [`PtyOptions::follow_rate`].
    follow_rate: bool,
}

impl Line {
    /// The rate the server's end runs at now.
    fn host(&self, master: &OwnedFd) -> u32 {
        if !self.follow_rate {
            return self.baud;
        }
        motion_link::serial::tty_speed(master.as_fd())
            .ok()
            .filter(|&rate| rate > 0)
            .unwrap_or(self.baud)
    }
}

/// `bytes` sent at `from` as a receiver at `to` takes them (`None`: the same rate).
fn cross(bytes: &[u8], from: u32, to: Option<u32>) -> Vec<u8> {
    match to {
        Some(to) if to != from => motion_link::sim::garble(bytes, from, to),
        _ => bytes.to_vec(),
    }
}

fn serve<D: StreamDevice>(
    master: &OwnedFd,
    device: &Mutex<D>,
    stop: &AtomicBool,
    epoch: Instant,
    rate: Line,
    logs: &Logs,
    mut channel: Option<Channel>,
) {
    let byte_time_at = |baud: u32| Duration::from_nanos(10_000_000_000 / u64::from(baud.max(1)));
    let trace = std::env::var_os("PTY_TRACE").is_some();
    let mut buf = [0u8; 512];
    let mut line: VecDeque<(Duration, u8)> = VecDeque::new();
    let mut line_free_at = Duration::ZERO;
    let mut incoming: VecDeque<(Duration, u8)> = VecDeque::new();
    let mut incoming_free_at = Duration::ZERO;
    let mut due = Vec::with_capacity(512);
    while !stop.load(Ordering::Relaxed) {
        let mut fds = [PollFd::new(master.as_fd(), PollFlags::POLLIN)];
        let wait: u8 = if line.is_empty() && incoming.is_empty() {
            1
        } else {
            0
        };
        let ready = poll(&mut fds, PollTimeout::from(wait)).unwrap_or(0);
        let now = epoch.elapsed();
        let host = rate.host(master);
        let byte_time = byte_time_at(host);
        let board_rate = if rate.follow_rate {
            device.lock().ok().and_then(|d| d.baud())
        } else {
            None
        };
        if ready > 0 {
            match nix::unistd::read(master, &mut buf) {
                Ok(len) if len > 0 => {
                    let heard = cross(&buf[..len], host, board_rate);
                    if trace {
                        eprintln!("{:>10.3} ms  in  {:02x?}", now.as_secs_f64() * 1e3, &heard);
                    }
                    // The host wrote these at once; on the wire they arrive one byte time
                    // apart, which is what the model's receiver times.
                    for &byte in &heard {
                        incoming_free_at = incoming_free_at.max(now) + byte_time;
                        incoming.push_back((incoming_free_at, byte));
                    }
                }
                _ => std::thread::sleep(Duration::from_millis(1)),
            }
        }
        while let Some(&(at, byte)) = incoming.front() {
            if at > now {
                break;
            }
            incoming.pop_front();
            if let Ok(mut device) = device.lock() {
                device.receive(at, &[byte]);
            }
            if let Ok(mut log) = logs.received.lock() {
                log.push((at, byte));
            }
        }
        let len = device
            .lock()
            .map(|mut device| device.transmit(now, &mut buf))
            .unwrap_or(0);
        let sent = match board_rate {
            Some(board) => cross(&buf[..len], board, Some(host)),
            None => buf[..len].to_vec(),
        };
        for &byte in &sent {
            line_free_at = line_free_at.max(now) + byte_time;
            line.push_back((line_free_at, byte));
        }
        due.clear();
        while line.front().is_some_and(|(at, _)| *at <= now) {
            if let Some((at, byte)) = line.pop_front() {
                if let Some(Ok(mut log)) = logs.sent.as_ref().map(|log| log.lock()) {
                    log.push((at, byte));
                }
                due.push(channel.as_mut().map_or(byte, |channel| channel.pass(byte)));
            }
        }
        if !due.is_empty() && trace {
            eprintln!("{:>10.3} ms  out {:02x?}", now.as_secs_f64() * 1e3, &due);
        }
        let mut sent = 0;
        while sent < due.len() {
            match nix::unistd::write(master, &due[sent..]) {
                Ok(n) => sent += n,
                Err(_) => break,
            }
        }
        if !line.is_empty() || !incoming.is_empty() {
            std::thread::sleep(Duration::from_micros(100));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_flips_bits_at_about_the_set_rate() {
        let noise = LineNoise::new(7);
        let mut channel = Channel::new(Arc::clone(&noise));
        for _ in 0..1000 {
            assert_eq!(channel.pass(0x5A), 0x5A, "a quiet line changes nothing");
        }
        noise.set_ber(1e-2);
        let mut changed = 0u32;
        for _ in 0..100_000 {
            changed += (channel.pass(0) != 0) as u32;
        }
        let flipped = noise.flipped() as f64;
        // 800 000 bits at 1e-2: 8000 expected, a few sigma either side.
        assert!((7_500.0..8_500.0).contains(&flipped), "{flipped}");
        assert!(changed > 7_000, "{changed}");
        assert_eq!(noise.bytes(), 101_000);
    }
}
