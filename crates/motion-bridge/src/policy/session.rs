//! Remote sessions: opened by the bridge (a public [`SessionId`] and a secret
//! [`SessionToken`] only the querier receives), bound to the identity they were opened for,
//! their time stamps judged against the bridge's clock from the moment they opened. At most
//! [`MAX_SESSIONS`], and at most its share for each `[[remote]]` entry (its `sessions`): one
//! identity cannot pin every slot. Stop and e-stop need none, so a full table never holds
//! them back.

use core::time::Duration;
use std::collections::{HashMap, HashSet};

use motion_wire::keys::{SessionId, SessionToken};

/// Sessions open at most; past it, sessions without a liveliness token and silent for
/// [`SESSION_IDLE`] are forgotten, and a new one is refused while none is (a flood of
/// session openings never grows the bridge's memory; stop and e-stop need no session).
pub const MAX_SESSIONS: usize = 1024;
/// A session without a liveliness token not heard from for this long may be forgotten to
/// make room.
pub(super) const SESSION_IDLE: Duration = Duration::from_secs(60);
/// How fast the floor of a session's clock offset may rise, s per s: room for clock drift
/// between the hosts (1000 ppm, far above what NTP lets a clock drift).
const FLOOR_CREEP: f64 = 1e-3;
/// Counters a session's requests may arrive out of order by (the e-stop takes a path of its
/// own through the bridge, so a session's requests are not judged in the order sent): one
/// seen already, or more than this below the highest seen, is a replay.
pub(super) const REPLAY_WINDOW: u64 = 1024;
/// How much earlier than the session's floor a request may say it was sent, at least: the
/// floor starts from the session's opening, which may itself have been slow (a loaded
/// host, a new link), so a prompt request may look that much "ahead". A stamp further
/// ahead than this and the window is a clock from the future.
pub(super) const AHEAD_SLACK: Duration = Duration::from_secs(2);

/// One open session.
#[derive(Debug)]
pub(super) struct SessionState {
    /// The identity it was opened for: its token is good for this identity only.
    pub(super) identity: String,
    /// The `[[remote]]` entry whose share it takes (the identity's, or `*`).
    entry: String,
    /// Its secret: the key of its requests' MACs.
    pub(super) token: SessionToken,
    /// The zenoh id of the transport it was opened through, when the bridge saw that
    /// transport: the session ends when it closes.
    transport: Option<String>,
    /// The highest request counter seen, and which of the [`REPLAY_WINDOW`] below it were.
    highest: Option<u64>,
    window: Vec<u64>,
    /// Its public id.
    pub(super) id: SessionId,
    /// Smallest (bridge time − send time) seen, ns, rising by at most `FLOOR_CREEP`, and
    /// when it was last set.
    floor: (i128, Duration),
    /// When it was last heard from (opened, a request).
    seen: Duration,
    /// Whether its liveliness token is there (such a session is never forgotten for room;
    /// it ends when the token goes).
    live: bool,
}

/// How a request's time stamp lies against its session's clock.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Timing {
    /// Within the window.
    OnTime,
    /// Arrived this much later than the session's fastest request.
    Late(Duration),
    /// Says it was sent this much later than it could have been (a clock from the future).
    Ahead(Duration),
}

impl SessionState {
    /// Whether `counter` was not seen before (and is within [`REPLAY_WINDOW`] of the
    /// highest); notes it as seen.
    pub(super) fn fresh(&mut self, counter: u64) -> bool {
        let words = (REPLAY_WINDOW / 64) as usize;
        if self.window.len() != words {
            self.window = vec![0; words];
        }
        let bit = |counter: u64| ((counter / 64) as usize % words, 1u64 << (counter % 64));
        match self.highest {
            Some(highest) if counter <= highest => {
                if highest - counter >= REPLAY_WINDOW {
                    return false;
                }
                let (word, mask) = bit(counter);
                if self.window[word] & mask != 0 {
                    return false;
                }
                self.window[word] |= mask;
                true
            }
            _ => {
                // Clear what slides out of the window between the old highest and this one.
                let from = self.highest.map_or(counter, |h| h + 1);
                if counter - from >= REPLAY_WINDOW {
                    self.window.iter_mut().for_each(|word| *word = 0);
                } else {
                    for cleared in from..counter {
                        let (word, mask) = bit(cleared);
                        self.window[word] &= !mask;
                    }
                }
                let (word, mask) = bit(counter);
                self.window[word] |= mask;
                self.highest = Some(counter);
                true
            }
        }
    }

