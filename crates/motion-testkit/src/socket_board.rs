//! A simulated SPI board served on a Unix socket by a thread of the calling process (the SPI
//! socket contract: a `u16` LE length and the MOSI bytes in, as many MISO bytes out), so that
//! motiond (a child process) talks to it through a `spi-socket` link while the test watches
//! and changes the model, and reads every transaction the server clocked out.

use core::time::Duration;
use std::io::{ErrorKind, Read, Write};
use std::os::unix::net::UnixListener;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Instant;

use motion_link::sim::SpiDevice;

use crate::KitError;

/// Every MOSI transaction the server sent, with its time since the board's epoch.
pub type Transactions = Arc<Mutex<Vec<(Duration, Vec<u8>)>>>;

/// A board model listening on `path`.
#[derive(Debug)]
pub struct SocketBoard {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
    /// The socket path the server's config names.
    pub path: PathBuf,
    /// What the server sent.
    pub transactions: Transactions,
    /// The instant all model times count from.
    pub epoch: Instant,
}

impl SocketBoard {
    /// Serves `device` on a new socket at `path` (replacing a stale one); panics when the
    /// socket cannot be made.
    pub fn start<D: SpiDevice + Send + 'static>(
        path: &Path,
        device: Arc<Mutex<D>>,
        epoch: Instant,
    ) -> Self {
        Self::try_start(path, device, epoch)
            .unwrap_or_else(|e| panic!("serve a board on an SPI socket: {e}"))
    }

    /// [`SocketBoard::start`] with the reason when it fails.
    pub fn try_start<D: SpiDevice + Send + 'static>(
        path: &Path,
        device: Arc<Mutex<D>>,
        epoch: Instant,
    ) -> Result<Self, KitError> {
        let _ = std::fs::remove_file(path);
        let listener = UnixListener::bind(path).map_err(KitError::io(format!(
            "bind the SPI socket {}",
            path.display()
        )))?;
        listener
            .set_nonblocking(true)
            .map_err(KitError::io("non-blocking accept"))?;
        let stop = Arc::new(AtomicBool::new(false));
        let transactions: Transactions = Arc::default();
        let thread = {
            let (stop, transactions) = (Arc::clone(&stop), Arc::clone(&transactions));
            std::thread::Builder::new()
                .name("spi-board".to_owned())
                .spawn(move || {
                    // A board answers on its own clock, never starved (module board_priority).
                    let _ = crate::board_priority::raise();
                    serve(&listener, &device, &stop, &transactions, epoch)
                })
                .map_err(KitError::io("spawn the SPI socket thread"))?
        };
        Ok(Self {
            stop,
            thread: Some(thread),
            path: path.to_owned(),
            transactions,
            epoch,
        })
    }

    /// Model time now.
    pub fn now(&self) -> Duration {
        self.epoch.elapsed()
    }

    /// The transactions sent after `since` (model time).
    pub fn sent_since(&self, since: Duration) -> Vec<Vec<u8>> {
        self.transactions
            .lock()
            .map(|log| {
                log.iter()
                    .filter(|(at, _)| *at >= since)
                    .map(|(_, mosi)| mosi.clone())
                    .collect()
            })
            .unwrap_or_default()
    }

    /// Takes every transaction logged so far out of the log.
    pub fn take_transactions(&self) -> Vec<(Duration, Vec<u8>)> {
        self.transactions
            .lock()
            .map(|mut log| core::mem::take(&mut *log))
            .unwrap_or_default()
    }
}

impl Drop for SocketBoard {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
        let _ = std::fs::remove_file(&self.path);
    }
}

fn serve<D: SpiDevice>(
    listener: &UnixListener,
    device: &Mutex<D>,
    stop: &AtomicBool,
    transactions: &Transactions,
    epoch: Instant,
) {
    while !stop.load(Ordering::Relaxed) {
        let mut conn = match listener.accept() {
            Ok((conn, _)) => conn,
            Err(e) if e.kind() == ErrorKind::WouldBlock => {
                if let Ok(mut device) = device.lock() {
                    device.advance(epoch.elapsed());
                }
                std::thread::sleep(Duration::from_millis(1));
                continue;
            }
            Err(_) => return,
        };
        let _ = conn.set_read_timeout(Some(Duration::from_millis(1)));
        let mut pending: Vec<u8> = Vec::new();
        let mut buf = [0u8; 4096];
        'connection: while !stop.load(Ordering::Relaxed) {
            match conn.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => pending.extend_from_slice(&buf[..n]),
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                    if let Ok(mut device) = device.lock() {
                        device.advance(epoch.elapsed());
                    }
                    continue;
                }
                Err(_) => break,
            }
            while pending.len() >= 2 {
                let len = usize::from(u16::from_le_bytes([pending[0], pending[1]]));
                if pending.len() < 2 + len {
                    break;
                }
                let mosi: Vec<u8> = pending[2..2 + len].to_vec();
                pending.drain(..2 + len);
                let mut miso = vec![0xFF; len];
                let now = epoch.elapsed();
                if let Ok(mut device) = device.lock() {
                    device.transfer(now, &mosi, &mut miso);
                }
                if let Ok(mut log) = transactions.lock() {
                    log.push((now, mosi));
                }
                if conn.write_all(&miso).is_err() {
                    // The server went away mid-transaction (killed): this connection is
                    // over, the board waits for the next one as a real bridge would.
                    break 'connection;
                }
            }
        }
    }
}
