//! What the bridge lets through, decided without I/O (time is an argument): the allow-list
//! of each remote identity, its rate limit, the sessions the bridge opened and the lateness
//! of their requests, and claims per remote.
//!
//! Stop and e-stop need nothing but the allow-list here: no session, no lateness check —
//! they are forwarded however many sessions are open. Where a query arrives, before it waits
//! anywhere, the [`Gate`] sends an e-stop on its own path and holds stops to a rate of their
//! own per entry (`stop_burst`). Every other
//! command needs a session the bridge opened for the identity it is sent under (its secret
//! token in the attachment), arrives within the window on that session's clock, and fits
//! the rate of its `[[remote]]` entry: one bucket per entry, so every identity that falls
//! under `*` shares the wildcard's bucket.
//!
//! The server sees the bridge's iceoryx2 node as the sender of every forwarded request, so
//! to the server every claim a remote takes is the bridge's. The bridge therefore keeps its
//! own table of which remote session holds what, and answers for the server where remotes
//! would otherwise share one identity: a claim or a goal on a target another remote holds is
//! refused with `ClaimedByOther`, a release of a claim the remote does not hold with
//! `NotClaimed` — the same reasons the server gives between local clients. Stop, e-stop and
//! reset are never held back by claims (as in the engine).

use core::time::Duration;
use std::collections::HashMap;

use motion_ipc::{
    AxisFlags, ClientId, CommandKind, CommandReply, CommandRequest, MotionFrame, Reason,
    SCHEMA_VERSION, SignalFlags, Target,
};

use motion_wire::keys::{Refusal, RequestMeta, SessionId, SessionOpen, SessionToken};

mod gate;
mod session;

pub use gate::{Early, Gate};
pub use session::MAX_SESSIONS;
use session::{Full, Lookup, Sessions, Timing};

/// A set of command kinds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct KindSet(u32);

impl KindSet {
    /// No kind.
    pub const NONE: Self = Self(0);

    /// Every kind.
    pub fn all() -> Self {
        CommandKind::ALL.into_iter().fold(Self::NONE, Self::with)
    }

    /// The set with `kind` added.
    #[must_use]
    pub const fn with(self, kind: CommandKind) -> Self {
        Self(self.0 | (1 << kind as u32))
    }

    /// Every kind of either set.
    #[must_use]
    pub const fn union(self, other: Self) -> Self {
        Self(self.0 | other.0)
    }

    /// Whether `kind` is in the set.
    pub const fn contains(self, kind: CommandKind) -> bool {
        self.0 & (1 << kind as u32) != 0
    }

    /// The kinds in the set, by name.
    pub fn names(self) -> Vec<&'static str> {
        CommandKind::ALL
            .into_iter()
            .filter(|kind| self.contains(*kind))
            .map(CommandKind::name)
            .collect()
    }

    /// The kinds a name of the config's `allow` list stands for: a kind's own name
    /// (`ramp-position`, `e-stop`, …) or a group: `estop` (= `e-stop`), `move` (`position`,
    /// `ramp-position`), `jog` (`velocity`, `ramp-velocity`), `io` (`set-output`), `all`.
    pub fn from_name(name: &str) -> Option<Self> {
        use CommandKind::*;
        let set = |kinds: &[CommandKind]| kinds.iter().fold(Self::NONE, |set, k| set.with(*k));
        Some(match name {
            "all" | "*" => Self::all(),
            "estop" => set(&[EStop]),
            "move" => set(&[Position, RampPosition]),
            "jog" => set(&[Velocity, RampVelocity]),
            "io" => set(&[SetOutput]),
            other => set(&[CommandKind::ALL.into_iter().find(|k| k.name() == other)?]),
        })
    }

    /// Every name [`KindSet::from_name`] takes, for messages.
    pub fn known_names() -> String {
        let mut names: Vec<&str> = CommandKind::ALL
            .into_iter()
            .map(CommandKind::name)
            .collect();
        names.extend(["estop", "move", "jog", "io", "all"]);
        names.join(", ")
    }
}