    /// Judges a request sent at `sent_ns` (the session's clock) and received at `now` (the
    /// bridge's): at most `window` later than the session's fastest, at most `window` (or
    /// [`AHEAD_SLACK`], if more) earlier; a request on time moves the floor.
    pub(super) fn judge(&mut self, now: Duration, sent_ns: u64, window: Duration) -> Timing {
        let offset = now.as_nanos() as i128 - i128::from(sent_ns);
        let (floor, at) = self.floor;
        let creep = (now.saturating_sub(at).as_secs_f64() * FLOOR_CREEP * 1e9) as i128;
        let floor = floor.saturating_add(creep);
        let window_ns = window.as_nanos() as i128;
        let to_duration = |ns: i128| Duration::from_nanos(u64::try_from(ns).unwrap_or(u64::MAX));
        if offset.saturating_sub(floor) > window_ns {
            return Timing::Late(to_duration(offset.saturating_sub(floor)));
        }
        if floor.saturating_sub(offset) > window.max(AHEAD_SLACK).as_nanos() as i128 {
            return Timing::Ahead(to_duration(floor.saturating_sub(offset)));
        }
        self.floor = (floor.min(offset), now);
        self.seen = now;
        Timing::OnTime
    }
}

/// What a session id names for an identity.
#[derive(Debug)]
pub(super) enum Lookup<'s> {
    /// A session of this identity.
    Found(&'s mut SessionState),
    /// No session, or one this bridge did not open (or forgot).
    Unknown,
    /// A session of another identity.
    OtherIdentity,
}

/// Why a session was not opened.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Full {
    /// The entry has its share open (none idle enough to forget).
    Share,
    /// The whole table is full.
    Table,
    /// The id or token drawn is taken (or zero): draw again.
    Taken,
}

/// Every open session.
#[derive(Debug, Default)]
pub(super) struct Sessions {
    by_id: HashMap<SessionId, SessionState>,
    /// The secrets given out (each once).
    tokens: HashSet<SessionToken>,
    /// Sessions open per entry.
    per_entry: HashMap<String, usize>,
}

