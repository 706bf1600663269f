//! The commands waiting for a request slot of the server, in order, and the queries each
//! one answers.
//!
//! - A command the bridge forwards is a [`Job`]: the request it sends and the remote
//!   queries ([`Waiter`]s) its reply answers (none for the bridge's own stops and releases).
//! - **Stops of one axis coalesce**: a stop for a target whose last queued command is a
//!   queued stop of the same target joins that job (one request to the server, every
//!   query answered by its reply) — never across a command in between for that target, so
//!   a stop never overtakes the goal it stops.
//! - **An e-stop goes first and supersedes every queued stop**: e-stops join one job at the
//!   front of the queue (until it is sent: later ones make the next); every queued stop is
//!   taken into it and answered with its outcome. Goals queued behind stay queued: the
//!   server refuses them while the e-stop is latched.
//! - Bounds: [`MAX_QUEUED`] jobs for other commands, [`MAX_QUEUED_SAFETY`] stop queries
//!   held; e-stops have none (they are sent within a round trip; their count is bounded by
//!   time).

use std::collections::VecDeque;

use motion_ipc::{CommandKind, CommandReply, CommandRequest, Reason};
use zenoh::query::Query;

use crate::policy::Remote;

/// Commands other than stop and e-stop waiting for a request slot of the server; more are
/// refused as busy.
pub(crate) const MAX_QUEUED: usize = 256;
/// Stop queries held in the queue (coalesced or not); more are refused as busy.
pub(crate) const MAX_QUEUED_SAFETY: usize = 4 * MAX_QUEUED;

/// A remote query a job's reply answers.
pub(crate) struct Waiter {
    pub(crate) query: Query,
    /// Its session (`None`: a stop or e-stop without one).
    pub(crate) remote: Option<Remote>,
    /// The request as the remote sent it (its sequence is the one its reply carries).
    pub(crate) request: CommandRequest,
    /// When zenoh handed it over.
    pub(crate) received: std::time::Instant,
}

/// A command waiting for a request slot, or in flight; `W`: what its reply answers (a
/// [`Waiter`]; the unit tests use plain numbers).
pub(crate) struct Job<W = Waiter> {
    /// What goes to the server.
    pub(crate) request: CommandRequest,
    /// The queries its reply answers (none: the bridge's own).
    pub(crate) waiters: Vec<W>,
    /// The stops an e-stop took over: answered with its outcome.
    pub(crate) superseded: Vec<Job<W>>,
}

impl<W> Job<W> {
    /// The bridge's own request (a stop or release for a remote that went away).
    pub(crate) fn own(request: CommandRequest) -> Self {
        Self {
            request,
            waiters: Vec::new(),
            superseded: Vec::new(),
        }
    }

    /// A remote's request.
    pub(crate) fn of(forwarded: CommandRequest, waiter: W) -> Self {
        Self {
            request: forwarded,
            waiters: vec![waiter],
            superseded: Vec::new(),
        }
    }

    pub(crate) fn is_estop(&self) -> bool {
        self.request.kind() == Ok(CommandKind::EStop)
    }

    fn is_stop(&self) -> bool {
        self.request.kind() == Ok(CommandKind::Stop)
    }

    /// Queries this job answers, with those of the stops it took over.
    fn held(&self) -> usize {
        self.waiters.len() + self.superseded.iter().map(Self::held).sum::<usize>()
    }
}

/// Whether `a` and `b` act on different things: the same kind of target, different
/// indices, neither of them "all". Anything else is taken to interact.
fn independent(a: &CommandRequest, b: &CommandRequest) -> bool {
    a.target == b.target
        && a.axis != b.axis
        && a.axis != CommandRequest::ALL_AXES
        && b.axis != CommandRequest::ALL_AXES
}

/// The queue, in order.
pub(crate) struct Queue<W = Waiter> {
    jobs: VecDeque<Job<W>>,
    /// Stop queries held (coalesced, or taken over by a queued e-stop).
    stops_held: usize,
}

impl<W> Default for Queue<W> {
    fn default() -> Self {
        Self {
            jobs: VecDeque::new(),
            stops_held: 0,
        }
    }
}

