//! The bridge's refusals in its log, bounded however many arrive: the first refusal of each
//! code in a period is logged whole (who, why), the others of the period are counted, and
//! one summary line at the period's end gives the counts by code and by identity (the
//! identities most refused, at most [`NAMED`] of them: a flood under made-up names does not
//! make the line grow). So a flood of 8 000 bad tokens a second writes a few lines every
//! [`PERIOD`], not a line per query. Time is passed in.

use core::fmt::Write as _;
use core::time::Duration;
use std::collections::BTreeMap;

use motion_wire::keys::Refusal;

/// How long a period of the refusal log lasts.
pub(crate) const PERIOD: Duration = Duration::from_secs(10);
/// Identities a summary names; the rest are counted together.
pub(crate) const NAMED: usize = 8;
/// Identities counted one by one in a period; past that, a new one counts as "others".
const TRACKED: usize = 64;

/// What to write to the log.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Line {
    /// The first refusal of its code in the period, whole.
    First {
        /// The identity it was sent under.
        identity: String,
        /// Why.
        refusal: Refusal,
        /// The text the remote was sent.
        text: String,
    },
    /// The period's refusals that were counted, not logged.
    Summary {
        /// How long the period lasted.
        period: Duration,
        /// How many were counted.
        counted: u64,
        /// `code count, …`.
        by_code: String,
        /// `identity count, …` (the most refused first, then `others N`).
        by_identity: String,
    },
}

/// The counts of the current period.
#[derive(Debug, Default)]
pub(crate) struct RefusalLog {
    /// When the period started (`None`: no refusal since the last summary).
    started: Option<Duration>,
    /// Refusals per code in the period (logged whole or counted).
    logged: BTreeMap<&'static str, bool>,
    counted: BTreeMap<&'static str, u64>,
    by_identity: BTreeMap<String, u64>,
    others: u64,
}

impl RefusalLog {
    /// Notes a refusal of `refusal` sent to `identity` with `text` at `now`; the lines to
    /// write (a summary of the period that ended, the refusal itself if it is the first
    /// of its code).
    pub(crate) fn note(
        &mut self,
        now: Duration,
        identity: &str,
        refusal: Refusal,
        text: &str,
    ) -> Vec<Line> {
        let mut lines: Vec<Line> = self.flush(now).into_iter().collect();
        self.started.get_or_insert(now);
        let code = refusal.code();
        if !self.logged.get(code).copied().unwrap_or(false) {
            self.logged.insert(code, true);
            lines.push(Line::First {
                identity: identity.to_owned(),
                refusal,
                text: text.to_owned(),
            });
            return lines;
        }
        *self.counted.entry(code).or_default() += 1;
        if let Some(count) = self.by_identity.get_mut(identity) {
            *count += 1;
        } else if self.by_identity.len() < TRACKED {
            self.by_identity.insert(identity.to_owned(), 1);
        } else {
            self.others += 1;
        }
        lines
    }

    /// The summary of the period if it ended by `now` (and anything was counted); the
    /// next period starts with the next refusal.
    pub(crate) fn flush(&mut self, now: Duration) -> Option<Line> {
        let started = self.started?;
        if now.saturating_sub(started) < PERIOD {
            return None;
        }
        self.summary(now)
    }

    /// The summary of the period so far, whether it ended or not (the bridge is exiting).
    pub(crate) fn summary(&mut self, now: Duration) -> Option<Line> {
        let period = now.saturating_sub(self.started?);
        let counted: u64 = self.counted.values().sum();
        let summary = (counted > 0).then(|| {
            let mut by_code = String::new();
            for (code, count) in &self.counted {
                let _ = write!(by_code, "{}{code} {count}", sep(&by_code));
            }
            let mut identities: Vec<(&String, &u64)> = self.by_identity.iter().collect();
            identities.sort_by(|a, b| b.1.cmp(a.1).then_with(|| a.0.cmp(b.0)));
            let mut by_identity = String::new();
            let mut others = self.others;
            for (index, (identity, count)) in identities.into_iter().enumerate() {
                if index < NAMED {
                    let _ = write!(by_identity, "{}`{identity}` {count}", sep(&by_identity));
                } else {
                    others += count;
                }
            }
            if others > 0 {
                let _ = write!(by_identity, "{}others {others}", sep(&by_identity));
            }
            Line::Summary {
                period,
                counted,
                by_code,
                by_identity,
            }
        });
        *self = Self::default();
        summary
    }
}

fn sep(text: &str) -> &'static str {
    if text.is_empty() { "" } else { ", " }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(seconds: f64) -> Duration {
        Duration::from_secs_f64(seconds)
    }

    #[test]
    fn a_flood_is_one_line_per_code_and_a_summary_per_period() {
        let mut log = RefusalLog::default();
        let mut lines = Vec::new();
        // 8000 bad tokens a second for 30 s, under 200 made-up names, and a few late ones.
        for n in 0..240_000u64 {
            let now = s(n as f64 / 8000.0);
            let identity = format!("made-up-{}", n % 200);
            lines.extend(log.note(now, &identity, Refusal::NoSession, "no session"));
            if n % 1000 == 0 {
                lines.extend(log.note(now, "panel", Refusal::Late, "late"));
            }
            lines.extend(log.flush(now));
        }
        lines.extend(log.flush(s(40.0)));
        let firsts = lines
            .iter()
            .filter(|line| matches!(line, Line::First { .. }))
            .count();
        let summaries: Vec<_> = lines
            .iter()
            .filter_map(|line| match line {
                Line::Summary {
                    counted,
                    by_code,
                    by_identity,
                    ..
                } => Some((*counted, by_code.clone(), by_identity.clone())),
                Line::First { .. } => None,
            })
            .collect();
        // Three periods of 10 s (the last flushed at 40 s): two first lines and one
        // summary each.
        assert_eq!((firsts, summaries.len()), (6, 3), "{lines:#?}");
        let total: u64 = summaries.iter().map(|(counted, ..)| counted).sum();
        assert_eq!(
            total + firsts as u64,
            240_000 + 240,
            "every refusal counted once"
        );
        let (_, by_code, by_identity) = &summaries[0];
        assert!(
            by_code.contains("late ") && by_code.contains("no-session "),
            "{by_code}"
        );
        // 8 names, the rest together.
        assert_eq!(by_identity.matches('`').count(), 2 * NAMED, "{by_identity}");
        assert!(by_identity.contains("others "), "{by_identity}");
    }

    #[test]
    fn a_lone_refusal_is_logged_whole_and_needs_no_summary() {
        let mut log = RefusalLog::default();
        let lines = log.note(s(1.0), "panel", Refusal::NotAllowed, "not on its list");
        assert_eq!(
            lines,
            [Line::First {
                identity: "panel".to_owned(),
                refusal: Refusal::NotAllowed,
                text: "not on its list".to_owned(),
            }]
        );
        assert_eq!(log.flush(s(30.0)), None);
        // Counted ones are summed up at exit before the period ends.
        let _ = log.note(s(31.0), "panel", Refusal::Late, "late");
        let _ = log.note(s(31.5), "other", Refusal::Late, "late");
        assert_eq!(log.flush(s(32.0)), None, "the period has not ended");
        match log.summary(s(32.0)) {
            Some(Line::Summary {
                counted, by_code, ..
            }) => assert_eq!((counted, by_code.as_str()), (1, "late 1")),
            other => panic!("a summary at exit: {other:?}"),
        }
        // A new period: logged whole again.
        assert_eq!(
            log.note(s(31.0), "panel", Refusal::NotAllowed, "again")
                .len(),
            1
        );
    }
}