/// Kinds that only ever make a machine safer (stop, e-stop): never refused as late or for
/// want of a session, never held back by claims (they still need the allow-list; stops have
/// a rate of their own, the [`Gate`]'s). `off` is not one of them: a de-energised vertical
/// axis falls.
pub const fn is_safety(kind: CommandKind) -> bool {
    matches!(kind, CommandKind::Stop | CommandKind::EStop)
}

/// Kinds whose goal the server's deadman ends unless renewed.
pub const fn is_deadman(kind: CommandKind) -> bool {
    matches!(
        kind,
        CommandKind::Velocity | CommandKind::RampVelocity | CommandKind::Power
    )
}

/// What one remote identity may do (`[[remote]]` of the config). The rate limit is the
/// entry's, shared by all its client sessions — for `*`, by every identity without an entry
/// of its own.
#[derive(Debug, Clone, PartialEq)]
pub struct RemoteRule {
    /// The identity (the last chunk of the command key), or `*` for any identity without a
    /// rule of its own.
    pub identity: String,
    /// The kinds it may send.
    pub allow: KindSet,
    /// Sustained requests per second.
    pub rate: f64,
    /// Requests it may send at once above the sustained rate.
    pub burst: f64,
    /// Stops it may send at once above `rate`: stops have a bucket of their own per entry
    /// (a remote that spent its requests on goals may still stop), refilled at `rate`.
    pub stop_burst: f64,
    /// Sessions the entry may hold open at once (all its identities together, for `*`):
    /// its share of the bridge's [`MAX_SESSIONS`].
    pub sessions: usize,
}

/// Default `rate`: requests per second a remote may sustain.
pub const DEFAULT_RATE: f64 = 200.0;
/// Default `burst`.
pub const DEFAULT_BURST: f64 = 100.0;
/// Default `stop_burst`: generous, a panel stopping every axis many times over.
pub const DEFAULT_STOP_BURST: f64 = 1000.0;

/// The lateness window when neither the config nor the server gives one (a server without
/// a deadman).
pub const FALLBACK_MAX_DELAY: Duration = Duration::from_secs(1);

impl RemoteRule {
    /// Whether the entry allows more than stop and e-stop (what needs a session).
    pub fn allows_more_than_safety(&self) -> bool {
        CommandKind::ALL
            .into_iter()
            .any(|kind| !is_safety(kind) && self.allow.contains(kind))
    }
}

/// Who sent a request: an identity and one client session of it.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Remote {
    /// The identity (the command key's last chunk).
    pub identity: String,
    /// The client's session.
    pub session: SessionId,
}

/// What to do with a request.
#[derive(Debug, Clone, PartialEq)]
pub enum Verdict {
    /// Send this (the request with its `client` cleared: the server takes the bridge's
    /// node) to the server and pass its reply back; from this remote session (`None`: a
    /// stop or e-stop without one).
    Forward(CommandRequest, Option<Remote>),
    /// Answer for the server with this reason (claims between remotes, schema).
    Answer(Reason),
    /// Refuse as the bridge, with a message.
    Refuse(Refusal, String),
}

/// The token bucket of one `[[remote]]` entry.
#[derive(Debug)]
struct Bucket {
    tokens: f64,
    refilled: Duration,
}

/// The bridge's policy: rules, and what it learnt of every remote session.
#[derive(Debug)]
pub struct Policy {
    rules: Vec<RemoteRule>,
    max_delay: Option<Duration>,
    sessions: Sessions,
    /// Per `[[remote]]` entry (its `identity`, `*` for the wildcard).
    buckets: HashMap<String, Bucket>,
    claims: HashMap<(Target, u32), Remote>,
    /// Per axis: the remote whose deadman goal (jog, power) runs there.
    deadman: HashMap<u32, Remote>,
}

impl Policy {
    /// A policy of `rules`, refusing non-safety requests older than `max_delay` (`None`:
    /// the server's deadman, given to [`Policy::admit`]).
    pub fn new(rules: Vec<RemoteRule>, max_delay: Option<Duration>) -> Self {
        Self {
            rules,
            max_delay,
            sessions: Sessions::default(),
            buckets: HashMap::new(),
            claims: HashMap::new(),
            deadman: HashMap::new(),
        }
    }

    /// The rule of `identity`: its own, else the `*` rule.
    pub fn rule(&self, identity: &str) -> Option<&RemoteRule> {
        rule_of(&self.rules, identity)
    }

