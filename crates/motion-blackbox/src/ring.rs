//! The recorder's ring: one byte buffer allocated (and touched) at start, holding the
//! newest ticks' records back to back, wrapping at its end, and an index of the ticks in
//! it. Its memory never grows: a tick begins by dropping the oldest beyond the tick count,
//! and bytes that do not fit drop the oldest ticks until they do. The start-up records
//! (before the first tick) are kept apart, for good.

use std::borrow::Cow;
use std::collections::VecDeque;

use super::file::Ticks;
use super::record::{HEADER_LEN, Kind, Trigger, records};

/// The least the ring holds, whatever the tick count.
pub const MIN_RING_BYTES: usize = 1 << 20;

/// A tick in the ring: its journal number, where its bytes start, how many.
#[derive(Debug, Clone, Copy)]
struct Held {
    tick: u64,
    start: usize,
    len: usize,
}

/// The ring and the drained bytes not yet split into records.
#[derive(Debug)]
pub struct Ring {
    /// Records before the first tick (the start).
    head: Vec<u8>,
    buf: Vec<u8>,
    /// Where the next byte goes.
    write: usize,
    /// Bytes held.
    used: usize,
    ticks: VecDeque<Held>,
    keep: usize,
    /// Drained bytes that do not make a whole record yet.
    partial: Vec<u8>,
    /// Triggers seen since the last take.
    triggers: Vec<(Trigger, u32)>,
    /// Records dropped because one tick outgrew the whole ring; the next tick starts with
    /// a `Lost` record saying how many.
    lost: u64,
    /// Ticks dropped from the front (the ring wrapped).
    pub dropped: u64,
}

impl Ring {
    /// A ring of `bytes` (at least [`MIN_RING_BYTES`]) keeping at most `keep` ticks.
    pub fn new(keep: usize, bytes: usize) -> Self {
        let keep = keep.max(1);
        Self {
            head: Vec::new(),
            // Zeroed by writing: the pages are resident from the start, so the server's
            // memory does not grow while the ring fills.
            buf: vec![1u8; bytes.max(MIN_RING_BYTES)],
            write: 0,
            used: 0,
            ticks: VecDeque::with_capacity(keep.min(1 << 20) + 1),
            keep,
            partial: Vec::new(),
            triggers: Vec::new(),
            lost: 0,
            dropped: 0,
        }
    }

    /// Ticks held.
    pub fn len(&self) -> usize {
        self.ticks.len()
    }

    /// Whether no tick is held.
    pub fn is_empty(&self) -> bool {
        self.ticks.is_empty()
    }

    fn drop_oldest(&mut self) {
        if let Some(old) = self.ticks.pop_front() {
            self.used -= old.len;
            self.dropped += 1;
        }
    }

    /// Appends `bytes` to the newest tick, dropping the oldest ticks for room; `false`
    /// when even the whole ring cannot hold that tick.
    fn append(&mut self, bytes: &[u8]) -> bool {
        let capacity = self.buf.len();
        let current = self.ticks.back().map_or(0, |held| held.len);
        if current + bytes.len() > capacity {
            return false;
        }
        while capacity - self.used < bytes.len() && self.ticks.len() > 1 {
            self.drop_oldest();
        }
        let first = bytes.len().min(capacity - self.write);
        self.buf[self.write..self.write + first].copy_from_slice(&bytes[..first]);
        self.buf[..bytes.len() - first].copy_from_slice(&bytes[first..]);
        self.write = (self.write + bytes.len()) % capacity;
        self.used += bytes.len();
        if let Some(held) = self.ticks.back_mut() {
            held.len += bytes.len();
        }
        true
    }

    /// Begins tick `tick` (journal number); its `Tick` record is appended next.
    fn begin(&mut self, tick: u64) {
        self.ticks.push_back(Held {
            tick,
            start: self.write,
            len: 0,
        });
        while self.ticks.len() > self.keep {
            self.drop_oldest();
        }
    }

    /// After a tick's first record: a `Lost` record if records were dropped.
    fn note_lost(&mut self) {
        if self.lost > 0 {
            let mut record = [0u8; HEADER_LEN + 8];
            record[0] = Kind::Lost as u8;
            record[2..6].copy_from_slice(&8u32.to_le_bytes());
            record[HEADER_LEN..].copy_from_slice(&self.lost.to_le_bytes());
            if self.append(&record) {
                self.lost = 0;
            }
        }
    }

