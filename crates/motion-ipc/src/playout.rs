//! When a streamed setpoint applies: the one rule the server's engine and the fake server of
//! `motion-client::testing` both follow (docs/GROUPS.md "Streaming setpoints").
//!
//! A setpoint for tick `k` applies in tick `k + delay`. The stream's `delay` starts at 0 and
//! grows to the lateness of a setpoint that arrives after its tick — at most
//! `stream_buffer`; one later than that is dropped as late — and never shrinks while the
//! stream runs: a shorter delay would skip a setpoint, a step in the path. So a client whose
//! setpoints arrive a tick late now and then, or several in one tick, moves the group along
//! exactly the path it sent, a few ticks behind, each setpoint once and in order. Setpoints
//! of one publisher arrive in the order sent (iceoryx2 keeps it); one that arrives after a
//! later one was applied is late.
//!
//! ```
//! use motion_ipc::playout::{Playout, Timed};
//!
//! #[derive(Clone, Copy)]
//! struct Sp(u64, u64); // sequence, for_tick
//! impl Timed for Sp {
//!     fn for_tick(&self) -> u64 { self.1 }
//!     fn sequence(&self) -> u64 { self.0 }
//! }
//! let mut playout = Playout::starting_at(10);
//! let mut late = 0;
//! // Tick 12: the setpoint for 11 arrives a tick late, with the one for 12.
//! let mut queue = vec![Sp(1, 11), Sp(2, 12)];
//! let (first, span) = playout.take_due(&mut queue, 12, 3, &mut late).expect("due");
//! assert_eq!((first.0, span, playout.delay), (1, 1, 1));
//! // Tick 13: the one for 12, on the stream's new time.
//! let (second, span) = playout.take_due(&mut queue, 13, 3, &mut late).expect("due");
//! assert_eq!((second.0, span, late), (2, 1, 0));
//! ```

/// A queued setpoint's own tick and sequence.
pub trait Timed {
    /// The tick it is for.
    fn for_tick(&self) -> u64;
    /// Its sequence number (increasing per setpoint sent).
    fn sequence(&self) -> u64;
}

/// One stream's playout: its delay and what it applied last.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Playout {
    /// Ticks the stream runs behind its setpoints' own ticks
    /// ([`GroupState::stream_delay`](crate::GroupState::stream_delay)).
    pub delay: u64,
    /// The `for_tick` of the last setpoint applied; the tick the stream started in before
    /// the first.
    pub last_for_tick: u64,
    /// The sequence of the last setpoint applied (0 before the first).
    pub last_sequence: u64,
}

impl Playout {
    /// A stream started in tick `tick`.
    pub const fn starting_at(tick: u64) -> Self {
        Self {
            delay: 0,
            last_for_tick: tick,
            last_sequence: 0,
        }
    }

    /// The setpoint to apply in tick `tick`, if one is due, with its span in ticks from the
    /// last one applied (≥ 1), taken out of `queue`. Setpoints that can no longer apply —
    /// not above the last applied tick and sequence, superseded by a newer sequence for the
    /// same tick, or more than `buffer` ticks behind — are removed and counted in `late`.
    /// Nothing allocates (the queue only shrinks).
    pub fn take_due<T: Timed + Copy>(
        &mut self,
        queue: &mut Vec<T>,
        tick: u64,
        buffer: u64,
        late: &mut u64,
    ) -> Option<(T, u64)> {
        loop {
            self.drop_passed(queue, late);
            // The lowest tick first; the newest sequence among setpoints for one tick.
            let index = (0..queue.len())
                .min_by_key(|&i| (queue[i].for_tick(), core::cmp::Reverse(queue[i].sequence())))?;
            let setpoint = queue[index];
            if setpoint.for_tick().saturating_add(self.delay) > tick {
                return None;
            }
            queue.remove(index);
            let behind = tick - setpoint.for_tick();
            if behind > buffer {
                *late += 1;
                continue;
            }
            self.delay = self.delay.max(behind);
            let span = setpoint.for_tick() - self.last_for_tick;
            self.last_for_tick = setpoint.for_tick();
            self.last_sequence = setpoint.sequence();
            self.drop_passed(queue, late);
            return Some((setpoint, span));
        }
    }

