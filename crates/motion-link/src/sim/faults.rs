//! Fault injection on a simulated wire, driven from a test while the link is in use.

use core::time::Duration;
use std::collections::VecDeque;
use std::sync::{Arc, Mutex, MutexGuard};

/// Which way a fault acts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Direction {
    /// Bytes from the device (or bus) to the host: replies, MISO.
    ToHost,
    /// Bytes from the host to the device: requests, MOSI.
    ToDevice,
}

/// A small deterministic generator (SplitMix64) for seeded noise.
#[derive(Debug, Clone)]
pub(crate) struct Noise(u64);

impl Noise {
    pub(crate) fn new(seed: u64) -> Self {
        Self(seed)
    }

    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A uniform draw in `[0, 1)`.
    pub(crate) fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[derive(Debug)]
pub(crate) struct FaultState {
    pub(crate) noise: Noise,
    pub(crate) garbage: VecDeque<u8>,
    pub(crate) drop_count: [u64; 2],
    pub(crate) drop_probability: [f64; 2],
    pub(crate) dropped: [u64; 2],
    pub(crate) reply_delay: Duration,
    pub(crate) unplugged: bool,
    /// Incremented by every unplug: a link opened before it is dead until reopened.
    pub(crate) generation: u64,
    pub(crate) device_baud: Option<u32>,
    /// Holds ([`SimFaults::hold`]): `(from, until)`, bytes due at the host in between wait
    /// until `until`.
    pub(crate) holds: Vec<(Duration, Duration)>,
}

impl FaultState {
    /// Whether the next byte going `dir` is lost.
    pub(crate) fn drops(&mut self, dir: Direction) -> bool {
        let i = dir as usize;
        let (Some(count), Some(p)) = (self.drop_count.get_mut(i), self.drop_probability.get(i))
        else {
            return false;
        };
        let lost = if *count > 0 {
            *count -= 1;
            true
        } else {
            *p > 0.0 && self.noise.unit() < *p
        };
        if lost && let Some(d) = self.dropped.get_mut(i) {
            *d += 1;
        }
        lost
    }

    /// When a byte due at the host at `at` reaches it: at the end of every hold whose
    /// window `at` falls in (holds that follow one another chain).
    pub(crate) fn held(&self, mut at: Duration) -> Duration {
        for _ in 0..=self.holds.len() {
            let Some(until) = self
                .holds
                .iter()
                .filter(|(from, until)| *from <= at && at < *until)
                .map(|(_, until)| *until)
                .max()
            else {
                break;
            };
            at = until;
        }
        at
    }
}

/// A handle on the faults of one [`SimLink`](crate::sim::SimLink). Clone it, keep it in the
/// test, and change the wire while the link is in use (from any thread). Every random
/// choice comes from the link's seed, so a run is reproducible.
#[derive(Debug, Clone)]
pub struct SimFaults(Arc<Mutex<FaultState>>);

impl SimFaults {
    pub(crate) fn new(seed: u64) -> Self {
        Self(Arc::new(Mutex::new(FaultState {
            noise: Noise::new(seed),
            garbage: VecDeque::new(),
            drop_count: [0; 2],
            drop_probability: [0.0; 2],
            dropped: [0; 2],
            reply_delay: Duration::ZERO,
            unplugged: false,
            generation: 0,
            device_baud: None,
            holds: Vec::new(),
        })))
    }

    pub(crate) fn lock(&self) -> MutexGuard<'_, FaultState> {
        self.0
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// Puts `bytes` on the wire towards the host, ahead of anything the device sends next.
    /// They take wire time like any other byte. On an SPI link they replace the next MISO
    /// bytes instead (a corrupted transfer).
    pub fn inject_garbage(&self, bytes: &[u8]) {
        self.lock().garbage.extend(bytes.iter().copied());
    }

    /// Like [`inject_garbage`](Self::inject_garbage) with `count` seeded random bytes.
    pub fn inject_noise(&self, count: usize) {
        let mut state = self.lock();
        for _ in 0..count {
            let byte = state.noise.next_u64().to_le_bytes()[0];
            state.garbage.push_back(byte);
        }
    }

    /// Loses the next `count` bytes going `dir`. On an SPI link a lost MISO byte reads as
    /// 0xFF (nobody drove the line) and a lost MOSI byte reaches the device as 0xFF.
    pub fn drop_next(&self, dir: Direction, count: u64) {
        if let Some(c) = self.lock().drop_count.get_mut(dir as usize) {
            *c += count;
        }
    }

    /// Loses each byte going `dir` with probability `p` (clamped to 0..=1).
    pub fn set_drop_probability(&self, dir: Direction, p: f64) {
        if let Some(slot) = self.lock().drop_probability.get_mut(dir as usize) {
            *slot = if p.is_nan() { 0.0 } else { p.clamp(0.0, 1.0) };
        }
    }

    /// How many bytes going `dir` were lost so far.
    pub fn dropped(&self, dir: Direction) -> u64 {
        self.lock().dropped.get(dir as usize).copied().unwrap_or(0)
    }