    /// Opens a session for `identity` as `open` asks, received at `now`, under the id and
    /// token the caller drew at random; refused when the identity may send only stop and
    /// e-stop (which need no session), over its rate, or when [`MAX_SESSIONS`] are open.
    pub fn open_session(
        &mut self,
        now: Duration,
        identity: &str,
        open: SessionOpen,
        id: SessionId,
        token: SessionToken,
    ) -> Result<(), (Refusal, String)> {
        let Some(rule) = self.rule(identity) else {
            return Err(no_rule(identity));
        };
        if !rule.allows_more_than_safety() {
            return Err((
                Refusal::NotAllowed,
                format!("remote `{identity}` may send only stop and e-stop, which need no session"),
            ));
        }
        let (key, rate, burst, share) =
            (rule.identity.clone(), rule.rate, rule.burst, rule.sessions);
        if !self.take_token(now, &key, rate, burst) {
            return Err(rate_limited(identity, &key, rate, burst));
        }
        match self
            .sessions
            .open(now, identity, &key, share, open.sent_ns, id, token)
        {
            Ok(()) => Ok(()),
            Err(Full::Share) => Err((
                Refusal::Busy,
                format!(
                    "{} {share} sessions open already, its share of the bridge's \
                     {MAX_SESSIONS} (`sessions` of its [[remote]] entry; stop and e-stop still \
                     pass without one)",
                    if key == identity {
                        format!("remote `{identity}` has its")
                    } else {
                        format!("the identities under `{key}` (here `{identity}`) have their")
                    }
                ),
            )),
            Err(Full::Table) => Err((
                Refusal::Busy,
                format!(
                    "the bridge has {MAX_SESSIONS} remote sessions open already (stop and \
                     e-stop still pass without one)"
                ),
            )),
            Err(Full::Taken) => Err((Refusal::Busy, "the session id drawn is taken".to_owned())),
        }
    }

    /// Whether `id` or `token` is taken (or the token is zero): draw again.
    pub fn session_taken(&self, id: SessionId, token: SessionToken) -> bool {
        self.sessions.taken(id, token)
    }

    /// The liveliness token of `identity`'s session `id` appeared: the session is not
    /// forgotten to make room while it is there.
    pub fn session_live(&mut self, identity: &str, id: SessionId) {
        self.sessions.live(identity, id);
    }

    /// Sessions open now.
    pub fn session_count(&self) -> usize {
        self.sessions.len()
    }

    /// Sessions open now under the `[[remote]]` entry `entry` (its `identity`, or `*`).
    pub fn sessions_of_entry(&self, entry: &str) -> usize {
        self.sessions.of_entry(entry)
    }

