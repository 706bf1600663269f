//! A simulated board (a QSB unless told otherwise) served on a pseudo-terminal by a thread
//! of the bench, so that a motiond child opens a real tty (its `[[link]] type = "serial"`)
//! while the bench stamps, on CLOCK_MONOTONIC, the moment the first byte of each command
//! line reaches the master side.
//!
//! The technique of `crates/motiond/tests/support/pty_board.rs`, written again here (a bench
//! does not import test code): both fds close-on-exec so the server cannot inherit the master,
//! the tty raw from the start, and pacing both ways at the baud — bytes the host writes at
//! once are handed to the model one byte time apart, and the model's bytes reach the tty one
//! byte time apart, as on a real line — or, for a board behind USB (the QSB, [`Wire::QSB`]),
//! together at the end of each 1 ms bus frame, as a USB serial device's do.

use core::time::Duration;
use std::collections::VecDeque;
use std::os::fd::{AsFd, AsRawFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::Sender;
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Instant;

use motion_base::Model as BoardModel;
use motion_link::sim::StreamDevice;
use nix::poll::{PollFd, PollFlags, PollTimeout, poll};

use crate::rt::now_ns;
use crate::sim_boards::serial_board;

/// The QSB's line rate (factory setting), 8N1.
pub const BAUD: u32 = 230_400;

/// One command line the host wrote, with the CLOCK_MONOTONIC instant (ns) at which the
/// read that returned its first byte came back on the master side.
#[derive(Debug, Clone)]
pub struct LineSeen {
    /// First byte at the master, ns.
    pub first_byte_ns: u64,
    /// The line without its end-of-command bytes.
    pub line: Vec<u8>,
}

/// How a board's bytes travel to the host.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Wire {
    /// Line rate, 8N1: both ways, bytes are one byte time apart on the line.
    pub baud: u32,
    /// `Some(frame)`: the board is behind USB and its bytes reach the host's tty together
    /// at the end of each bus frame (a full-speed device is polled once per 1 ms frame);
    /// `None`: each byte as its stop bit passes (a UART).
    pub usb_frame: Option<Duration>,
}

impl Wire {
    /// The QSB: 230400 baud "in RS-232 format over a virtual COM port connection through
    /// the USB" (QSB command list), 1 ms frames.
    pub const QSB: Self = Self {
        baud: BAUD,
        usb_frame: Some(Duration::from_millis(1)),
    };

    /// A UART at `baud` (the Trinamic pack's RS-232/RS-485).
    pub const fn uart(baud: u32) -> Self {
        Self {
            baud,
            usb_frame: None,
        }
    }
}

/// How the host's bytes are cut into the messages [`LineSeen`] reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Framing {
    /// ASCII command lines ended by CR or LF (the QSB).
    Lines,
    /// Fixed-size binary words (the Trinamic pack's 9 bytes); a pause longer than `gap_ns`
    /// between two bytes starts a new word (the pack's own packet timeout, `$41`).
    Words {
        /// Bytes per word.
        len: usize,
        /// Longest pause within one word, ns.
        gap_ns: u64,
    },
}

/// A simulated board on a pty, reachable at `link` (a symlink to the slave side).
#[derive(Debug)]
pub struct PtyBoard {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    link: PathBuf,
    /// A descriptor of the slave side of the bench's own (for [`queued`]).
    watch: OwnedFd,
    /// What went wrong in the serving thread, if anything.
    pub failure: Arc<Mutex<Option<String>>>,
}

/// The model a [`PtyBoard`] serves.
pub type Model = Box<dyn StreamDevice + Send>;

impl PtyBoard {
    /// Serves a fresh QSB model on a new pty and points `link` at its slave (replacing an
    /// old symlink). Every command line the host writes whose bytes start with `prefix` is
    /// sent to `lines` with its first-byte stamp.
    pub fn start(
        link: &Path,
        prefix: &'static [u8],
        lines: Sender<LineSeen>,
    ) -> Result<Self, String> {
        Self::start_with(
            link,
            serial_board(BoardModel::QSB)?,
            Wire::QSB,
            prefix,
            lines,
        )
    }

    /// [`start`](Self::start) with another model, on `wire`.
    pub fn start_with(
        link: &Path,
        device: Model,
        wire: Wire,
        prefix: &'static [u8],
        lines: Sender<LineSeen>,
    ) -> Result<Self, String> {
        Self::start_framed(link, device, wire, Framing::Lines, prefix, lines)
    }

