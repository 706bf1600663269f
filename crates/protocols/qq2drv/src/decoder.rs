//! Incremental decoder for the byte stream clocked out on MISO.
//!
//! The slave clocks filler while it has nothing to say, so the decoder skips everything up
//! to an STX, then checks the id (a documented one), the size (possible for that id, see
//! [`PacketId::max_packet_len`]) and the checksum. A failed candidate is dropped one byte at a time, so a real packet hidden
//! inside garbage is still found (resync one byte after the false STX).

use crate::frame::{MAX_PACKET_LEN, MIN_PACKET_LEN, PacketBuf, PacketId, STX, checksum};

const CAPACITY: usize = 2 * MAX_PACKET_LEN;

/// Counters of what the decoder has seen.
#[derive(
    serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Hash, Default,
)]
pub struct DecoderStats {
    /// Valid packets returned.
    pub packets: u64,
    /// Bytes skipped while looking for STX (filler, noise).
    pub skipped: u64,
    /// Candidates rejected for an impossible Packet Size (below 4, or outside what the id
    /// allows).
    pub bad_size: u64,
    /// Candidates rejected for an undocumented Packet ID.
    pub bad_id: u64,
    /// Candidates rejected for a wrong checksum.
    pub bad_checksum: u64,
}

impl DecoderStats {
    /// All rejected candidates (size, id and checksum failures).
    pub const fn bad_packets(&self) -> u64 {
        self.bad_size + self.bad_id + self.bad_checksum
    }
}

/// Push bytes in, take whole packets out. Fixed 510-byte buffer, no allocation.
#[derive(serde::Serialize, serde::Deserialize, Clone)]
pub struct StreamDecoder {
    #[serde(with = "serde_big_array::BigArray")]
    buf: [u8; CAPACITY],
    start: usize,
    end: usize,
    stats: DecoderStats,
}

impl Default for StreamDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl core::fmt::Debug for StreamDecoder {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("StreamDecoder")
            .field("buffered", &self.buffered())
            .field("stats", &self.stats)
            .finish()
    }
}

impl StreamDecoder {
    /// An empty decoder.
    pub const fn new() -> Self {
        Self {
            buf: [0; CAPACITY],
            start: 0,
            end: 0,
            stats: DecoderStats {
                packets: 0,
                skipped: 0,
                bad_size: 0,
                bad_id: 0,
                bad_checksum: 0,
            },
        }
    }

    /// Copies as many of `bytes` as fit; returns how many were taken. Call
    /// [`next_packet`](Self::next_packet) until it returns `None` before pushing the rest:
    /// that always frees room.
    pub fn push(&mut self, bytes: &[u8]) -> usize {
        if self.start > 0 {
            self.buf.copy_within(self.start..self.end, 0);
            self.end -= self.start;
            self.start = 0;
        }
        let free = self.buf.get_mut(self.end..).unwrap_or_default();
        let n = free.len().min(bytes.len());
        if let (Some(dst), Some(src)) = (free.get_mut(..n), bytes.get(..n)) {
            dst.copy_from_slice(src);
        }
        self.end += n;
        n
    }

    /// The next valid packet in the buffered bytes, or `None` when more bytes are needed.
    pub fn next_packet(&mut self) -> Option<PacketBuf> {
        loop {
            let pending = self.buf.get(self.start..self.end).unwrap_or_default();
            let Some(stx_at) = pending.iter().position(|b| *b == STX) else {
                self.stats.skipped += pending.len() as u64;
                self.start = self.end;
                return None;
            };
            self.stats.skipped += stx_at as u64;
            self.start += stx_at;
            let pending = self.buf.get(self.start..self.end).unwrap_or_default();
            let &size = pending.get(1)?;
            let size = usize::from(size);
            if size < MIN_PACKET_LEN {
                self.stats.bad_size += 1;
                self.start += 1;
                continue;
            }
            let &id = pending.get(2)?;
            let Ok(id) = PacketId::try_from(id) else {
                self.stats.bad_id += 1;
                self.start += 1;
                continue;
            };
            if !(id.min_packet_len()..=id.max_packet_len()).contains(&size) {
                self.stats.bad_size += 1;
                self.start += 1;
                continue;
            }
            let Some(packet) = pending.get(..size) else {
                if self.end - self.start >= MAX_PACKET_LEN {
                    // Cannot happen (size ≤ 255 always fits); drop a byte rather than stall.
                    self.start += 1;
                    continue;
                }
                return None;
            };
            if checksum(packet) != 0 {
                self.stats.bad_checksum += 1;
                self.start += 1;
                continue;
            }
            let out = PacketBuf::copy_from(packet);
            self.start += size;
            if out.is_some() {
                self.stats.packets += 1;
            }
            return out;
        }
    }