    /// Judges `request` (`signed`: its payload's bytes as received, which the MAC of `meta`
    /// covers) sent under `identity` with `meta` (`None`: no readable attachment), received
    /// at `now` (the bridge's monotonic clock). `deadman` is the server's
    /// `command_timeout_ms` (the lateness window when the config sets none).
    pub fn admit(
        &mut self,
        now: Duration,
        identity: &str,
        meta: Option<RequestMeta>,
        request: &CommandRequest,
        signed: &[u8],
        deadman: Duration,
    ) -> Verdict {
        if request.schema_version != SCHEMA_VERSION {
            return Verdict::Answer(Reason::SchemaMismatch);
        }
        let Ok(kind) = request.kind() else {
            return Verdict::Answer(Reason::UnknownKind);
        };
        let Ok(target) = request.target() else {
            return Verdict::Answer(Reason::UnknownTarget);
        };
        let Some(rule) = self.rule(identity) else {
            let (refusal, text) = no_rule(identity);
            return Verdict::Refuse(refusal, text);
        };
        if !rule.allow.contains(kind) {
            let (refusal, text) = not_allowed(kind, identity, rule);
            return Verdict::Refuse(refusal, text);
        }
        let (key, rate, burst) = (rule.identity.clone(), rule.rate, rule.burst);
        let window = match self.max_delay.unwrap_or(deadman) {
            Duration::ZERO => FALLBACK_MAX_DELAY,
            window => window,
        };
        let id = meta.map_or(SessionId(0), |meta| meta.session);
        let session = match self.sessions.find(identity, id) {
            Lookup::Found(state)
                if meta.is_some_and(|meta| meta.verify(state.token, identity, signed)) =>
            {
                state
            }
            // Stop and e-stop: nothing more to judge and nothing to keep — never late,
            // never held back by claims.
            _ if is_safety(kind) => return Verdict::Forward(cleared(request), None),
            Lookup::Found(_) => {
                return Verdict::Refuse(
                    Refusal::NoSession,
                    format!(
                        "the attachment's MAC is not that of `{}` under `{identity}` with the \
                         secret of the session it names: not sent by that session's client",
                        kind.name()
                    ),
                );
            }
            // Stop and e-stop: nothing more to judge and nothing to keep — never late,
            // never over the rate, never held back by claims.
            _ if is_safety(kind) => return Verdict::Forward(cleared(request), None),
            Lookup::OtherIdentity => {
                return Verdict::Refuse(
                    Refusal::NoSession,
                    format!(
                        "the attachment names a session opened for another identity than \
                         `{identity}`: a session is good only for its own identity"
                    ),
                );
            }
            Lookup::Unknown => {
                return Verdict::Refuse(
                    Refusal::NoSession,
                    format!(
                        "`{}` needs a session this bridge opened for `{identity}`; the \
                         attachment names none (open one on the session key; a bridge that \
                         restarted forgot its sessions)",
                        kind.name()
                    ),
                );
            }
        };
        let remote = Remote {
            identity: identity.to_owned(),
            session: session.id,
        };
        let counter = meta.map_or(0, |meta| meta.counter);
        if !session.fresh(counter) {
            if is_safety(kind) {
                return Verdict::Forward(cleared(request), None);
            }
            return Verdict::Refuse(
                Refusal::Late,
                format!(
                    "{} carries request counter {counter} of its session, seen already (or \
                     far below the newest): a replay, not applied",
                    kind.name()
                ),
            );
        }
        if is_safety(kind) {
            return Verdict::Forward(cleared(request), Some(remote));
        }
        let sent_ns = meta.map_or(0, |meta| meta.sent_ns);
        match session.judge(now, sent_ns, window) {
            Timing::OnTime => {}
            Timing::Late(by) => {
                return Verdict::Refuse(
                    Refusal::Late,
                    format!(
                        "{} arrived {by:?} later than this session's requests usually take \
                         (limit {window:?}): held up in the network, not applied",
                        kind.name()
                    ),
                );
            }
            Timing::Ahead(by) => {
                return Verdict::Refuse(
                    Refusal::Late,
                    format!(
                        "{} says it was sent {by:?} later than it could have been on this \
                         session's clock (limit {window:?}): not applied",
                        kind.name()
                    ),
                );
            }
        }
        if !self.take_token(now, &key, rate, burst) {
            let (refusal, text) = rate_limited(identity, &key, rate, burst);
            return Verdict::Refuse(refusal, text);
        }
        if let Some(reason) = self.claim_check(&remote, kind, target, request.axis) {
            return Verdict::Answer(reason);
        }
        Verdict::Forward(cleared(request), Some(remote))
    }

    /// Takes one request from the bucket of the `[[remote]]` entry `key`.
    fn take_token(&mut self, now: Duration, key: &str, rate: f64, burst: f64) -> bool {
        if !self.buckets.contains_key(key) {
            self.buckets.insert(
                key.to_owned(),
                Bucket {
                    tokens: burst,
                    refilled: now,
                },
            );
        }
        self.buckets
            .get_mut(key)
            .is_some_and(|bucket| bucket.take(now, rate, burst))
    }