    fn drop_passed<T: Timed>(&self, queue: &mut Vec<T>, late: &mut u64) {
        let before = queue.len();
        queue.retain(|q| q.for_tick() > self.last_for_tick && q.sequence() > self.last_sequence);
        *late += (before - queue.len()) as u64;
    }
}

#[cfg(test)]
mod tests {
    use super::{Playout, Timed};

    #[derive(Debug, Clone, Copy, PartialEq)]
    struct Sp(u64, u64);
    impl Timed for Sp {
        fn for_tick(&self) -> u64 {
            self.1
        }
        fn sequence(&self) -> u64 {
            self.0
        }
    }

    #[test]
    fn on_time_setpoints_apply_in_their_tick_and_sparse_ones_wait() {
        let mut playout = Playout::starting_at(0);
        let mut late = 0;
        let mut queue = vec![Sp(1, 1), Sp(2, 3)];
        assert_eq!(
            playout.take_due(&mut queue, 1, 3, &mut late),
            Some((Sp(1, 1), 1))
        );
        assert_eq!(playout.take_due(&mut queue, 2, 3, &mut late), None);
        assert_eq!(
            playout.take_due(&mut queue, 3, 3, &mut late),
            Some((Sp(2, 3), 2))
        );
        assert_eq!((playout.delay, late), (0, 0));
    }

    #[test]
    fn a_late_one_grows_the_delay_and_the_rest_follow_on_its_time() {
        let mut playout = Playout::starting_at(0);
        let mut late = 0;
        let mut queue = vec![Sp(1, 1)];
        assert_eq!(
            playout.take_due(&mut queue, 1, 3, &mut late),
            Some((Sp(1, 1), 1))
        );
        // The one for 2 arrives at 4 with the ones for 3 and 4: two behind.
        assert_eq!(playout.take_due(&mut queue, 2, 3, &mut late), None);
        assert_eq!(playout.take_due(&mut queue, 3, 3, &mut late), None);
        queue.extend([Sp(2, 2), Sp(3, 3), Sp(4, 4)]);
        assert_eq!(
            playout.take_due(&mut queue, 4, 3, &mut late),
            Some((Sp(2, 2), 1))
        );
        assert_eq!(playout.delay, 2);
        assert_eq!(
            playout.take_due(&mut queue, 5, 3, &mut late),
            Some((Sp(3, 3), 1))
        );
        assert_eq!(
            playout.take_due(&mut queue, 6, 3, &mut late),
            Some((Sp(4, 4), 1))
        );
        // On time again: the delay stays.
        queue.push(Sp(5, 7));
        assert_eq!(playout.take_due(&mut queue, 7, 3, &mut late), None);
        assert_eq!(
            playout.take_due(&mut queue, 9, 3, &mut late),
            Some((Sp(5, 7), 3))
        );
        assert_eq!((playout.delay, late), (2, 0));
    }

    #[test]
    fn too_late_superseded_and_replayed_ones_are_late() {
        let mut playout = Playout::starting_at(0);
        let mut late = 0;
        // For 1, arriving at 6 with buffer 3: late; two for 5: the newer sequence applies.
        let mut queue = vec![Sp(1, 1), Sp(2, 5), Sp(3, 5)];
        assert_eq!(
            playout.take_due(&mut queue, 6, 3, &mut late),
            Some((Sp(3, 5), 5))
        );
        assert_eq!((playout.delay, late), (1, 2));
        assert!(queue.is_empty());
        // A sequence already applied, an earlier tick: late.
        queue.extend([Sp(3, 9), Sp(4, 4)]);
        assert_eq!(playout.take_due(&mut queue, 10, 3, &mut late), None);
        assert_eq!(late, 4);
    }
}
