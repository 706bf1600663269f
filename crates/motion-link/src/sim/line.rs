//! Wire time on a simulated line, and what a UART at the wrong baud rate makes of it.

use core::time::Duration;

const NANOS_PER_SEC: u128 = 1_000_000_000;

/// One direction of a wire (or both, on a half-duplex pair): a transmitter that sends
/// `bits` at `rate` bits per second, one frame after the other.
///
/// Frame ends are computed from the start of the current busy period, so rounding never
/// accumulates: 9 frames of 10 bits at 19200 baud end exactly 4.6875 ms after the first
/// started.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Line {
    rate: u64,
    origin: Duration,
    bits: u64,
    free: Duration,
}

impl Line {
    pub(crate) fn new(rate: u64) -> Self {
        Self {
            rate: rate.max(1),
            origin: Duration::ZERO,
            bits: 0,
            free: Duration::ZERO,
        }
    }

    /// The bit rate.
    pub(crate) fn rate(&self) -> u64 {
        self.rate
    }

    /// When the line is next free.
    pub(crate) fn free_at(&self) -> Duration {
        self.free
    }

    /// Sends a frame of `bits` no earlier than `earliest`; returns its start and end.
    pub(crate) fn send(&mut self, earliest: Duration, bits: u64) -> (Duration, Duration) {
        if earliest > self.free {
            self.origin = earliest;
            self.bits = 0;
            self.free = earliest;
        }
        let start = self.free;
        self.bits = self.bits.saturating_add(bits);
        self.free = self.origin.saturating_add(bits_time(self.bits, self.rate));
        (start, self.free)
    }

    /// Carries the frames sent from now on at `rate` (a rate change after the line fell
    /// silent: what was sent stays timed as it was).
    pub(crate) fn retime(&mut self, rate: u64) {
        self.origin = self.free;
        self.bits = 0;
        self.rate = rate.max(1);
    }

    /// Forgets everything in flight (the wire was reset).
    pub(crate) fn reset(&mut self, now: Duration) {
        self.origin = now;
        self.bits = 0;
        self.free = now;
    }
}

/// The time `bits` take at `rate` bits per second, rounded up to the nanosecond.
pub(crate) fn bits_time(bits: u64, rate: u64) -> Duration {
    let nanos = (u128::from(bits) * NANOS_PER_SEC).div_ceil(u128::from(rate.max(1)));
    Duration::from_nanos(u64::try_from(nanos).unwrap_or(u64::MAX))
}

/// A byte as a receiving UART saw it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Received {
    /// When the receiver had the byte (the end of its stop bit at its own rate).
    pub(crate) at: Duration,
    pub(crate) byte: u8,
    /// The stop bit was sampled low.
    pub(crate) framing_error: bool,
}

/// What an 8N1 receiver at `rx_baud` makes of `bytes` sent back to back at `tx_baud`,
/// the first start bit beginning at `start`. The receiver hunts for a falling edge, samples
/// each bit in the middle of its own bit time, rejects a start bit that is high again by its
/// middle, and flags a low stop bit as a framing error.
pub(crate) fn resample(
    bytes: &[u8],
    start: Duration,
    tx_baud: u64,
    rx_baud: u64,
    mut out: impl FnMut(Received),
) {
    let tx = u128::from(tx_baud.max(1));
    let rx = u128::from(rx_baud.max(1));
    let total_bits = bytes.len() as u128 * 10;
    // Line level during transmitted bit `i` (idle high outside the burst).
    let level = |i: u128| -> bool {
        if i >= total_bits {
            return true;
        }
        let byte = bytes
            .get(usize::try_from(i / 10).unwrap_or(usize::MAX))
            .copied()
            .unwrap_or(0xFF);
        match i % 10 {
            0 => false,
            9 => true,
            bit => (byte >> (bit - 1)) & 1 == 1,
        }
    };
    // Transmitted bit index at `t` nanoseconds after `start`.
    let bit_at = |t: u128| t * tx / NANOS_PER_SEC;
    // Start of transmitted bit `i`, in nanoseconds after `start`.
    let edge_time = |i: u128| (i * NANOS_PER_SEC).div_ceil(tx);
    // Nanoseconds from a start edge to the middle of received bit `k` (k + 0.5 bits).
    let sample_offset = |k: u128| ((2 * k + 1) * NANOS_PER_SEC).div_ceil(2 * rx);
    let mut cursor: u128 = 0;
    let mut i = 0u128;
    while i < total_bits {
        // Find the next falling edge at or after `cursor`.
        i = i.max(bit_at(cursor));
        if edge_time(i) < cursor {
            i += 1;
        }
        let falling = |i: u128| !level(i) && (i == 0 || level(i - 1));
        while i < total_bits && !falling(i) {
            i += 1;
        }
        if i >= total_bits {
            break;
        }
        let edge = edge_time(i);
        let sample = |k: u128| level(bit_at(edge + sample_offset(k)));
        if sample(0) {
            // Glitch: high again by the middle of the start bit.
            cursor = edge + sample_offset(0);
            i += 1;
            continue;
        }
        let mut byte = 0u8;
        for k in 1..=8u128 {
            if sample(k) {
                byte |= 1 << (k - 1);
            }
        }
        let framing_error = !sample(9);
        let end = edge + (10 * NANOS_PER_SEC).div_ceil(rx);
        out(Received {
            at: start.saturating_add(Duration::from_nanos(u64::try_from(end).unwrap_or(u64::MAX))),
            byte,
            framing_error,
        });
        cursor = edge + sample_offset(9);
        i += 1;
    }
}

