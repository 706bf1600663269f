//! Serves an SPI device (or a bus of them) on a Unix socket, per the docs/ARCHITECTURE.md SPI socket
//! contract: each transaction arrives as a `u16` little-endian length and that many MOSI
//! bytes; the answer is exactly `length` MISO bytes, sent once the transaction's last
//! clock would have ticked at the configured SPI rate.

use std::io::{self, Read, Write};
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use motion_link::Link;
use motion_link::sim::SimLink;

use crate::faults::FaultPlan;
use crate::trace::Trace;

/// How often a blocked accept or read looks at the stop flag.
const POLL: Duration = Duration::from_millis(20);

/// A listening socket, removed again when dropped.
pub struct SpiSocket {
    listener: UnixListener,
    path: PathBuf,
}

impl SpiSocket {
    /// Binds `path`. A stale socket file nobody listens on is replaced; a live one is an
    /// error.
    pub fn bind(path: &Path) -> Result<Self> {
        if path.exists() {
            if UnixStream::connect(path).is_ok() {
                bail!("{} is in use by another listener", path.display());
            }
            std::fs::remove_file(path)
                .with_context(|| format!("removing the stale socket {}", path.display()))?;
        }
        let listener =
            UnixListener::bind(path).with_context(|| format!("binding {}", path.display()))?;
        listener
            .set_nonblocking(true)
            .context("non-blocking accept")?;
        Ok(Self {
            listener,
            path: path.to_owned(),
        })
    }

    /// The socket's path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for SpiSocket {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Accepts one client at a time and answers its transactions until `stop` is set. The
/// boards keep their state from one client to the next.
pub fn serve(
    socket: &SpiSocket,
    link: &mut SimLink,
    stop: &AtomicBool,
    trace: &mut Trace,
    plan: &mut FaultPlan,
) -> Result<()> {
    let start = Instant::now();
    while !stop.load(Ordering::SeqCst) {
        match socket.listener.accept() {
            Ok((conn, _)) => {
                trace.note(start.elapsed(), "client connected");
                let outcome = serve_client(conn, link, stop, trace, plan, start);
                let why = match outcome {
                    Ok(()) => "client disconnected".to_owned(),
                    Err(e) => format!("client dropped: {e:#}"),
                };
                trace.note(start.elapsed(), &why);
            }
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                // Let the boards' physics run while nobody is connected.
                let _ = link.read(start.elapsed(), &mut []);
                std::thread::sleep(POLL);
            }
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e).context("accept on the SPI socket"),
        }
    }
    Ok(())
}

fn serve_client(
    mut conn: UnixStream,
    link: &mut SimLink,
    stop: &AtomicBool,
    trace: &mut Trace,
    plan: &mut FaultPlan,
    start: Instant,
) -> Result<()> {
    let faults = link.faults();
    conn.set_nonblocking(false)?;
    conn.set_read_timeout(Some(POLL))?;
    let mut pending: Vec<u8> = Vec::new();
    let mut buf = vec![0u8; 64 * 1024];
    let mut miso: Vec<u8> = Vec::new();
    while !stop.load(Ordering::SeqCst) {
        match conn.read(&mut buf) {
            Ok(0) => return Ok(()),
            Ok(n) => pending.extend_from_slice(buf.get(..n).unwrap_or_default()),
            Err(e)
                if matches!(
                    e.kind(),
                    io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
                ) =>
            {
                let _ = link.read(start.elapsed(), &mut []);
                continue;
            }
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e).context("reading the SPI socket"),
        }
        while let Some(&[lo, hi]) = pending.get(..2) {
            let len = usize::from(u16::from_le_bytes([lo, hi]));
            let Some(mosi) = pending.get(2..2 + len) else {
                break;
            };
            let now = start.elapsed();
            plan.tick(now, &faults, 1);
            trace.bytes(now, "<-", mosi);
            transact(link, start, mosi, &mut miso)?;
            trace.bytes(start.elapsed(), "->", &miso);
            conn.write_all(&miso)
                .context("answering on the SPI socket")?;
            pending.drain(..2 + len);
        }
    }
    Ok(())
}

/// Runs one transaction on the simulated bus and waits out its wire time.
fn transact(link: &mut SimLink, start: Instant, mosi: &[u8], miso: &mut Vec<u8>) -> Result<()> {
    miso.clear();
    if mosi.is_empty() {
        return Ok(());
    }
    link.write(start.elapsed(), mosi)
        .context("SPI transaction")?;
    let mut buf = [0u8; 4096];
    while miso.len() < mosi.len() {
        let now = start.elapsed();
        let n = link.read(now, &mut buf).context("SPI transaction")?;
        miso.extend_from_slice(buf.get(..n).unwrap_or_default());
        if n == 0 {
            let wait = link
                .next_event(now)
                .map_or(Duration::from_micros(50), |t| t.saturating_sub(now));
            std::thread::sleep(wait.max(Duration::from_micros(10)));
        }
    }
    Ok(())
}
