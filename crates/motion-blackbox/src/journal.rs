//! The tick's end of the black box: each input the tick hands the engine and each output
//! it takes, written as a record into a lock-free byte queue the recorder thread drains.
//! Nothing here allocates or blocks: a record that does not fit in the queue is dropped
//! and counted, and the next one that fits is preceded by a [`Kind::Lost`] record.

use core::time::Duration;

use motion_drivers::{Driver, SavedReference};
use motion_engine::Engine;
use motion_ipc::schema::Fields;
use motion_ipc::{ClientId, CommandReply, CommandRequest, GroupPath, MotionFrame, Setpoint};
use rtrb::Producer;
use serde::Serialize;

use super::digest::FrameDigest;
use super::record::{
    HEADER_LEN, Kind, SplitWriter, Trigger, client_bytes, put_header, put_sparse, sparse_len,
};

/// The tick's journal; a disabled one (`blackbox_seconds = 0`) records nothing.
#[derive(Debug)]
pub struct Journal {
    queue: Option<Producer<u8>>,
    /// Records dropped since the last [`Kind::Lost`] record.
    lost: u64,
    /// Records dropped since start.
    lost_total: u64,
    /// Ticks journaled (the next tick's number in the journal).
    ticks: u64,
    /// Every this many ticks the engine's state is journaled ([`Kind::Snapshot`]); 0:
    /// never.
    snapshot_every: u64,
    /// Where a snapshot is serialized before it is queued (sized at start-up by
    /// [`Journal::prepare_snapshots`]).
    snapshot_buf: Vec<u8>,
    /// Snapshots that did not fit in `snapshot_buf` (counted as lost records too).
    snapshots_failed: u64,
}

fn ns(duration: Duration) -> u64 {
    u64::try_from(duration.as_nanos()).unwrap_or(u64::MAX)
}

impl Journal {
    /// A journal that records nothing.
    pub fn disabled() -> Self {
        Self {
            queue: None,
            lost: 0,
            lost_total: 0,
            ticks: 0,
            snapshot_every: 0,
            snapshot_buf: Vec::new(),
            snapshots_failed: 0,
        }
    }

    /// A journal writing into `queue`, with a snapshot of the engine's state every
    /// `snapshot_every` ticks (0: none).
    pub fn new(queue: Producer<u8>, snapshot_every: u64) -> Self {
        Self {
            queue: Some(queue),
            lost: 0,
            lost_total: 0,
            ticks: 0,
            snapshot_every,
            snapshot_buf: Vec::new(),
            snapshots_failed: 0,
        }
    }

    /// Sizes the snapshot buffer for `engine`: its state as it is at start-up, twice (the
    /// numbers' varints and the drivers' queues vary), the most its paths may grow by
    /// ([`Engine::snapshot_growth`]), and 64 KiB. Start-up only: it allocates.
    pub fn prepare_snapshots<D: Driver + Serialize>(&mut self, engine: &Engine<D>) {
        if self.queue.is_none() || self.snapshot_every == 0 {
            return;
        }
        let len = postcard::to_allocvec(engine).map_or(0, |bytes| bytes.len());
        self.snapshot_buf = vec![0u8; 2 * len + engine.snapshot_growth() + (64 << 10)];
    }

    /// Bytes of the snapshot buffer.
    pub fn snapshot_capacity(&self) -> usize {
        self.snapshot_buf.len()
    }

    /// Whether the tick just begun journals a snapshot (every `snapshot_every` ticks,
    /// never the first: a recording from the start needs none).
    pub fn snapshot_due(&self) -> bool {
        self.snapshot_every > 0
            && !self.snapshot_buf.is_empty()
            && self.ticks > 1
            && (self.ticks - 1).is_multiple_of(self.snapshot_every)
    }

    /// Journals `state` (the engine, drivers included) as it is between two ticks: the
    /// point a replay of a wrapped ring starts from. Serialized into the buffer sized at
    /// start-up, then queued: nothing allocates. A state that outgrew the buffer is
    /// counted (snapshots failed, records lost) and the next one is tried as usual.
    pub fn snapshot<T: Serialize>(&mut self, state: &T) {
        let mut buf = core::mem::take(&mut self.snapshot_buf);
        match postcard::to_slice(state, &mut buf) {
            Ok(bytes) => {
                let bytes: &[u8] = bytes;
                self.record(Kind::Snapshot, 0, bytes.len(), |writer| writer.put(bytes));
            }
            Err(_) => {
                self.snapshots_failed += 1;
                self.lost_total += 1;
            }
        }
        self.snapshot_buf = buf;
    }

    /// Snapshots that did not fit their buffer since start.
    pub fn snapshots_failed(&self) -> u64 {
        self.snapshots_failed
    }

    /// Whether it records.
    pub fn enabled(&self) -> bool {
        self.queue.is_some()
    }

    /// Records dropped since start (the queue was full).
    pub fn lost_since_start(&self) -> u64 {
        self.lost_total
    }

