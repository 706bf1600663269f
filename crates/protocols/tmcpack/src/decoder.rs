//! The incremental 9-byte word decoder for an RS-232 / RS-485 byte stream.
//!
//! The wire has no start byte and no checksum: a word is simply the next nine bytes. The
//! pack stays in step with the host in two ways only, both from manual 6.1, and this decoder
//! does exactly the same:
//!
//! - **packet timeout** ($41): "The command word always has to be completely transmitted
//!   during a parameterized timeout". A word whose ninth byte has not arrived within the
//!   timeout after its first byte is aborted and not interpreted; the next byte starts a new
//!   word. So an idle gap longer than the timeout always resynchronises.
//! - **break code**: "It will be aborted and not interpreted, when a break-code is received.
//!   If errors occur the interface can be newly synchronized via break-code." A byte stream
//!   cannot carry a break, so the owner of the UART calls [`FrameDecoder::line_break`].
//!
//! The manual gives no default for the $41 timeout; we use
//! [`DEFAULT_PACKET_TIMEOUT`] (10 × 2 ms = 20 ms): four times a word's 4.7 ms at 19200 baud,
//! yet shorter than a host's usual pause between requests. A word is complete when its last
//! byte arrives no later than `timeout` after its first. The decoder knows nothing of
//! addresses: every nine bytes make a word, whoever they were for, which is what keeps every
//! pack on a shared RS-485 bus in step with replies from the others.

use core::time::Duration;

use crate::{FRAME_LEN, Word};

/// Our default packet timeout (the manual is silent): 10 units of 2 ms.
pub const DEFAULT_PACKET_TIMEOUT: Duration = Duration::from_millis(20);

/// Counters of a [`FrameDecoder`].
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DecoderStats {
    /// Complete 9-byte words.
    pub words: u64,
    /// Partial words thrown away by the timeout or a break.
    pub aborted: u64,
    /// Bytes inside aborted words.
    pub aborted_bytes: u64,
    /// Breaks seen.
    pub breaks: u64,
}

/// Incremental decoder: push bytes with their arrival time, take complete words.
#[derive(Debug, Clone)]
pub struct FrameDecoder {
    word: Word,
    len: usize,
    first_at: Duration,
    timeout: Duration,
    byte_time: Duration,
    stats: DecoderStats,
}

impl FrameDecoder {
    /// A decoder with a packet timeout and the time one byte takes on the wire (10 bit
    /// times for 8N1), used to date the bytes of a chunk that arrived back to back.
    pub const fn new(timeout: Duration, byte_time: Duration) -> Self {
        Self {
            word: [0; FRAME_LEN],
            len: 0,
            first_at: Duration::ZERO,
            timeout,
            byte_time,
            stats: DecoderStats {
                words: 0,
                aborted: 0,
                aborted_bytes: 0,
                breaks: 0,
            },
        }
    }

    /// Changes the packet timeout (command $41).
    pub fn set_timeout(&mut self, timeout: Duration) {
        self.timeout = timeout;
    }

    /// Changes the byte time (command $40).
    pub fn set_byte_time(&mut self, byte_time: Duration) {
        self.byte_time = byte_time;
    }

    /// The packet timeout.
    pub const fn timeout(&self) -> Duration {
        self.timeout
    }

    /// Counters.
    pub const fn stats(&self) -> DecoderStats {
        self.stats
    }

    /// Bytes of the word being collected.
    pub const fn pending(&self) -> usize {
        self.len
    }

    /// When the partial word will be aborted unless completed, if one is pending.
    pub fn deadline(&self) -> Option<Duration> {
        (self.len > 0).then(|| self.first_at.saturating_add(self.timeout))
    }

    fn abort(&mut self) {
        if self.len > 0 {
            self.stats.aborted += 1;
            self.stats.aborted_bytes += self.len as u64;
            self.len = 0;
        }
    }

    /// Aborts a partial word whose timeout has passed at `now`; returns `true` if it did.
    pub fn poll(&mut self, now: Duration) -> bool {
        if self.len > 0 && now.saturating_sub(self.first_at) > self.timeout {
            self.abort();
            return true;
        }
        false
    }

    /// A break code was received: the partial word is aborted.
    pub fn line_break(&mut self) {
        self.stats.breaks += 1;
        self.abort();
    }

    /// Drops any partial word without counting it (e.g. at a reset).
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// One byte that arrived at `at`; returns the word it completes.
    pub fn push_byte(&mut self, at: Duration, byte: u8) -> Option<Word> {
        self.poll(at);
        if self.len == 0 {
            self.first_at = at;
        }
        if let Some(slot) = self.word.get_mut(self.len) {
            *slot = byte;
        }
        self.len += 1;
        if self.len >= FRAME_LEN {
            self.len = 0;
            self.stats.words += 1;
            return Some(self.word);
        }
        None
    }

    /// Bytes that finished arriving at `now`, back to back (the last at `now`, each earlier
    /// one a byte time before). Iterate the result to the end for the words they complete:
    /// bytes are consumed only as the iterator is driven.
    #[must_use = "bytes are consumed only as the returned iterator is driven"]
    pub fn push<'a>(&'a mut self, now: Duration, bytes: &'a [u8]) -> Words<'a> {
        Words {
            decoder: self,
            bytes,
            index: 0,
            now,
        }
    }
}

/// The words completed by one [`FrameDecoder::push`].
#[derive(Debug)]
#[must_use = "bytes are consumed only as the iterator is driven"]
pub struct Words<'a> {
    decoder: &'a mut FrameDecoder,
    bytes: &'a [u8],
    index: usize,
    now: Duration,
}

impl Iterator for Words<'_> {
    type Item = Word;

    fn next(&mut self) -> Option<Word> {
        while let Some(&b) = self.bytes.get(self.index) {
            let behind = (self.bytes.len() - 1 - self.index) as u32;
            let at = self
                .now
                .saturating_sub(self.decoder.byte_time.saturating_mul(behind));
            self.index += 1;
            if let Some(w) = self.decoder.push_byte(at, b) {
                return Some(w);
            }
        }
        None
    }
}