    /// Feeds `input` and calls `on_packet` for every packet completed.
    pub fn feed(&mut self, mut input: &[u8], mut on_packet: impl FnMut(PacketBuf)) {
        loop {
            let n = self.push(input);
            input = input.get(n..).unwrap_or_default();
            while let Some(p) = self.next_packet() {
                on_packet(p);
            }
            if input.is_empty() {
                return;
            }
        }
    }

    /// Bytes held waiting for the rest of a packet.
    pub fn buffered(&self) -> usize {
        self.end - self.start
    }

    /// When the bytes pushed so far (with every complete packet taken out by
    /// [`next_packet`](Self::next_packet)) end inside a packet: how many more bytes it
    /// needs at least — its exact rest once its Packet Size arrived, else the rest of the
    /// longest packet. `None` between packets.
    pub fn missing(&self) -> Option<usize> {
        let pending = self.buf.get(self.start..self.end).unwrap_or_default();
        if pending.first() != Some(&STX) {
            return None;
        }
        let size = pending
            .get(1)
            .map_or(MAX_PACKET_LEN, |size| usize::from(*size));
        Some(size.saturating_sub(pending.len()).max(1))
    }

    /// Counters so far.
    pub const fn stats(&self) -> DecoderStats {
        self.stats
    }

    /// Drops buffered bytes (e.g. after a link reset); counters are kept.
    pub fn clear(&mut self) {
        self.start = 0;
        self.end = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::StreamDecoder;

    #[test]
    fn false_stx_inside_garbage_resyncs_one_byte_later() {
        // STX, size 8, id 1 … but the checksum is wrong; a real packet starts inside it.
        let mut d = StreamDecoder::new();
        d.push(&[2, 8, 1, 2, 4, 1, 249, 0]);
        let p = d.next_packet().expect("the embedded packet");
        assert_eq!(p.as_bytes(), &[2, 4, 1, 249]);
        assert_eq!(d.stats().bad_checksum, 1);
    }

    #[test]
    fn impossible_size_and_unknown_id_are_counted() {
        let mut d = StreamDecoder::new();
        d.push(&[2, 3, 9, 2, 5, 15, 0, 0, 2, 4, 1, 249]);
        assert!(d.next_packet().is_some());
        assert_eq!(d.stats().bad_size, 1);
        assert_eq!(d.stats().bad_id, 1);
    }

    #[test]
    fn a_size_impossible_for_the_id_is_rejected_without_waiting() {
        // Packet 1 is never longer than 8 bytes: STX 200 1 is rejected at once.
        let mut d = StreamDecoder::new();
        d.push(&[2, 200, 1, 0, 0, 2, 4, 1, 249]);
        assert_eq!(d.next_packet().map(|p| p.frame().id), Some(1));
        assert_eq!(d.stats().bad_size, 1);
    }

    #[test]
    fn waits_for_the_rest_of_a_packet() {
        let mut d = StreamDecoder::new();
        assert_eq!(d.missing(), None);
        d.push(&[0, 0, 2]);
        assert!(d.next_packet().is_none());
        assert_eq!(
            d.missing(),
            Some(254),
            "size not known yet: up to the longest"
        );
        d.push(&[8, 1, 0]);
        assert!(d.next_packet().is_none());
        assert_eq!(d.buffered(), 4);
        assert_eq!(d.missing(), Some(4));
        d.push(&[0, 1, 0, 244]);
        assert!(d.next_packet().is_some());
        assert_eq!(d.buffered(), 0);
        assert_eq!(d.missing(), None);
    }

    #[test]
    fn push_never_overflows() {
        let mut d = StreamDecoder::new();
        let junk = [7u8; 2000];
        let mut total = 0;
        let mut rest = &junk[..];
        while !rest.is_empty() {
            let n = d.push(rest);
            total += n;
            rest = &rest[n..];
            assert!(d.next_packet().is_none());
        }
        assert_eq!(total, 2000);
        assert_eq!(d.stats().skipped, 2000);
    }
}