    /// Writes one record of `len` payload bytes, filled by `fill`.
    fn record(
        &mut self,
        kind: Kind,
        link: usize,
        len: usize,
        fill: impl FnOnce(&mut SplitWriter<'_>),
    ) {
        let Some(queue) = self.queue.as_mut() else {
            return;
        };
        let link = u8::try_from(link).unwrap_or(u8::MAX);
        if self.lost > 0 {
            let lost = self.lost;
            match queue.write_chunk(HEADER_LEN + 8) {
                Ok(mut chunk) => {
                    let (first, second) = chunk.as_mut_slices();
                    let mut writer = SplitWriter::new(first, second);
                    put_header(&mut writer, Kind::Lost, 0, 8);
                    writer.put(&lost.to_le_bytes());
                    chunk.commit_all();
                    self.lost = 0;
                }
                Err(_) => {
                    self.lost += 1;
                    self.lost_total += 1;
                    return;
                }
            }
        }
        match queue.write_chunk(HEADER_LEN + len) {
            Ok(mut chunk) => {
                let (first, second) = chunk.as_mut_slices();
                let mut writer = SplitWriter::new(first, second);
                put_header(&mut writer, kind, link, len);
                fill(&mut writer);
                debug_assert_eq!(writer.written(), HEADER_LEN + len, "{kind:?}");
                chunk.commit_all();
            }
            Err(_) => {
                self.lost += 1;
                self.lost_total += 1;
            }
        }
    }

    fn words(&mut self, kind: Kind, link: usize, words: &[u64]) {
        self.record(kind, link, words.len() * 8, |writer| {
            for word in words {
                writer.put(&word.to_le_bytes());
            }
        });
    }

    fn sparse<T: Fields>(&mut self, kind: Kind, prefix: &[u8], value: &T) {
        let len = prefix.len() + sparse_len(value);
        self.record(kind, 0, len, |writer| {
            writer.put(prefix);
            put_sparse(writer, value);
        });
    }

    /// The server started at `epoch` (CLOCK_MONOTONIC) with `links` links.
    pub fn start(&mut self, epoch: Duration, links: usize) {
        self.words(Kind::Start, 0, &[ns(epoch), links as u64]);
    }

    /// A tick at engine time `now` begins (numbered in the journal from 0).
    pub fn tick(&mut self, now: Duration) {
        let number = self.ticks;
        self.ticks += 1;
        self.words(Kind::Tick, 0, &[ns(now), number]);
    }

    /// Start-up handed `device`'s driver `reference`.
    pub fn restored_reference(&mut self, device: usize, reference: &SavedReference) {
        self.words(
            Kind::RestoredReference,
            0,
            &[
                device as u64,
                reference.channel as u64,
                reference.counts as u64,
            ],
        );
    }

    /// `link`'s line rate changes to `baud` before the message just queued.
    pub fn link_rate(&mut self, link: usize, baud: u32) {
        self.words(Kind::LinkRate, link, &[u64::from(baud)]);
    }

    /// `link` is handed to its I/O thread closed.
    pub fn link_opening(&mut self, link: usize) {
        self.record(Kind::LinkOpening, link, 0, |_| {});
    }

    /// `link` went down.
    pub fn link_down(&mut self, link: usize) {
        self.record(Kind::LinkDown, link, 0, |_| {});
    }

    /// `link` is up.
    pub fn link_up(&mut self, link: usize) {
        self.record(Kind::LinkUp, link, 0, |_| {});
    }

    /// `link`'s I/O thread wrote a message at `at`.
    pub fn link_written(&mut self, link: usize, at: Duration) {
        self.words(Kind::LinkWritten, link, &[ns(at)]);
    }

    /// `link` received `bytes`, stamped `at` by its I/O thread.
    pub fn link_rx(&mut self, link: usize, at: Duration, bytes: &[u8]) {
        self.record(Kind::LinkRx, link, 8 + bytes.len(), |writer| {
            writer.put(&ns(at).to_le_bytes());
            writer.put(bytes);
        });
    }

    /// `link` was read up to `heard`.
    pub fn link_heard(&mut self, link: usize, heard: Duration) {
        self.words(Kind::LinkHeard, link, &[ns(heard)]);
    }

    /// A client node died.
    pub fn client_dead(&mut self, client: ClientId) {
        let bytes = client_bytes(client);
        self.record(Kind::ClientDead, 0, 16, |writer| writer.put(&bytes));
    }

    /// The e-stop event (`by` 1) or SIGUSR1 (`by` 2) latched the e-stop.
    pub fn estop(&mut self, by: u8) {
        self.record(Kind::Estop, 0, 1, |writer| writer.put(&[by]));
    }

    /// A departed client's claims end.
    pub fn release_claims(&mut self, client: ClientId) {
        let bytes = client_bytes(client);
        self.record(Kind::ReleaseClaims, 0, 16, |writer| writer.put(&bytes));
    }

    /// The shutdown stop began.
    pub fn shutdown(&mut self) {
        self.record(Kind::Shutdown, 0, 0, |_| {});
    }

    /// A setpoint from `sender`, received at `received_ns`.
    pub fn setpoint(&mut self, sender: ClientId, received_ns: u64, setpoint: &Setpoint) {
        let mut prefix = [0u8; 24];
        prefix[..16].copy_from_slice(&client_bytes(sender));
        prefix[16..].copy_from_slice(&received_ns.to_le_bytes());
        self.sparse(Kind::Setpoint, &prefix, setpoint);
    }

    /// The step begins.
    pub fn step(&mut self) {
        self.record(Kind::Step, 0, 0, |_| {});
    }

    /// The engine took `request` from `sender`.
    pub fn request(&mut self, sender: ClientId, request: &CommandRequest) {
        self.sparse(Kind::Request, &client_bytes(sender), request);
    }

    /// The engine took `client`'s path `id`: `path`, or none.
    pub fn path(&mut self, client: ClientId, id: u64, path: Option<&GroupPath>) {
        let mut prefix = [0u8; 24];
        prefix[..16].copy_from_slice(&client_bytes(client));
        prefix[16..].copy_from_slice(&id.to_le_bytes());
        match path {
            Some(path) => self.sparse(Kind::Path, &prefix, path),
            None => self.record(Kind::NoPath, 0, 24, |writer| writer.put(&prefix)),
        }
    }

    /// The engine's reply.
    pub fn reply(&mut self, reply: &CommandReply) {
        self.sparse(Kind::Reply, &[], reply);
    }

    /// The frame the engine wrote.
    pub fn frame(&mut self, frame: &MotionFrame) {
        let digest = FrameDigest::of(frame);
        self.words(Kind::Frame, 0, digest.values());
    }

    /// The frame's digest, and a trigger when the e-stop latched since the frame before
    /// (`estop_seen` holds the last frame's latch).
    pub fn frame_and_estop(&mut self, frame: &MotionFrame, estop_seen: &mut bool) {
        self.frame(frame);
        let estop = frame.flags & motion_ipc::FrameFlags::ESTOP_LATCHED.0 != 0;
        if estop && !*estop_seen {
            self.trigger(Trigger::Estop, usize::MAX);
        }
        *estop_seen = estop;
    }

    /// The engine queued `bytes` for `link`.
    pub fn link_tx(&mut self, link: usize, bytes: &[u8]) {
        self.record(Kind::LinkTx, link, bytes.len(), |writer| writer.put(bytes));
    }

    /// The engine had nothing more for `link`.
    pub fn link_tx_none(&mut self, link: usize) {
        self.record(Kind::LinkTxNone, link, 0, |_| {});
    }

    /// `ticks` missed deadlines were skipped.
    pub fn skip(&mut self, ticks: u64) {
        self.words(Kind::Skip, 0, &[ticks]);
    }

    /// Every axis stopped with the `Overrun` fault.
    pub fn overrun_fault(&mut self) {
        self.record(Kind::OverrunFault, 0, 0, |_| {});
    }

    /// Something to save the black box for.
    pub fn trigger(&mut self, why: Trigger, axis: usize) {
        let axis = u32::try_from(axis).unwrap_or(u32::MAX);
        self.record(Kind::Trigger, 0, 5, |writer| {
            writer.put(&[why as u8]);
            writer.put(&axis.to_le_bytes());
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::records;

    #[test]
    fn a_full_queue_drops_counts_and_marks_the_hole() {
        // Room for two tick records (header + two words each) and a little more.
        let (producer, mut consumer) = rtrb::RingBuffer::<u8>::new(2 * (HEADER_LEN + 16) + 4);
        let mut journal = Journal::new(producer, 0);
        for n in 0..5u64 {
            journal.tick(Duration::from_millis(n));
        }
        assert_eq!(journal.lost_since_start(), 3, "three ticks did not fit");
        let drained = |consumer: &mut rtrb::Consumer<u8>| {
            let chunk = consumer.read_chunk(consumer.slots()).unwrap();
            let bytes: Vec<u8> = chunk.into_iter().collect();
            records(&bytes)
                .map(|record| record.map(|record| (record.kind, record.u64_at(8))))
                .collect::<Result<Vec<_>, _>>()
                .unwrap()
        };
        assert_eq!(drained(&mut consumer), [(Kind::Tick, 0), (Kind::Tick, 1)]);
        // Room again: the hole is marked before the next record, and counted once.
        journal.tick(Duration::from_millis(5));
        let after = drained(&mut consumer);
        assert_eq!(after[0].0, Kind::Lost);
        assert_eq!(after[1], (Kind::Tick, 5));
        assert_eq!(journal.lost_since_start(), 3);
        // A disabled journal records and loses nothing.
        let mut disabled = Journal::disabled();
        disabled.tick(Duration::ZERO);
        assert_eq!(disabled.lost_since_start(), 0);
    }
}
