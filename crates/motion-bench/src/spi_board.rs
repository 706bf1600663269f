//! A simulated SPI board served on a Unix socket by a thread of the bench (the SPI socket
//! contract, docs/ARCHITECTURE.md: each transaction a `u16` little-endian length and that
//! many MOSI bytes, answered by exactly as many MISO bytes), so that a motiond child opens a
//! real `type = "spi-socket"` link.

use std::io::{Read, Write};
use std::os::fd::AsFd;
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::Sender;
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Instant;

use motion_link::sim::SpiDevice;
use nix::poll::{PollFd, PollFlags, PollTimeout, poll};

use crate::pty::LineSeen;
use crate::rt::now_ns;

/// The model an [`SpiBoard`] serves.
pub type Model = Box<dyn SpiDevice + Send>;

/// Which transactions an [`SpiBoard`] reports, and to whom: every transaction whose MOSI
/// bytes `select` accepts goes to `seen`, stamped with the CLOCK_MONOTONIC instant the
/// read of its length header returned (its first bytes at the board).
#[derive(Debug)]
pub struct Watch {
    /// Which transactions to report.
    pub select: fn(&[u8]) -> bool,
    /// Where to.
    pub seen: Sender<LineSeen>,
}

/// A simulated SPI board listening at `path`.
#[derive(Debug)]
pub struct SpiBoard {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    path: PathBuf,
    /// What went wrong in the serving thread, if anything.
    pub failure: Arc<Mutex<Option<String>>>,
}

impl SpiBoard {
    /// Listens at `path` (replacing an old socket file) and serves `device` to one client at
    /// a time.
    pub fn start(path: &Path, device: Model) -> Result<Self, String> {
        Self::start_watched(path, device, None)
    }

    /// [`start`](Self::start), reporting the transactions `watch` selects.
    pub fn start_watched(path: &Path, device: Model, watch: Option<Watch>) -> Result<Self, String> {
        let _ = std::fs::remove_file(path);
        let listener =
            UnixListener::bind(path).map_err(|e| format!("bind {}: {e}", path.display()))?;
        listener
            .set_nonblocking(true)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        let stop = Arc::new(AtomicBool::new(false));
        let failure = Arc::new(Mutex::new(None));
        let thread = {
            let stop = Arc::clone(&stop);
            let failure = Arc::clone(&failure);
            std::thread::Builder::new()
                .name("spi-board".to_owned())
                .spawn(move || {
                    let _ = crate::rt::set_up_thread(crate::rt::board_priority(), None);
                    if let Err(e) = serve(&listener, device, &stop, watch.as_ref())
                        && let Ok(mut slot) = failure.lock()
                    {
                        *slot = Some(e);
                    }
                })
                .map_err(|e| format!("spawn the SPI board thread: {e}"))?
        };
        Ok(Self {
            stop,
            thread: Some(thread),
            path: path.to_owned(),
            failure,
        })
    }

    /// Stops the thread and removes the socket file.
    pub fn stop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
        let _ = std::fs::remove_file(&self.path);
    }
}

impl Drop for SpiBoard {
    fn drop(&mut self) {
        self.stop();
    }
}

/// Waits up to 50 ms for `stream` to be readable.
fn readable(stream: &UnixStream) -> bool {
    let mut fds = [PollFd::new(stream.as_fd(), PollFlags::POLLIN)];
    poll(&mut fds, PollTimeout::from(50u16)).unwrap_or(0) > 0
}

fn serve(
    listener: &UnixListener,
    mut device: Model,
    stop: &AtomicBool,
    watch: Option<&Watch>,
) -> Result<(), String> {
    let epoch = Instant::now();
    let mut mosi = vec![0u8; usize::from(u16::MAX)];
    let mut miso = vec![0u8; usize::from(u16::MAX)];
    while !stop.load(Ordering::Relaxed) {
        let mut stream = match listener.accept() {
            Ok((stream, _)) => stream,
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                std::thread::sleep(std::time::Duration::from_millis(20));
                continue;
            }
            Err(e) => return Err(format!("accept: {e}")),
        };
        stream
            .set_nonblocking(false)
            .map_err(|e| format!("socket: {e}"))?;
        // One client until it hangs up (motiond reconnects after a failure).
        while !stop.load(Ordering::Relaxed) {
            if !readable(&stream) {
                continue;
            }
            let mut header = [0u8; 2];
            if stream.read_exact(&mut header).is_err() {
                break;
            }
            let first_byte_ns = now_ns();
            let len = usize::from(u16::from_le_bytes(header));
            let (Some(mosi), Some(miso)) = (mosi.get_mut(..len), miso.get_mut(..len)) else {
                break;
            };
            if stream.read_exact(mosi).is_err() {
                break;
            }
            if let Some(watch) = watch
                && (watch.select)(mosi)
            {
                let _ = watch.seen.send(LineSeen {
                    first_byte_ns,
                    line: mosi.to_vec(),
                });
            }
            miso.fill(0xFF);
            let _driven = device.transfer(epoch.elapsed(), mosi, miso);
            if stream.write_all(miso).is_err() {
                break;
            }
        }
    }
    Ok(())
}
