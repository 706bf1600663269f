//! Line-noise guards. The QSB's responses carry no checksum (command list, "Command
//! Response": `Register[2] Data[8] <Time Stamp[8]> '!' <EOR>`, ASCII hex): a flipped bit
//! that turns one hex digit into another makes a valid line with a wrong value, and no
//! decoder can tell. What a single corrupted line must never do is change what the driver
//! believes about the board — a restart, a disabled drive, a jump of the encoder. So every
//! line whose content contradicts what came before is held until the next line confirms
//! it; one corrupted line is dropped (counted as a bad reply), a real change costs one line
//! of delay.
//!
//! - [`StampGuard`]: the time stamp (a 32-bit count of 1/512 s ticks since power-up) goes
//!   forward at most as fast as time passes between the lines' arrivals, plus the lines'
//!   delivery latency. A line outside that is held; the next line decides whether the old
//!   timeline goes on (the held line was corrupted), a new one began (backwards: the board
//!   restarted; forwards: lines were delayed on the host), or the line accepted before the
//!   held one was the corrupted one.
//! - MD STATUS: a line saying the drive is disabled (a reset) counts when the next agrees.
//! - The encoder count's own guard is [`EncoderTrack::offer`](super::encoder::EncoderTrack::offer).

use core::time::Duration;

use ::qsb::TICK;

/// Time-stamp ticks a line may run ahead of the time that passed between arrivals (lines
/// delivered late after earlier ones came promptly), besides the host latency.
const STAMP_SLACK_TICKS: u32 = 8;

/// Half the time-stamp range: a difference above it is a step backwards.
const HALF: u32 = u32::MAX / 2;

/// What to do with a line, judged by its time stamp.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum StampVerdict {
    /// The line continues the board's timeline.
    Accept,
    /// The line continues the timeline from before the last accepted line, whose stamp
    /// (within the slack) was the corrupted one: take it, and forget what that line
    /// brought.
    Rewound,
    /// The line continues a timeline that jumped forwards (confirmed by two lines): take
    /// it, but samples before the jump are no base for a velocity.
    NewTimeline,
    /// The line contradicts the timeline: drop it until the next line confirms it.
    Hold,
    /// Two lines in a row say the board restarted (the stamp went backwards, or the lines
    /// lost their time stamps although EOR asks for them).
    Reset(StampReset),
}

/// What two lines showed of a restart (the evidence of the reset verdict).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum StampReset {
    /// The time stamp went back from `last` to `held`, then `stamp` went on from there:
    /// "This counter is cleared on a power-cycle".
    Backwards { last: u32, held: u32, stamp: u32 },
    /// Two read or stream lines in a row without the time stamp EOR asks for: the board
    /// answers in its saved EOR again (the driver never saves).
    Unstamped,
}

/// A held line: its stamp, or none where one was due.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
enum Suspect {
    Missing,
    Stamp(u32),
}

/// The board's timeline as the lines tell it (see the module documentation).
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Default)]
pub(crate) struct StampGuard {
    /// The newest accepted stamp and when its line arrived.
    last: Option<(u32, Duration)>,
    /// The accepted stamp before it.
    before: Option<(u32, Duration)>,
    suspect: Option<Suspect>,
}

impl StampGuard {
    /// The newest accepted stamp.
    pub(crate) fn last(&self) -> Option<u32> {
        self.last.map(|(stamp, _)| stamp)
    }

    /// Forgets the timeline (a start-up: the board may have been reset on purpose).
    pub(crate) fn clear(&mut self) {
        *self = Self::default();
    }

