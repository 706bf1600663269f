//! Requests sent and not yet answered, oldest first (the board answers in order).

use core::time::Duration;

use qq2drv::PacketId;

use super::packet::Packet;

/// Requests that may be unanswered at once.
pub const IN_FLIGHT_CAPACITY: usize = 48;

/// What an answer is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Tag {
    /// A start-up read (version, data masks, stream config, stream period).
    Probe,
    /// A start-up write.
    Setup,
    /// A goal packet of `channel`, step generation `seq`.
    Goal {
        channel: u8,
        seq: u32,
        packet: Packet,
    },
}

/// One unanswered request.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Sent {
    pub(super) id: PacketId,
    pub(super) at: Duration,
    pub(super) tag: Tag,
}

/// Fixed-capacity FIFO of [`Sent`].
#[derive(Debug, Clone)]
pub(super) struct InFlight {
    items: [Option<Sent>; IN_FLIGHT_CAPACITY],
    len: usize,
}

impl InFlight {
    pub(super) const fn new() -> Self {
        Self {
            items: [None; IN_FLIGHT_CAPACITY],
            len: 0,
        }
    }

    pub(super) fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Room for `count` more.
    pub(super) fn has_room(&self, count: usize) -> bool {
        self.len + count <= IN_FLIGHT_CAPACITY
    }

    /// Appends; `false` when full.
    pub(super) fn push(&mut self, sent: Sent) -> bool {
        match self.items.get_mut(self.len) {
            Some(slot) => {
                *slot = Some(sent);
                self.len += 1;
                true
            }
            None => false,
        }
    }

    /// The oldest.
    pub(super) fn oldest(&self) -> Option<Sent> {
        self.items
            .first()
            .copied()
            .flatten()
            .filter(|_| self.len > 0)
    }

    /// Removes and returns the oldest.
    pub(super) fn pop(&mut self) -> Option<Sent> {
        self.remove(0)
    }

    /// Position of the oldest request with `id`.
    pub(super) fn find(&self, id: PacketId) -> Option<usize> {
        self.items
            .iter()
            .take(self.len)
            .position(|sent| sent.is_some_and(|sent| sent.id == id))
    }

    fn remove(&mut self, index: usize) -> Option<Sent> {
        if index >= self.len {
            return None;
        }
        let sent = self.items.get(index).copied().flatten();
        if let Some(slots) = self.items.get_mut(index..self.len) {
            slots.rotate_left(1);
        }
        self.len -= 1;
        if let Some(slot) = self.items.get_mut(self.len) {
            *slot = None;
        }
        sent
    }

    pub(super) fn clear(&mut self) {
        self.items = [None; IN_FLIGHT_CAPACITY];
        self.len = 0;
    }
}