impl Sessions {
    /// Opens session `id` with secret `token` for `identity` under the entry `entry` (of
    /// `share` sessions at most), whose opening query was sent at `sent_ns` (its clock) and
    /// received at `now`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn open(
        &mut self,
        now: Duration,
        identity: &str,
        entry: &str,
        share: usize,
        sent_ns: u64,
        id: SessionId,
        token: SessionToken,
    ) -> Result<(), Full> {
        if self.taken(id, token) {
            return Err(Full::Taken);
        }
        self.make_room(now, entry, share)?;
        self.tokens.insert(token);
        *self.per_entry.entry(entry.to_owned()).or_default() += 1;
        self.by_id.insert(
            id,
            SessionState {
                identity: identity.to_owned(),
                entry: entry.to_owned(),
                token,
                transport: None,
                highest: None,
                window: Vec::new(),
                id,
                floor: (now.as_nanos() as i128 - i128::from(sent_ns), now),
                seen: now,
                live: false,
            },
        );
        Ok(())
    }

    /// Sessions open under `entry`.
    pub(super) fn of_entry(&self, entry: &str) -> usize {
        self.per_entry.get(entry).copied().unwrap_or(0)
    }

    /// Whether `id` or `token` is taken, or either is zero.
    pub(super) fn taken(&self, id: SessionId, token: SessionToken) -> bool {
        token.is_none() || id.0 == 0 || self.tokens.contains(&token) || self.by_id.contains_key(&id)
    }

    /// Whether a new session of `entry` fits (its share, the table), forgetting idle ones
    /// without liveliness if needed (of the entry when its share is full).
    fn make_room(&mut self, now: Duration, entry: &str, share: usize) -> Result<(), Full> {
        let entry_full = self.of_entry(entry) >= share;
        if !entry_full && self.by_id.len() < MAX_SESSIONS {
            return Ok(());
        }
        let (tokens, per_entry) = (&mut self.tokens, &mut self.per_entry);
        self.by_id.retain(|_, state| {
            let idle = !state.live && now.saturating_sub(state.seen) >= SESSION_IDLE;
            let forget = idle && (!entry_full || state.entry == entry);
            if forget {
                tokens.remove(&state.token);
                if let Some(count) = per_entry.get_mut(&state.entry) {
                    *count = count.saturating_sub(1);
                }
            }
            !forget
        });
        if self.of_entry(entry) >= share {
            Err(Full::Share)
        } else if self.by_id.len() >= MAX_SESSIONS {
            Err(Full::Table)
        } else {
            Ok(())
        }
    }

    /// The session `id` names for `identity`.
    pub(super) fn find(&mut self, identity: &str, id: SessionId) -> Lookup<'_> {
        match self.by_id.get_mut(&id) {
            Some(state) if state.identity == identity => Lookup::Found(state),
            Some(_) => Lookup::OtherIdentity,
            None => Lookup::Unknown,
        }
    }

    /// Binds session `id` to the transport of zenoh id `zid`.
    pub(super) fn bind(&mut self, id: SessionId, zid: &str) {
        if let Some(state) = self.by_id.get_mut(&id) {
            state.transport = Some(zid.to_owned());
        }
    }

    /// The sessions (identity, id) bound to the transport of `zid`.
    pub(super) fn bound_to(&self, zid: &str) -> Vec<(String, SessionId)> {
        let mut sessions: Vec<(String, SessionId)> = self
            .by_id
            .values()
            .filter(|state| state.transport.as_deref() == Some(zid))
            .map(|state| (state.identity.clone(), state.id))
            .collect();
        sessions.sort_unstable_by_key(|(_, id)| *id);
        sessions
    }

    /// The liveliness token of `identity`'s session `id` appeared.
    pub(super) fn live(&mut self, identity: &str, id: SessionId) {
        if let Some(state) = self.by_id.get_mut(&id)
            && state.identity == identity
        {
            state.live = true;
        }
    }

    /// Ends `identity`'s session `id`; whether it was open.
    pub(super) fn close(&mut self, identity: &str, id: SessionId) -> bool {
        if self
            .by_id
            .get(&id)
            .is_none_or(|state| state.identity != identity)
        {
            return false;
        }
        if let Some(state) = self.by_id.remove(&id) {
            self.tokens.remove(&state.token);
            if let Some(count) = self.per_entry.get_mut(&state.entry) {
                *count = count.saturating_sub(1);
            }
        }
        true
    }

    /// Ends every session.
    pub(super) fn clear(&mut self) {
        self.by_id.clear();
        self.tokens.clear();
        self.per_entry.clear();
    }

    /// Sessions open.
    pub(super) fn len(&self) -> usize {
        self.by_id.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_counter_counts_once_within_the_window() {
        let mut sessions = Sessions::default();
        let id = SessionId(1);
        sessions
            .open(Duration::ZERO, "a", "a", 4, 0, id, SessionToken([1; 16]))
            .expect("room");
        let Lookup::Found(state) = sessions.find("a", id) else {
            panic!("opened");
        };
        assert!(state.fresh(1));
        assert!(!state.fresh(1), "a replay");
        assert!(state.fresh(3));
        assert!(state.fresh(2), "out of order, not seen");
        assert!(!state.fresh(2));
        assert!(state.fresh(3 + REPLAY_WINDOW));
        assert!(!state.fresh(3), "below the window");
        assert!(
            state.fresh(4 + REPLAY_WINDOW / 2),
            "in the window, not seen"
        );
        assert!(!state.fresh(4 + REPLAY_WINDOW / 2));
        assert!(state.fresh(10 * REPLAY_WINDOW));
        assert!(state.fresh(10 * REPLAY_WINDOW - 5));
        assert!(!state.fresh(3 + REPLAY_WINDOW), "slid out");
    }
}