    /// Judges a line that arrived at `now` with `stamp`; `expected`: EOR asks for time
    /// stamps; `latency`: how late the host may deliver a line.
    pub(crate) fn check(
        &mut self,
        now: Duration,
        stamp: Option<u32>,
        expected: bool,
        latency: Duration,
    ) -> StampVerdict {
        let Some(stamp) = stamp else {
            if !expected {
                return StampVerdict::Accept;
            }
            if self.suspect == Some(Suspect::Missing) {
                self.clear();
                return StampVerdict::Reset(StampReset::Unstamped);
            }
            self.suspect = Some(Suspect::Missing);
            return StampVerdict::Hold;
        };
        let Some(last) = self.last else {
            self.accept(now, stamp);
            return StampVerdict::Accept;
        };
        if follows(last, now, stamp, latency) {
            self.accept(now, stamp);
            return StampVerdict::Accept;
        }
        let Some(Suspect::Stamp(held)) = self.suspect else {
            self.suspect = Some(Suspect::Stamp(stamp));
            return StampVerdict::Hold;
        };
        if !follows((held, now), now, stamp, latency) {
            // Contradicts both: hold this one instead.
            self.suspect = Some(Suspect::Stamp(stamp));
            return StampVerdict::Hold;
        }
        // Two lines agree on a timeline the last accepted line is not on.
        if let Some(before) = self.before
            && follows(before, now, held, latency)
        {
            // The line accepted last was the corrupted one (its stamp ran ahead).
            self.last = self.before;
            self.accept(now, stamp);
            return StampVerdict::Rewound;
        }
        if held.wrapping_sub(last.0) > HALF {
            self.clear();
            return StampVerdict::Reset(StampReset::Backwards {
                last: last.0,
                held,
                stamp,
            });
        }
        self.accept(now, stamp);
        StampVerdict::NewTimeline
    }

    fn accept(&mut self, now: Duration, stamp: u32) {
        if self.last.map(|(last, _)| last) != Some(stamp) {
            self.before = self.last;
        }
        self.last = Some((stamp, now));
        self.suspect = None;
    }
}

/// Whether `stamp`, on a line that arrived at `now`, continues from `(from, at)`: not
/// backwards, and not further ahead than the time between the arrivals allows.
fn follows((from, at): (u32, Duration), now: Duration, stamp: u32, latency: Duration) -> bool {
    let ahead = stamp.wrapping_sub(from);
    if ahead > HALF {
        return false;
    }
    let passed = now.saturating_sub(at).saturating_add(latency);
    let allowed = ticks_in(passed).saturating_add(STAMP_SLACK_TICKS);
    ahead <= allowed
}