    /// The claim rule between remotes, as the engine applies it between local clients.
    fn claim_check(
        &self,
        remote: &Remote,
        kind: CommandKind,
        target: Target,
        index: u32,
    ) -> Option<Reason> {
        let held_by_other = |target: Target, index: u32| {
            self.claims
                .get(&(target, index))
                .is_some_and(|holder| holder != remote)
        };
        match kind {
            CommandKind::Stop | CommandKind::EStop | CommandKind::Reset => None,
            CommandKind::Release => {
                (self.claims.get(&(target, index)) != Some(remote)).then_some(Reason::NotClaimed)
            }
            CommandKind::Off if index == CommandRequest::ALL_AXES => self
                .claims
                .iter()
                .any(|((t, _), holder)| *t == Target::Axis && holder != remote)
                .then_some(Reason::ClaimedByOther),
            // The server checks the device's claims against the bridge's node, which holds
            // every remote's: while another remote holds any claim through the bridge, a
            // remote may not commission (the bridge does not know which device it is on).
            CommandKind::Commission => self
                .claims
                .values()
                .any(|holder| holder != remote)
                .then_some(Reason::ClaimedByOther),
            _ => held_by_other(target, index).then_some(Reason::ClaimedByOther),
        }
    }

    /// Notes the server's reply to a request `remote` had forwarded.
    pub fn on_reply(&mut self, remote: &Remote, request: &CommandRequest, reply: &CommandReply) {
        if reply.result().is_err() {
            return;
        }
        let (Ok(kind), Ok(target)) = (request.kind(), request.target()) else {
            return;
        };
        let key = (target, request.axis);
        match kind {
            CommandKind::Claim => {
                self.claims.insert(key, remote.clone());
            }
            CommandKind::Release => {
                self.claims.remove(&key);
            }
            CommandKind::EStop => self.deadman.clear(),
            _ if target == Target::Signal || target == Target::Device => {}
            _ if request.axis == CommandRequest::ALL_AXES => self.deadman.clear(),
            kind if is_deadman(kind) => {
                self.deadman.insert(request.axis, remote.clone());
            }
            _ => {
                self.deadman.remove(&request.axis);
            }
        }
    }

    /// Notes the server's reply to a stop or e-stop a remote sent without a session: the
    /// jogs it ended are nobody's to stop any more.
    pub fn on_sessionless_reply(&mut self, request: &CommandRequest, reply: &CommandReply) {
        if reply.result().is_err() || request.target() != Ok(Target::Axis) {
            return;
        }
        match request.kind() {
            Ok(CommandKind::EStop) => self.deadman.clear(),
            Ok(CommandKind::Stop) if request.axis == CommandRequest::ALL_AXES => {
                self.deadman.clear();
            }
            Ok(CommandKind::Stop) => {
                self.deadman.remove(&request.axis);
            }
            _ => {}
        }
    }

    /// Session `id` was opened through the transport of zenoh id `zid` (a remote connected
    /// to the bridge directly): it ends when that transport closes
    /// ([`Policy::transport_gone`]), whatever liveliness tokens name it — a copy of its key
    /// declared by another peer does not keep it.
    pub fn bind_transport(&mut self, id: SessionId, zid: &str) {
        self.sessions.bind(id, zid);
    }

    /// The transport of zenoh id `zid` closed: every session bound to it ends, as in
    /// [`Policy::session_gone`]; what the bridge sends for them.
    pub fn transport_gone(&mut self, zid: &str) -> Vec<CommandRequest> {
        let mut requests = Vec::new();
        for (identity, id) in self.sessions.bound_to(zid) {
            requests.extend(self.session_gone(&identity, id));
        }
        requests
    }

    /// A remote session ended (its liveliness token went away): what the bridge sends for
    /// it — a stop of every axis whose deadman goal it started and nobody replaced, and a
    /// release of every claim it held. Returns them as requests (client zero).
    pub fn session_gone(&mut self, identity: &str, session: SessionId) -> Vec<CommandRequest> {
        if !self.sessions.close(identity, session) {
            // Not one of ours (a token declared under another's id, or long forgotten).
            return Vec::new();
        }
        let mut requests = Vec::new();
        let mut axes: Vec<u32> = self
            .deadman
            .iter()
            .filter(|(_, holder)| holder.session == session)
            .map(|(axis, _)| *axis)
            .collect();
        axes.sort_unstable();
        for axis in axes {
            self.deadman.remove(&axis);
            requests.push(CommandRequest::new(
                ClientId::NONE,
                0,
                axis,
                CommandKind::Stop,
            ));
        }
        let mut held: Vec<(Target, u32)> = self
            .claims
            .iter()
            .filter(|(_, holder)| holder.session == session)
            .map(|(key, _)| *key)
            .collect();
        held.sort_unstable_by_key(|(target, index)| (*target as u32, *index));
        for (target, index) in held {
            self.claims.remove(&(target, index));
            let mut release = CommandRequest::new(ClientId::NONE, 0, index, CommandKind::Release);
            release.target = target as u32;
            requests.push(release);
        }
        requests
    }