    /// Holds every device transmission back by `delay` before it starts on the wire
    /// (stream links; an SPI device answers within its own transactions).
    pub fn set_reply_delay(&self, delay: Duration) {
        self.lock().reply_delay = delay;
    }

    /// Holds the host's side of the wire: every byte from the device (a reply, a streamed
    /// line, MISO) that would reach the host at or after `from` and before `from + length`
    /// reaches it at `from + length` instead, in order, together with those held with it;
    /// bytes due earlier or later are not touched. What a host (or a board's process
    /// serving a pty or an SPI socket) that got no CPU for `length` does to the bytes: the
    /// board's side of the wire keeps its own timing, the host sees nothing, then
    /// everything at once. Several holds may be set; one ending inside another extends it.
    pub fn hold(&self, from: Duration, length: Duration) {
        if length.is_zero() {
            return;
        }
        self.lock().holds.push((from, from.saturating_add(length)));
    }

    /// Pulls the plug: every call on the link returns `Disconnected`, bytes in flight are
    /// lost, and the link stays dead until [`replug`](Self::replug) *and* a reopen.
    pub fn unplug(&self) {
        let mut state = self.lock();
        state.unplugged = true;
        state.generation += 1;
    }

    /// Plugs the device back in; the link recovers on its next reopen.
    pub fn replug(&self) {
        self.lock().unplugged = false;
    }

    /// Whether the plug is out.
    pub fn is_unplugged(&self) -> bool {
        self.lock().unplugged
    }

    /// Makes the device listen and talk at `baud` whatever the model says (`None`: the
    /// model's own rate, or the link's). A mismatch with the link's rate garbles bytes both
    /// ways, as a real UART at the wrong rate would, including framing errors.
    pub fn set_device_baud(&self, baud: Option<u32>) {
        self.lock().device_baud = baud;
    }
}

/// What a simulated link knows of its plug, and the one rule every simulated link keeps:
/// connected while the plug is in and was not pulled since the link was (re)opened; after a
/// pull every operation fails until the link is reopened, and reopening fails while the plug
/// is out — as a USB adapter's tty does.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Plug {
    /// The fault generation the link was opened in; `None` once it saw a disconnection.
    generation: Option<u64>,
}

/// Why a simulated link is not connected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Unplugged {
    /// The plug is out now.
    Now,
    /// The plug was pulled (and maybe put back) since the link was opened: reopen it.
    Since,
}

impl Plug {
    /// Opened with fresh faults.
    pub(crate) const OPEN: Self = Self {
        generation: Some(0),
    };

    /// Whether the link has not seen a disconnection since it was opened.
    pub(crate) fn connected(self) -> bool {
        self.generation.is_some()
    }

    /// Whether the plug is out or was pulled since the link was opened (the link has
    /// something to report now).
    pub(crate) fn changed(self, state: &FaultState) -> bool {
        state.unplugged || self.generation != Some(state.generation)
    }

    /// `Ok` while connected; otherwise why, and whether the link was connected until now
    /// (then the bytes it had in flight are lost).
    pub(crate) fn check(&mut self, faults: &SimFaults) -> Result<(), (Unplugged, bool)> {
        let (unplugged, generation) = {
            let state = faults.lock();
            (state.unplugged, state.generation)
        };
        if !unplugged && self.generation == Some(generation) {
            return Ok(());
        }
        let was_connected = self.generation.take().is_some();
        let why = if unplugged {
            Unplugged::Now
        } else {
            Unplugged::Since
        };
        Err((why, was_connected))
    }

    /// Connects again in the current generation; `Err` while the plug is out.
    pub(crate) fn reconnect(&mut self, faults: &SimFaults) -> Result<(), Unplugged> {
        let state = faults.lock();
        if state.unplugged {
            return Err(Unplugged::Now);
        }
        self.generation = Some(state.generation);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pulled_plug_needs_a_replug_and_a_reopen() {
        let faults = SimFaults::new(1);
        let mut plug = Plug::OPEN;
        assert_eq!(plug.check(&faults), Ok(()));
        faults.unplug();
        // The first look loses what was in flight; later ones only fail.
        assert_eq!(plug.check(&faults), Err((Unplugged::Now, true)));
        assert_eq!(plug.check(&faults), Err((Unplugged::Now, false)));
        assert!(!plug.connected());
        assert_eq!(plug.reconnect(&faults), Err(Unplugged::Now));
        faults.replug();
        // Plugged back in, but not reopened: the link must not carry on as if nothing
        // happened.
        assert_eq!(plug.check(&faults), Err((Unplugged::Since, false)));
        assert_eq!(plug.reconnect(&faults), Ok(()));
        assert_eq!(plug.check(&faults), Ok(()));
        assert!(plug.connected());
        // A pull and a replug while the link was not looking: it notices.
        faults.unplug();
        faults.replug();
        assert!(plug.changed(&faults.lock()));
        assert_eq!(plug.check(&faults), Err((Unplugged::Since, true)));
    }
}