/// Whole time-stamp ticks in `span`, rounded up.
fn ticks_in(span: Duration) -> u32 {
    let ticks = span.as_nanos().div_ceil(TICK.as_nanos().max(1));
    u32::try_from(ticks).unwrap_or(u32::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: Duration = Duration::from_millis(1);
    const LATENCY: Duration = Duration::from_millis(5);

    /// Feeds lines one tick (1.95 ms) apart, stamps `first..`; returns the guard.
    fn running(first: u32, lines: u32) -> (StampGuard, Duration) {
        let mut guard = StampGuard::default();
        let mut now = Duration::ZERO;
        for k in 0..lines {
            now += TICK;
            assert_eq!(
                guard.check(now, Some(first + k), true, LATENCY),
                StampVerdict::Accept
            );
        }
        (guard, now)
    }

    #[test]
    fn one_stamp_corrupted_backwards_is_dropped_not_a_reset() {
        // "00001234" with a bit of its second digit flipped: far backwards.
        let (mut guard, mut now) = running(0x1000_0000, 10);
        now += TICK;
        assert_eq!(
            guard.check(now, Some(0x0000_0009), true, LATENCY),
            StampVerdict::Hold
        );
        now += TICK;
        assert_eq!(
            guard.check(now, Some(0x1000_000B), true, LATENCY),
            StampVerdict::Accept
        );
        assert_eq!(guard.last(), Some(0x1000_000B));
    }

    #[test]
    fn one_stamp_corrupted_far_forwards_is_dropped() {
        let (mut guard, mut now) = running(100, 10);
        now += TICK;
        assert_eq!(
            guard.check(now, Some(100 + 10 + 0x0100_0000), true, LATENCY),
            StampVerdict::Hold
        );
        now += TICK;
        assert_eq!(
            guard.check(now, Some(111), true, LATENCY),
            StampVerdict::Accept
        );
    }

    #[test]
    fn a_stamp_corrupted_slightly_forwards_is_undone_by_the_next_two_lines() {
        // Accepted (within the slack), then the real timeline comes back: not a reset.
        let (mut guard, mut now) = running(100, 10);
        now += TICK;
        assert_eq!(
            guard.check(now, Some(110 + 8), true, LATENCY),
            StampVerdict::Accept
        );
        now += TICK;
        assert_eq!(
            guard.check(now, Some(111), true, LATENCY),
            StampVerdict::Hold
        );
        now += TICK;
        assert_eq!(
            guard.check(now, Some(112), true, LATENCY),
            StampVerdict::Rewound
        );
        assert_eq!(guard.last(), Some(112));
    }

    #[test]
    fn a_restart_is_two_lines_back_at_the_start() {
        let (mut guard, mut now) = running(50_000, 10);
        now += TICK;
        assert_eq!(guard.check(now, Some(3), true, LATENCY), StampVerdict::Hold);
        now += TICK;
        assert_eq!(
            guard.check(now, Some(4), true, LATENCY),
            StampVerdict::Reset(StampReset::Backwards {
                last: 50_009,
                held: 3,
                stamp: 4
            })
        );
        // The new timeline is taken from its next line on.
        now += TICK;
        assert_eq!(
            guard.check(now, Some(5), true, LATENCY),
            StampVerdict::Accept
        );
    }

    #[test]
    fn lines_held_up_on_the_host_are_a_new_timeline_not_a_reset() {
        // Lines buffered while the process stood still arrive in a burst, then fresh ones
        // whose stamps are seconds ahead of the last buffered one.
        let (mut guard, mut now) = running(1000, 10);
        now += MS / 10;
        assert_eq!(
            guard.check(now, Some(1000 + 10 + 2048), true, LATENCY),
            StampVerdict::Hold
        );
        now += TICK;
        assert_eq!(
            guard.check(now, Some(1000 + 10 + 2049), true, LATENCY),
            StampVerdict::NewTimeline
        );
        // After a real pause the stamps may jump by the pause.
        now += 3 * 1000 * MS;
        assert_eq!(
            guard.check(now, Some(1000 + 10 + 2049 + 1536), true, LATENCY),
            StampVerdict::Accept
        );
    }

    #[test]
    fn a_line_without_its_stamp_is_held_and_two_are_a_reset() {
        let (mut guard, mut now) = running(7, 3);
        now += TICK;
        assert_eq!(guard.check(now, None, true, LATENCY), StampVerdict::Hold);
        now += TICK;
        assert_eq!(
            guard.check(now, Some(11), true, LATENCY),
            StampVerdict::Accept
        );
        now += TICK;
        assert_eq!(guard.check(now, None, true, LATENCY), StampVerdict::Hold);
        now += TICK;
        assert_eq!(
            guard.check(now, None, true, LATENCY),
            StampVerdict::Reset(StampReset::Unstamped)
        );
        // Without EOR time stamps configured, no stamp is no news.
        assert_eq!(guard.check(now, None, false, LATENCY), StampVerdict::Accept);
    }

    #[test]
    fn same_tick_lines_share_a_stamp_and_a_wrap_is_forwards() {
        let (mut guard, now) = running(u32::MAX - 2, 2);
        assert_eq!(
            guard.check(now, Some(u32::MAX - 1), true, LATENCY),
            StampVerdict::Accept
        );
        assert_eq!(
            guard.check(now + TICK, Some(0), true, LATENCY),
            StampVerdict::Accept
        );
    }
}
