//! The black box's records: every input the tick hands the engine, in the order it hands
//! them, and what came out (the bytes for each link, the replies, a digest of the frame).
//!
//! A record is a 6-byte header — kind (`u8`), link (`u8`), payload length (`u32`,
//! little-endian) — and its payload. Numbers are little-endian. A shared-memory payload
//! (a command, its reply, a path, a setpoint) is written sparse: the `(offset: u32,
//! bits: u64)` of every number that is not all-zero bits, in memory order, walked with
//! [`Fields`] — a path of 400 KiB whose line uses a dozen numbers takes a dozen entries.
//!
//! Encoding writes into caller-given memory and decoding reads borrowed bytes: nothing
//! here allocates, so the tick can record.

use motion_ipc::ClientId;
use motion_ipc::schema::{Fields, each_number, from_numbers};

/// Bytes of a record's header.
pub const HEADER_LEN: usize = 6;

/// What a record holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum Kind {
    /// The server started: `epoch_ns: u64` (CLOCK_MONOTONIC at start), `links: u32`.
    Start = 1,
    /// A tick begins: `now_ns: u64` (the engine's time), `number: u64` (ticks journaled
    /// before it: 0 for the server's first).
    Tick = 2,
    /// The link went down (its generation ends).
    LinkDown = 3,
    /// The link is up.
    LinkUp = 4,
    /// The link's I/O thread wrote a queued message: `at_ns: u64`.
    LinkWritten = 5,
    /// Bytes the link received: `at_ns: u64` (the I/O thread's stamp), then the bytes.
    LinkRx = 6,
    /// The link was read up to `heard_ns: u64`.
    LinkHeard = 7,
    /// A client node died: `client: ClientId` (16 bytes).
    ClientDead = 8,
    /// The e-stop event or SIGUSR1 latched the e-stop: `by: u8` (1 event, 2 SIGUSR1).
    Estop = 9,
    /// A departed client's claims end: `client`.
    ReleaseClaims = 10,
    /// The shutdown stop began.
    Shutdown = 11,
    /// A streamed setpoint: `sender`, `received_ns: u64`, the sparse `Setpoint`.
    Setpoint = 12,
    /// The step begins (the engine takes commands from here on).
    Step = 13,
    /// A request the engine took: `sender`, the sparse `CommandRequest`.
    Request = 14,
    /// A path the engine took: `client`, `id: u64`, the sparse `GroupPath`.
    Path = 15,
    /// The engine asked for a path that was not there: `client`, `id: u64`.
    NoPath = 16,
    /// The engine's reply: the sparse `CommandReply`.
    Reply = 17,
    /// The frame's digest: one `u64` per region (see `digest`).
    Frame = 18,
    /// A message the engine queued for the link: the bytes.
    LinkTx = 19,
    /// The engine had nothing more for the link this tick.
    LinkTxNone = 20,
    /// Missed deadlines skipped: `ticks: u64`.
    Skip = 21,
    /// Too many consecutive overruns: every axis stopped with the `Overrun` fault.
    OverrunFault = 22,
    /// Records the recorder lost (its queue was full): `count: u64`. The journal has a
    /// hole here: a replay cannot cross it.
    Lost = 23,
    /// Something to save the black box for: `reason: u8` ([`Trigger`]), `axis: u32`.
    Trigger = 24,
    /// The link is handed to its I/O thread closed (its boards start once it is up).
    LinkOpening = 25,
    /// The engine's state (drivers included) between the tick before and this one,
    /// serialized with postcard: where a replay of a ring that wrapped begins.
    Snapshot = 26,
    /// Start-up handed a driver a reference a previous run saved: `device: u64`,
    /// `channel: u64`, `counts: i64` (before the first tick; a replay hands it the same).
    RestoredReference = 27,
    /// The engine asked for the link's line rate to change before the message just
    /// queued (`Engine::take_link_rate`): `baud: u64`.
    LinkRate = 28,
}

impl Kind {
    /// The kind of byte `value`.
    pub fn from_u8(value: u8) -> Option<Self> {
        use Kind::*;
        const ALL: [Kind; 28] = [
            Start,
            Tick,
            LinkDown,
            LinkUp,
            LinkWritten,
            LinkRx,
            LinkHeard,
            ClientDead,
            Estop,
            ReleaseClaims,
            Shutdown,
            Setpoint,
            Step,
            Request,
            Path,
            NoPath,
            Reply,
            Frame,
            LinkTx,
            LinkTxNone,
            Skip,
            OverrunFault,
            Lost,
            Trigger,
            LinkOpening,
            Snapshot,
            RestoredReference,
            LinkRate,
        ];
        ALL.into_iter().find(|kind| *kind as u8 == value)
    }
}

/// Why a [`Kind::Trigger`] record asks for a save.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum Trigger {
    /// An axis faulted.
    Fault = 1,
    /// The e-stop latched.
    Estop = 2,
}

/// Writes into memory that may be split in two (a ring's free space).
#[derive(Debug)]
pub struct SplitWriter<'a> {
    first: &'a mut [u8],
    second: &'a mut [u8],
    at: usize,
}

impl<'a> SplitWriter<'a> {
    /// A writer over `first` then `second`.
    pub fn new(first: &'a mut [u8], second: &'a mut [u8]) -> Self {
        Self {
            first,
            second,
            at: 0,
        }
    }

