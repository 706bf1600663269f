//! What a driver knows of its link's I/O side ([`Driver::handle_written`],
//! [`Driver::handle_heard`](crate::Driver::handle_heard)): which of its messages went out,
//! and up to when silence can be judged.
//!
//! [`Driver::handle_written`]: crate::Driver::handle_written

use core::time::Duration;

/// Messages made and reported written, and the link's horizon: the bookkeeping a driver
/// keeps to match [`Driver::handle_written`] reports to the messages it made, and to judge
/// a reply missing only up to where the link has heard.
///
/// [`Driver::handle_written`]: crate::Driver::handle_written
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct IoStamps {
    /// Messages made (the number of the newest).
    sent: u64,
    /// Messages reported written.
    written: u64,
    /// The horizon last given; `None` without one (judge up to `now`).
    heard: Option<Duration>,
}

impl IoStamps {
    /// A message was made: its number (1, 2, …).
    pub fn sent(&mut self) -> u64 {
        self.sent += 1;
        self.sent
    }

    /// The number the next message will get.
    pub fn next_number(&self) -> u64 {
        self.sent + 1
    }

    /// A write report: the number of the message it is for (0 for a report nothing is
    /// owed for, which no message carries).
    pub fn written(&mut self) -> u64 {
        if self.written < self.sent {
            self.written += 1;
            self.written
        } else {
            0
        }
    }

    /// The link's horizon.
    pub fn heard(&mut self, until: Duration) {
        self.heard = Some(until);
    }

    /// Up to when silence can be judged at `now`.
    pub fn judged(&self, now: Duration) -> Duration {
        self.heard.map_or(now, |heard| heard.min(now))
    }

    /// The link went down or came back: reports still owed never come.
    pub fn link_reset(&mut self) {
        self.written = self.sent;
        self.heard = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reports_match_messages_in_order_and_a_reset_voids_the_rest() {
        let mut stamps = IoStamps::default();
        assert_eq!(stamps.written(), 0, "nothing owed");
        assert_eq!(stamps.next_number(), 1);
        let (a, b) = (stamps.sent(), stamps.sent());
        assert_eq!((a, b), (1, 2));
        assert_eq!(stamps.written(), a);
        stamps.link_reset();
        assert_eq!(stamps.written(), 0, "b's report is void");
        let c = stamps.sent();
        assert_eq!(stamps.written(), c);
    }

    #[test]
    fn silence_is_judged_up_to_the_horizon_never_beyond_now() {
        let mut stamps = IoStamps::default();
        let now = Duration::from_millis(50);
        assert_eq!(stamps.judged(now), now);
        stamps.heard(Duration::from_millis(20));
        assert_eq!(stamps.judged(now), Duration::from_millis(20));
        stamps.heard(Duration::from_millis(60));
        assert_eq!(stamps.judged(now), now);
    }
}
