//! Links the tick runs itself (`[[link]] io = "tick"`, docs/ARCHITECTURE.md "Links the tick
//! runs itself"): no I/O thread, no eventfd, no second wake-up. After publishing the frame
//! and queueing the drivers' messages, the tick writes them on the link within a wire-time
//! budget; at the start of the next tick, before the link's input is taken, it reads what
//! came back. The same [`Worker`] an I/O thread runs does both, so a failed link is taken
//! down, its queue dropped and the link reopened with the same backoff — only never by
//! waiting: every call here returns at once (an SPI socket's write only queues; a spidev
//! transfer holds the tick for its wire time, which the budget bounds).

use core::fmt;
use core::time::Duration;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use super::worker::Worker;
use super::{LinkPort, PACKET_LEN};
use motion_link::Link;

/// The tick's own I/O for one link.
pub struct InlineIo {
    worker: Worker,
    /// Wire time one tick may spend on the link.
    budget: Duration,
    /// The SPI clock a transfer holds the tick for (`None`: writes only queue).
    bit_rate: Option<u32>,
    buf: [u8; PACKET_LEN],
}

impl fmt::Debug for InlineIo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("InlineIo")
            .field("budget", &self.budget)
            .field("bit_rate", &self.bit_rate)
            .finish_non_exhaustive()
    }
}

/// How long `len` bytes hold the bus at `bit_rate` bits per second (zero without one).
pub fn wire_time(len: usize, bit_rate: Option<u32>) -> Duration {
    match bit_rate {
        Some(rate) if rate > 0 => {
            Duration::from_nanos((len as u64 * 8).saturating_mul(1_000_000_000) / u64::from(rate))
        }
        _ => Duration::ZERO,
    }
}

impl InlineIo {
    /// Start of a tick, before the link's input is taken: reopens a failed link when its
    /// backoff is over, else hands over the bytes that came back and publishes the horizon.
    pub fn look(&mut self) {
        self.worker.look(&mut self.buf);
    }

    /// After the tick queued the drivers' messages: writes them in order while their wire
    /// time fits the budget (the first always goes, so no message waits forever); the rest
    /// wait for the next tick and are counted ([`IoCounters::deferred`]).
    pub fn transfer(&mut self) {
        if !self.worker.is_up() {
            return;
        }
        let now = self.worker.now();
        let (budget, rate) = (self.budget, self.bit_rate);
        let mut spent: Option<Duration> = None;
        self.worker.write_queued(now, |len| {
            let wire = wire_time(len, rate);
            let total = spent.map_or(wire, |spent| spent.saturating_add(wire));
            let fits = spent.is_none() || total <= budget;
            if fits {
                spent = Some(total);
            }
            fits
        });
    }
}

/// Makes the port of a link the tick runs itself, and tries to open the link at once on
/// the calling thread (so the reason a link is not there yet is logged at start-up, not by
/// the tick; later attempts are the tick's, silent, with the I/O threads' backoff).
pub fn start(
    link: Box<dyn Link>,
    epoch: Duration,
    budget: Duration,
    bit_rate: Option<u32>,
) -> std::io::Result<LinkPort> {
    // Nobody sleeps on the port's waker and nothing stops a thread: there is none.
    let (mut port, mut worker) =
        super::port_and_worker(link, Arc::new(AtomicBool::new(false)), super::IDLE_WAIT)?;
    worker.set_epoch(epoch);
    let mut inline = Box::new(InlineIo {
        worker,
        budget,
        bit_rate,
        buf: [0; PACKET_LEN],
    });
    inline.look();
    port.inline = Some(inline);
    Ok(port)
}
