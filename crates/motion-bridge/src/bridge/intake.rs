//! Where remote queries arrive: zenoh's threads run the queryables' callbacks, which hand
//! each query to the bridge's loop through a channel bounded by [`MAX_WAITING_QUERIES`]
//! (past it a query is answered `busy` where it arrived: a flood never grows the bridge's
//! memory) — except what must not wait behind a flood:
//!
//! - **E-stop**: decoded in the callback and, if the identity may send it, put on the
//!   e-stop's own path: a list of its own (never full, never `busy`) the loop empties
//!   before anything else, waking it if it sleeps. The loop sends one e-stop to the server
//!   for every e-stop that arrived since the last it sent, ahead of every queued command,
//!   and it supersedes every queued stop.
//! - **Stop**: held to its entry's stop rate in the callback ([`Gate`]), so a stop flood is
//!   refused `rate-limited` here and never fills the channel.
//! - A request that is no `CommandRequest`, or on no command key, or not on the
//!   identity's allow-list (for stop and e-stop), is refused here.
//!
//! Every refusal goes to the bounded refusal log ([`RefusalLog`]), and is sent by a thread
//! of its own (`bridge-refusals`), never on zenoh's thread: a reply to a peer that does not
//! read its replies may wait, and zenoh's threads are what every other remote's queries —
//! the e-stop among them — arrive through. At most [`REFUSALS_WAITING`] refusals wait for
//! that thread; past that, a refused query is dropped unanswered (zenoh ends it without a
//! reply: the flooder learns nothing, and the bridge does no more work for it).

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::mpsc::{Sender, SyncSender, TrySendError};
use std::sync::{Mutex, PoisonError};
use std::time::Instant;

use motion_ipc::CommandRequest;
use zenoh::query::Query;

use super::refusals::{Line, RefusalLog};
use super::{Event, MAX_WAITING_QUERIES, refuse};
use crate::policy::{Early, Gate, RemoteRule};
use motion_wire::keys::{Keys, Refusal, RequestMeta};
use motion_wire::wire;

/// Refusals waiting for the thread that sends them; past that, refused queries are dropped
/// unanswered.
pub(crate) const REFUSALS_WAITING: usize = 4096;

/// An e-stop on its own path, as it arrived.
pub(crate) struct EstopCall {
    pub(crate) query: Query,
    pub(crate) identity: String,
    pub(crate) request: CommandRequest,
    /// The request's bytes as received (what the attachment's MAC covers).
    pub(crate) signed: Vec<u8>,
    pub(crate) meta: Option<RequestMeta>,
    pub(crate) received: Instant,
}

/// What the callbacks share with the loop.
pub(crate) struct Intake {
    keys: Keys,
    started: Instant,
    gate: Mutex<Gate>,
    estops: Mutex<Vec<EstopCall>>,
    /// Set when an e-stop waits in `estops` (and the loop was woken for it).
    estop_waiting: AtomicBool,
    /// Queries in the loop's channel.
    waiting: AtomicUsize,
    events: Sender<Event>,
    log: Mutex<RefusalLog>,
    /// To the thread that sends refusals.
    refusals: SyncSender<(Query, Refusal, String)>,
}

impl core::fmt::Debug for Intake {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Intake")
            .field("waiting", &self.waiting.load(Ordering::Relaxed))
            .finish_non_exhaustive()
    }
}

impl Intake {
    /// The intake of a bridge of `keys` judging by `rules`, handing events to `events`;
    /// times are counted from `started` (the loop's clock). Starts the thread that sends
    /// refusals (it ends when the intake is dropped).
    pub(crate) fn new(
        keys: Keys,
        rules: Vec<RemoteRule>,
        events: Sender<Event>,
        started: Instant,
    ) -> std::io::Result<Self> {
        let (refusals, to_send) =
            std::sync::mpsc::sync_channel::<(Query, Refusal, String)>(REFUSALS_WAITING);
        std::thread::Builder::new()
            .name("bridge-refusals".to_owned())
            .spawn(move || {
                for (query, refusal, text) in to_send {
                    refuse(Some(&query), refusal, &text);
                }
            })?;
        Ok(Self {
            keys,
            started,
            gate: Mutex::new(Gate::new(rules)),
            estops: Mutex::new(Vec::new()),
            estop_waiting: AtomicBool::new(false),
            waiting: AtomicUsize::new(0),
            events,
            log: Mutex::new(RefusalLog::default()),
            refusals,
        })
    }

