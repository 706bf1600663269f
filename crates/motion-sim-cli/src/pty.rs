//! Serves a stream device (or an RS-485 bus of them) on a pseudo-terminal.
//!
//! The device sits behind a [`SimLink`]: bytes the client writes cross a simulated wire at
//! the configured baud rate before the model sees them, and the model's replies reach the
//! client only when their last bit would have arrived. The clock is the monotonic clock
//! (this binary is the I/O shell; the models only ever see the `now` it passes).
//!
//! The wire runs at the rate the client set on its end of the pty (termios, read from the
//! master side: [`motion_link::serial::tty_speed`]), starting at `--baud`: a client that
//! switches its port to another rate (after telling its board so, e.g. the Trinamic pack's
//! `$40`) moves the wire with it, and a board still at the old rate hears garbage, as on a
//! real line.

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

use crate::faults::FaultPlan;
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
pub fn serve(
    pty: &Pty,
    link: &mut SimLink,
    stop: &AtomicBool,
    trace: &mut Trace,
    plan: &mut FaultPlan,
) -> Result<()> {
    let start = Instant::now();
    let faults = link.faults();
    let mut inbound: Vec<u8> = Vec::new();
    let mut outbound: Vec<u8> = Vec::new();
    let mut buf = [0u8; 1024];
    let mut client_rate = None;
    while !stop.load(Ordering::SeqCst) {
        let now = start.elapsed();
        plan.tick(now, &faults, 64);
        // The rate the client's end runs at now (it may have changed it).
        if let Ok(rate) = motion_link::serial::tty_speed(pty.master.as_fd())
            && rate > 0
            && client_rate != Some(rate)
        {
            // The first reading is the pty's own setting (the wire starts at --baud, which a
            // pty may not spell); from then on the wire follows the client's changes.
            if client_rate.is_some() {
                trace.note(now, &format!("the client set {rate} baud"));
                link.set_baud(now, rate)
                    .context("moving the simulated wire to the client's rate")?;
            }
            client_rate = Some(rate);
        }
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
        let next = [link.next_event(now), plan.next_event()]
            .into_iter()
            .flatten()
            .min();
        let wake = next.map_or(MAX_SLEEP, |t| t.saturating_sub(now).min(MAX_SLEEP));
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

#[cfg(test)]
mod tests {
    use super::*;
    use motion_link::serial::{SerialConfig, SerialLink};
    use motion_link::sim::StreamDevice;

    /// Answers every byte with its upper-case form.
    #[derive(Default)]
    struct Shout(Vec<u8>);

    impl StreamDevice for Shout {
        fn receive(&mut self, _now: Duration, bytes: &[u8]) {
            self.0.extend(bytes.iter().map(u8::to_ascii_uppercase));
        }
        fn transmit(&mut self, _now: Duration, out: &mut [u8]) -> usize {
            let n = out.len().min(self.0.len());
            out[..n].copy_from_slice(&self.0[..n]);
            self.0.drain(..n);
            n
        }
        fn next_event(&self, now: Duration) -> Option<Duration> {
            (!self.0.is_empty()).then_some(now)
        }
    }

    /// [`Shout`] listening at a rate of its own.
    struct ShoutAt(Shout, u32);

    impl StreamDevice for ShoutAt {
        fn receive(&mut self, now: Duration, bytes: &[u8]) {
            self.0.receive(now, bytes);
        }
        fn transmit(&mut self, now: Duration, out: &mut [u8]) -> usize {
            self.0.transmit(now, out)
        }
        fn next_event(&self, now: Duration) -> Option<Duration> {
            self.0.next_event(now)
        }
        fn baud(&self) -> Option<u32> {
            Some(self.1)
        }
    }

    /// What `client` reads within 200 ms after writing `message`.
    fn ask(client: &mut SerialLink, start: Instant, message: &[u8]) -> Vec<u8> {
        client.write(start.elapsed(), message).expect("write");
        let mut got = Vec::new();
        let mut buf = [0u8; 64];
        let until = start.elapsed() + Duration::from_millis(200);
        while start.elapsed() < until {
            if let Ok(n) = client.read(start.elapsed(), &mut buf) {
                got.extend_from_slice(&buf[..n]);
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        got
    }

    #[test]
    fn the_wire_follows_the_rate_the_client_sets_and_garbles_across_rates() {
        let pty = Pty::open(19_200).expect("pty");
        let path = pty.path().to_string_lossy().into_owned();
        let stop = AtomicBool::new(false);
        std::thread::scope(|scope| {
            let server = scope.spawn(|| {
                let device = ShoutAt(Shout::default(), 115_200);
                let mut link = SimLink::stream("test", 19_200, Box::new(device));
                let mut trace = Trace::new("test", false);
                let mut plan = FaultPlan::new(0.0, Duration::ZERO, Duration::ZERO);
                serve(&pty, &mut link, &stop, &mut trace, &mut plan)
            });
            let mut client = SerialLink::open(SerialConfig::new(&path, 19_200)).expect("open");
            let start = Instant::now();
            let garbled = ask(&mut client, start, b"hello");
            assert_ne!(garbled, b"HELLO", "at 19200 to a board at 115200");
            client.set_baud(start.elapsed(), 115_200).expect("set_baud");
            assert_eq!(ask(&mut client, start, b"hello"), b"HELLO");
            stop.store(true, Ordering::SeqCst);
            server.join().expect("server thread").expect("serve");
        });
    }

    #[test]
    fn a_serial_client_talks_to_the_model_through_the_pty_at_the_wire_rate() {
        let pty = Pty::open(9600).expect("pty");
        let path = pty.path().to_string_lossy().into_owned();
        let stop = AtomicBool::new(false);
        std::thread::scope(|scope| {
            let server = scope.spawn(|| {
                let mut link = SimLink::stream("test", 9600, Box::new(Shout::default()));
                let mut trace = Trace::new("test", false);
                let mut plan = FaultPlan::new(0.0, Duration::ZERO, Duration::ZERO);
                serve(&pty, &mut link, &stop, &mut trace, &mut plan)
            });
            let mut client = SerialLink::open(SerialConfig::new(&path, 9600)).expect("open");
            let start = Instant::now();
            let message = b"hello, pty";
            assert_eq!(client.write(start.elapsed(), message).expect("write"), 10);
            let mut got = Vec::new();
            let mut buf = [0u8; 64];
            while got.len() < message.len() && start.elapsed() < Duration::from_secs(5) {
                let n = client.read(start.elapsed(), &mut buf).expect("read");
                got.extend_from_slice(&buf[..n]);
                std::thread::sleep(Duration::from_millis(1));
            }
            let took = start.elapsed();
            stop.store(true, Ordering::SeqCst);
            assert_eq!(got, b"HELLO, PTY");
            // 10 bytes out, the last echo one byte time later: 11 × 10 / 9600 s ≈ 11.5 ms.
            assert!(took >= Duration::from_micros(11_458), "{took:?}");
            server.join().expect("server thread").expect("serve");
        });
    }
}