    /// [`start_with`](Self::start_with) for a board whose host messages are cut by
    /// `framing`: every message that starts with `prefix` is sent to `lines`.
    pub fn start_framed(
        link: &Path,
        device: Model,
        wire: Wire,
        framing: Framing,
        prefix: &'static [u8],
        lines: Sender<LineSeen>,
    ) -> Result<Self, String> {
        let pty = nix::pty::openpty(None, None).map_err(|e| format!("openpty: {e}"))?;
        for fd in [&pty.master, &pty.slave] {
            nix::fcntl::fcntl(
                fd,
                nix::fcntl::FcntlArg::F_SETFD(nix::fcntl::FdFlag::FD_CLOEXEC),
            )
            .map_err(|e| format!("FD_CLOEXEC on the pty: {e}"))?;
        }
        let slave_path =
            nix::unistd::ttyname(pty.slave.as_fd()).map_err(|e| format!("ttyname: {e}"))?;
        let mut termios =
            nix::sys::termios::tcgetattr(&pty.slave).map_err(|e| format!("tcgetattr: {e}"))?;
        nix::sys::termios::cfmakeraw(&mut termios);
        nix::sys::termios::tcsetattr(&pty.slave, nix::sys::termios::SetArg::TCSANOW, &termios)
            .map_err(|e| format!("tcsetattr: {e}"))?;
        let _ = std::fs::remove_file(link);
        std::os::unix::fs::symlink(&slave_path, link)
            .map_err(|e| format!("symlink {} → {}: {e}", link.display(), slave_path.display()))?;
        let stop = Arc::new(AtomicBool::new(false));
        let failure = Arc::new(Mutex::new(None));
        let watch = pty
            .slave
            .try_clone()
            .map_err(|e| format!("dup the pty slave: {e}"))?;
        let thread = {
            let stop = Arc::clone(&stop);
            let failure = Arc::clone(&failure);
            let master = pty.master;
            // Our own slave fd stays open so the master never reads EIO while the server is
            // between opens.
            let slave = pty.slave;
            std::thread::Builder::new()
                .name("pty-board".to_owned())
                .spawn(move || {
                    let _ = crate::rt::set_up_thread(crate::rt::board_priority(), None);
                    let watch = LineWatch::new(framing, prefix, lines);
                    if let Err(e) = serve(&master, device, wire, &stop, watch)
                        && let Ok(mut slot) = failure.lock()
                    {
                        *slot = Some(e);
                    }
                    drop(slave);
                })
                .map_err(|e| format!("spawn the pty thread: {e}"))?
        };
        Ok(Self {
            stop,
            thread: Some(thread),
            link: link.to_owned(),
            watch,
            failure,
        })
    }

    /// Bytes the board sent that nobody has read from the slave side yet.
    pub fn unread(&self) -> usize {
        queued(&self.watch)
    }

    /// A descriptor of the slave side (to read it as a host would, or to watch [`queued`]).
    pub fn slave(&self) -> Result<OwnedFd, String> {
        self.watch
            .try_clone()
            .map_err(|e| format!("dup the pty slave: {e}"))
    }