    /// The command queryable's callback.
    pub(crate) fn command(&self, query: Query) {
        let received = Instant::now();
        let key = query.key_expr().as_str();
        let Some(identity) = self.keys.identity_of(key).map(str::to_owned) else {
            let identity = last_chunk(&query);
            self.refuse(
                query,
                &identity,
                Refusal::BadRequest,
                "not a command key of this bridge",
            );
            return;
        };
        let signed = match query.payload() {
            Some(bytes) => bytes.to_bytes().into_owned(),
            None => {
                self.refuse(
                    query,
                    &identity,
                    Refusal::BadRequest,
                    "a command needs a CommandRequest",
                );
                return;
            }
        };
        let request = match wire::decode::<CommandRequest>(&signed) {
            Ok(request) => request,
            Err(error) => {
                self.refuse(query, &identity, Refusal::BadRequest, &error.to_string());
                return;
            }
        };
        let now = received.saturating_duration_since(self.started);
        let early = self
            .gate
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .judge(now, &identity, &request);
        match early {
            Early::EStop => {
                let meta = query
                    .attachment()
                    .and_then(|bytes| RequestMeta::decode(&bytes.to_bytes()));
                self.estop(EstopCall {
                    query,
                    identity,
                    request,
                    signed,
                    meta,
                    received,
                });
            }
            Early::Refuse(refusal, text) => self.refuse(query, &identity, refusal, &text),
            Early::Stop | Early::Loop => self.hand_over(Event::Command(query, received)),
        }
    }

    /// Puts `call` on the e-stop's path and wakes the loop if it may sleep.
    fn estop(&self, call: EstopCall) {
        self.estops
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .push(call);
        if !self.estop_waiting.swap(true, Ordering::AcqRel) {
            // Unbounded channel, one wake-up at a time: never refused.
            let _ = self.events.send(Event::Estop);
        }
    }

    /// Whether an e-stop waits (cheap: the loop asks between any two events).
    pub(crate) fn estop_waiting(&self) -> bool {
        self.estop_waiting.load(Ordering::Acquire)
    }

    /// Every e-stop that arrived since the last call, in order.
    pub(crate) fn take_estops(&self) -> Vec<EstopCall> {
        self.estop_waiting.store(false, Ordering::Release);
        std::mem::take(&mut *self.estops.lock().unwrap_or_else(PoisonError::into_inner))
    }

    /// Hands `event` (a query) to the loop, unless too many queries wait already.
    pub(crate) fn hand_over(&self, event: Event) {
        if self.waiting.fetch_add(1, Ordering::AcqRel) >= MAX_WAITING_QUERIES {
            self.waiting.fetch_sub(1, Ordering::AcqRel);
            if let Event::Command(query, _) | Event::Open(query, _) | Event::Read(_, query) = event
            {
                let identity = last_chunk(&query);
                self.refuse(
                    query,
                    &identity,
                    Refusal::Busy,
                    "the bridge is overloaded: retry",
                );
            }
            return;
        }
        if self.events.send(event).is_err() {
            self.waiting.fetch_sub(1, Ordering::AcqRel);
        }
    }

    /// The loop took a query handed over.
    pub(crate) fn took_one(&self) {
        self.waiting.fetch_sub(1, Ordering::AcqRel);
    }

    /// Refuses `query` sent under `identity` (through the refusals' thread) and notes it in
    /// the log.
    pub(crate) fn refuse(&self, query: Query, identity: &str, refusal: Refusal, text: &str) {
        self.refused(identity, refusal, text);
        match self.refusals.try_send((query, refusal, text.to_owned())) {
            Ok(()) => {}
            // Dropped unanswered (zenoh ends the query), or the thread is gone.
            Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) => {}
        }
    }

    /// Notes a refusal in the bounded log.
    pub(crate) fn refused(&self, identity: &str, refusal: Refusal, text: &str) {
        let now = self.started.elapsed();
        let lines = self
            .log
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .note(now, identity, refusal, text);
        lines.into_iter().for_each(write);
    }

    /// Writes the refusal log's summary if its period ended (`at_exit`: whether it did or
    /// not).
    pub(crate) fn flush_log(&self, at_exit: bool) {
        let now = self.started.elapsed();
        let mut log = self.log.lock().unwrap_or_else(PoisonError::into_inner);
        let line = if at_exit {
            log.summary(now)
        } else {
            log.flush(now)
        };
        drop(log);
        line.into_iter().for_each(write);
    }
}

/// The last chunk of the query's key (the identity on a command or session key), for the
/// log.
fn last_chunk(query: &Query) -> String {
    query
        .key_expr()
        .as_str()
        .rsplit('/')
        .next()
        .unwrap_or_default()
        .to_owned()
}

fn write(line: Line) {
    match line {
        Line::First {
            identity,
            refusal,
            text,
        } => tracing::info!(
            remote = %identity,
            %refusal,
            %text,
            "refused (the first `{refusal}` of this period; the others are counted)"
        ),
        Line::Summary {
            period,
            counted,
            by_code,
            by_identity,
        } => tracing::info!(
            counted,
            by_code = %by_code,
            by_identity = %by_identity,
            "refused {counted} more requests in the last {:.0} s",
            period.as_secs_f64()
        ),
    }
}