    /// Takes in drained journal bytes.
    pub fn push(&mut self, bytes: &[u8]) {
        self.partial.extend_from_slice(bytes);
        let mut used = 0;
        let mut partial = std::mem::take(&mut self.partial);
        while let Some(header) = partial.get(used..used + HEADER_LEN) {
            let len = u32::from_le_bytes([header[2], header[3], header[4], header[5]]) as usize;
            let end = used + HEADER_LEN + len;
            if end > partial.len() {
                break;
            }
            let record = &partial[used..end];
            match Kind::from_u8(header[0]) {
                Some(Kind::Tick) => {
                    let tick = records(record)
                        .next()
                        .and_then(Result::ok)
                        .map_or(0, |record| record.u64_at(8));
                    self.begin(tick);
                    if !self.append(record) {
                        self.lost += 1;
                    }
                    self.note_lost();
                    used = end;
                    continue;
                }
                Some(Kind::Trigger) => {
                    let payload = &record[HEADER_LEN..];
                    let why = match payload.first() {
                        Some(2) => Trigger::Estop,
                        _ => Trigger::Fault,
                    };
                    let axis = payload
                        .get(1..5)
                        .map_or(u32::MAX, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
                    self.triggers.push((why, axis));
                }
                _ => {}
            }
            if self.ticks.is_empty() {
                self.head.extend_from_slice(record);
            } else if !self.append(record) {
                self.lost += 1;
            }
            used = end;
        }
        partial.drain(..used);
        self.partial = partial;
    }

    /// The triggers seen since the last call.
    pub fn take_triggers(&mut self) -> Vec<(Trigger, u32)> {
        std::mem::take(&mut self.triggers)
    }

    /// The ring as the file writes it (a tick that wraps at the buffer's end is copied).
    pub fn ticks(&self) -> Ticks<'_> {
        let capacity = self.buf.len();
        let ticks = self
            .ticks
            .iter()
            .map(|held| {
                let end = held.start + held.len;
                let bytes = if end <= capacity {
                    Cow::Borrowed(&self.buf[held.start..end])
                } else {
                    let mut joined = self.buf[held.start..].to_vec();
                    joined.extend_from_slice(&self.buf[..end - capacity]);
                    Cow::Owned(joined)
                };
                (held.tick, bytes)
            })
            .collect();
        Ticks {
            head: &self.head,
            ticks,
            dropped: self.dropped,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(kind: Kind, payload: &[u8]) -> Vec<u8> {
        let mut bytes = vec![kind as u8, 0];
        bytes.extend_from_slice(&(payload.len() as u32).to_le_bytes());
        bytes.extend_from_slice(payload);
        bytes
    }

    fn tick(n: u64) -> Vec<u8> {
        let mut payload = (n * 1_000_000).to_le_bytes().to_vec();
        payload.extend_from_slice(&n.to_le_bytes());
        record(Kind::Tick, &payload)
    }

    fn held(ring: &Ring) -> Vec<(u64, Vec<u8>)> {
        ring.ticks()
            .ticks
            .into_iter()
            .map(|(tick, bytes)| (tick, bytes.into_owned()))
            .collect()
    }

    #[test]
    fn the_ring_keeps_the_start_and_the_last_ticks_from_bytes_split_anywhere() {
        let mut journal = record(Kind::Start, &[0; 16]);
        for n in 0..10 {
            journal.extend(tick(n));
            journal.extend(record(Kind::LinkRx, &[1, 2, 3]));
        }
        journal.extend(record(Kind::Trigger, &[2, 4, 0, 0, 0]));
        let mut ring = Ring::new(4, 0);
        // Fed in pieces of 7 bytes: records cut in the middle wait for their rest.
        for piece in journal.chunks(7) {
            ring.push(piece);
        }
        let ticks = ring.ticks();
        assert_eq!(ticks.head, record(Kind::Start, &[0; 16]).as_slice());
        assert_eq!(ticks.dropped, 6);
        let kept: Vec<u64> = held(&ring).iter().map(|(tick, _)| *tick).collect();
        assert_eq!(kept, [6, 7, 8, 9]);
        let mut last = tick(9);
        last.extend(record(Kind::LinkRx, &[1, 2, 3]));
        last.extend(record(Kind::Trigger, &[2, 4, 0, 0, 0]));
        assert_eq!(held(&ring)[3].1, last);
        assert_eq!(ring.take_triggers(), [(Trigger::Estop, 4)]);
        assert!(ring.take_triggers().is_empty());
    }

    #[test]
    fn a_full_ring_wraps_keeps_whole_ticks_in_order_and_never_grows() {
        let mut ring = Ring::new(usize::MAX, 0);
        let capacity = ring.buf.len();
        let payload = vec![7u8; 1000];
        let mut expected = Vec::new();
        for n in 0..5000u64 {
            let mut bytes = tick(n);
            bytes.extend(record(Kind::LinkRx, &payload[..(n % 900) as usize]));
            ring.push(&bytes);
            expected.push((n, bytes));
        }
        assert_eq!(ring.buf.len(), capacity, "the buffer never grows");
        let kept = held(&ring);
        assert!(kept.len() < 5000 && ring.dropped > 0);
        assert_eq!(kept.len() as u64 + ring.dropped, 5000);
        assert!(ring.used <= capacity);
        // The newest ticks, whole and in order, one of them wrapped at the buffer's end.
        let newest = &expected[expected.len() - kept.len()..];
        assert_eq!(kept, newest);
        for (tick, bytes) in &kept {
            assert_eq!(records(bytes).count(), 2, "tick {tick}");
        }
    }

    #[test]
    fn a_tick_larger_than_the_ring_loses_records_and_says_so() {
        let mut ring = Ring::new(10, 0);
        let big = vec![0u8; MIN_RING_BYTES];
        ring.push(&tick(0));
        ring.push(&record(Kind::LinkRx, &big));
        ring.push(&tick(1));
        let kept = held(&ring);
        assert_eq!(kept.len(), 2);
        let lost: Vec<_> = records(&kept[1].1).filter_map(Result::ok).collect();
        assert_eq!(lost[0].kind, Kind::Tick);
        assert_eq!((lost[1].kind, lost[1].u64_at(0)), (Kind::Lost, 1));
    }
}