    /// Stops the thread, closes the pty and removes the link.
    pub fn stop(&mut self) {
        let _ = std::fs::remove_file(&self.link);
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

impl Drop for PtyBoard {
    fn drop(&mut self) {
        self.stop();
    }
}

/// Cuts the host's bytes into messages and reports the ones that start with a prefix.
struct LineWatch {
    framing: Framing,
    prefix: &'static [u8],
    lines: Sender<LineSeen>,
    current: Vec<u8>,
    first_byte_ns: u64,
    last_byte_ns: u64,
}

impl LineWatch {
    fn new(framing: Framing, prefix: &'static [u8], lines: Sender<LineSeen>) -> Self {
        Self {
            framing,
            prefix,
            lines,
            current: Vec::new(),
            first_byte_ns: 0,
            last_byte_ns: 0,
        }
    }

    fn report(&mut self) {
        let line = core::mem::take(&mut self.current);
        if line.starts_with(self.prefix) {
            let _ = self.lines.send(LineSeen {
                first_byte_ns: self.first_byte_ns,
                line,
            });
        }
    }

    fn push(&mut self, byte: u8, read_ns: u64) {
        match self.framing {
            Framing::Lines => {
                if byte == b'\r' || byte == b'\n' {
                    if !self.current.is_empty() {
                        self.report();
                    }
                    return;
                }
            }
            Framing::Words { gap_ns, .. } => {
                if read_ns.saturating_sub(self.last_byte_ns) > gap_ns {
                    // A pause: whatever came before was a torn word.
                    self.current.clear();
                }
                self.last_byte_ns = read_ns;
            }
        }
        if self.current.is_empty() {
            self.first_byte_ns = read_ns;
        }
        // A command line is at most a dozen bytes; garbage is not allowed to grow.
        if self.current.len() < 64 {
            self.current.push(byte);
        }
        if let Framing::Words { len, .. } = self.framing
            && self.current.len() >= len
        {
            self.report();
        }
    }
}

/// Bytes waiting in a tty's input queue (FIONREAD): received, not yet read by anyone.
#[allow(unsafe_code)] // an ioctl nix has no safe wrapper for, see the SAFETY note
pub fn queued(tty: &OwnedFd) -> usize {
    let mut count: libc::c_int = 0;
    // SAFETY: FIONREAD writes one c_int through the pointer, which points at `count`, a
    // live local of that type; the descriptor is borrowed from an open OwnedFd.
    let result = unsafe { libc::ioctl(tty.as_raw_fd(), libc::FIONREAD, &mut count) };
    if result < 0 {
        0
    } else {
        usize::try_from(count).unwrap_or(0)
    }
}

fn serve(
    master: &OwnedFd,
    mut device: Model,
    wire: Wire,
    stop: &AtomicBool,
    mut watch: LineWatch,
) -> Result<(), String> {
    let epoch = Instant::now();
    let byte_time = Duration::from_nanos(10_000_000_000 / u64::from(wire.baud.max(1)));
    let mut buf = [0u8; 512];
    let mut outgoing: VecDeque<(Duration, u8)> = VecDeque::new();
    let mut outgoing_free_at = Duration::ZERO;
    let mut incoming: VecDeque<(Duration, u8)> = VecDeque::new();
    let mut incoming_free_at = Duration::ZERO;
    let mut due = Vec::with_capacity(512);
    while !stop.load(Ordering::Relaxed) {
        let mut fds = [PollFd::new(master.as_fd(), PollFlags::POLLIN)];
        let wait: u8 = if outgoing.is_empty() && incoming.is_empty() {
            1
        } else {
            0
        };
        let ready = poll(&mut fds, PollTimeout::from(wait)).unwrap_or(0);
        if ready > 0 {
            match nix::unistd::read(master, &mut buf) {
                Ok(len) if len > 0 => {
                    let read_ns = now_ns();
                    let now = epoch.elapsed();
                    for &byte in buf.get(..len).unwrap_or(&[]) {
                        watch.push(byte, read_ns);
                        // Written at once by the host; on the wire one byte time apart,
                        // which is what the model's receiver times.
                        incoming_free_at = incoming_free_at.max(now) + byte_time;
                        incoming.push_back((incoming_free_at, byte));
                    }
                }
                Ok(_) | Err(nix::errno::Errno::EAGAIN | nix::errno::Errno::EINTR) => {}
                // EIO: no slave open right now (the server between opens).
                Err(nix::errno::Errno::EIO) => std::thread::sleep(Duration::from_millis(1)),
                Err(e) => return Err(format!("read the pty master: {e}")),
            }
        }
        let now = epoch.elapsed();
        while let Some(&(at, byte)) = incoming.front() {
            if at > now {
                break;
            }
            incoming.pop_front();
            device.receive(at, &[byte]);
        }
        let len = device.transmit(now, &mut buf);
        for &byte in buf.get(..len).unwrap_or(&[]) {
            outgoing_free_at = outgoing_free_at.max(now) + byte_time;
            outgoing.push_back((outgoing_free_at, byte));
        }
        due.clear();
        // Behind USB, only what arrived by the end of the last whole frame has reached the
        // host.
        let delivered_by = wire.usb_frame.map_or(now, |frame| {
            let frame_ns = frame.as_nanos().max(1);
            let whole = now.as_nanos() / frame_ns * frame_ns;
            Duration::from_nanos(u64::try_from(whole).unwrap_or(u64::MAX))
        });
        while let Some(&(at, byte)) = outgoing.front() {
            if at > delivered_by {
                break;
            }
            outgoing.pop_front();
            due.push(byte);
        }
        let mut sent = 0;
        while sent < due.len() {
            match nix::unistd::write(master, due.get(sent..).unwrap_or(&[])) {
                Ok(n) if n > 0 => sent += n,
                _ => break,
            }
        }
        if !outgoing.is_empty() || !incoming.is_empty() {
            std::thread::sleep(Duration::from_micros(100));
        }
    }
    Ok(())
}