    /// Appends `bytes`; what does not fit is dropped (the caller sized the memory).
    pub fn put(&mut self, bytes: &[u8]) {
        for &byte in bytes {
            let first = self.first.len();
            let slot = if self.at < first {
                self.first.get_mut(self.at)
            } else {
                self.second.get_mut(self.at - first)
            };
            if let Some(slot) = slot {
                *slot = byte;
            }
            self.at += 1;
        }
    }

    /// Bytes written.
    pub fn written(&self) -> usize {
        self.at
    }
}

/// Bytes of `value` written sparse.
pub fn sparse_len<T: Fields>(value: &T) -> usize {
    let mut entries = 0;
    each_number(value, |_, bits| entries += usize::from(bits != 0));
    entries * 12
}

/// Writes `value` sparse: an `(offset: u32, bits: u64)` entry for each non-zero number.
pub fn put_sparse<T: Fields>(writer: &mut SplitWriter<'_>, value: &T) {
    each_number(value, |at, bits| {
        if bits != 0 {
            writer.put(&(at as u32).to_le_bytes());
            writer.put(&bits.to_le_bytes());
        }
    });
}

/// A payload from its sparse bytes; `None` when they are not a sparse payload of `T`
/// (a length that is no multiple of an entry, an entry out of order or past the end).
pub fn get_sparse<T: Fields>(bytes: &[u8]) -> Option<T> {
    if !bytes.len().is_multiple_of(12) {
        return None;
    }
    let mut entries = bytes;
    let mut malformed = false;
    // The bits at `at`: the next entry's if it is at `at`, else zero.
    let value = from_numbers(|at| {
        loop {
            let Some((head, rest)) = entries.split_first_chunk::<12>() else {
                return 0;
            };
            let offset = u32::from_le_bytes([head[0], head[1], head[2], head[3]]) as usize;
            if offset < at {
                // Entries are in memory order: one the walk went past is not a field's.
                malformed = true;
                entries = rest;
                continue;
            }
            if offset != at {
                return 0;
            }
            entries = rest;
            let mut bits = [0u8; 8];
            bits.copy_from_slice(&head[4..12]);
            return u64::from_le_bytes(bits);
        }
    });
    (!malformed && entries.is_empty()).then_some(value)
}

/// A client id's 16 bytes.
pub fn client_bytes(client: ClientId) -> [u8; 16] {
    let mut bytes = [0u8; 16];
    bytes[..8].copy_from_slice(&client.lo.to_le_bytes());
    bytes[8..].copy_from_slice(&client.hi.to_le_bytes());
    bytes
}

/// One record, borrowed from the journal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Record<'a> {
    /// What it holds.
    pub kind: Kind,
    /// The link it is about (0 when none).
    pub link: u8,
    /// Its payload.
    pub payload: &'a [u8],
}

impl<'a> Record<'a> {
    /// The `u64` at byte `at` of the payload (0 past its end).
    pub fn u64_at(&self, at: usize) -> u64 {
        self.payload
            .get(at..at + 8)
            .and_then(|bytes| bytes.try_into().ok())
            .map_or(0, u64::from_le_bytes)
    }

    /// The client id at byte `at`.
    pub fn client_at(&self, at: usize) -> ClientId {
        ClientId {
            lo: self.u64_at(at),
            hi: self.u64_at(at + 8),
        }
    }

    /// The payload from byte `at` on.
    pub fn rest(&self, at: usize) -> &'a [u8] {
        self.payload.get(at..).unwrap_or(&[])
    }
}

/// Why a journal could not be read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum JournalError {
    /// A kind byte no record has.
    #[error("byte {at}: no record kind {kind}")]
    UnknownKind {
        /// Offset of the record.
        at: usize,
        /// The byte.
        kind: u8,
    },
    /// A record longer than what is left.
    #[error("byte {at}: a record of {len} bytes runs past the end ({left} left)")]
    Truncated {
        /// Offset of the record.
        at: usize,
        /// Its stated payload length.
        len: usize,
        /// Bytes left after its header.
        left: usize,
    },
}

/// The records of `bytes`, in order.
pub fn records(bytes: &[u8]) -> Records<'_> {
    Records { bytes, at: 0 }
}

/// Iterator over a journal's records.
#[derive(Debug, Clone)]
pub struct Records<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Iterator for Records<'a> {
    type Item = Result<Record<'a>, JournalError>;

    fn next(&mut self) -> Option<Self::Item> {
        let rest = self.bytes.get(self.at..)?;
        let (header, body) = rest.split_first_chunk::<HEADER_LEN>()?;
        let at = self.at;
        let Some(kind) = Kind::from_u8(header[0]) else {
            self.at = self.bytes.len();
            return Some(Err(JournalError::UnknownKind {
                at,
                kind: header[0],
            }));
        };
        let len = u32::from_le_bytes([header[2], header[3], header[4], header[5]]) as usize;
        let Some(payload) = body.get(..len) else {
            self.at = self.bytes.len();
            return Some(Err(JournalError::Truncated {
                at,
                len,
                left: body.len(),
            }));
        };
        self.at += HEADER_LEN + len;
        Some(Ok(Record {
            kind,
            link: header[1],
            payload,
        }))
    }
}

/// Writes a record's header.
pub fn put_header(writer: &mut SplitWriter<'_>, kind: Kind, link: u8, len: usize) {
    writer.put(&[kind as u8, link]);
    writer.put(&(len as u32).to_le_bytes());
}

#[cfg(test)]
mod tests;