impl<W> Queue<W> {
    /// Jobs waiting.
    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.jobs.len()
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.jobs.is_empty()
    }

    /// Queues a remote's command other than stop and e-stop; gives it back when
    /// [`MAX_QUEUED`] jobs wait.
    pub(crate) fn push(&mut self, forwarded: CommandRequest, waiter: W) -> Result<(), W> {
        if self.jobs.len() >= MAX_QUEUED {
            return Err(waiter);
        }
        self.jobs.push_back(Job::of(forwarded, waiter));
        Ok(())
    }

    /// Queues the bridge's own request (bounded by the sessions and axes it stems from).
    pub(crate) fn push_own(&mut self, request: CommandRequest) {
        self.jobs.push_back(Job::own(request));
    }

    /// Queues a remote's stop, joining the queued stop of the same target when nothing
    /// queued after that one acts on the target; gives it back when [`MAX_QUEUED_SAFETY`]
    /// stop queries are held.
    pub(crate) fn push_stop(&mut self, forwarded: CommandRequest, waiter: W) -> Result<(), W> {
        if self.stops_held >= MAX_QUEUED_SAFETY {
            return Err(waiter);
        }
        self.stops_held += 1;
        let last = self
            .jobs
            .iter_mut()
            .rev()
            .find(|job| !independent(&job.request, &forwarded));
        if let Some(job) = last
            && job.is_stop()
            && job.request.target == forwarded.target
            && job.request.axis == forwarded.axis
        {
            job.waiters.push(waiter);
            return Ok(());
        }
        self.jobs.push_back(Job::of(forwarded, waiter));
        Ok(())
    }

    /// Puts e-stop queries at the front: into the e-stop job there if it was not sent yet,
    /// else into a new one of `forwarded`; every queued stop is taken into it.
    pub(crate) fn push_estop(&mut self, forwarded: CommandRequest, waiters: Vec<W>) {
        let mut job = match self.jobs.front() {
            Some(front) if front.is_estop() => self.jobs.pop_front().expect("a front"),
            _ => Job {
                request: forwarded,
                waiters: Vec::new(),
                superseded: Vec::new(),
            },
        };
        job.waiters.extend(waiters);
        let (stops, rest): (VecDeque<Job<W>>, VecDeque<Job<W>>) = std::mem::take(&mut self.jobs)
            .into_iter()
            .partition(Job::is_stop);
        self.jobs = rest;
        job.superseded.extend(stops);
        self.jobs.push_front(job);
    }

    /// The next job to send; with `reserve` (one request slot of the server left), only an
    /// e-stop: that slot is kept for it.
    pub(crate) fn pop(&mut self, reserve: bool) -> Option<Job<W>> {
        if reserve && !self.jobs.front().is_some_and(Job::is_estop) {
            return None;
        }
        let job = self.jobs.pop_front()?;
        let stops = if job.is_stop() {
            job.waiters.len()
        } else {
            job.superseded.iter().map(Job::held).sum()
        };
        self.stops_held = self.stops_held.saturating_sub(stops);
        Some(job)
    }

    /// Every job, the queue emptied.
    pub(crate) fn drain(&mut self) -> Vec<Job<W>> {
        self.stops_held = 0;
        self.jobs.drain(..).collect()
    }
}

/// The server's `reply` to a job as the reply to a query that sent `request`: with its own
/// sequence (coalesced queries had their own); for a stop an e-stop took over, the
/// e-stop's outcome and tick.
pub(crate) fn reply_for(request: &CommandRequest, reply: &CommandReply) -> CommandReply {
    if request.kind != reply.kind {
        let reason = reply.result().err().unwrap_or(Reason::Accepted);
        return CommandReply::to(request, reason, reply.tick_applied);
    }
    let mut own = *reply;
    own.sequence = request.sequence;
    own
}

#[cfg(test)]
mod tests {
    use motion_ipc::{ClientId, Target};

    use super::*;

    fn request(kind: CommandKind, axis: u32) -> CommandRequest {
        CommandRequest::new(ClientId::NONE, 1, axis, kind)
    }

    /// (kind, axis, the waiters, the waiters of the stops it took over) of every job.
    fn jobs(queue: &Queue<u32>) -> Vec<(CommandKind, u32, Vec<u32>, Vec<u32>)> {
        queue
            .jobs
            .iter()
            .map(|job| {
                (
                    job.request.kind().expect("a kind"),
                    job.request.axis,
                    job.waiters.clone(),
                    job.superseded
                        .iter()
                        .flat_map(|stop| stop.waiters.clone())
                        .collect(),
                )
            })
            .collect()
    }

    const ALL: u32 = CommandRequest::ALL_AXES;