/// The bytes an 8N1 receiver at `rx_baud` takes from `bytes` sent back to back at
/// `tx_baud` ([`resample`]), without those it flags with a framing error (a UART's
/// firmware drops them): the bytes themselves at equal rates, garbage or nothing at others.
/// For device models that see a line at another rate than their own (a bus of boards
/// where one was switched to a new rate, a pty whose client set another rate).
pub fn garble(bytes: &[u8], tx_baud: u32, rx_baud: u32) -> Vec<u8> {
    if tx_baud == rx_baud {
        return bytes.to_vec();
    }
    let mut out = Vec::with_capacity(bytes.len() * 2);
    resample(
        bytes,
        Duration::ZERO,
        u64::from(tx_baud),
        u64::from(rx_baud),
        |r| {
            if !r.framing_error {
                out.push(r.byte);
            }
        },
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(bytes: &[u8], tx: u64, rx: u64) -> Vec<Received> {
        let mut v = Vec::new();
        resample(bytes, Duration::from_millis(1), tx, rx, |r| v.push(r));
        v
    }

    #[test]
    fn wire_time_of_nine_bytes_at_19200_is_4_6875_ms() {
        let mut line = Line::new(19_200);
        let t0 = Duration::from_millis(3);
        let mut end = t0;
        for _ in 0..9 {
            end = line.send(t0, 10).1;
        }
        assert_eq!(
            end - t0,
            Duration::from_micros(4_687) + Duration::from_nanos(500)
        );
        // An idle gap restarts the busy period.
        let (s, e) = line.send(t0 + Duration::from_secs(1), 10);
        assert_eq!(s, t0 + Duration::from_secs(1));
        assert_eq!(e - s, bits_time(10, 19_200));
    }

    #[test]
    fn same_rate_resamples_to_the_same_bytes() {
        let bytes: Vec<u8> = (0..=255).collect();
        let got = run(&bytes, 19_200, 19_200);
        assert_eq!(got.len(), 256);
        for (r, b) in got.iter().zip(&bytes) {
            assert_eq!(r.byte, *b);
            assert!(!r.framing_error);
        }
        let last = got.last().unwrap();
        assert_eq!(last.at, Duration::from_millis(1) + bits_time(2560, 19_200));
    }

    #[test]
    fn garble_keeps_bytes_at_one_rate_and_loses_a_trinamic_word_at_another() {
        let word = [0x01, 0x43, 0xFE, 0, 0, 0, 0, 0, 0];
        assert_eq!(garble(&word, 19_200, 19_200), word);
        for (tx, rx) in [(19_200, 115_200), (115_200, 19_200), (19_200, 57_600)] {
            let got = garble(&word, tx, rx);
            assert_ne!(got, word, "{tx} → {rx}: {got:02x?}");
        }
        // 2.5 % apart: a UART takes it.
        assert_eq!(garble(&word, 115_200, 113_636), word);
    }

    #[test]
    fn wrong_rate_garbles() {
        let bytes = b"R14\r\nR14\r\n";
        let slow = run(bytes, 9_600, 19_200);
        let fast = run(bytes, 38_400, 9_600);
        let decoded: Vec<u8> = slow.iter().map(|r| r.byte).collect();
        assert_ne!(decoded, bytes.to_vec());
        assert!(slow.iter().any(|r| r.framing_error) || fast.iter().any(|r| r.framing_error));
        assert!(fast.len() < bytes.len(), "a slow receiver misses frames");
    }
}
