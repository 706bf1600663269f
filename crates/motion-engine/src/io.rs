//! The links' I/O side as the shell reports it (see `motion_drivers::Driver`): when each
//! message went out, how far each link has been looked at, and from that when each axis's
//! goal reached the wire.

use core::time::Duration;
use motion_drivers::Driver;

use crate::Engine;

/// How far the I/O side of a link may fall behind before the engine stops waiting for it:
/// a message not reported written this long after it was made counts as written then, and
/// silence is judged at least up to `now` minus this. A starved I/O thread gets this long
/// before its boards can look dead; a hung one cannot hide a dead board for longer.
pub const IO_STALL_LIMIT: Duration = Duration::from_secs(1);

impl<D: Driver> Engine<D> {
    /// From now on the shell reports, for every link, each message written
    /// ([`link_written`](Self::link_written)) and the link's horizon
    /// ([`link_heard`](Self::link_heard)) before every step. Without it (a rig that moves
    /// bytes at once) a message counts as written when it is made and silence is judged up
    /// to `now`.
    pub fn stamp_links(&mut self) {
        for bus in &mut self.buses {
            bus.set_stamped(true);
        }
    }

    /// CLOCK_MONOTONIC at the engine's time zero (what `now` counts from), so that the
    /// frame's `wire_ns` stamps are CLOCK_MONOTONIC. Zero unless set.
    pub fn set_clock_origin(&mut self, origin: Duration) {
        self.clock_origin = origin;
    }

    /// The oldest message queued on `link` and not reported yet went out whole at `at`
    /// (its last byte was accepted by the transport). Call before [`step`](Self::step), in
    /// the order the messages were queued.
    pub fn link_written(&mut self, link: usize, at: Duration) {
        let Some(bus) = self.buses.get_mut(link) else {
            return;
        };
        if let Some(message) = bus.handle_written(at) {
            self.goal_on_wire(link, message.driver, message.goal_starts, at);
        }
    }

    /// The horizon of `link`: every byte it received before `until` has been handed to
    /// [`handle_link_rx`](Self::handle_link_rx), and every message queued before it was
    /// written. Used at the next step.
    pub fn link_heard(&mut self, link: usize, until: Duration) {
        if let Some(heard) = self.heard.get_mut(link) {
            *heard = Some(until);
        }
    }

    /// The line rate `link` must take before the message
    /// [`poll_link_transmit`](Self::poll_link_transmit) returned last is written, taken
    /// (`LinkBus::take_rate_change`: a driver changed its board's rate). The shell changes
    /// the link's rate after writing the messages before, then writes that message.
    pub fn take_link_rate(&mut self, link: usize) -> Option<u32> {
        self.buses.get_mut(link)?.take_rate_change()
    }

    /// The earliest instant a driver of `link` has timed work (a reply deadline, a poll
    /// period): the shell has the link looked at again by then, so that a silent board is
    /// seen to be silent.
    #[must_use]
    pub fn link_poll_timeout(&self, link: usize) -> Option<Duration> {
        if !self.link_opened.get(link).copied().unwrap_or(false) {
            return None;
        }
        self.buses.get(link)?.poll_timeout()
    }

    /// Step 0: the I/O reports of every stamped link reach its drivers, with the stall
    /// limit applied.
    pub(crate) fn apply_io_stamps(&mut self, now: Duration) {
        for link in 0..self.buses.len() {
            if !self.buses[link].stamped() || !self.link_opened[link] {
                continue;
            }
            while let Some(oldest) = self.buses[link].oldest_unwritten()
                && now.saturating_sub(oldest.queued_at) >= IO_STALL_LIMIT
            {
                self.link_written(link, now);
            }
            let floor = now.saturating_sub(IO_STALL_LIMIT);
            let heard = self.heard.get(link).copied().flatten().unwrap_or(now);
            self.buses[link].handle_heard(heard, floor);
        }
    }

    /// The message with `goal_starts` from driver `slot` of `bus` went out at `at`.
    pub(crate) fn goal_on_wire(&mut self, bus: usize, slot: usize, goal_starts: u8, at: Duration) {
        if goal_starts == 0 {
            return;
        }
        let tick = self.tick_at(at);
        for axis in &mut self.axes {
            let bit = 1u8.checked_shl(axis.channel as u32).unwrap_or(0);
            if axis.bus == bus && axis.slot == slot && goal_starts & bit != 0 {
                axis.goal_wire = Some((tick, at));
            }
        }
    }

    /// Axis `index` got a new goal from its driver's point of view (this tick).
    pub(crate) fn goal_set(&mut self, index: usize) {
        let tick = self.tick;
        if let Some(axis) = self.axes.get_mut(index) {
            axis.goal_tick = tick;
            axis.goal_wire = None;
        }
    }

    /// The tick during which `at` fell: the last tick that began at or before it.
    pub(crate) fn tick_at(&self, at: Duration) -> u64 {
        let period = self.config.period().as_nanos().max(1);
        if at >= self.now {
            let ahead = (at - self.now).as_nanos() / period;
            self.tick
                .saturating_add(u64::try_from(ahead).unwrap_or(u64::MAX))
        } else {
            let back = (self.now - at).as_nanos().div_ceil(period);
            self.tick
                .saturating_sub(u64::try_from(back).unwrap_or(u64::MAX))
        }
    }

    /// CLOCK_MONOTONIC ns of engine time `at` (at least 1: 0 means "never" in the frame).
    pub(crate) fn monotonic_ns(&self, at: Duration) -> u64 {
        u64::try_from((self.clock_origin + at).as_nanos())
            .unwrap_or(u64::MAX)
            .max(1)
    }
}
