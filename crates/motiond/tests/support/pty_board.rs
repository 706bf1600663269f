//! A simulated serial board served on a pseudo-terminal by a thread of the test process, so
//! that motiond (a child process) opens a real tty through serialport while the test watches
//! the model's true state — and can "unplug" it by closing the master side.

use core::time::Duration;
use std::collections::VecDeque;
use std::os::fd::{AsFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Instant;

use motion_link::sim::StreamDevice;
use nix::poll::{PollFd, PollFlags, PollTimeout, poll};

/// A board model on a pty, reachable at `link` (a symlink to the pty's slave).
pub struct PtyBoard {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    /// The symlink the server's config names.
    pub link: PathBuf,
    /// Every byte the server sent, with the model time it reached the board.
    pub received: Arc<Mutex<Vec<(Duration, u8)>>>,
}

impl PtyBoard {
    /// Serves `device` on a new pty and points `link` at it (replacing an old symlink).
    /// Bytes the board sends reach the tty at `baud` (10 bits a byte), as on a real line:
    /// a byte is written when its last bit would have arrived.
    pub fn start<D: StreamDevice + 'static>(
        link: &Path,
        device: Arc<Mutex<D>>,
        epoch: Instant,
        baud: u32,
    ) -> Self {
        let pty = nix::pty::openpty(None, None).expect("openpty");
        // Child processes (the server under test) must not inherit the master: an
        // inherited copy would keep the "adapter" plugged in after `unplug`.
        for fd in [&pty.master, &pty.slave] {
            nix::fcntl::fcntl(
                fd,
                nix::fcntl::FcntlArg::F_SETFD(nix::fcntl::FdFlag::FD_CLOEXEC),
            )
            .expect("FD_CLOEXEC");
        }
        let slave_path = nix::unistd::ttyname(pty.slave.as_fd()).expect("ttyname");
        // Raw from the start (no echo, no line discipline), as a UART is.
        let mut termios = nix::sys::termios::tcgetattr(&pty.slave).expect("tcgetattr");
        nix::sys::termios::cfmakeraw(&mut termios);
        nix::sys::termios::tcsetattr(&pty.slave, nix::sys::termios::SetArg::TCSANOW, &termios)
            .expect("tcsetattr");
        let _ = std::fs::remove_file(link);
        std::os::unix::fs::symlink(&slave_path, link).expect("symlink to the pty");
        let stop = Arc::new(AtomicBool::new(false));
        let received: Arc<Mutex<Vec<(Duration, u8)>>> = Arc::default();
        let thread = {
            let stop = Arc::clone(&stop);
            let log = Arc::clone(&received);
            let master = pty.master;
            // Keep our own slave fd open so the master never reads EIO while the server is
            // between opens.
            let slave = pty.slave;
            std::thread::spawn(move || serve(master, slave, device, stop, epoch, baud, log))
        };
        Self {
            stop,
            thread: Some(thread),
            link: link.to_owned(),
            received,
        }
    }

    /// Closes the master side and removes the link: the server's tty reports a hang-up and
    /// the path is gone, as with an unplugged USB adapter (and the pty number cannot be
    /// reused under the old path by another test's pty).
    pub fn unplug(&mut self) {
        let _ = std::fs::remove_file(&self.link);
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

impl Drop for PtyBoard {
    fn drop(&mut self) {
        self.unplug();
    }
}

fn serve<D: StreamDevice>(
    master: OwnedFd,
    slave: OwnedFd,
    device: Arc<Mutex<D>>,
    stop: Arc<AtomicBool>,
    epoch: Instant,
    baud: u32,
    log: Arc<Mutex<Vec<(Duration, u8)>>>,
) {
    let byte_time = Duration::from_nanos(10_000_000_000 / u64::from(baud.max(1)));
    let mut buf = [0u8; 512];
    let mut line: VecDeque<(Duration, u8)> = VecDeque::new();
    let mut line_free_at = Duration::ZERO;
    let mut incoming: VecDeque<(Duration, u8)> = VecDeque::new();
    let mut incoming_free_at = Duration::ZERO;
    while !stop.load(Ordering::Relaxed) {
        let mut fds = [PollFd::new(master.as_fd(), PollFlags::POLLIN)];
        let wait: u8 = if line.is_empty() && incoming.is_empty() {
            1
        } else {
            0
        };
        let ready = poll(&mut fds, PollTimeout::from(wait)).unwrap_or(0);
        let now = epoch.elapsed();
        if ready > 0 {
            match nix::unistd::read(&master, &mut buf) {
                Ok(len) if len > 0 => {
                    if std::env::var_os("PTY_TRACE").is_some() {
                        eprintln!(
                            "{:>10.3} ms  in  {:02x?}",
                            now.as_secs_f64() * 1e3,
                            &buf[..len]
                        );
                    }
                    // The host wrote these at once; on the wire they arrive one byte time
                    // apart, which is what the model's receiver times.
                    for &byte in &buf[..len] {
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
            device.lock().unwrap().receive(at, &[byte]);
            log.lock().unwrap().push((at, byte));
        }
        let len = device.lock().unwrap().transmit(now, &mut buf);
        for &byte in &buf[..len] {
            line_free_at = line_free_at.max(now) + byte_time;
            line.push_back((line_free_at, byte));
        }
        let mut due = Vec::new();
        while line.front().is_some_and(|(at, _)| *at <= now) {
            if let Some((_, byte)) = line.pop_front() {
                due.push(byte);
            }
        }
        if !due.is_empty() && std::env::var_os("PTY_TRACE").is_some() {
            eprintln!("{:>10.3} ms  out {:02x?}", now.as_secs_f64() * 1e3, &due);
        }
        let mut sent = 0;
        while sent < due.len() {
            match nix::unistd::write(&master, &due[sent..]) {
                Ok(n) => sent += n,
                Err(_) => break,
            }
        }
        if !line.is_empty() || !incoming.is_empty() {
            std::thread::sleep(Duration::from_micros(100));
        }
    }
    drop(slave);
    drop(master);
}