    /// The bridge is stopping: a stop of every axis running a remote's deadman goal (the
    /// claims die with the bridge's node on the server anyway).
    pub fn shutdown(&mut self) -> Vec<CommandRequest> {
        let mut axes: Vec<u32> = self.deadman.drain().map(|(axis, _)| axis).collect();
        axes.sort_unstable();
        self.sessions.clear();
        self.claims.clear();
        axes.into_iter()
            .map(|axis| CommandRequest::new(ClientId::NONE, 0, axis, CommandKind::Stop))
            .collect()
    }

    /// Forgets the claims the server no longer holds for the bridge (`bridge`: its node):
    /// leases that ran out, claims voided by a restart.
    pub fn reconcile(&mut self, frame: &MotionFrame, bridge: ClientId) {
        self.claims.retain(|(target, index), _| {
            let index = *index as usize;
            match target {
                Target::Axis => frame.axes().get(index).is_some_and(|axis| {
                    axis.flags().contains(AxisFlags::CLAIMED) && axis.claimed_by == bridge
                }),
                Target::Signal => frame.signals().get(index).is_some_and(|signal| {
                    signal.flags().contains(SignalFlags::CLAIMED) && signal.claimed_by == bridge
                }),
                Target::Group => frame
                    .groups()
                    .get(index)
                    .is_some_and(|group| group.owner == bridge),
                // Nothing to claim on a device itself (its axes and signals are claimed).
                Target::Device => false,
            }
        });
    }

    /// The remote holding a claim on `target` `index` through this bridge.
    pub fn holder(&self, target: Target, index: u32) -> Option<&Remote> {
        self.claims.get(&(target, index))
    }

    /// Forgets every claim and deadman goal (the server restarted: they died with it).
    pub fn server_restarted(&mut self) {
        self.claims.clear();
        self.deadman.clear();
    }
}

/// The rule of `identity` among `rules`: its own, else the `*` rule.
fn rule_of<'r>(rules: &'r [RemoteRule], identity: &str) -> Option<&'r RemoteRule> {
    rules
        .iter()
        .find(|rule| rule.identity == identity)
        .or_else(|| rules.iter().find(|rule| rule.identity == "*"))
}

fn not_allowed(kind: CommandKind, identity: &str, rule: &RemoteRule) -> (Refusal, String) {
    let allowed = rule.allow.names();
    (
        Refusal::NotAllowed,
        format!(
            "`{}` is not allowed for remote `{identity}` by the bridge's config (allowed: {})",
            kind.name(),
            if allowed.is_empty() {
                "nothing".to_owned()
            } else {
                allowed.join(", ")
            }
        ),
    )
}

/// `request` as the bridge forwards it: its `client` cleared (the server takes the
/// bridge's node).
fn cleared(request: &CommandRequest) -> CommandRequest {
    let mut forwarded = *request;
    forwarded.client = ClientId::NONE;
    forwarded
}

fn no_rule(identity: &str) -> (Refusal, String) {
    (
        Refusal::NotAllowed,
        format!(
            "the bridge has no [[remote]] entry for identity `{identity}` (nor one for `*`): \
             it may not command"
        ),
    )
}

fn rate_limited(identity: &str, key: &str, rate: f64, burst: f64) -> (Refusal, String) {
    let whose = if key == identity {
        format!("remote `{identity}`")
    } else {
        format!("the identities under `{key}` (here `{identity}`) together")
    };
    (
        Refusal::RateLimited,
        format!("{whose} sent more than {rate} requests/s (burst {burst})"),
    )
}

impl Bucket {
    /// Takes one token; false when the bucket is empty.
    fn take(&mut self, now: Duration, rate: f64, burst: f64) -> bool {
        let elapsed = now.saturating_sub(self.refilled).as_secs_f64();
        self.tokens = (self.tokens + elapsed * rate).min(burst);
        self.refilled = now;
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            true
        } else {
            false
        }
    }
}

#[cfg(test)]
mod test_support;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_sessions;
