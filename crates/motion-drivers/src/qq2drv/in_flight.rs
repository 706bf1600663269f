//! Requests sent and not yet answered, oldest first (the board answers in order).

use core::time::Duration;

use motion_base::FixedQueue;
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

/// Requests in flight, oldest first.
pub(super) type InFlight = FixedQueue<Sent, IN_FLIGHT_CAPACITY>;