    #[test]
    fn independence_is_the_same_target_kind_on_different_indices() {
        let stop = |axis| request(CommandKind::Stop, axis);
        assert!(independent(&stop(0), &stop(1)));
        assert!(!independent(&stop(0), &stop(0)));
        assert!(!independent(&stop(0), &stop(ALL)));
        let mut output = request(CommandKind::SetOutput, 1);
        output.target = Target::Signal as u32;
        assert!(!independent(&stop(0), &output), "another kind of target");
    }

    #[test]
    fn stops_of_one_axis_coalesce_but_never_across_a_goal_for_it() {
        use CommandKind::{EStop, Position, Stop};
        let mut queue = Queue::<u32>::default();
        queue.push_stop(request(Stop, 0), 1).expect("room");
        queue.push_stop(request(Stop, 1), 2).expect("room");
        // Axis 1's stop in between does not act on axis 0: joins the first.
        queue.push_stop(request(Stop, 0), 3).expect("room");
        queue.push(request(Position, 0), 4).expect("room");
        // Behind a goal for axis 0: a job of its own (it must stop that goal).
        queue.push_stop(request(Stop, 0), 5).expect("room");
        queue.push_stop(request(Stop, 0), 6).expect("room");
        queue.push_stop(request(Stop, 1), 7).expect("room");
        // Axis 1's last stop joins its first: nothing queued since acts on axis 1.
        assert_eq!(
            jobs(&queue),
            [
                (Stop, 0, vec![1, 3], vec![]),
                (Stop, 1, vec![2, 7], vec![]),
                (Position, 0, vec![4], vec![]),
                (Stop, 0, vec![5, 6], vec![]),
            ]
        );
        assert_eq!(queue.stops_held, 6);
        // An e-stop goes first and takes over every queued stop; the goal stays queued
        // (the server refuses it while latched).
        queue.push_estop(request(EStop, ALL), vec![8]);
        queue.push_estop(request(EStop, ALL), vec![9]);
        assert_eq!(
            jobs(&queue),
            [
                (EStop, ALL, vec![8, 9], vec![1, 3, 2, 7, 5, 6]),
                (Position, 0, vec![4], vec![]),
            ]
        );
        let estop = queue.pop(true).expect("the e-stop may take the last slot");
        assert!(estop.is_estop());
        assert_eq!(queue.stops_held, 0);
        assert!(
            queue.pop(true).is_none(),
            "the goal waits for a slot of its own"
        );
        // Sent: the next e-stop makes a job of its own.
        queue.push_estop(request(EStop, ALL), vec![10]);
        assert_eq!(jobs(&queue).len(), 2);
    }

    #[test]
    fn the_bounds() {
        let mut queue = Queue::<usize>::default();
        for n in 0..MAX_QUEUED_SAFETY {
            queue
                .push_stop(request(CommandKind::Stop, 3), n)
                .expect("room");
        }
        assert_eq!(queue.len(), 1, "one job for every stop of axis 3");
        assert_eq!(
            queue.push_stop(request(CommandKind::Stop, 4), 0),
            Err(0),
            "{MAX_QUEUED_SAFETY} stop queries held"
        );
        for n in 1..MAX_QUEUED {
            queue
                .push(request(CommandKind::Velocity, 1), n)
                .expect("room");
        }
        assert_eq!(queue.push(request(CommandKind::Velocity, 1), 0), Err(0));
        // The e-stop is never refused; the bridge's own requests neither.
        queue.push_estop(request(CommandKind::EStop, ALL), vec![1]);
        queue.push_own(request(CommandKind::Stop, 5));
        assert_eq!(queue.drain().len(), MAX_QUEUED + 1);
    }

    #[test]
    fn reply_for_a_coalesced_or_superseded_query() {
        let mut estop = request(CommandKind::EStop, ALL);
        estop.sequence = 90;
        let served = CommandReply::to(&estop, Reason::Accepted, 4711);
        let mut mine = request(CommandKind::Stop, 2);
        mine.sequence = 7;
        // The sequence, kind and axis of the stop; the e-stop's tick.
        assert_eq!(
            reply_for(&mine, &served),
            CommandReply::to(&mine, Reason::Accepted, 4711)
        );
        let refused = CommandReply::to(&estop, Reason::Unsupported, 4712);
        assert_eq!(
            reply_for(&mine, &refused).reason,
            Reason::Unsupported as u32
        );
        let mut first = request(CommandKind::Stop, 2);
        first.sequence = 1;
        let coalesced = CommandReply::to(&first, Reason::Accepted, 12);
        assert_eq!(
            reply_for(&mine, &coalesced),
            CommandReply::to(&mine, Reason::Accepted, 12)
        );
    }
}
