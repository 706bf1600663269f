//! The line rate (`baud`, manual 6.1 and 8.6 `$40`): "The baud-rate is pre-configured to
//! 19200 baud. It can be changed via command." A pack keeps a rate set with `$40` until it
//! is reset or loses power; the link keeps its own configured rate whenever it is
//! (re)opened. So with a `baud` the driver does not know at which rate its pack answers:
//!
//! - it asks `$43` at the link's rate first; every unanswered `$43` moves it to the next
//!   candidate, in turn: the link's rate, the `baud`, the factory 19200
//!   ([`LineRate::probe_next`]) — a server restarted while the pack kept its new rate finds
//!   it on the second try, a pack that was power-cycled on the first (or third);
//! - found at another rate than the `baud`, the pack gets `$40` with the `baud`'s divisor
//!   (and the configured switch-over delay), then `$43` goes at the `baud` — once per
//!   start-up: a pack that does not answer at the new rate is found again at its old one
//!   and kept there;
//! - the driver never touches the link: it says at which rate its next message goes
//!   ([`Driver::line_rate`](motion_drivers::Driver::line_rate)), and the link bus has the
//!   link changed to it before that message (after the `$40`, which went at the old rate,
//!   has left the transmitter).
//!
//! Without a `baud` nothing changes: the driver talks at the link's rate and writes the
//! link's own divisor back with `$40`. It still says that rate for every message, so that
//! on a bus where another pack was switched (`motionctl commission --baud`) its own
//! messages keep going at the rate its pack listens at.

use core::time::Duration;

use tmcpack::convert::DEFAULT_BAUD;

use super::spec::word_time;
use super::{Phase, TmcpackDriver};

/// The driver's view of the line rate.
#[derive(serde::Serialize, serde::Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct LineRate {
    /// The link's configured rate: it opens at it.
    link: u32,
    /// The rate the pack is switched to (the `baud` key, or a commissioned rate).
    target: Option<u32>,
    /// The rate the driver talks at now.
    now: u32,
    /// The rate the pack was found at and switched from in this start-up (not again).
    switched_from: Option<u32>,
}

impl LineRate {
    pub fn new(link: u32, target: Option<u32>) -> Self {
        Self {
            link,
            target,
            now: link,
            switched_from: None,
        }
    }

    /// The rate the driver talks at now.
    pub fn now(&self) -> u32 {
        self.now
    }

    /// The rate the link must run at for the next message (always said: see the module
    /// docs).
    pub fn wanted(&self) -> Option<u32> {
        Some(self.now)
    }

    /// The rates tried in turn while the pack is silent: the link's, the target, the
    /// factory rate (each once).
    fn candidates(&self) -> [u32; 3] {
        let target = self.target.unwrap_or(self.link);
        let factory = if DEFAULT_BAUD == self.link || DEFAULT_BAUD == target {
            self.link
        } else {
            DEFAULT_BAUD
        };
        [self.link, target, factory]
    }

    /// The next candidate after the current rate (the current one when there is no other).
    pub fn probe_next(&mut self) {
        if self.target.is_none() {
            return;
        }
        let candidates = self.candidates();
        let mut distinct = [self.link; 3];
        let mut count = 0;
        for rate in candidates {
            if !distinct[..count].contains(&rate) {
                distinct[count] = rate;
                count += 1;
            }
        }
        let at = distinct[..count].iter().position(|&r| r == self.now);
        self.now = match at {
            Some(i) => distinct[(i + 1) % count],
            None => distinct[0],
        };
    }

    /// The rate to switch a pack found at the current rate to, once per start-up.
    pub fn switch_to(&self) -> Option<u32> {
        self.target
            .filter(|&target| target != self.now && self.switched_from != Some(self.now))
    }

    /// The pack was told `$40` for `rate`: from now on the driver talks at it.
    pub fn switched(&mut self, rate: u32) {
        self.switched_from = Some(self.now);
        self.now = rate;
    }

    /// A commissioned rate: the pack is told it now, and again after a reset.
    pub fn commission(&mut self, rate: u32) {
        self.target = Some(rate);
    }

    /// The pack was reset to its factory rate (`$CC`).
    pub fn factory(&mut self) {
        self.now = DEFAULT_BAUD;
        self.switched_from = None;
    }

    /// The link was (re)opened at its configured rate.
    pub fn link_up(&mut self) {
        self.now = self.link;
        self.switched_from = None;
    }

    /// The start-up is over (online): the next one may switch again.
    pub fn online(&mut self) {
        self.switched_from = None;
    }
}

impl TmcpackDriver {
    /// The word time follows the rate the driver talks at.
    pub(super) fn retime(&mut self) {
        self.word_time = word_time(self.rate.now());
    }

    /// An unanswered `$43` of the start-up: the next candidate rate.
    pub(super) fn probe_next_rate(&mut self) {
        self.rate.probe_next();
        self.retime();
    }

    /// The pack answered `$43` of the start-up at the current rate: `$40` to the target
    /// rate first when it differs (then `$43` again at the target), else on to the survey.
    pub(super) fn identified(&mut self) {
        match self.rate.switch_to() {
            Some(rate) => self.service = Some(super::commission::Service::Baud(rate)),
            None => self.phase = Phase::Survey,
        }
    }

    /// Finds the pack again from `at` on: `$43` where it now answers (after a change of
    /// its address or rate, or its reset). Not online meanwhile; no fault.
    pub(super) fn reprobe(&mut self, at: Duration) {
        self.service = None;
        self.phase = Phase::Identify;
        self.retry_at = at;
        self.timeouts_in_row = 0;
        self.status.online = false;
        self.status.fault = None;
        self.quiesce = None;
        self.line = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn candidates_go_round_the_link_the_target_and_the_factory_rate_once_each() {
        let mut rate = LineRate::new(38_400, Some(115_200));
        let mut seen = Vec::new();
        for _ in 0..6 {
            seen.push(rate.now());
            rate.probe_next();
        }
        assert_eq!(seen, [38_400, 115_200, 19_200, 38_400, 115_200, 19_200]);
        let mut rate = LineRate::new(19_200, Some(115_200));
        let mut seen = Vec::new();
        for _ in 0..4 {
            seen.push(rate.now());
            rate.probe_next();
        }
        assert_eq!(seen, [19_200, 115_200, 19_200, 115_200]);
        let mut plain = LineRate::new(19_200, None);
        plain.probe_next();
        assert_eq!((plain.now(), plain.wanted()), (19_200, Some(19_200)));
    }

    #[test]
    fn a_pack_is_switched_once_per_start_up() {
        let mut rate = LineRate::new(19_200, Some(115_200));
        assert_eq!(rate.wanted(), Some(19_200));
        assert_eq!(rate.switch_to(), Some(115_200));
        rate.switched(115_200);
        assert_eq!(rate.wanted(), Some(115_200));
        assert_eq!(rate.switch_to(), None);
        // Silent at 115200: found at 19200 again, and not switched a second time.
        rate.probe_next();
        assert_eq!(rate.now(), 19_200);
        assert_eq!(rate.switch_to(), None);
        rate.online();
        assert_eq!(rate.switch_to(), Some(115_200));
    }
}
