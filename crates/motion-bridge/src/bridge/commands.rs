//! The loop's side of remote commands: judging each ([`Policy::admit`]), queueing it
//! ([`Queue`]), e-stops first, sending what the server has request slots for (one slot
//! kept for an e-stop), and answering every query a job stands for when its reply comes.

use core::time::Duration;
use std::time::Instant;

use motion_ipc::{CommandKind, CommandReply, CommandRequest};
use zenoh::query::Query;

use super::intake::EstopCall;
use super::jobs::{Job, Waiter, reply_for};
use super::server::Pending;
use super::{Bridge, answer, refuse};
use crate::policy::Verdict;
use motion_wire::keys::{Refusal, RequestMeta};

/// A job sent to the server, waiting for its reply.
pub(crate) struct InFlight {
    pub(crate) job: Job,
    pub(crate) pending: Pending,
    pub(crate) sent: Instant,
    pub(crate) deadline: Instant,
}

/// How a job ended.
enum Outcome {
    /// The server's reply, from its node.
    Reply(CommandReply, u128),
    /// The bridge's refusal (no server, no reply).
    Refused(Refusal, String),
}

impl Bridge {
    /// A command query the intake handed over (anything but an e-stop, which has its own
    /// path).
    pub(super) fn on_command(&mut self, query: Query, received: Instant) {
        let key = query.key_expr().as_str().to_owned();
        let Some(identity) = self.keys.identity_of(&key).map(str::to_owned) else {
            self.intake.refuse(
                query,
                "",
                Refusal::BadRequest,
                "not a command key of this bridge",
            );
            return;
        };
        let signed = match query.payload().map(|bytes| bytes.to_bytes().into_owned()) {
            Some(bytes) => bytes,
            None => {
                self.intake.refuse(
                    query,
                    &identity,
                    Refusal::BadRequest,
                    "a command needs a CommandRequest",
                );
                return;
            }
        };
        let request = match motion_wire::wire::decode::<CommandRequest>(&signed) {
            Ok(request) => request,
            Err(error) => {
                self.intake
                    .refuse(query, &identity, Refusal::BadRequest, &error.to_string());
                return;
            }
        };
        // Stop and e-stop pass without a readable attachment; everything else is refused by
        // the policy for want of a session.
        let meta = query
            .attachment()
            .and_then(|bytes| RequestMeta::decode(&bytes.to_bytes()));
        if request.kind() == Ok(CommandKind::EStop) {
            self.queue_estops(vec![EstopCall {
                query,
                identity,
                request,
                signed,
                meta,
                received,
            }]);
            return;
        }
        let now = received.saturating_duration_since(self.started);
        match self
            .policy
            .admit(now, &identity, meta, &request, &signed, self.deadman())
        {
            Verdict::Forward(forwarded, remote) => {
                if self.server.is_none() {
                    refuse(Some(&query), Refusal::NoServer, &self.no_server());
                    return;
                }
                let waiter = Waiter {
                    query,
                    remote,
                    request,
                    received,
                };
                let queued = if request.kind() == Ok(CommandKind::Stop) {
                    self.queue.push_stop(forwarded, waiter)
                } else {
                    self.queue.push(forwarded, waiter)
                };
                match queued {
                    Ok(()) => self.counters.forwarded += 1,
                    Err(waiter) => self.intake.refuse(
                        waiter.query,
                        &identity,
                        Refusal::Busy,
                        "too many commands wait for the server",
                    ),
                }
            }
            Verdict::Answer(reason) => {
                let reply = CommandReply::to(&request, reason, self.latest_tick());
                answer(&query, &reply, self.server_node());
            }
            Verdict::Refuse(refusal, text) => {
                self.counters.refused += 1;
                self.intake.refuse(query, &identity, refusal, &text);
            }
        }
    }

    /// Takes the e-stops waiting on their own path (see `intake.rs`).
    pub(super) fn take_estops(&mut self) {
        let calls = self.intake.take_estops();
        if !calls.is_empty() {
            self.queue_estops(calls);
        }
    }

    /// Judges e-stops and puts those to forward at the front of the queue, as one job.
    fn queue_estops(&mut self, calls: Vec<EstopCall>) {
        let deadman = self.deadman();
        let mut waiters = Vec::with_capacity(calls.len());
        let mut forwarded = None;
        for call in calls {
            let now = call.received.saturating_duration_since(self.started);
            match self.policy.admit(
                now,
                &call.identity,
                call.meta,
                &call.request,
                &call.signed,
                deadman,
            ) {
                Verdict::Forward(_, _) if self.server.is_none() => {
                    refuse(Some(&call.query), Refusal::NoServer, &self.no_server());
                }
                Verdict::Forward(request, remote) => {
                    forwarded.get_or_insert(request);
                    self.counters.forwarded += 1;
                    waiters.push(Waiter {
                        query: call.query,
                        remote,
                        request: call.request,
                        received: call.received,
                    });
                }
                Verdict::Answer(reason) => {
                    let reply = CommandReply::to(&call.request, reason, self.latest_tick());
                    answer(&call.query, &reply, self.server_node());
                }
                Verdict::Refuse(refusal, text) => {
                    self.counters.refused += 1;
                    self.intake
                        .refuse(call.query, &call.identity, refusal, &text);
                }
            }
        }
        if let Some(request) = forwarded {
            self.queue.push_estop(request, waiters);
            self.pump();
        }
    }

