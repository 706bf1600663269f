//! Serves a stream device (or an RS-485 bus of them) on a pseudo-terminal.
//!
//! The device sits behind a [`SimLink`]: bytes the client writes cross a simulated wire at
//! the configured baud rate before the model sees them, and the model's replies reach the
//! client only when their last bit would have arrived. The clock is the monotonic clock
//! (this binary is the I/O shell; the models only ever see the `now` it passes).

use std::os::fd::{AsFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use motion_link::Link;
use motion_link::sim::SimLink;
use nix::errno::Errno;
use nix::fcntl::{FcntlArg, OFlag, fcntl};
use nix::poll::{PollFd, PollFlags, ppoll};
use nix::sys::termios::{self, BaudRate, SetArg};
use nix::sys::time::TimeSpec;

use crate::trace::Trace;

/// The longest the loop sleeps, so a stop request is seen quickly.
const MAX_SLEEP: Duration = Duration::from_millis(20);
/// The shortest the loop sleeps.
const MIN_SLEEP: Duration = Duration::from_micros(20);
/// Replies the client has not read yet, at most (older bytes are dropped, as a full
/// tty buffer would).
const MAX_PENDING_OUT: usize = 64 * 1024;

/// An open pseudo-terminal pair. The server keeps the slave open itself, so the pty
/// survives clients opening and closing it.
pub struct Pty {
    master: OwnedFd,
    _slave: OwnedFd,
    path: PathBuf,
}

impl Pty {
    /// Opens a pty in raw mode (no echo, no line editing) at `baud`.
    pub fn open(baud: u32) -> Result<Self> {
        let pair = nix::pty::openpty(None, None).context("openpty")?;
        let path = nix::unistd::ttyname(pair.slave.as_fd()).context("ttyname of the pty")?;
        let mut attrs = termios::tcgetattr(pair.slave.as_fd()).context("tcgetattr")?;
        termios::cfmakeraw(&mut attrs);
        if let Some(rate) = baud_rate(baud) {
            termios::cfsetspeed(&mut attrs, rate).context("cfsetspeed")?;
        }
        termios::tcsetattr(pair.slave.as_fd(), SetArg::TCSANOW, &attrs).context("tcsetattr")?;
        fcntl(pair.master.as_fd(), FcntlArg::F_SETFL(OFlag::O_NONBLOCK))
            .context("O_NONBLOCK on the pty master")?;
        Ok(Self {
            master: pair.master,
            _slave: pair.slave,
            path,
        })
    }

    /// The slave's path, for the client.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// The termios constant for `baud`, when there is one.
fn baud_rate(baud: u32) -> Option<BaudRate> {
    Some(match baud {
        1200 => BaudRate::B1200,
        2400 => BaudRate::B2400,
        4800 => BaudRate::B4800,
        9600 => BaudRate::B9600,
        19_200 => BaudRate::B19200,
        38_400 => BaudRate::B38400,
        57_600 => BaudRate::B57600,
        115_200 => BaudRate::B115200,
        230_400 => BaudRate::B230400,
        460_800 => BaudRate::B460800,
        921_600 => BaudRate::B921600,
        _ => return None,
    })
}

/// Moves bytes between the pty and the simulated wire until `stop` is set.
pub fn serve(pty: &Pty, link: &mut SimLink, stop: &AtomicBool, trace: &mut Trace) -> Result<()> {
    let start = Instant::now();
    let mut inbound: Vec<u8> = Vec::new();
    let mut outbound: Vec<u8> = Vec::new();
    let mut buf = [0u8; 1024];
    while !stop.load(Ordering::SeqCst) {
        let now = start.elapsed();
        // Client to wire: what the wire accepts now; the rest waits in `inbound`.
        if !inbound.is_empty() {
            let n = link
                .write(now, &inbound)
                .context("writing to the simulated wire")?;
            inbound.drain(..n);
        }
        // Wire to client.
        loop {
            let n = link
                .read(now, &mut buf)
                .context("reading the simulated wire")?;
            let Some(bytes) = buf.get(..n).filter(|b| !b.is_empty()) else {
                break;
            };
            trace.bytes(now, "->", bytes);
            outbound.extend_from_slice(bytes);
        }
        if outbound.len() > MAX_PENDING_OUT {
            let excess = outbound.len() - MAX_PENDING_OUT;
            outbound.drain(..excess);
            trace.note(now, &format!("client not reading: dropped {excess} bytes"));
        }
        flush_out(pty, &mut outbound)?;

        // Sleep until the client writes, the wire has something, or MAX_SLEEP.
        let now = start.elapsed();
        let wake = link
            .next_event(now)
            .map_or(MAX_SLEEP, |t| t.saturating_sub(now).min(MAX_SLEEP));
        let mut flags = PollFlags::empty();
        if inbound.len() < 4096 {
            flags |= PollFlags::POLLIN;
        }
        if !outbound.is_empty() {
            flags |= PollFlags::POLLOUT;
        }
        // Never a zero wait: a model that keeps saying "now" must not make this spin.
        let timeout = TimeSpec::from_duration(wake.max(MIN_SLEEP));
        let mut fds = [PollFd::new(pty.master.as_fd(), flags)];
        match ppoll(&mut fds, Some(timeout), None) {
            Ok(_) | Err(Errno::EINTR) => {}
            Err(e) => return Err(e).context("poll on the pty master"),
        }
        let readable = fds
            .first()
            .and_then(PollFd::revents)
            .is_some_and(|r| r.contains(PollFlags::POLLIN));
        if readable {
            match nix::unistd::read(&pty.master, &mut buf) {
                Ok(n) => {
                    let bytes = buf.get(..n).unwrap_or_default();
                    trace.bytes(start.elapsed(), "<-", bytes);
                    inbound.extend_from_slice(bytes);
                }
                Err(Errno::EAGAIN | Errno::EINTR) => {}
                // No client has the slave open right now (cannot happen while we hold it).
                Err(Errno::EIO) => std::thread::sleep(MAX_SLEEP),
                Err(e) => return Err(e).context("reading the pty master"),
            }
        }
    }
    Ok(())
}

fn flush_out(pty: &Pty, outbound: &mut Vec<u8>) -> Result<()> {
    while !outbound.is_empty() {
        match nix::unistd::write(&pty.master, outbound) {
            Ok(n) => {
                outbound.drain(..n);
            }
            Err(Errno::EAGAIN) => break,
            Err(Errno::EINTR) => {}
            Err(e) => return Err(e).context("writing the pty master"),
        }
    }
    Ok(())
}