    /// Sends queued commands while the server has request slots for the bridge, the last
    /// slot kept for an e-stop.
    pub(super) fn pump(&mut self) {
        let Some(ports) = self.server.as_ref() else {
            return;
        };
        let timeout = self.config.reply_timeout;
        while self.in_flight.len() < ports.max_in_flight {
            let reserve =
                ports.max_in_flight > 1 && self.in_flight.len() + 1 == ports.max_in_flight;
            let Some(job) = self.queue.pop(reserve) else {
                break;
            };
            match ports.send(job.request) {
                Ok(Some(pending)) => {
                    let sent = Instant::now();
                    self.in_flight.push(InFlight {
                        job,
                        pending,
                        sent,
                        deadline: sent + timeout,
                    });
                }
                Ok(None) => finish(
                    &mut self.policy,
                    job,
                    &Outcome::Refused(
                        Refusal::NoServer,
                        "no motiond serves the command service".to_owned(),
                    ),
                ),
                Err(error) => finish(
                    &mut self.policy,
                    job,
                    &Outcome::Refused(Refusal::NoServer, error.to_string()),
                ),
            }
        }
    }

    /// Answers the jobs whose replies arrived or whose time ran out.
    pub(super) fn collect_replies(&mut self, now: Instant) {
        let mut index = 0;
        while index < self.in_flight.len() {
            let flight = &self.in_flight[index];
            let outcome = match super::server::take_reply(&flight.pending) {
                Ok(Some((reply, node))) => Some(Outcome::Reply(reply, node)),
                Ok(None) if now >= flight.deadline => Some(Outcome::Refused(
                    Refusal::NoReply,
                    format!(
                        "motiond did not answer within {:?}",
                        self.config.reply_timeout
                    ),
                )),
                Ok(None) => None,
                Err(error) => Some(Outcome::Refused(Refusal::NoServer, error.to_string())),
            };
            match outcome {
                Some(outcome) => {
                    let flight = self.in_flight.swap_remove(index);
                    if flight.job.is_estop() {
                        let first = flight.job.waiters.iter().map(|w| w.received).min();
                        tracing::debug!(
                            queries = flight.job.waiters.len(),
                            stops_taken_over = flight.job.superseded.len(),
                            in_bridge_us = first.map_or(0, |first| {
                                flight.sent.saturating_duration_since(first).as_micros()
                            }),
                            at_server_us = now.saturating_duration_since(flight.sent).as_micros(),
                            "e-stop answered"
                        );
                    }
                    finish(&mut self.policy, flight.job, &outcome);
                }
                None => index += 1,
            }
        }
    }

    /// Answers everything queued or in flight with `refusal` (the server went away).
    pub(super) fn refuse_all(&mut self, refusal: Refusal, text: &str) {
        let jobs = std::mem::take(&mut self.in_flight)
            .into_iter()
            .map(|flight| flight.job)
            .chain(self.queue.drain());
        for job in jobs {
            finish(
                &mut self.policy,
                job,
                &Outcome::Refused(refusal, text.to_owned()),
            );
        }
    }

    /// The server's deadman (`command_timeout_ms`), zero when not known.
    fn deadman(&self) -> Duration {
        self.info.as_ref().map_or(Duration::ZERO, |info| {
            Duration::from_millis(u64::from(info.value.command_timeout_ms))
        })
    }

    fn no_server(&self) -> String {
        format!(
            "motiond `{}` is not running behind this bridge",
            self.config.server
        )
    }
}

/// Answers every query `job` stands for with `outcome` (the stops it took over with the
/// e-stop's), and notes accepted ones in the policy.
fn finish(policy: &mut crate::policy::Policy, job: Job, outcome: &Outcome) {
    match outcome {
        Outcome::Reply(reply, node) => {
            if job.waiters.is_empty() && reply.result().is_err() {
                tracing::warn!(?reply, "the bridge's own request was refused");
            }
            for waiter in &job.waiters {
                let own = reply_for(&waiter.request, reply);
                note(policy, waiter, &own);
                answer(&waiter.query, &own, *node);
            }
        }
        Outcome::Refused(refusal, text) => {
            for waiter in &job.waiters {
                refuse(Some(&waiter.query), *refusal, text);
            }
        }
    }
    for stop in job.superseded {
        finish(policy, stop, outcome);
    }
}

/// Notes the server's `reply` to `waiter`'s request in the policy (claims, jogs).
fn note(policy: &mut crate::policy::Policy, waiter: &Waiter, reply: &CommandReply) {
    match &waiter.remote {
        Some(remote) => policy.on_reply(remote, &waiter.request, reply),
        None => policy.on_sessionless_reply(&waiter.request, reply),
    }
}
